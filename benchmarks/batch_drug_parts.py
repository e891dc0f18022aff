"""A drug batch's bands and three-part uncertainty on the truth (issue 26,
dosing.population.medium).

Run:  PYTHONPATH=. .venv/bin/python benchmarks/batch_drug_parts.py [--cv 0.3]

ANB 302 -> 308 K, mean dry radius 50 um, a number-weighted lognormal, D0 = 1e-7 cm^2/s
(hindrance none), 50 % of the load, into a perfect sink and into 1 mL shared by 1e5 beads;
the truth's mechanics (moving grid, N = 400) per interfacial-length band.  Prints the dose
time, each band's bead and ell, the numerical / interfacial-length / model-form parts, the
quadrature error, the mass balance and the wall seconds.
"""

from __future__ import annotations

import argparse
import time

from dosing.payload.release import DrugDoseRequest
from dosing.population.medium import drug_batch_dose


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cv", type=float, default=0.3)
    args = p.parse_args()
    req = DrugDoseRequest("ANB", 302, 308, {"diffusivity_cm2_s": 1e-7, "hindrance": "none"},
                          dose_fraction=0.5, dry_radius_um=50.0)
    for ml, count in ((None, None), (1.0, 1e5)):
        w = time.perf_counter()
        a = drug_batch_dose(req, {"cv": args.cv}, ml, count)
        w = time.perf_counter() - w
        medium = "a perfect sink" if ml is None else f"{ml:g} mL for {count:g} beads"
        print(f"CV {args.cv:g}, {medium}: {a.seconds:.4g} s ({a.time:.5g} tau_ref); bands "
              + ", ".join(f"{b['dry_radius_um']:.4g} um at ell {b['interfacial_length']:.3g}"
                          for b in a.bands)
              + f"; quadrature {a.quadrature_error:.1e}; mass balance "
              f"{a.mass_balance_error:.1e}; {w:.0f} s wall")
        for part in a.uncertainty.values():
            print(f"  {part.text}")


if __name__ == "__main__":
    main()
