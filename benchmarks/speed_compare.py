"""Before/after speed of the work-precision smoke run: this tree against a git revision.

Run:  .venv/bin/python -m benchmarks.speed_compare --before REV [--repeats 4]

Checks out ``REV`` into a temporary git worktree, then alternates the smoke run
(benchmarks/work_precision.py --smoke) of that revision and of this tree ``repeats`` times
each (alternating, so both see the same machine load), and prints every full-solver row's
median wall time before and after, the errors' agreement and the sum of the medians.  The
first run of each tree compiles its numba kernels (cached in its own __pycache__) and only
warms; issue 16's acceptance asks the sum to be within 5 % of the revision's.
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TIME_COLUMNS = ("wall_s", "timing", "steps", "rejected")


def smoke(tree: Path, out: Path) -> list[dict[str, str]]:
    """One smoke run of the tree at ``tree``; its full-solver rows."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    subprocess.run([sys.executable, str(tree / "benchmarks" / "work_precision.py"), "--smoke",
                    "--out", str(out)], cwd=tree, env=env, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with (out / "work_precision.csv").open() as fh:
        return [r for r in csv.DictReader(fh) if r["method"].startswith("full")]


def _key(row: dict[str, str]) -> tuple[str, ...]:
    return row["case"], row["method"], row["grid"], row["n"], row["rtol"], row["ell"]


def compare(before: list[list[dict[str, str]]], after: list[list[dict[str, str]]]) -> float:
    """Print the medians of the rows both trees run (matched by case, method, grid, N, rtol,
    ell); return after/before - 1 of their sums."""
    total_b = total_a = 0.0
    later = [{_key(r): r for r in run} for run in after]
    for i, row in enumerate(before[0]):
        if _key(row) not in later[0]:
            continue
        mb = statistics.median(float(run[i]["wall_s"]) for run in before)
        ma = statistics.median(float(run[_key(row)]["wall_s"]) for run in later)
        mine = later[0][_key(row)]
        same = all(mine[k] == v for k, v in row.items() if k not in TIME_COLUMNS)
        total_b, total_a = total_b + mb, total_a + ma
        print(f"{row['case']:<14}{row['method'][:34]:<36}{row['n']:>5}{row['rtol']:>8}  "
              f"before {mb:8.4f} s  after {ma:8.4f} s  {100 * (ma / mb - 1):+6.1f} %"
              f"{'' if same else '  (errors differ)'}")
    change = total_a / total_b - 1.0
    print(f"sum of the per-row medians ({len(before)} runs each): before {total_b:.3f} s, "
          f"after {total_a:.3f} s ({100 * change:+.1f} %)")
    return change


def main(argv: list[str] | None = None) -> int:
    """Alternate the two trees' smoke runs and print the comparison."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", required=True, help="git revision to compare against")
    ap.add_argument("--repeats", type=int, default=4)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "before"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(base), args.before],
                       cwd=ROOT, check=True)
        try:
            for tree in (base, ROOT):  # warm: compile or load each tree's kernels
                smoke(tree, Path(tmp) / "warm")
            runs: dict[Path, list] = {base: [], ROOT: []}
            for k in range(args.repeats):
                for tree in (base, ROOT):
                    runs[tree].append(smoke(tree, Path(tmp) / f"{tree.name}{k}"))
                print(f"pair {k + 1}/{args.repeats} done", flush=True)
            compare(runs[base], runs[ROOT])
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT,
                           check=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
