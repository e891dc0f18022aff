"""Warm every numba kernel before the service takes requests, so no request pays a compile.

Two passes.  First every signature already in numba's on-disk cache (``cache=True``) is
loaded for every kernel in ``solver`` and ``dosing``; then a small representative workload
(equilibria, folds, the jump classifier, a front-model dose, a few steps of the full solver
on each grid and integrator) compiles whatever a fresh machine has not cached yet and
writes it to that cache, where the planner's worker processes load it.  The report lists
the kernels still cold (no signature compiled in this process, and no compiled kernel that
calls it), which ``/health`` shows; a helper called only from other kernels is compiled
into them (numba compiles a callee into its caller: loaded from the disk cache, the
caller's machine code holds it) and counts as warm through its caller.

It logs as it goes (``thermogel.warmup``, INFO: ``thermogel serve`` shows it between
uvicorn's "Waiting for application startup" and "startup complete"): each group of kernels
loaded from the disk cache (solver.full, solver.front, ...) and each call of the workload,
with its seconds.
"""

from __future__ import annotations

import importlib
import logging
import pkgutil
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

log = logging.getLogger("thermogel.warmup")

PACKAGES = ("solver", "dosing")


@dataclass
class WarmupReport:
    """What the warm-up did: kernels warm, kernels cold, and how long it took (in all, per
    group of kernels loaded from the disk cache, per call of the workload)."""

    warm: list[str] = field(default_factory=list)
    cold: list[str] = field(default_factory=list)
    loaded_signatures: int = 0
    seconds: float = 0.0
    errors: list[str] = field(default_factory=list)
    inlined: dict[str, str] = field(default_factory=dict)  # helper -> a compiled caller
    steps: list[tuple[str, float]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"warm": len(self.warm), "cold": list(self.cold), "seconds": self.seconds,
                "loaded_signatures": self.loaded_signatures, "errors": list(self.errors),
                "inlined": dict(self.inlined),
                "steps": [{"step": name, "seconds": round(sec, 3)}
                          for name, sec in self.steps]}


def _is_kernel(obj: Any) -> bool:
    """True for a numba dispatcher (an ``@njit`` function)."""
    from numba.core.dispatcher import Dispatcher

    return isinstance(obj, Dispatcher)


def _modules(packages: tuple[str, ...]) -> Iterator[Any]:
    """Every importable module of the packages (a module that fails to import is skipped)."""
    for name in packages:
        try:
            pkg = importlib.import_module(name)
        except ImportError:
            continue
        yield pkg
        for info in pkgutil.walk_packages(getattr(pkg, "__path__", []), prefix=f"{name}."):
            try:
                yield importlib.import_module(info.name)
            except Exception as exc:
                log.warning("warm-up: cannot import %s: %s", info.name, exc)


def kernels(packages: tuple[str, ...] = PACKAGES) -> dict[str, Any]:
    """Every numba kernel defined in the packages, by qualified name."""
    from solver.jit import Kernel

    out: dict[str, Any] = {}
    for mod in _modules(packages):
        for attr, obj in vars(mod).items():
            if isinstance(obj, Kernel) and obj.__module__ == mod.__name__:
                obj = obj.compiled  # numba loaded on first compiled use (solver.jit)
            if _is_kernel(obj) and obj.py_func.__module__ == mod.__name__:
                out[f"{mod.__name__}.{attr}"] = obj
    return out


def cached_signatures(kernel: Any) -> list[tuple]:
    """Signatures stored in the kernel's on-disk cache (empty when none or not cached)."""
    cache = getattr(kernel, "_cache", None)
    cache_file = getattr(cache, "_cache_file", None)
    if cache_file is None:
        return []
    try:
        return [key[0] for key in cache_file._load_index()]
    except Exception:
        return []


def load_cached(kernel: Any) -> int:
    """Compile (load from disk) every cached signature; returns how many loaded."""
    n = 0
    for sig in cached_signatures(kernel):
        try:
            kernel.compile(sig)
            n += 1
        except Exception:
            continue
    return n


