"""Drug doses and schedules on the command line (``dose`` / ``schedule`` with drug options;
``schedule`` prints both kinds)."""

from __future__ import annotations

import argparse
from typing import Any

from solver.errors import ParameterError

from .common import print_json, print_uncertainty, wrap


def add_wait_options(p: argparse.ArgumentParser) -> None:
    """Time in the medium at T_start before the first heating (drug doses)."""
    w = p.add_mutually_exclusive_group()
    w.add_argument("--wait", type=float, default=None,
                   help="with a drug: time at T_start before heating, dimensionless (default 0)")
    w.add_argument("--wait-seconds", type=float, default=None,
                   help="with a drug: the wait in seconds (needs a bead size)")


def _planner(args: argparse.Namespace) -> Any:
    from concurrent.futures import ThreadPoolExecutor

    from dosing import Planner

    return Planner(cache_path=args.cache, executor=ThreadPoolExecutor(2))


def run_drug_dose(args: argparse.Namespace, drug: Any, kwargs: dict[str, Any]) -> int:
    """``thermogel dose`` with a drug: the actuation time for a drug dose."""
    from dosing.drug_dose import DrugDoseRequest, plan_drug_dose

    if args.volume_ul is not None:
        raise ParameterError("volume_ul", args.volume_ul, "None with a drug (give --fraction "
                             "of the load or --drug-mass-ug)")
    if args.concentration_ug_per_ul is not None:
        raise ParameterError("concentration_ug_per_ul", args.concentration_ug_per_ul,
                             "None with a drug (give --load-ug or "
                             "--loading-concentration-ug-per-ul)")
    req = DrugDoseRequest(drug=drug, dose_fraction=args.fraction, drug_mass_ug=args.drug_mass_ug,
                          wait=args.wait, wait_seconds=args.wait_seconds, **kwargs)
    planner = _planner(args)
    try:
        ans = plan_drug_dose(planner, req, validate=bool(getattr(args, "validate", False)))
    finally:
        planner.close()
    if args.json:
        print_json(ans.to_dict())
        return 0
    mass = "" if ans.dose_ug is None else f" = {ans.dose_ug:.4g} ug"
    secs = "" if ans.seconds is None else f" = {ans.seconds:.4g} s"
    heat = (f"from {req.t_start:g} K under {'; '.join(ans.protocol.steps)}"
            if ans.protocol is not None else f"{req.t_start:g} K -> {req.t_end:g} K")
    print(f"{req.gel.name} {heat}: release {ans.dose_fraction:.1%} of the loaded drug{mass}")
    print(f"  {ans.model}: " + (f"t = {ans.time:.4g} tau{secs} from the protocol's start "
                                 f"(at {ans.protocol.temperature_at_dose:.4g} K)"
                                 if ans.protocol is not None else
                                 f"heat for t = {ans.time:.4g} (dimensionless){secs}, after "
                                 f"waiting {ans.wait:.4g} at T_start"))
    print(f"  leaked before heating: {ans.leaked_before_heating:.4g} of the load; at T_start "
          f"the bead leaks 10% in {ans.leak_time_10pct:.4g} tau"
          + ("" if ans.leak_time_10pct_seconds is None
             else f" ({ans.leak_time_10pct_seconds:.4g} s)"))
    print(f"  mechanism: {ans.mechanism}; fluid expelled meanwhile {ans.fluid_fraction:.4g} of "
          f"the stored fluid; D_eff = {ans.effective_diffusivity_cm2_s:.3g} cm^2/s")
    if ans.split:
        print(wrap(f"  {ans.split}"))
    if ans.mesh:
        print(wrap(f"  {ans.mesh}"))
    if ans.medium_concentration_ug_per_ul is not None:
        print(f"  release medium concentration {ans.medium_concentration_ug_per_ul:.4g} ug/uL")
    print(wrap(f"truth of the drug runs: {ans.truth}"))
    print_uncertainty(ans.uncertainty, "the drug dose time")
    print(wrap(ans.note))
    return 0


def run_drug_schedule(args: argparse.Namespace, drug: Any, kwargs: dict[str, Any]
                      ) -> tuple[Any, Any]:
    """``thermogel schedule`` with a drug: (request, answer); ``--plot`` draws it."""
    from dosing.drug_schedule import DrugScheduleRequest, plan_drug_schedule

    req = DrugScheduleRequest(drug=drug, doses=args.doses, doses_ug=args.doses_ug,
                              wait=args.wait, wait_seconds=args.wait_seconds, **kwargs)
    planner = _planner(args)
    try:
        ans = plan_drug_schedule(planner, req)
        if getattr(args, "plot", None):
            _plot(planner, req, ans, args.plot)
    finally:
        planner.close()
    return req, ans


def _plot(planner: Any, req: Any, ans: Any, path: str) -> None:
    """Cumulative drug through the corrected (else the checked) protocol."""
    from api.plots.release import draw_schedule_release
    from dosing.drug import runs_for
    from dosing.drug_dose import DrugHeatings

    res = ans.corrected if ans.corrected and ans.corrected.get("actuation_times") \
        else ans.protocol_check
    if not res:
        raise ParameterError("plot", path, "used with the protocol check or the correction")
    rel = DrugHeatings(req, runs_for(planner), req.fractions).run(res["actuation_times"])
    print(f"wrote {draw_schedule_release(ans.to_dict(), rel, path)}")
