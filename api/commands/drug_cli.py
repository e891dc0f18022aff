"""Drug doses and schedules on the command line (``dose`` / ``schedule`` with drug options;
``dose`` and ``schedule`` each print both kinds with one printer)."""

from __future__ import annotations

import argparse
from typing import Any

from solver.errors import ParameterError

from .common import add_at_start_options


def add_wait_options(p: argparse.ArgumentParser) -> None:
    """Time in the medium at T_start before the first heating (drug doses)."""
    add_at_start_options(p, "wait", "with a drug: time at T_start before heating (default 0)",
                         drug_only=True)


def _planner(args: argparse.Namespace) -> Any:
    from concurrent.futures import ThreadPoolExecutor

    from dosing import Planner

    return Planner(cache_path=args.cache, executor=ThreadPoolExecutor(2))


def drug_dose(args: argparse.Namespace, drug: Any, kwargs: dict[str, Any]) -> tuple[Any, Any]:
    """``thermogel dose`` with a drug: (request, answer), printed by the dose printer."""
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
        return req, plan_drug_dose(planner, req, validate=bool(getattr(args, "validate", False)))
    finally:
        planner.close()


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