def representative_workload(planner: Any = None) -> list[Callable[[], Any]]:
    """Small calls touching every kernel a request reaches (front-model dose if a planner);
    each call's ``__name__`` says what it warms (the log's lines)."""
    from solver.equilibrium import equilibria, folds
    from solver.gel import ANB, HHT
    from solver.phase import classify_jump

    def equilibria_and_folds() -> None:
        equilibria(ANB, 305.0)
        folds(HHT)

    def jump_classifier() -> None:
        classify_jump(ANB, 302.0, 308.0)
        classify_jump(HHT, 308.0, 304.0)

    work: list[Callable[[], Any]] = [equilibria_and_folds, jump_classifier]
    if planner is not None:
        work += [_named("front-model dose", lambda: _front_dose(planner)),
                 _named("drug dose lookup", lambda: _drug_dose_lookup(planner)),
                 _named("planner's process pool", lambda: _start_pool(planner))]
    work += [_slow_heating, _tiny_full_runs, _tiny_drug_run, _shared_medium, _direct_kernels]
    return work


def _named(name: str, call: Callable[[], Any]) -> Callable[[], Any]:
    call.__name__ = name
    return call


def _slow_heating() -> None:
    """The reduced model for slow heating (solver.front.slow: its compiled integrator)."""
    from solver.front.slow import slow_front_trajectory
    from solver.heating import Hold, Program, Ramp

    slow_front_trajectory("ANB", 302.0, Program((Ramp(308.0, 50.0), Hold(308.0, 0.05))))


def _shared_medium() -> None:
    """A batch releasing into one shared medium (solver.solute.medium's march)."""
    import numpy as np

    from solver.solute import Solute
    from solver.solute.medium import coupled_release

    s = np.linspace(0.0, 0.2, 9)
    a3 = 3.0 + (2.0 - 3.0) * np.sqrt(s / 0.2)
    s3 = ((np.arange(9) / 8) ** 3)[None, :] * a3[:, None]
    coupled_release(s, s3, Solute(diffusivity=5.0), [1.0], [1.0], 10.0,
                    np.linspace(0.0, 0.2, 5))


def _direct_kernels() -> None:
    """Kernels a Python caller runs as Python until compiled (solver.jit's @kernel) and
    library kernels no request path calls yet: compiled for their float signature."""
    import numpy as np

    from solver.front.evolve import _invert_decreasing
    from solver.front.maxwell import _lower_hull
    from solver.solute.hindrance import hindrance_factor
    from solver.thermo import mixing_energy

    mixing_energy.compiled(2.0, -0.5, 0.3)
    hindrance_factor(0.5, 1, 0.2, 1.0)
    x = np.linspace(0.0, 1.0, 5)
    _lower_hull.compiled(x, (x - 0.5) ** 2)
    _invert_decreasing.compiled(np.array([1.0, -0.5]), np.array([0.5, 0.0]), 0.0, 1.0,
                                np.array([0.9]), 1e-12, 50)


def _tiny_drug_run() -> None:
    """A few steps of the solute on a tiny run (the drug's kernels, solver/solute)."""
    from solver.gel import ANB
    from solver.solute import Solute, simulate_release

    simulate_release(ANB, 302.0, Solute(diffusivity=1.0), protocol=[(1.0e-4, 308.0)], n=20,
                     samples=10, rtol=1.0e-3)


def _tiny_full_runs() -> None:
    """A few steps of the full solver on every grid and integrator (N = 20): compiles its
    kernels into numba's disk cache, which the planner's worker processes then load."""
    from dosing.runs.scenario import GRIDS, INTEGRATORS
    from solver.full import simulate
    from solver.gel import ANB

    for grid in GRIDS:
        for integrator in INTEGRATORS:
            if grid == "moving" and integrator != "implicit":
                continue  # the moving grid runs the implicit integrator only
            simulate(ANB, 302.0, protocol=[(1.0e-4, 308.0)], grid=grid, n=20,
                     integrator=integrator, rtol=1.0e-3,
                     interfacial_length=0.01 if grid == "moving" else 0.0)


def _start_pool(planner: Any) -> Any:
    """Start the planner's executor (a process pool's spawned worker imports the solver)
    now, not under the first burst of requests that need a run."""
    jobs = getattr(planner, "jobs", None)
    if jobs is None:
        return None
    return jobs.executor.submit(_import, "dosing.payload.drug").result(timeout=300)


def _import(name: str) -> None:
    """Import a module (in a pool worker; returns nothing picklable-heavy)."""
    importlib.import_module(name)


