"""Presenters of answers and runs: tables (``tables``: pandas frames and HTML) and
datasets (``export``: xarray, netCDF, CSV).  Modules are imported by name: this package
imports none of them."""
