"""A regression table of the planner's answers, made at commit 70c49c7 (before the dosing/
refactor "one request, one answer"), so the refactored code can be checked against it.

Run:  PYTHONPATH=. .venv/bin/python -m benchmarks.regression_table \\
          --out tests/data/regression_70c49c7.json

Every answer goes through the public Python API (``dosing.DoseRequest``,
``dosing.ScheduleRequest``, ``dosing.plan_dose``, ``dosing.plan_schedule``,
``dosing.Planner``, ``dosing.population.front.batch_answer``, ``dosing.population.curves.
batch_protocol_answer``, ``dosing.payload.release.DrugDoseRequest`` with ``plan_drug_dose``) on a
temporary cache (no stored run is reused), over the combinations that answer without a
long full-solver run:

* fluid, one bead, jump, dose: the front model (ANB 302 -> 308 / 310 K, HHT 304 -> 308 /
  310 K; 10, 30, 50, 80 %; without a bead size and at 50 um dry);
* fluid, batch, jump, dose: a lognormal batch of CV 0.2 (as ``--size-cv 0.2`` builds it)
  around 50 um: the mean bead's answer and the batch's own (``batch``);
* fluid, one bead, protocol, dose: the reduced slow-heating model (5 and 1 K/min to 308 K,
  50 um, 30 and 80 %);
* fluid, batch, protocol, dose: the reduced model per bead size (mean 120 um: a 50 um
  batch's small beads are outside the reduced model's region and refused);
* drug, one bead, jump, dose: the reduced drug model, and D0 = 0 (the fluid answer);
* fluid, one bead, jump, schedule: the hold reading (no protocol check, no correction);
* two validated entries (``check: "full"``): the full solver's truth within its numerical
  part.

Each entry: ``id`` (the combination and its inputs), ``kind``, ``check`` ("exact": to rel
1e-9, abs 1e-12 for zeros, strings equal; "full": the outputs named in ``tolerance`` within
it, the others exact), ``inputs`` (in words), ``request`` (the recipe: the public call and
the keyword arguments of its request), ``outputs`` (plain floats, strings, None; each key
its attribute path on the answer: ``batch.time`` the batch's own answer, ``hold[1].end``)
and ``cost_seconds`` (the first entry of a kind includes numba's start-up, if its cache is
cold).  ``not_answered`` lists the combinations tried that do not answer today without the
full solver, with the error.  ``tests/test_regression_table.py`` rebuilds every entry from
its recipe.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

COMMIT = "70c49c7"
COMMAND = "python -m benchmarks.regression_table --out tests/data/regression_70c49c7.json"
REL, ABS = 1e-9, 1e-12

JUMPS = (("ANB", 302.0, (308.0, 310.0)), ("HHT", 304.0, (308.0, 310.0)))
JUMP_FRACTIONS = (0.1, 0.3, 0.5, 0.8)
BEAD_UM = 50.0
BATCH = {"kind": "lognormal", "cv": 0.2, "state": "dry"}  # the CLI's --size-cv 0.2
BATCH_FRACTIONS = (0.3, 0.8)
RAMPS = ("Heat to 308 K at 5 K/min", "Heat to 308 K at 1 K/min")
PROTOCOL_FRACTIONS = (0.3, 0.8)
BATCH_PROTOCOL_UM = 120.0  # every bead of a CV 0.2 batch inside the reduced region
# the cheaper ones (1.3-1.5 s: 32 nodes; HHT at 5 K/min and at 1 K/min 80 % take 2.7 s, 64)
BATCH_PROTOCOLS = (("ANB", 302.0, RAMPS[0], 0.8), ("ANB", 302.0, RAMPS[1], 0.3),
                   ("ANB", 302.0, RAMPS[1], 0.8), ("HHT", 304.0, RAMPS[1], 0.3))
DRUGS = (  # (drug, fractions): inside the reduced drug model's measured region, or D0 = 0
    ({"diffusivity_cm2_s": 1e-8, "hindrance": "none"}, (0.3, 0.5, 0.8)),
    ({"diffusivity_cm2_s": 1e-7, "hindrance": "none"}, (0.5, 0.8)),
    ({"diffusivity_cm2_s": 1e-6, "hindrance": "none"}, (0.5, 0.8)),
    ({"diffusivity_cm2_s": 1e-8, "hindrance": "ogston", "solute_radius_nm": 1.0,
      "fiber_radius_nm": 1.0}, (0.9,)),
    ({"diffusivity_cm2_s": 0.0}, (0.3, 0.8)),
)
DRUGS_OUTSIDE = (  # tried: the full solver's drug run would answer (not run here)
    ({"diffusivity_cm2_s": 1e-7, "hindrance": "none"}, 0.3),
    ({"diffusivity_cm2_s": 1e-7, "hindrance": "free-volume"}, 0.5),
)
SCHEDULE = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dry_radius_um": BEAD_UM,
            "doses": [0.3, 0.3, 0.3], "rests": [0.5, 0.5], "check_protocol": False,
            "correct": False}
FULL = (("ANB", 302.0, 308.0), ("HHT", 304.0, 308.0))  # 80 %, 50 um, validate=True
FULL_MAX_SECONDS = 30.0

FLUID_FIELDS = ("model", "time", "seconds", "error_estimate", "final_radius")
PROTOCOL_FIELDS = (*FLUID_FIELDS, "temperature_at_dose")
BATCH_FIELDS = ("model", "time", "seconds", "mean_bead_time", "mean_bead_seconds", "delay",
                "fraction_delivered")
DRUG_FIELDS = ("model", "time", "seconds", "squeezed_fraction", "fluid_fraction")
HOLD_FIELDS = ("start", "end", "actuation_time", "actuation_seconds", "error_estimate")


def _plain(x: Any) -> Any:
    """A JSON leaf: str, None, or float (numpy scalars and ints as float)."""
    if x is None or isinstance(x, str):
        return x
    return float(x)


def _pick(obj: Any, names: tuple[str, ...], prefix: str = "") -> dict[str, Any]:
    return {prefix + n: _plain(getattr(obj, n)) for n in names}


def _fraction_id(f: float) -> str:
    return f"f={f:g}"


# ----------------------------------------------------------------------------- recipes
def dose_args(gel: str, t_start: float, t_end: float | None, fraction: float,
              dry_radius_um: float | None = None, **extra: Any) -> dict[str, Any]:
    """DoseRequest's keyword arguments (JSON-ready)."""
    out: dict[str, Any] = {"gel": gel, "t_start": t_start}
    if t_end is not None:
        out["t_end"] = t_end
    out["dose_fraction"] = fraction
    if dry_radius_um is not None:
        out["dry_radius_um"] = dry_radius_um
    return {**out, **extra}


