"""Issue 23's speed figures, in CPU seconds, this tree side by side with other revisions.

Run:  .venv/bin/python -m benchmarks.speed [--before 4aa7d90] [--only help,dose,warm]
      .venv/bin/python -m benchmarks.speed --before 70c49c7 --only warm_dose

Each figure is measured in a fresh interpreter per tree (``PYTHONPATH`` = that tree), in
CPU seconds (user + system, ``resource.getrusage`` of the children, threads and worker
processes included), so the machine's other load changes them little; the trees run
alternately and each figure is the median of ``--repeats``.  ``--before`` names git
revisions (checked out into temporary worktrees, removed at the end) or existing trees.

Figures (``--only``):

* ``help``: ``thermogel dose --help``;
* ``dose``: a front-model ``thermogel dose --gel ANB --t-start 302 --t-end 308
  --fraction 0.8 --dry-radius-um 50`` (numba caches warm, the validation cache fresh);
* ``warm``: ``Planner.dose`` on a kept planner, milliseconds of CPU per answer (nine
  front-model requests in turn, 3,000 answers);
* ``warm_dose``: ``Planner.dose`` of one front-model request (ANB 302 -> 308 K, 80 %, a
  50 um bead) on a kept planner, milliseconds of CPU per answer (3,000 answers), with its
  truth (the validation runs) stored in the planner's cache, and beside it the same
  request on a fresh cache (no truth stored: the prior), measured in the same process
  (issue 35).  Each tree stores its truth once (``dose(validate=True)``, about 30 s, not
  counted) in a cache file kept for the repeats;
* ``load``: the HTTP service's requests per second (benchmarks/load.py: 3,000 requests
  over 16 connections after 300 uncounted, 2-4 s at this service's rate, where 600 took
  well under a second and two runs of one tree differed by up to 1.5x; wall-clock
  throughput, so its ratio is what counts), and
  the server process's CPU per request (its pool's validation runs left out).  Every tree's
  server is driven by this tree's client (``load.py --tree``), with the same options, so
  only the servers differ; median of ``--repeats`` runs, the trees alternating;
* ``validation``: a cold (fresh cache) validation of the ANB 302 -> 308 K 80 % dose of a
  50 um bead (``Planner.dose(validate=True)``), with its answer, the truth's numerical
  bound and the model-form lattice, so that the answers can be compared;
* ``schedule``: a cold three-dose schedule with the protocol check;
* ``drug``: a cold drug dose on the full solver: ANB 302 -> 308 K, a 50 um bead, 50 % of
  an unhindered drug with D0 = 1e-7 cm^2/s (``plan_drug_dose(..., validate=True)``: the
  drug run and its n / 2 check), with its time and numerical bound;
* ``drug_schedule``: a cold drug schedule on the full solver (the same bead, an unhindered
  D0 = 1e-8 cm^2/s drug, doses 0.2 x 3 of the load, rests 0.05 tau: hold reading, protocol
  check, shooting and the n / 2 check), with its corrected times;
* ``moving``: the moving grid (400 cells, rtol 1e-5) at ell = 1e-3 and 3e-5, ANB 302 ->
  308 K to t = 0.08: CPU, accepted and rejected steps, remaps, the 80 % dose time.

The first call of each tree compiles or loads its numba kernels and is not counted.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import resource
import signal
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PY = sys.executable
DOSE_ARGS = ["--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction", "0.8",
             "--dry-radius-um", "50"]

WARM = """
import json, resource
from concurrent.futures import ThreadPoolExecutor
from dosing import DoseRequest, Planner
p = Planner(cache_path={cache!r}, executor=ThreadPoolExecutor(1))
reqs = [DoseRequest("ANB", 302, 308, dose_fraction=f, dry_radius_um=r)
        for f in (0.3, 0.5, 0.8) for r in (20, 50, 100)]
for r in reqs:
    p.dose(r)
def cpu():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime
n = 3000
t0 = cpu()
for i in range(n):
    p.dose(reqs[i % len(reqs)])
print(json.dumps({{"ms": 1e3 * (cpu() - t0) / n}}))
p.close()
"""

WARM_DOSE = """
import json, resource
from concurrent.futures import ThreadPoolExecutor
from dosing import DoseRequest, Planner
def cpu():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime
req = DoseRequest("ANB", 302, 308, dose_fraction=0.8, dry_radius_um=50)
out = {{}}
for name, path in (("stored", {stored!r}), ("fresh", {fresh!r})):
    p = Planner(cache_path=path, executor=ThreadPoolExecutor(1))
    first = p.dose(req).to_dict()
    n = 3000
    t0 = cpu()
    for _ in range(n):
        ans = p.dose(req)
    out[name] = 1e3 * (cpu() - t0) / n
    out[name + "_validated"] = ans.validation is not None
    out[name + "_same"] = ans.to_dict() == first
    out[name + "_time"] = ans.time
    p.close()
