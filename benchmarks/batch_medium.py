"""A drug batch sharing one finite medium (issue 26): how wrong the perfect-sink sum is.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/batch_medium.py [--d0 1e-6 1e-7]

Two bead sizes (dry radii 40 and 60 um, equal numbers), ANB 302 -> 308 K, the drug
uniformly loaded (hindrance none, K = 1), the reference bead's full-solver mechanics at its
own interfacial length (dosing.population.medium).  For a medium of 1x and 10x the batch's
partition-weighted pore volume, prints by how much the sum of perfect-sink beads overstates
the drug released at the sink sum's own 30 / 50 / 80 % dose times and at the end of the
run, the coupled batch's dose times, the mass balance, the numerical error (steps halved)
and the CPU seconds of each coupled solve.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from dosing.payload.release import DrugDoseRequest
from dosing.population.medium import HORIZON, SUB, Bands, batch_classes, coupled
from dosing.population.sizes import as_distribution
from dosing.runs.mechanics import jump_mechanics
from dosing.runs.solute import drug_settings
from solver.solute import node_volumes

SIZES = {"kind": "table", "sizes_um": [40.0, 60.0]}
DOSES = (0.3, 0.5, 0.8)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--d0", type=float, nargs="+", default=[1e-6, 1e-7],
                    help="drug diffusivities in water, cm^2/s")
    args = ap.parse_args()
    for d0 in args.d0:
        req = DrugDoseRequest("ANB", 302, 308, {"diffusivity_cm2_s": d0, "hindrance": "none"},
                              dose_fraction=0.5, dry_radius_um=50.0)
        sizes = as_distribution(SIZES).resolve(req.start_radius)
        st = drug_settings(req.settings)
        c0 = time.process_time()
        res = jump_mechanics(req.gel, req.t_start, req.t_end, req.branch, st, HORIZON)
        mech = time.process_time() - c0
        s, s3 = np.asarray(res.t, dtype=float), node_volumes(res)
        one = Bands(np.array([]), [s], [s3], [st])  # the reference bead's mechanics
        rho, nu = batch_classes(sizes, 0)
        pore = req.start_radius**3 - 1.0  # K = 1: the pore volume, units of the dry volume
        sink = coupled(one, req.solute, sizes, 0, None, SUB[1])
        print(f"D0 = {d0:g} cm^2/s ({req.solute.diffusivity:.3g} x the gel's D); mechanics "
              f"{st.grid} N = {st.n}, ell {st.interfacial_length:.3g}: {mech:.1f} s CPU; "
              f"classes rho = {np.round(rho, 3).tolist()}, load shares "
              f"{np.round(nu, 3).tolist()}")
        ts = [sink.time_to_release(f) for f in DOSES]
        for mult in (1.0, 10.0):
            c0 = time.process_time()
            mr = coupled(one, req.solute, sizes, 0, mult * pore, SUB[1])
            cpu = time.process_time() - c0
            half = coupled(one, req.solute, sizes, 0, mult * pore, SUB[0])
            over = [sink.released_at(t) / mr.released_at(t) - 1.0 for t in ts]
            end = sink.released[-1] / mr.released[-1] - 1.0
            own = []
            for f in DOSES:
                try:
                    own.append(f"{mr.time_to_release(f):.4g}")
                except ValueError:
                    own.append("never")
            num = np.max(np.abs(mr.released - half.released))
            print(f"  medium {mult:g}x pore volume: the sink sum overstates the release by "
                  + ", ".join(f"{o:+.1%} at its {f:.0%} time ({t:.4g})"
                              for o, f, t in zip(over, DOSES, ts, strict=True))
                  + f", {end:+.1%} at the run's end; coupled dose times {', '.join(own)} "
                  f"(sink {', '.join(f'{t:.4g}' for t in ts)}); mass balance "
                  f"{mr.mass_balance_error:.1e}; numerical |dV| {num:.1e}; {mr.steps} steps, "
                  f"{cpu:.2f} s CPU")


if __name__ == "__main__":
    main()
