"""A batch's drug dose on the command line (``dose`` with a drug and --size-cv / --sizes;
dosing.batch_drug, docs/batch.md)."""

from __future__ import annotations

from typing import Any

from .common import table_row, wrap


def print_drug_batch(req: Any, ans: Any) -> None:
    """A batch's drug dose into a shared medium (or a perfect sink), in words."""
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


def print_batch_schedule(req: Any, ans: Any) -> None:
    """A batch's schedule (dosing.batch_schedule) in words: its readings, nodes and errors."""
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