print(json.dumps(out))
"""

STORE_TRUTH = """
from concurrent.futures import ThreadPoolExecutor
from dosing import DoseRequest, Planner
p = Planner(cache_path={stored!r}, executor=ThreadPoolExecutor(2))
assert p.dose(DoseRequest("ANB", 302, 308, dose_fraction=0.8, dry_radius_um=50),
              validate=True).validation is not None
p.close()
"""

KERNELS = """
from solver.errors import ParameterError
from solver.full import simulate
for grid, ell in (("moving", 1e-3), ("lagrangian", 0.0), ("eulerian", 0.0)):
    try:
        simulate("ANB", 302, 308, until=1e-3, grid=grid, n=40, interfacial_length=ell)
    except ParameterError:  # a revision without this grid
        pass
"""

VALIDATION = KERNELS + """
import json, resource
from concurrent.futures import ThreadPoolExecutor
from dosing import DoseRequest, Planner
def cpu():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime
t0 = cpu()
p = Planner(cache_path={cache!r}, executor=ThreadPoolExecutor(2))
ans = p.dose(DoseRequest("ANB", 302, 308, dose_fraction=0.8, dry_radius_um=50),
             validate=True)
took = cpu() - t0
v = ans.validation
u = (v.uncertainty if hasattr(v, "uncertainty") else v.get("uncertainty")) or {{}}
runs = v.runs if hasattr(v, "runs") else v["runs"]
print(json.dumps({{"cpu": took, "time": v.time if hasattr(v, "time") else v["time"],
                  "numerical": (u.get("numerical") or {{}}).get("relative"),
                  "model_form_ns": u.get("delayed_transition_ns"),
                  "model_form_times": u.get("delayed_transition_times"),
                  "model_form_spread": u.get("delayed_transition_spread"),
                  "runs": [[e["grid"], e["n"], e["interfacial_length"], e.get("time")]
                           for e in runs]}}))
p.close()
"""

SCHEDULE = KERNELS + """
import json, resource
from concurrent.futures import ThreadPoolExecutor
from dosing import Planner, ScheduleRequest
def cpu():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime
t0 = cpu()
p = Planner(cache_path={cache!r}, executor=ThreadPoolExecutor(2))
ans = p.schedule(ScheduleRequest("ANB", 302, 308, doses=[0.2, 0.2, 0.2], rests=[0.05, 0.05],
                                 check_protocol=True))
d = ans.to_dict()
print(json.dumps({{"cpu": cpu() - t0,
                  "checked": (d.get("protocol_check") or {{}}).get("delivered_fractions"),
                  "corrected": (d.get("corrected") or {{}}).get("actuation_times")}}))
p.close()
"""

DRUG_KERNELS = KERNELS + """
import json, resource
from concurrent.futures import ThreadPoolExecutor
from solver.full import simulate
from solver.solute import Solute, release
release(simulate("ANB", 302, 308, until=1e-3, grid="moving", n=40, interfacial_length=1e-3,
                 saveat=[0.0, 5e-4, 1e-3]), Solute(1.0))  # the solute's kernels loaded
from dosing import Planner
from dosing.payload.drug import DrugModel
"""

DRUG_START = """
def cpu():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime
t0 = cpu()
p = Planner(cache_path={cache!r}, executor=ThreadPoolExecutor(2))
"""

DRUG = DRUG_KERNELS + """
from dosing.payload.release import DrugDoseRequest, plan_drug_dose
""" + DRUG_START + """
ans = plan_drug_dose(p, DrugDoseRequest("ANB", 302, 308,
                                        DrugModel(diffusivity_cm2_s=1e-7, hindrance="none"),
                                        dose_fraction=0.5, dry_radius_um=50), validate=True)
print(json.dumps({{"cpu": cpu() - t0, "model": ans.model, "time": ans.time,
                  "numerical": ans.uncertainty.numerical.relative}}))
p.close()
"""

DRUG_SCHEDULE = DRUG_KERNELS + """
from dosing.payload.cycles import DrugScheduleRequest, plan_drug_schedule
""" + DRUG_START + """
ans = plan_drug_schedule(p, DrugScheduleRequest(
    "ANB", 302, 308, DrugModel(diffusivity_cm2_s=1e-8, hindrance="none", load_ug=1.0),
    doses=[0.2, 0.2, 0.2], rests=[0.05, 0.05], dry_radius_um=50))
print(json.dumps({{"cpu": cpu() - t0, "corrected": ans.corrected["actuation_times"],
                  "numerical": ans.uncertainty.numerical.relative}}))
