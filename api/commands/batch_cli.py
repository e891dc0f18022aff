"""A batch's drug dose on the command line (``dose`` with a drug and --size-cv / --sizes;
dosing.batch_drug, docs/batch.md)."""

from __future__ import annotations

import argparse
from typing import Any

from solver.errors import ParameterError

from .common import print_json, wrap


def run_drug_batch(args: argparse.Namespace, drug: Any, kwargs: dict[str, Any],
                   dist: Any) -> int:
    """The batch's drug dose into a shared medium (--medium-volume-ml, --bead-count) or a
    perfect sink."""
    from dosing.batch_drug import drug_batch_dose
    from dosing.drug_dose import DrugDoseRequest

    for name in ("volume_ul", "drug_mass_ug", "concentration_ug_per_ul"):
        if getattr(args, name) is not None:
            raise ParameterError(name, getattr(args, name), "None for a batch's drug dose "
                                 "(give --fraction of the batch's load)")
    if args.fraction is None:
        raise ParameterError("--fraction", None, "a fraction of the batch's load, 0-1")
    if (args.medium_volume_ml is None) != (args.bead_count is None):
        name = "--bead-count" if args.bead_count is None else "--medium-volume-ml"
        raise ParameterError(name, None, "given with " + ("--medium-volume-ml" if
                             name == "--bead-count" else "--bead-count") + " (both or none)")
    req = DrugDoseRequest(drug=drug, dose_fraction=args.fraction, wait=args.wait,
                          wait_seconds=args.wait_seconds, **kwargs)
    ans = drug_batch_dose(req, dist, args.medium_volume_ml, args.bead_count)
    if args.json:
        print_json(ans.to_dict())
        return 0
    secs = "" if ans.seconds is None else f" = {ans.seconds:.4g} s"
    print(f"{req.gel.name} {req.t_start:g} K -> {req.t_end:g} K: a batch ({ans.description}) "
          f"releases {ans.dose_fraction:.1%} of its drug")
    print(f"  {ans.model}: heat for t = {ans.time:.4g} (reference tau){secs}")
    if ans.medium_volume_ml is not None:
        print(f"  medium {ans.medium_volume_ml:.4g} mL for {ans.bead_count:.4g} beads "
              f"({ans.medium_over_pore_volume:.3g}x their partition-weighted pore volume): "
              f"the perfect-sink sum says {ans.sink_time:.4g} and overstates the release at "
              f"the dose time by {ans.sink_overestimate:.1%}")
    if ans.medium_concentration_ug_per_ul is not None:
        print(f"  medium concentration at the dose {ans.medium_concentration_ug_per_ul:.4g} "
              "ug/uL")
    print(f"  errors: numerical {ans.numerical_error:.1e} (steps halved), quadrature "
          f"{ans.quadrature_error:.1e} ({ans.classes} size classes against twice as many); "
          f"mass balance {ans.mass_balance_error:.1e}")
    print(wrap(ans.note))
    return 0
