"""Fits to a lab's data: a gel's swelling and kinetics (``gel``, CSV tables in
``csv_tables``, the stored gels in ``gel_store``, the fitted parameters' interval in
``uncertainty``, ``calibrate``), and release curves (``release``; under heating steps
``release_steps``).  Modules are imported by name: this package imports none of them."""
