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
    """The command's one-shot planner (``dosing._one_shot``: runs in this process; its
    executor stops with it, :func:`close_planner`)."""
    import dosing

    return dosing._one_shot(args.cache, None)


def close_planner(planner: Any) -> None:
    """Close the one-shot planner and stop its executor."""
    planner.close()
    planner.jobs.executor.shutdown(wait=True)


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
