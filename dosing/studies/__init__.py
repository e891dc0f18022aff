"""Studies over many requests: parameter sweeps (``sweep``) and global sensitivity
(``sensitivity``).  Modules are imported by name: this package imports none of them."""
