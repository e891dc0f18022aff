"""The population axis: one bead, or a batch of sizes.  ``sizes`` holds the size laws and
measured tables (each law picks its quadrature rule); a batch's dose is the one-bead
answer lifted over the sizes by the model that answers it: the front model's table
(``front``), per-node release curves under heating steps (``curves``: the reduced
slow-heating model or the full solver per node), the truth per interfacial-length band
(``bands``), a drug's classes coupled through one shared medium (``medium``), and the
nodes' runs shot together through heat-and-rest cycles (``cycles``).  Modules are
imported by name: this package imports none of them."""
