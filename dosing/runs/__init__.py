"""Full-solver runs for the planner: what a run is (``scenario``: Scenario, SolverSettings,
Trajectory, ``run_scenario``), where it is kept (``store``: RunStore, memory then the
SQLite ``cache`` then the ``jobs`` executor; ``solute``: a drug's runs in the same file),
where a protocol run restarts (``restart``), and the one import of the full solver
(``full``).  Modules are imported by name: this package imports none of them."""
