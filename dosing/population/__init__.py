"""The population axis: one bead, or a batch of sizes (docs/batch.md).  ``sizes``: size laws
and measured tables (each law picks its quadrature rule).  A batch's dose lifts the one-bead
answer over the sizes by the model that answers it: ``front`` (the front model's table),
``curves`` (per-node release curves under heating steps), ``bands`` (the truth per
interfacial-length band), ``medium`` (a drug's classes in one medium), ``cycles`` (heat and
rest cycles).  Modules are imported by name: this package imports none of them."""
