"""The README's batch figure (issue 26): release curves of a batch for CV 0, 0.1, 0.2, 0.3,
and a design map with the CV as an axis.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/batch_figure.py [--out docs/batch.png]

ANB 302 -> 308 K, a number-weighted lognormal of mean dry radius 50 um, the front model
(one dimensionless trajectory for every bead).  Left: the batch's released fraction of its
stored fluid against time in seconds, with the 80 % dose marked; right: the batch's delay
against its mean bead over CV x dose (contours), the spread a dose tolerates.
"""

from __future__ import annotations

import argparse

import numpy as np

from dosing import DoseRequest
from dosing.population.front import batch_answer, batch_release
from dosing.studies.batch_design import design_map


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/batch.png")
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    t = np.linspace(0.0, 0.3, 601)
    for cv in (0.0, 0.1, 0.2, 0.3):
        req = DoseRequest("ANB", 302, 308, dose_fraction=0.8, dry_radius_um=50.0,
                          size_distribution={"cv": cv})
        b = batch_answer(req)
        c = batch_release(req, t)
        line, = ax.plot(t * b.timescale_seconds, c["batch"], label=f"CV {cv:g}: 80 % at "
                        f"{b.seconds:.0f} s ({b.delay:+.0%})")
        ax.plot([b.seconds], [0.8], "o", color=line.get_color())
    ax.axhline(0.8, color="0.6", lw=0.8, ls="--")
    ax.set_xlabel("time at 308 K (s)")
    ax.set_ylabel("released fraction of the batch's stored fluid")
    ax.set_title("a batch of ANB beads, mean dry radius 50 um")
    ax.legend(loc="lower right", fontsize=8)
    base = DoseRequest("ANB", 302, 308, dose_fraction=0.5, dry_radius_um=50.0)
    cvs, fs = np.linspace(0.0, 0.4, 21), np.linspace(0.1, 0.9, 17)
    m = design_map(base, cvs, fs)
    d = 100 * np.array(m["delay"])
    cs = bx.contourf(cvs, fs, d, levels=[0, 5, 10, 25, 50, 75, 100, 150], cmap="viridis")
    bx.contour(cvs, fs, d, levels=[10, 25, 50], colors="w", linewidths=0.8)
    fig.colorbar(cs, ax=bx, label="batch's delay vs its mean bead (%)")
    bx.set_xlabel("size CV (number-weighted lognormal)")
    bx.set_ylabel("dose (fraction of the stored fluid)")
    bx.set_title("the spread a dose tolerates (white: +10, +25, +50 %)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
