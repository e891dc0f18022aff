"""Design (issue 39): the heating that meets a target, and the experiment that pins the
model.

    from . import HeatingTarget, design_heating, ExperimentAsk, design_experiment
    out = design_heating(HeatingTarget("ANB", 302, at_seconds=60, fraction=0.5,
                                       dry_radius_um=50, validate=True), planner)
    out.value            # the jump temperature (K) at which 50 % is out at 60 s

- :mod:`dosing.design.heating`: the inverse search over the planner's answer (a bracketing
  root search, ``scipy.optimize.brentq``, on the reduced model first, the truth polished
  when a validation is asked), with the envelope at that heating, the heatings that keep the
  target inside it, and optionally the heating that meets it with probability P;
- :mod:`dosing.design.experiment`: the measurement that best pins the answer's dominant
  parts (the jump, the bead size, the sampling times), its predicted envelope from the
  Fisher information of the kinetics fit, and the separation of the two front laws.
"""

from __future__ import annotations

from .experiment import ExperimentAsk, ExperimentDesign, design_experiment
from .heating import HeatingDesign, HeatingTarget, design_heating

__all__ = ["ExperimentAsk", "ExperimentDesign", "HeatingDesign", "HeatingTarget",
           "design_experiment", "design_heating"]
