"""Drug release: the cost of the drug against the same run without it, and its accuracy.

Run:  .venv/bin/python benchmarks/drug.py [--repeats 3] [--quick]
      .venv/bin/python benchmarks/drug.py --truth   (one truth: drug vs fluid answers)
      .venv/bin/python -m benchmarks.drug --section reduced [--repeats 20]
                     (issue 23: the reduced drug model's answers, CPU ms per answer)

For each case (ANB 302->308 K and HHT 304->308 K for t = 0.3, and ANB heat 0.05 / rest 0.5 /
heat 0.1; Lagrangian N = 400, ell = 0.01, rtol 1e-5) and drug (D0 = 0; the protein of the
README: D0 = 1e-7 cm^2/s = 8.8 D_gel, free-volume law Y = 1 with sieving r_s/xi = 0.98 in
the swollen gel; and the same protein without sieving) it prints
  * the wall time of the mechanics alone (``simulate``, its default 200 outputs), of the
    mechanics sampled densely for the drug, and of the solute on those samples (warm, median
    of --repeats), and the cost ratio (mechanics + solute) / mechanics alone (median over
    back-to-back pairs, so a shared machine's load affects both alike);
  * the error of the released fraction (max over the samples, absolute) against a reference
    with 16000 samples per unit time and a 100 x tighter solute tolerance, for 500, 1000,
    2000 and 4000 (the planner's drug runs) samples per unit time: 'solute err' on the
    reference's own mechanics subsampled (the solute's sampling error alone), 'total err'
    on a run sampled so (which adds the mechanics' change: its steps stop at every output);
  * the mass balance max |in gel + released - 1|.

``--truth`` (issue 12): a 50 um bead of ANB, 302 -> 308 K, planned by the planner on its
default truth (the moving grid at the bead's ell): the validated fluid 50 % dose against the
50 % drug dose of the README's protein (squeezed out with the fluid, so the two times must
agree to the fluid answer's numerical bound), with their wall times and ell.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from dosing.runs.solute import SAMPLES_PER_TAU
from solver.full import FullResult, simulate
from solver.solute import Hindrance, Solute, release

N, ELL, RTOL = 400, 0.01, 1e-5
CASES = {"ANB 302->308": ("ANB", 302.0, [(0.3, 308.0)]),
         "HHT 304->308": ("HHT", 304.0, [(0.3, 308.0)]),
         "ANB heat/rest/heat": ("ANB", 302.0, [(0.05, 308.0), (0.5, 302.0), (0.1, 308.0)])}
DRUGS = {"D0 = 0": Solute(0.0),
         "protein, sieved": Solute(8.8, Hindrance("free-volume", sieve=2.25, y=1.0)),
         "protein, no sieve": Solute(8.8, Hindrance("free-volume", sieve=0.0, y=1.0))}
SAMPLES = (500, 1000, 2000, 4000)  # per unit time (drug runs: dosing.runs.solute.SAMPLES_PER_TAU)


def median_time(fun: Callable[[], object], repeats: int) -> tuple[float, object]:
    """(median wall time in s after one warm-up call, the last result)."""
    out = fun()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fun()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def mechanics(gel: str, t0: float, protocol: list, samples: int | None) -> object:
    total = sum(d for d, _ in protocol)
    every = None if samples is None else total / (samples * total)
    return simulate(gel, t0, protocol=protocol, grid="lagrangian", n=N, rtol=RTOL,
                    interfacial_length=ELL, every=every)


def subsample(res: FullResult, every: int) -> FullResult:
    """Every ``every``-th output of a run (the same mechanics, sampled more coarsely)."""
    keep = np.unique(np.concatenate([np.arange(0, res.t.size, every), [res.t.size - 1]]))
    return replace(res, **{k: getattr(res, k)[keep] for k in
                           ("t", "radius", "front", "jump", "phi", "temperature",
                            "expelled_volume", "solid_error")})


def one_truth() -> None:
    """The fluid truth and the drug answer of the same bead and dose (``--truth``)."""
    import tempfile
    from concurrent.futures import ThreadPoolExecutor

    from dosing import DoseRequest, Planner
    from dosing.payload.drug import DrugModel
    from dosing.payload.release import DrugDoseRequest, plan_drug_dose

    protein = DrugModel(diffusivity_cm2_s=1e-7, mesh_size_nm=23.0, load_ug=1.0)
    with tempfile.TemporaryDirectory() as tmp, Planner(
            cache_path=f"{tmp}/truth.sqlite", executor=ThreadPoolExecutor(1)) as planner:
        w = time.perf_counter()
        fluid = planner.dose(DoseRequest("ANB", 302, 308, dose_fraction=0.5, dry_radius_um=50),
                             validate=True)
        w_fluid = time.perf_counter() - w
        w = time.perf_counter()
        drug = plan_drug_dose(planner, DrugDoseRequest("ANB", 302, 308, protein,
                                                       dose_fraction=0.5, dry_radius_um=50))
        w_drug = time.perf_counter() - w
    truth = fluid.validation.time
    print(f"ANB 302 -> 308 K, 50 um, 50 %: fluid truth {truth:.6f} (ell = "
          f"{fluid.interfacial_length:.3g}, numerical bound "
          f"{fluid.uncertainty.numerical.relative:.3%}; validation {w_fluid:.1f} s); drug "
          f"(protein, {drug.mechanism}) {drug.time:.6f} (ell = {drug.interfacial_length:.3g}; "
          f"{w_drug:.1f} s): gap {abs(drug.time / truth - 1):.3%}")


REDUCED_CASES = (("ANB", 302.0, {"diffusivity_cm2_s": 1e-7, "hindrance": "none"}, 0.5),
                 ("ANB", 302.0, {"diffusivity_cm2_s": 1e-7, "hindrance": "ogston",
                                 "solute_radius_nm": 1.0, "fiber_radius_nm": 1.0}, 0.7),
                 ("HHT", 304.0, {"diffusivity_cm2_s": 1e-7, "hindrance": "amsden",
                                 "solute_radius_nm": 1.0, "fiber_radius_nm": 1.0}, 0.5),
                 ("HHT", 304.0, {"diffusivity_cm2_s": 1e-8, "hindrance": "free-volume",
                                 "solute_radius_nm": 0.25}, 0.5),
                 ("HHT", 304.0, {"diffusivity_cm2_s": 1e-5, "hindrance": "none"}, 0.9))


def reduced_section(repeats: int) -> None:
    """``--section reduced``: CPU ms of a drug dose answered by the reduced drug model
    (``plan_drug_dose`` without validate; a 50 um bead), the first call of a jump (its
    front trajectory computed, then memoised) and warm (median of ``repeats``), with the
    model, its stated error and the dose time; the target is under 10 ms."""
    from dosing.payload.drug import DrugModel
    from dosing.payload.reduced import applies
    from dosing.payload.release import DrugDoseRequest, plan_drug_dose
    from dosing.runs.solute import drug_settings

    print(f"reduced drug model: CPU ms per answer (plan_drug_dose; warm: median of {repeats})")
    print(f"  {'case':<58} {'model':<13} {'first':>7} {'warm':>7} {'error':>6} {'time':>10}")
    for gel, t0, drug, dose in REDUCED_CASES:
        req = DrugDoseRequest(gel, t0, 308.0, DrugModel(**drug), dose_fraction=dose,
                              dry_radius_um=50.0)
        if not applies(req, drug_settings(req.settings)).applies:
            print(f"  {gel} {dose:.0%} {drug}: outside the reduced model's region (full)")
            continue
        c = time.process_time()
        ans = plan_drug_dose(None, req)
        first = time.process_time() - c
        warm = []
        for _ in range(repeats):
            c = time.process_time()
            ans = plan_drug_dose(None, req)
            warm.append(time.process_time() - c)
        err = ans.uncertainty.model_form.relative
        name = f"{gel} {t0:g}->308 K, {dose:.0%}, " + ", ".join(
            f"{k.replace('_cm2_s', '').replace('_nm', '')}={v:g}" if isinstance(v, float)
            else f"{v}" for k, v in drug.items())
        print(f"  {name:<58} {ans.model:<13} {1e3 * first:>7.2f} "
              f"{1e3 * float(np.median(warm)):>7.2f} {err:>6.1%} {ans.time:>10.6g}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--quick", action="store_true", help="the first case only")
    p.add_argument("--truth", action="store_true", help="drug vs fluid answer of one bead")
    p.add_argument("--section", choices=("cost", "truth", "reduced"), default="cost",
                   help="cost: the drug's cost and accuracy (default); truth: as --truth; "
                        "reduced: the reduced drug model's answers (issue 23)")
    args = p.parse_args()
    if args.truth or args.section == "truth":
        one_truth()
        return
    if args.section == "reduced":
        reduced_section(max(args.repeats, 1))
        return
    print(f"Lagrangian N = {N}, ell = {ELL}, rtol {RTOL}; times in s (warm, median of "
          f"{args.repeats})")
    for name, (gel, t0, protocol) in list(CASES.items())[: 1 if args.quick else None]:
        total = sum(d for d, _ in protocol)
        plain, _ = median_time(lambda g=gel, t=t0, pr=protocol: mechanics(g, t, pr, None),
                               args.repeats)
        # (the dense run takes the same steps: the integrator's output times are stops of its
        # dense output, not step ends, so 'total err' equals 'solute err')
        ref_res = mechanics(gel, t0, protocol, 4 * SAMPLES[-1])
        print(f"\n{name} (t = {total:g}): mechanics alone {plain:.3f} s")
        print(f"  {'drug':<18} {'samples/tau':>11} {'mech dense':>10} {'solute':>8} "
              f"{'ratio':>6} {'solute err':>9} {'total err':>9} {'balance':>8}")
        for dname, sol in DRUGS.items():
            ref = release(ref_res, sol, rtol=1e-8).released_fraction
            for k in SAMPLES:
                dense, ts, ratio, rel = paired(gel, t0, protocol, k, sol, args.repeats)
                err = np.max(np.abs(np.interp(rel.t, ref_res.t, ref) - rel.released_fraction))
                sub = subsample(ref_res, 4 * SAMPLES[-1] // k)
                own = release(sub, sol).released_fraction
                err_s = np.max(np.abs(np.interp(sub.t, ref_res.t, ref) - own))
                mark = " <- drug runs" if k == SAMPLES_PER_TAU else ""
                print(f"  {dname:<18} {k:>11d} {dense:>10.3f} {ts:>8.3f} "
                      f"{ratio:>6.2f} {err_s:>9.1e} {err:>9.1e} "
                      f"{rel.mass_balance_error:>8.1e}{mark}")


def paired(gel: str, t0: float, protocol: list, k: int, sol: Solute, repeats: int
           ) -> tuple[float, float, float, object]:
    """Medians of (dense mechanics, solute, (dense + solute) / plain mechanics): each repeat
    times the plain run and the drug run back to back, so the ratio sees the same load."""
    mechanics(gel, t0, protocol, k)
    dense, ts, ratio = [], [], []
    rel = None
    for _ in range(repeats):
        t = time.perf_counter()
        mechanics(gel, t0, protocol, None)
        plain = time.perf_counter() - t
        t = time.perf_counter()
        res = mechanics(gel, t0, protocol, k)
        d = time.perf_counter() - t
        t = time.perf_counter()
        rel = release(res, sol)
        s = time.perf_counter() - t
        dense.append(d)
        ts.append(s)
        ratio.append((d + s) / plain)
    return float(np.median(dense)), float(np.median(ts)), float(np.median(ratio)), rel

if __name__ == "__main__":
    main()
