"""The heating axis: a jump to T_end (the paper's) or steps in seconds.  ``grammar`` reads
the steps (texts, dicts, traces; ``Protocol``), ``program`` turns them into the solver's
continuous program, ``reduced`` is the slow-heating front model and its measured region,
``response`` a bead's dose under the steps (until-steps, the reduced model or the full
solver), ``cycles`` the heat-and-rest cycles of a schedule under steps.  Modules are
imported by name: this package imports none of them."""
