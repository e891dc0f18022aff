"""Warm every numba kernel before the service takes requests, so no request pays a compile.

Two passes.  First every signature already in numba's on-disk cache (``cache=True``) is
loaded for every kernel in ``solver`` and ``dosing``; then a small representative workload
(equilibria, folds, the jump classifier, a front-model dose, a few steps of the full solver
on each grid and integrator) compiles whatever a fresh machine has not cached yet and
writes it to that cache, where the planner's worker processes load it.  The report lists
the kernels still cold (no signature compiled in this process: unused ones, and helpers
only ever called from other kernels), which ``/health`` shows.
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
    """What the warm-up did: kernels warm, kernels cold, and how long it took."""

    warm: list[str] = field(default_factory=list)
    cold: list[str] = field(default_factory=list)
    loaded_signatures: int = 0
    seconds: float = 0.0
    errors: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"warm": len(self.warm), "cold": list(self.cold), "seconds": self.seconds,
                "loaded_signatures": self.loaded_signatures, "errors": list(self.errors)}


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
    """Small calls touching every kernel a request reaches (front-model dose if a planner)."""
    from solver.equilibrium import equilibria, folds
    from solver.gel import ANB, HHT
    from solver.phase import classify_jump

    work: list[Callable[[], Any]] = [
        lambda: equilibria(ANB, 305.0),
        lambda: folds(HHT),
        lambda: classify_jump(ANB, 302.0, 308.0),
        lambda: classify_jump(HHT, 308.0, 304.0),
    ]
    if planner is not None:
        work.append(lambda: _front_dose(planner))
        work.append(lambda: _drug_dose_lookup(planner))
        work.append(lambda: _start_pool(planner))
    work.append(_tiny_full_runs)
    work.append(_tiny_drug_run)
    return work


def _tiny_drug_run() -> None:
    """A few steps of the solute on a tiny run (the drug's kernels, solver/solute)."""
    from solver.gel import ANB
    from solver.solute import Solute, simulate_release

    simulate_release(ANB, 302.0, Solute(diffusivity=1.0), protocol=[(1.0e-4, 308.0)], n=20,
                     samples=10, rtol=1.0e-3)


def _tiny_full_runs() -> None:
    """A few steps of the full solver on every grid and integrator (N = 20): compiles its
    kernels into numba's disk cache, which the planner's worker processes then load."""
    from dosing.scenario import GRIDS, INTEGRATORS
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
    return jobs.executor.submit(_import, "dosing.drug").result(timeout=300)


def _import(name: str) -> None:
    """Import a module (in a pool worker; returns nothing picklable-heavy)."""
    importlib.import_module(name)


def _drug_dose_lookup(planner: Any) -> Any:
    """A drug dose with diffusion looked up in the cache (nothing is computed): the first
    real one then finds its modules imported and its kernels loaded (a burst of drug doses
    does not hold the GIL for seconds in the server process)."""
    from dosing.drug import DrugModel
    from dosing.drug_dose import DrugDoseRequest, drug_dose_now

    return drug_dose_now(planner, DrugDoseRequest(
        "ANB", 302.0, 308.0, DrugModel(diffusivity_cm2_s=1e-7, load_ug=1.0),
        dose_fraction=0.3, dry_radius_um=50.0))


def _front_dose(planner: Any) -> Any:
    """One front-model dose (ANB 302 -> 308 K, 80%, 50 um): the front model's kernels."""
    from dosing import DoseRequest
    from solver.gel import ANB

    return planner.dose(DoseRequest(gel=ANB, t_start=302.0, t_end=308.0, dose_fraction=0.8,
                                    dry_radius_um=50.0))


def warm_up(planner: Any = None, packages: tuple[str, ...] = PACKAGES) -> WarmupReport:
    """Load cached kernels, run the representative workload, report warm and cold kernels."""
    t0 = time.perf_counter()
    report = WarmupReport()
    found = kernels(packages)
    for kernel in found.values():
        report.loaded_signatures += load_cached(kernel)
    for call in representative_workload(planner):
        try:
            call()
        except Exception as exc:
            report.errors.append(f"{type(exc).__name__}: {exc}")
            log.warning("warm-up call failed: %s", exc)
    for name, kernel in sorted(found.items()):
        (report.warm if kernel.signatures else report.cold).append(name)
    report.seconds = time.perf_counter() - t0
    log.info("warm-up: %d kernels warm, %d cold, %.2f s", len(report.warm), len(report.cold),
             report.seconds)
    return report
