"""Every range a rule checks, defined once (pure constants: no numba, no numpy).

The solver (``solver.full.options``), the planner's truth (``dosing.scenario``), the HTTP
schemas and the CLI all import their bounds from here; ``tests/test_limits.py`` fails if a
range is written again elsewhere.  Two kinds of range are deliberately distinct: what the
solver can run at all (``SOLVER_*``) and what the planner accepts for a validation, where a
run must also be affordable and converged (``TRUTH_*``).
"""

from __future__ import annotations

# temperatures: liquid water at 1 atm (K)
T_MIN = 273.15
T_MAX = 373.15

# grid cells of one full-solver run
SOLVER_N_RANGE = (10, 20000)
# the interfacial length ell (dry radii) must stay small against the dry radius
SOLVER_ELL_MAX = 0.2

# grid cells of a validation run (its check run has n / 2, a ladder's finest rung 4 n)
TRUTH_N_RANGE = (20, 6400)
# ell of a ladder (uniform grids: its finest rung at TRUTH_N_RANGE's top)
TRUTH_LADDER_ELL_RANGE = (0.000625, 0.02)
# ell of a direct run on the moving grid: down to a 10 um dry bead's xi_lo / a_d
TRUTH_DIRECT_ELL_RANGE = (2e-5, 0.02)
# the ladder's coarsest ell: its rungs ell/2, ell/4 stay within TRUTH_LADDER_ELL_RANGE, and above
# 0.01 the nucleation delay is a third of an 80 % dose (three rungs can look asymptotic
# while they are not: ANB from 0.02 misses the limit by 1 %)
LADDER_RUNGS = 3
TRUTH_LADDER_START_RANGE = (TRUTH_LADDER_ELL_RANGE[0] * (1 << (LADDER_RUNGS - 1)), 0.01)

# a temperature program's steps (solver.heating; simulate's protocol steps and horizon): the
# longest step, bath time constant or trace (tau), the fastest ramp (K per tau), how long an
# until-step waits when no duration bounds it (tau), the most rows of a trace.  The grammar
# (dosing.heating) is checked against them in tau before anything runs
# (dosing.heating_program.check_program)
PROGRAM_STEP_MAX = 1e6
PROGRAM_RATE_MAX = 1e12
UNTIL_LIMIT = 1e4
TRACE_ROWS_MAX = 100_000

# a time at T_start before or between heatings (a schedule's rest, a drug's wait), tau; given
# in seconds it is bounded after the conversion with the bead's tau (dosing.request.at_start)
REST_RANGE = (0.0, 1e3)
# a drug run holds each protocol step (its wait and rests too) in one simulate call of at
# most 100000 outputs, 2000 per tau (dosing.drug): a step of a drug run is at most this, tau
DRUG_STEP_MAX = 32.0

# a drug batch's shared release medium (mL) and its number of beads (dosing.batch_drug)
MEDIUM_VOLUME_ML_RANGE = (1e-6, 1e4)
BEAD_COUNT_RANGE = (1.0, 1e15)

# bead sizes, um: a dry radius (and every size a batch resolves to, after unit conversion);
# 1 nm below (a subnormal radius made tau 0, issue 22), 10 cm above
DRY_RADIUS_UM_RANGE = (1.0e-3, 1.0e5)
# a swollen size (or a diameter) may be larger than the dry radius it stands for
SIZE_UM_RANGE = (DRY_RADIUS_UM_RANGE[0], 1.0e6)
