"""The payload axis: what a dose is a fraction of.  The stored pore fluid is the bead's own
(no module: eq. FluidVolExpelled); a drug is ``drug`` (DrugModel, its solute and runs),
read by the reduced drug model (``reduced``), at a dose (``release``: under a jump or
heating steps) and through heat-and-rest cycles (``cycles``).  Modules are imported by
name: this package imports none of them."""