def _drug_dose_lookup(planner: Any) -> Any:
    """A drug dose with diffusion looked up in the cache (nothing is computed): the first
    real one then finds its modules imported and its kernels loaded (a burst of drug doses
    does not hold the GIL for seconds in the server process)."""
    from dosing.payload.drug import DrugModel
    from dosing.payload.release import DrugDoseRequest, drug_dose_now

    return drug_dose_now(planner, DrugDoseRequest(
        "ANB", 302.0, 308.0, DrugModel(diffusivity_cm2_s=1e-7, load_ug=1.0),
        dose_fraction=0.3, dry_radius_um=50.0))


def _front_dose(planner: Any) -> Any:
    """One front-model dose (ANB 302 -> 308 K, 80%, 50 um): the front model's kernels."""
    from dosing import DoseRequest
    from solver.gel import ANB

    return planner.dose(DoseRequest(gel=ANB, t_start=302.0, t_end=308.0, dose_fraction=0.8,
                                    dry_radius_um=50.0))


GROUP_DEPTH = 2  # kernels are grouped by their first two module names (solver.full, ...)


def _group(name: str) -> str:
    return ".".join(name.split(".")[:GROUP_DEPTH])


def _callers(found: dict[str, Any]) -> dict[str, str]:
    """Each kernel whose name a compiled kernel's source calls (``name(``): the helper,
    compiled into that caller, -> one such caller."""
    import inspect
    import re

    sources = {}
    for qual, kernel in found.items():
        if kernel.signatures:
            try:
                sources[qual] = inspect.getsource(kernel.py_func)
            except (OSError, TypeError):
                continue
    out: dict[str, str] = {}
    changed = True
    while changed:  # a helper of a helper: reached through a caller already counted
        changed = False
        for qual, kernel in found.items():
            if kernel.signatures or qual in out:
                continue
            short = qual.rsplit(".", 1)[-1]
            pattern = re.compile(rf"(?<![\w.]){re.escape(short)}\s*\(|\.{re.escape(short)}\s*\(")
            for caller, src in sources.items():
                if caller != qual and pattern.search(src.split("\n", 1)[-1]):
                    out[qual] = caller
                    sources[qual] = inspect.getsource(kernel.py_func)
                    changed = True
                    break
    return out


def warm_up(planner: Any = None, packages: tuple[str, ...] = PACKAGES) -> WarmupReport:
    """Load cached kernels, run the representative workload, report warm and cold kernels;
    log each group and call with its seconds as it goes (module doc)."""
    t0 = time.perf_counter()
    report = WarmupReport()
    found = kernels(packages)
    groups: dict[str, list[Any]] = {}
    for name, kernel in sorted(found.items()):
        groups.setdefault(_group(name), []).append(kernel)
    log.info("warm-up: %d numba kernels in %d groups (%.1f s to find them); loading numba's "
             "disk cache", len(found), len(groups), time.perf_counter() - t0)
    for group, members in groups.items():
        t1 = time.perf_counter()
        loaded = sum(load_cached(kernel) for kernel in members)
        report.loaded_signatures += loaded
        sec = time.perf_counter() - t1
        report.steps.append((f"load {group}", sec))
        log.info("warm-up: %-16s %3d kernels, %3d cached signatures loaded, %5.2f s", group,
                 len(members), loaded, sec)
    for call in representative_workload(planner):
        name = getattr(call, "__name__", "call").strip("_").replace("_", " ")
        t1 = time.perf_counter()
        try:
            call()
        except Exception as exc:
            report.errors.append(f"{name}: {type(exc).__name__}: {exc}")
            log.warning("warm-up call %s failed: %s", name, exc)
        sec = time.perf_counter() - t1
        report.steps.append((name, sec))
        log.info("warm-up: %-30s %5.2f s", name, sec)
    report.inlined = _callers(found)
    for name, kernel in sorted(found.items()):
        (report.warm if kernel.signatures or name in report.inlined
         else report.cold).append(name)
    report.seconds = time.perf_counter() - t0
    log.info("warm-up: done in %.1f s: %d kernels warm (%d of them compiled into their "
             "callers), %d cold%s", report.seconds, len(report.warm), len(report.inlined),
             len(report.cold), (": " + ", ".join(report.cold)) if report.cold else "")
    return report
