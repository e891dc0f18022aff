"""thermogel's benchmark scripts (error against run time, never timed unit tests).

Each module runs as a script (``python benchmarks/NAME.py``) and is importable as
``benchmarks.NAME`` from a source checkout (``pip install -e .`` installs the package), so
``thermogel bench`` and the tests import the work-precision library without path hacks.
"""
