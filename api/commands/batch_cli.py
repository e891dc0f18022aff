"""A batch's drug dose on the command line (``dose`` with a drug and --size-cv / --sizes;
dosing.batch_drug, docs/batch.md)."""

from __future__ import annotations

import argparse
from typing import Any

from solver.errors import ParameterError

from .common import print_json, table_row, wrap


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


def run_batch_schedule(args: argparse.Namespace, kwargs: dict[str, Any], dist: Any) -> int:
    """A batch's fluid schedule (``schedule`` with --size-cv / --sizes;
    dosing.batch_schedule): actuation times whose summed release meets each dose."""
    from dosing import ScheduleRequest
    from dosing.batch_schedule import plan_batch_schedule, reference_fields

    if args.plot is not None:
        raise ParameterError("--plot", args.plot, "absent with a batch's schedule (--json "
                             "gives every node's delivery)")
    kwargs = {**kwargs, **reference_fields(dist, kwargs.get("dry_radius_um"),
                                           kwargs.get("swollen_radius_um"))}
    req = ScheduleRequest(doses=args.doses, **kwargs)
    ans = plan_batch_schedule(req, dist, cache_path=args.cache)
    if args.json:
        print_json(ans.to_dict())
        return 0
    print(f"{req.gel.name} {req.t_start:g} K -> {req.t_end:g} K, a batch ({ans.description}), "
          f"doses {', '.join(f'{d:.0%}' for d in ans.doses)} of its stored fluid, rests "
          f"{', '.join(f'{r:.4g}' for r in ans.rests) or '-'} (reference tau "
          f"{ans.timescale_seconds:.4g} s, {ans.reference_dry_radius_um:.4g} um dry)")
    print(table_row(f"hold ({ans.hold_model}):", [h.actuation_time for h in ans.hold]))
    for name, res in (("protocol check", ans.protocol_check), ("corrected", ans.corrected)):
        if not res:
            continue
        print(table_row(f"{name}: actuation times", res["actuation_times"]))
        print(table_row("  actuation seconds", res["actuation_seconds"]))
        print(table_row("  batch delivered (of stored)", res["delivered_fractions"]))
        print(table_row("  relative error", res["relative_errors"], "{:+.2%}"))
    print("  nodes (dry um, fluid share, ell): " + ", ".join(
        f"{n['dry_radius_um']:.4g} {n['volume_weight']:.3f} {n['interfacial_length']:.3g}"
        for n in ans.nodes))
    for part in ans.uncertainty.values():
        print(wrap(part["text"]))
    print(wrap(f"truth of each node's runs: {ans.truth}"))
    print(wrap(ans.note))
    return 0
