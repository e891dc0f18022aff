"""Issue 28: an answer without a bead size says how far ell = 1e-4 may be from the sharp
limit (the ladder in benchmarks/sharp_limit.py, docs/drug.md)."""

from __future__ import annotations

from dosing import DoseRequest
from dosing.truth import SHARP_LIMIT_NOTE, truth_text


def test_no_bead_truth_states_its_distance_from_the_sharp_limit() -> None:
    req = DoseRequest("HHT", 304, 308, dose_fraction=0.1)
    assert req.bead_dry_radius_um is None and req.settings.direct
    text = truth_text(req)
    assert SHARP_LIMIT_NOTE in text
    assert "NOT the limit" in text and "47 %" in text and "2.9 %" in text
    with_bead = truth_text(DoseRequest("HHT", 304, 308, dose_fraction=0.1, dry_radius_um=50))
    assert SHARP_LIMIT_NOTE not in with_bead