class Table:
    """The entries and the combinations that did not answer, computed on one cache."""

    def __init__(self, cache_path: str) -> None:
        self.cache_path = cache_path
        self.entries: list[dict[str, Any]] = []
        self.not_answered: list[dict[str, Any]] = []

    def add(self, kind: str, ident: str, inputs: dict[str, Any], request: dict[str, Any],
            compute: Callable[[], dict[str, Any]], check: str = "exact",
            tolerance: Callable[[dict[str, Any]], dict[str, Any]] | None = None) -> None:
        t0 = time.perf_counter()
        try:
            outputs = compute()
        except Exception as exc:  # recorded: the table says what does not answer today
            self.miss(kind, ident, inputs, exc)
            return
        cost = time.perf_counter() - t0
        entry = {"id": f"{kind}:{ident}", "kind": kind, "check": check, "inputs": inputs,
                 "request": request, "outputs": outputs, "cost_seconds": round(cost, 3)}
        if tolerance is not None:
            entry["tolerance"] = tolerance(outputs)
        self.entries.append(entry)
        print(f"{cost:7.3f} s  {entry['id']}", file=sys.stderr, flush=True)

    def miss(self, kind: str, ident: str, inputs: dict[str, Any], exc: BaseException) -> None:
        self.not_answered.append({"id": f"{kind}:{ident}", "kind": kind, "inputs": inputs,
                                  "error": f"{type(exc).__name__}: {exc}"})
        print(f"   --     {kind}:{ident}: {type(exc).__name__}: {str(exc)[:120]}",
              file=sys.stderr, flush=True)

    # ------------------------------------------------------------------ the combinations
    def fluid_jumps(self) -> None:
        from dosing import DoseRequest, Planner, plan_dose

        kind = "fluid/one/jump/dose"
        with Planner(cache_path=self.cache_path, executor=ThreadPoolExecutor(1)) as guard:
            for gel, t0, ends in JUMPS:
                for t1 in ends:
                    for dry in (None, BEAD_UM):
                        for f in JUMP_FRACTIONS:
                            args = dose_args(gel, t0, t1, f, dry)
                            ident = (f"{gel}:{t0:g}->{t1:g}:{_fraction_id(f)}:"
                                     f"dry={'none' if dry is None else f'{dry:g}'}")
                            choice = guard.model_answer(DoseRequest(**args))
                            if choice.needs_full:  # a front-model table only
                                self.miss(kind, ident, args, RuntimeError(
                                    f"needs the full solver: {choice.why}"))
                                continue
                            self.add(kind, ident, args,
                                     {"call": "dosing.plan_dose", "request": "DoseRequest",
                                      "args": args},
                                     lambda a=args: _pick(plan_dose(
                                         DoseRequest(**a), cache_path=self.cache_path),
                                         FLUID_FIELDS))
            guard.jobs.executor.shutdown(wait=True)

    def fluid_batches(self) -> None:
        from dosing import DoseRequest, plan_dose
        from dosing.population.front import batch_answer

        kind = "fluid/batch/jump/dose"
        for gel, t0, ends in JUMPS:
            for f in BATCH_FRACTIONS:
                args = dose_args(gel, t0, ends[0], f, BEAD_UM, size_distribution=dict(BATCH))
                ident = f"{gel}:{t0:g}->{ends[0]:g}:{_fraction_id(f)}:mean={BEAD_UM:g}:cv=0.2"

                def compute(a: dict[str, Any] = args) -> dict[str, Any]:
                    mean = plan_dose(DoseRequest(**a), cache_path=self.cache_path)
                    batch = batch_answer(DoseRequest(**a))
                    return {**_pick(mean, FLUID_FIELDS), **_pick(batch, BATCH_FIELDS, "batch.")}

                self.add(kind, ident, args,
                         {"call": "dosing.plan_dose + dosing.population.front.batch_answer",
                          "request": "DoseRequest", "args": args}, compute)

    def protocols(self) -> None:
        from dosing import DoseRequest, plan_dose, timescale
        from dosing.heating.reduced import choose  # the guard only: no full-solver run

        kind = "fluid/one/protocol/dose"
        for gel, t0, _ in JUMPS:
            for step in RAMPS:
                for f in PROTOCOL_FRACTIONS:
                    args = dose_args(gel, t0, None, f, BEAD_UM, protocol=[step])
                    ident = f"{gel}:{t0:g}:[{step}]:{_fraction_id(f)}:dry={BEAD_UM:g}"
                    req = DoseRequest(**args)
                    tau = timescale(BEAD_UM, req.t_end, req.constants).seconds
                    choice = choose(req, req.heating.program(tau), False)
                    if not choice.reduced:
                        self.miss(kind, ident, args, RuntimeError(
                            f"the full solver would answer: {choice.why}"))
                        continue
                    self.add(kind, ident, args,
                             {"call": "dosing.plan_dose", "request": "DoseRequest",
                              "args": args},
                             lambda a=args: _pick(plan_dose(DoseRequest(**a),
                                                            cache_path=self.cache_path),
                                                  PROTOCOL_FIELDS))

    def batch_protocols(self) -> None:
        from dosing import DoseRequest, plan_dose
        from dosing.population.curves import batch_protocol_answer

        kind = "fluid/batch/protocol/dose"
        for gel, t0, step, f in BATCH_PROTOCOLS:
            args = dose_args(gel, t0, None, f, BATCH_PROTOCOL_UM, protocol=[step],
                             size_distribution=dict(BATCH))
            ident = f"{gel}:{t0:g}:[{step}]:{_fraction_id(f)}:mean={BATCH_PROTOCOL_UM:g}:cv=0.2"

            def compute(a: dict[str, Any] = args) -> dict[str, Any]:
                mean = plan_dose(DoseRequest(**a), cache_path=self.cache_path)
                batch = batch_protocol_answer(DoseRequest(**a))
                return {**_pick(mean, PROTOCOL_FIELDS), **_pick(batch, BATCH_FIELDS, "batch.")}

            self.add(kind, ident, args,
                     {"call": "dosing.plan_dose + dosing.population.curves.batch_protocol_answer",
                      "request": "DoseRequest", "args": args}, compute)
        for gel, t0, _ in JUMPS:  # tried: a 50 um batch is refused (its small beads)
            args = dose_args(gel, t0, None, 0.8, BEAD_UM, protocol=[RAMPS[0]],
                             size_distribution=dict(BATCH))
            ident = f"{gel}:{t0:g}:[{RAMPS[0]}]:f=0.8:mean={BEAD_UM:g}:cv=0.2"
            try:
                batch_protocol_answer(DoseRequest(**args))
            except Exception as exc:
                self.miss(kind, ident, args, exc)

    def drugs(self) -> None:
        from dosing import Planner
        from dosing.payload.release import DrugDoseRequest, plan_drug_dose

        class NoFullRun:
            """Drug runs refused: an answer that needs the full solver is not tabled."""

            def run(self, sc: Any) -> Any:
                raise LookupError("needs the full solver's drug run (outside the reduced "
                                  "drug model's measured region)")

        kind = "drug/one/jump/dose"
        with Planner(cache_path=self.cache_path, executor=ThreadPoolExecutor(1)) as p:
            cases = [(d, f, True) for d, fs in DRUGS for f in fs]
            cases += [(d, f, False) for d, f in DRUGS_OUTSIDE]
            for gel, t0, ends in JUMPS:
                for drug, f, inside in cases:
                    args = {"gel": gel, "t_start": t0, "t_end": ends[0], "drug": dict(drug),
                            "dose_fraction": f, "dry_radius_um": BEAD_UM}
                    ident = (f"{gel}:{t0:g}->{ends[0]:g}:{_fraction_id(f)}:dry={BEAD_UM:g}:"
                             + ",".join(f"{k}={v}" for k, v in drug.items()))

                    def compute(a: dict[str, Any] = args) -> dict[str, Any]:
                        ans = plan_drug_dose(p, DrugDoseRequest(**a), runs=NoFullRun())
                        u = ans.uncertainty
                        return {**_pick(ans, DRUG_FIELDS),  # D0 = 0: no uncertainty yet
                                "uncertainty.numerical.relative": None if u is None
                                else _plain(u.numerical.relative),
                                "uncertainty.model_form.relative": None if u is None
                                else _plain(u.model_form.relative)}

                    if inside:
                        self.add(kind, ident, args,
                                 {"call": "dosing.payload.release.plan_drug_dose(Planner(...), .)",
                                  "request": "DrugDoseRequest", "args": args}, compute)
                    else:
                        try:
                            compute()
                            raise AssertionError(f"{ident} answered: move it to DRUGS")
                        except LookupError as exc:
                            self.miss(kind, ident, args, exc)
            p.jobs.executor.shutdown(wait=True)

    def schedules(self) -> None:
        from dosing import ScheduleRequest, plan_schedule

        kind = "fluid/one/jump/schedule"
        args = dict(SCHEDULE)
        ident = "ANB:302->308:doses=0.3,0.3,0.3:rests=0.5,0.5:dry=50:hold"

        def compute() -> dict[str, Any]:
            ans = plan_schedule(ScheduleRequest(**args), cache_path=self.cache_path)
            out = {"model": _plain(ans.model)}
            for i, row in enumerate(ans.hold):
                out.update(_pick(row, HOLD_FIELDS, f"hold[{i}]."))
            return out

        self.add(kind, ident, args, {"call": "dosing.plan_schedule",
                                     "request": "ScheduleRequest", "args": args}, compute)

    def full(self) -> None:
        from dosing import DoseRequest, plan_dose

        kind = "fluid/one/jump/dose/validated"
        for gel, t0, t1 in FULL:
            args = dose_args(gel, t0, t1, 0.8, BEAD_UM)
            ident = f"{gel}:{t0:g}->{t1:g}:f=0.8:dry={BEAD_UM:g}:validate"

            def compute(a: dict[str, Any] = args) -> dict[str, Any]:
                t = time.perf_counter()
                ans = plan_dose(DoseRequest(**a), validate=True, cache_path=self.cache_path)
                wall = time.perf_counter() - t
                if wall > FULL_MAX_SECONDS:
                    raise TimeoutError(f"the validation took {wall:.1f} s "
                                       f"(> {FULL_MAX_SECONDS:g} s): not tabled")
                return {**_pick(ans, ("model", "time", "seconds", "final_radius")),
                        "validation.time": _plain(ans.validation.time),
                        "error_estimate": _plain(ans.error_estimate),
                        "numerical_part": _plain(ans.uncertainty.numerical.relative)}

            def tolerance(out: dict[str, Any]) -> dict[str, Any]:
                num = out.pop("numerical_part")
                # the truth within its numerical part; the error estimate (the front's gap
                # to the truth, with the truth's own parts) moves by about as much
                return {"validation.time": {"rel": num}, "error_estimate": {"abs": 3.0 * num}}

            self.add(kind, ident, args,
                     {"call": "dosing.plan_dose", "request": "DoseRequest", "args": args,
                      "validate": True}, compute, check="full", tolerance=tolerance)


