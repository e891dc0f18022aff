"""Sub-commands of the ``thermogel`` command line, one module each."""