p.close()
"""

MOVING = KERNELS + """
import json, resource
from solver.full import simulate
def cpu():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime
out = {{}}
for ell in (1e-3, 3e-5):
    t0 = cpu()
    res = simulate("ANB", 302, 308, until=0.08, grid="moving", n=400, interfacial_length=ell,
                   rtol=1e-5)
    d = res.diagnostics
    out[f"{{ell:g}}"] = {{"cpu": cpu() - t0, "steps": d["steps"], "rejected": d["rejected"],
                         "remaps": d.get("remaps"), "t80": res.time_to_radius(1.4749)}}
print(json.dumps({{"cpu": sum(v["cpu"] for v in out.values()), **out}}))
"""


def cpu_children() -> float:
    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


def run(tree: Path, argv: list[str], env: dict[str, str] | None = None,
        timeout: float = 900.0) -> tuple[float, str]:
    """(CPU seconds, stdout) of one child process in ``tree``.  The child runs in a session
    of its own, which is killed afterwards: an older tree's server may leave its pool's
    workers behind (4aa7d90's did), and none may outlive the measurement."""
    e = dict(os.environ, PYTHONPATH=str(tree), **(env or {}))
    t0 = cpu_children()
    proc = subprocess.Popen(argv, cwd=tree, env=e, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)  # the child's leftovers, if any
        proc.wait()
    took = cpu_children() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{tree}: {' '.join(argv[:4])}... failed:\n{err[-2000:]}")
    return took, out


def _json(out: str) -> dict:
    return json.loads(out.strip().splitlines()[-1])


def fig_help(tree: Path, tmp: Path) -> tuple[float, str]:
    took, _ = run(tree, [PY, "-m", "api.cli", "dose", "--help"])
    return took, ""


def fig_dose(tree: Path, tmp: Path) -> tuple[float, str]:
    cache = tmp / f"dose-{tree.name}.sqlite"
    took, out = run(tree, [PY, "-m", "api.cli", "dose", *DOSE_ARGS],
                    env={"THERMOGEL_CACHE": str(cache)})
    return took, out.splitlines()[1].strip() if out else ""


def fig_warm(tree: Path, tmp: Path) -> tuple[float, str]:
    _, out = run(tree, [PY, "-c", WARM.format(cache=str(tmp / f"warm-{tree.name}.sqlite"))])
    return _json(out)["ms"], "ms of CPU per answer"


def fig_warm_dose(tree: Path, tmp: Path) -> tuple[float, str]:
    stored = tmp / f"warm-dose-truth-{tree.name}.sqlite"
    done = Path(f"{stored}.done")
    if not done.exists():  # this tree's truth, stored once (kept for the repeats)
        run(tree, [PY, "-c", STORE_TRUTH.format(stored=str(stored))], timeout=1800)
        done.touch()
    fresh = _fresh(tmp, f"warm-dose-fresh-{tree.name}.sqlite")
    _, out = run(tree, [PY, "-c", WARM_DOSE.format(stored=str(stored), fresh=str(fresh))])
    res = _json(out)
    if not res["stored_validated"] or res["fresh_validated"]:
        raise RuntimeError(f"{tree}: the stored truth does not validate the answer: {res}")
    return res["stored"], (f"ms of CPU per answer with its truth stored; without: "
                           f"{res['fresh']:.4f} ms (the stored truth costs "
                           f"{res['stored'] / res['fresh']:.2f}x); warm answers equal the "
                           f"first: {res['stored_same'] and res['fresh_same']}")


def fig_load(tree: Path, tmp: Path) -> tuple[float, str]:
    _, out = run(tree, [PY, str(ROOT / "benchmarks" / "load.py"), "--tree", str(tree),
                        "--requests", "3000", "--warmup", "300", "--concurrency", "16",
                        "--json"], timeout=900)
    res = json.loads(out[out.index("{"):])
    closed = res.get("closed_loop") or res.get("closed") or res
    cpu = closed.get("server_cpu_ms_per_request")
    return float(closed["throughput_rps"]), "requests/s (closed loop)" + (
        "" if cpu is None else f"; server CPU {cpu:.2f} ms per request")


def _fresh(tmp: Path, name: str) -> Path:
    path = tmp / name
    for suffix in ("", "-wal", "-shm"):
        Path(str(path) + suffix).unlink(missing_ok=True)
    return path


def _cold(template: str, tag: str, tree: Path, tmp: Path) -> tuple[float, str]:
    """A cold figure: ``template`` run on a fresh cache; its CPU and its answers."""
    code = template.format(cache=str(_fresh(tmp, f"{tag}-{tree.name}.sqlite")))
    _, out = run(tree, [PY, "-c", code], timeout=1800)
    res = _json(out)
    return res["cpu"], json.dumps({k: v for k, v in res.items() if k != "cpu"})


def fig_validation(tree: Path, tmp: Path) -> tuple[float, str]:
    return _cold(VALIDATION, "val", tree, tmp)


def fig_schedule(tree: Path, tmp: Path) -> tuple[float, str]:
    return _cold(SCHEDULE, "sch", tree, tmp)


def fig_drug(tree: Path, tmp: Path) -> tuple[float, str]:
    return _cold(DRUG, "drug", tree, tmp)


def fig_drug_schedule(tree: Path, tmp: Path) -> tuple[float, str]:
    return _cold(DRUG_SCHEDULE, "dsch", tree, tmp)


def fig_moving(tree: Path, tmp: Path) -> tuple[float, str]:
    _, out = run(tree, [PY, "-c", MOVING.format()], timeout=1800)
    res = _json(out)
    return res["cpu"], json.dumps({k: v for k, v in res.items() if k != "cpu"})


FIGURES: dict[str, tuple[Callable[[Path, Path], tuple[float, str]], str, bool]] = {
    # name: (measure, unit, lower is better)
    "help": (fig_help, "s CPU", True),
    "dose": (fig_dose, "s CPU", True),
    "warm": (fig_warm, "ms CPU", True),
    "warm_dose": (fig_warm_dose, "ms CPU", True),
    "load": (fig_load, "req/s", False),
    "validation": (fig_validation, "s CPU", True),
    "schedule": (fig_schedule, "s CPU", True),
    "drug": (fig_drug, "s CPU", True),
    "drug_schedule": (fig_drug_schedule, "s CPU", True),
    "moving": (fig_moving, "s CPU", True),
}
WARMS = {"dose": True, "help": True}  # figures whose first call per tree is not counted


def _tree(spec: str, tmp: Path) -> tuple[Path, bool]:
    """An existing directory, or a git revision checked out under ``tmp`` (True: made)."""
    if Path(spec).is_dir():
        return Path(spec).resolve(), False
    path = tmp / f"rev-{spec}"
    subprocess.run(["git", "worktree", "add", "--detach", "-q", str(path), spec], cwd=ROOT,
                   check=True)
    return path, True


def main(argv: list[str] | None = None) -> int:
    """Measure the figures asked for in every tree and print them side by side."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", action="append", default=None,
                    help="revision or tree to compare with (repeatable; default 4aa7d90)")
    ap.add_argument("--only", default="help,dose,warm",
                    help=f"comma-separated figures among {', '.join(FIGURES)}")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    names = [n.strip() for n in args.only.split(",") if n.strip()]
    bad = [n for n in names if n not in FIGURES]
    if bad:
        ap.error(f"unknown figure(s) {bad}; choose among {list(FIGURES)}")
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        made: list[Path] = []
        trees: list[tuple[str, Path]] = []
        try:
            for spec in args.before or ["4aa7d90"]:
                path, new = _tree(spec, tmp)
                trees.append((spec, path))
                if new:
                    made.append(path)
            trees.append(("this tree", ROOT))
            if {"validation", "schedule", "drug", "drug_schedule", "moving"} & set(names):
                for tree in (t for _, t in trees):  # compile each tree's kernels once
                    run(tree, [PY, "-c", KERNELS])
            for name in names:
                fn, unit, lower = FIGURES[name]
                reps = 1 if name in ("validation", "schedule", "drug", "drug_schedule",
                                     "moving") else args.repeats
                got: dict[Path, list[float]] = {t: [] for _, t in trees}
                notes: dict[Path, str] = {}
                for k in range(reps + (1 if name in WARMS else 0)):
                    for _, tree in trees:
                        try:
                            value, note = fn(tree, tmp)
                        except (RuntimeError, KeyError, ValueError,
                                subprocess.TimeoutExpired) as exc:
                            value, note = float("nan"), f"failed: {str(exc)[-300:]}"
                        if name in WARMS and k == 0:
                            continue
                        got[tree].append(value)
                        notes[tree] = note
                last = statistics.median(got[ROOT])
                print(f"{name} ({unit}, median of {reps}):")
                for label, tree in trees:
                    med = statistics.median(got[tree])
                    ratio = med / last if lower else last / med
                    print(f"  {label:<14} {med:10.4g}   ({ratio:.2f}x this tree's speed)"
                          f"   {notes[tree][:400]}")
                    if tree != ROOT and len(got[tree]) > 1:  # the runs side by side, paired
                        pairs = [(a / b if lower else b / a) for a, b in
                                 zip(got[tree], got[ROOT], strict=True)]
                        print(f"  {'':<14} this tree / {label} run by run: "
                              f"{', '.join(f'{x:.2f}x' for x in pairs)} (paired median "
                              f"{statistics.median(pairs):.2f}x)")
                sys.stdout.flush()
        finally:
            for path in made:
                subprocess.run(["git", "worktree", "remove", "--force", str(path)], cwd=ROOT,
                               check=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