def _git_head() -> str | None:
    try:
        return subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                              check=True, cwd=os.path.dirname(__file__)).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def build(with_full: bool = True) -> dict[str, Any]:
    """The table (module doc), on a temporary cache."""
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="regression-") as tmp:
        table = Table(os.path.join(tmp, "cache.sqlite"))
        table.fluid_jumps()
        table.fluid_batches()
        table.protocols()
        table.batch_protocols()
        table.drugs()
        table.schedules()
        if with_full:
            table.full()
    kinds: dict[str, int] = {}
    for e in table.entries:
        kinds[e["kind"]] = kinds.get(e["kind"], 0) + 1
    return {
        "about": "the planner's answers at this commit, before the dosing/ refactor 'one "
                 "request, one answer' (benchmarks/regression_table.py's docstring)",
        "commit": COMMIT, "head": _git_head(), "command": COMMAND,
        "tolerance": {"exact": {"rel": REL, "abs": ABS},
                      "full": "per entry: the outputs in its 'tolerance' ({'rel': x} or "
                              "{'abs': x}), the others as 'exact'"},
        "counts": kinds, "runtime_seconds": round(time.perf_counter() - t0, 1),
        "entries": table.entries, "not_answered": table.not_answered,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="tests/data/regression_70c49c7.json")
    ap.add_argument("--no-full", action="store_true", help="leave out the validated entries")
    args = ap.parse_args(argv)
    data = build(with_full=not args.no_full)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as fh:
        json.dump(data, fh, indent=1)
        fh.write("\n")
    print(f"wrote {args.out}: {len(data['entries'])} entries {data['counts']}, "
          f"{len(data['not_answered'])} not answered, {data['runtime_seconds']} s",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
