"""The full solver's drug runs resolve the first moments of a jump
(dosing.runs.solute.step_outputs).

Between outputs the solute code takes the bead to shrink linearly in time; a fast drug's
small doses leave in the first 5e-4 tau, before the uniform outputs' first sample.  Measured
(ANB 302 -> 308 K, D0 = 1e-7 cm^2/s, no hindrance, 50 um, ell = 0.01): the 10 % dose at
0.0004473 with uniform outputs only, 0.00039592 with the geometric ones (40 a decade),
0.00039591 with 200 a decade; the 30 % dose moves by 2e-4 relative.  The geometric outputs
run until their spacing reaches the uniform one (t = 8.4e-3 tau at 40 a decade): an
unhindered D0 = 1e-6 cm^2/s drug's 50 % dose (50 um, the truth's settings) is 0.00116743
with them, 0.00116747 at 160 a decade, and was 0.0011831 (1.3 % late) when they stopped at
the first uniform output.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import dosing.payload.release as drug_dose
import dosing.runs.solute as drug_module
from dosing import PhysicalConstants, Planner
from dosing.payload.drug import DrugModel
from dosing.payload.release import DrugDoseRequest, plan_drug_dose
from dosing.runs.scenario import SolverSettings
from dosing.runs.solute import step_outputs


def test_step_outputs_are_geometric_early_then_uniform() -> None:
    t = step_outputs(0.5, 1000)
    assert t[0] == 0.0 and t[-1] == 0.5 and np.all(np.diff(t) > 0)
    assert t[1] == pytest.approx(drug_module.EARLY_OUTPUT)
    assert set(np.linspace(0.0, 0.5, 1001)) <= set(t)  # every uniform output kept
    # no interval longer than the uniform one, nor than the geometric ratio allows
    ratio = 10 ** (1 / drug_module.EARLY_PER_DECADE)
    gaps = np.diff(t)[1:]
    assert np.all(gaps <= np.maximum(5e-4, t[1:-1] * (ratio - 1)) * (1 + 1e-9))
    assert np.all(gaps <= 5e-4 * (1 + 1e-9))
    assert 0.005 < t[t < 0.5][np.argmax(np.diff(t[t < 0.5]) > 4.9e-4)] < 0.01
    # a step whose uniform outputs are already finer than the early floor gets no extras
    assert np.array_equal(step_outputs(1e-8, 200), np.linspace(0.0, 1e-8, 201))


def _ten_percent(tmp_path, monkeypatch, long: bool = False, **module: float) -> float:
    for name, value in module.items():
        monkeypatch.setattr(drug_module, name, value)
    if long:  # the run to FIRST_HEATING (0.5 tau), not to twice the reduced model's time
        monkeypatch.setattr(drug_dose, "first_heating", lambda r: (
            drug_dose.FIRST_HEATING / 2.0, drug_dose.READ_OFF_FLOOR))
    p = Planner(cache_path=tmp_path / f"c{len(module)}{sorted(module)}.sqlite",
                executor=ThreadPoolExecutor(1))
    try:
        req = DrugDoseRequest("ANB", 302, 308, DrugModel(diffusivity_cm2_s=1e-7, load_ug=1.0,
                                                         hindrance="none"),
                              dose_fraction=0.1, dry_radius_um=50,
                              settings=SolverSettings(interfacial_length=0.01),
                              constants=PhysicalConstants.paper())  # D0 / D_gel = 9: fast
        ans = plan_drug_dose(p, req, validate=True)
        assert ans.model == "full+solute" or ans.model == "full"
        return ans.time
    finally:
        p.close()
        p.jobs.executor.shutdown()


@pytest.mark.slow
def test_a_fast_drugs_small_dose_is_resolved(tmp_path, monkeypatch) -> None:
    planned = _ten_percent(tmp_path, monkeypatch)
    with monkeypatch.context() as m:
        dense = _ten_percent(tmp_path, m, EARLY_PER_DECADE=200)
    with monkeypatch.context() as m:  # uniform outputs only, on a run to 0.5 tau
        uniform = _ten_percent(tmp_path, m, long=True, EARLY_OUTPUT=1.0)
    assert planned == pytest.approx(dense, rel=1e-3)
    assert uniform > 1.05 * dense  # what the geometric outputs fix: a dose read late
    # the planned run stops at twice the reduced model's time (issue 23), where even the
    # uniform outputs (at least MIN_SAMPLES a step) resolve the jump: measured 0.00039591
    with monkeypatch.context() as m:
        short = _ten_percent(tmp_path, m, EARLY_OUTPUT=1.0)
    assert short == pytest.approx(dense, rel=1e-3)
