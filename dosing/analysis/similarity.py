"""Two release profiles compared: f1 and f2 with the FDA rules, and Shah's bootstrap f2.

FDA, Guidance for Industry: Dissolution Testing of Immediate Release Solid Oral Dosage Forms
(1997), model-independent approach (Moore & Flanner 1996), R and T the mean percent
released at the same times:

    f1 = 100 sum|R_t - T_t| / sum R_t        f2 = 50 log10(100 / sqrt(1 + mean (R_t - T_t)^2))

with the guidance's conditions: the same time points; 12 units of each product; at least
three points, zero excluded; only one point after 85 % dissolution of both products; the
CV of the units at most 20 % at the earlier points (e.g. 15 minutes: here the first point
used) and at most 10 % at the others.  "f1 values up to 15 (0-15) and f2 values greater
than 50 (50-100) ensure sameness or equivalence of the two curves."

Bootstrap (Shah, Tsong, Sathe & Liu 1998, Pharm Res 15:889): the units of each product
resampled with replacement (a product given as one profile is held fixed), f2 recomputed
on the points the rules chose, B >= 1000 seeded draws, vectorised; the 90 % interval
bias-corrected and accelerated (BCa: z0 from the share of draws below f2, the acceleration
from the jackknife leaving out one unit of either product) beside the percentile one;
similar when the interval's lower bound is at least 50.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from statistics import NormalDist
from typing import Any

import numpy as np

from solver.errors import ParameterError

from .profiles import Profile, same_grid

UNITS_REQUIRED = 12
MIN_POINTS = 3
CV_EARLY, CV_LATER = 20.0, 10.0  # percent
LIMIT_85 = 85.0
N_BOOT = 1000
MAX_BOOT = 100_000
CONFIDENCE = 0.90
_CHUNK = 2_000_000  # floats per bootstrap chunk (memory stays ~16 MB)
F2_WORDS = ("An f2 value between 50 and 100 suggests that the two dissolution profiles are "
            "similar")


def f1_value(ref: np.ndarray, test: np.ndarray) -> float:
    """Difference factor f1 (FDA 1997) of mean profiles in percent."""
    s = float(np.sum(ref))
    if s <= 0:
        raise ParameterError("reference", "no release", "a reference with release > 0")
    return 100.0 * float(np.sum(np.abs(ref - test))) / s


def f2_value(ref: np.ndarray, test: np.ndarray) -> float:
    """Similarity factor f2 (FDA 1997) of mean profiles in percent (the points given)."""
    d = np.asarray(ref, float) - np.asarray(test, float)
    return float(50.0 * math.log10(100.0 / math.sqrt(1.0 + float(np.mean(d * d)))))


def _f2_rows(ref: np.ndarray, test: np.ndarray) -> np.ndarray:
    """f2 of many mean-profile pairs (last axis: the points)."""
    d = ref - test
    return 50.0 * np.log10(100.0 / np.sqrt(1.0 + np.mean(d * d, axis=-1)))


def points_used(times: np.ndarray, ref: np.ndarray, test: np.ndarray) -> np.ndarray:
    """The FDA points: zero time excluded, none after the first at which both products
    exceed 85 %."""
    keep = np.asarray(times, float) > 0
    both = np.nonzero(keep & (ref > LIMIT_85) & (test > LIMIT_85))[0]
    if both.size:
        keep &= np.arange(keep.size) <= both[0]
    return keep


def fda_f2(reference: Any, test: Any, times: Any = None) -> float:
    """f2 of two mean profiles (percent, same times) on the FDA points (``points_used``;
    without ``times`` the points are taken as after zero unless both are 0)."""
    r = np.asarray(reference, float)
    t = np.asarray(test, float)
    if r.shape != t.shape or r.ndim != 1 or r.size == 0:
        raise ParameterError("f2", f"{r.shape} and {t.shape}", "two profiles of equal length")
    tt = np.where((r == 0) & (t == 0), 0.0, 1.0) if times is None else np.asarray(times)
    keep = points_used(tt, r, t)
    if not keep.any():
        raise ParameterError("f2", "no points", "at least one time after zero")
    return f2_value(r[keep], t[keep])


def _cv(p: Profile) -> np.ndarray | None:
    sd = p.sd
    if sd is None:
        return None
    m = p.mean
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(m > 0, 100.0 * sd / np.where(m > 0, m, 1.0), np.inf)


@dataclass
class Comparison:
    """f1, f2, the FDA conditions and the bootstrap of two profiles (module doc)."""

    f1: float
    f2: float
    points_used: list[int]
    times_used: list[float]
    time_unit: str
    reference_mean: list[float]
    test_mean: list[float]
    conditions: dict[str, dict[str, Any]]
    conditions_met: bool
    outcome: str
    f1_outcome: str
    bootstrap: dict[str, Any] | None
    reference: dict[str, Any] = field(default_factory=dict)
    test: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready)."""
        return asdict(self)

    def to_dataframe(self) -> Any:
        """One row per time: both means, SDs and CVs, and whether f2 used it (pandas,
        imported here)."""
        import pandas as pd

        rows = {"time": self.reference["time"], "used": [
            i in self.points_used for i in range(len(self.reference["time"]))]}
        for side, d in (("reference", self.reference), ("test", self.test)):
            rows[f"{side}_mean_percent"] = d["mean_percent"]
            n = len(d["mean_percent"])
            rows[f"{side}_sd_percent"] = d["sd_percent"] or [None] * n
            rows[f"{side}_cv_percent"] = d["cv_percent"] or [None] * n
        df = pd.DataFrame(rows)
        df.attrs.update(f1=self.f1, f2=self.f2, time_unit=self.time_unit,
                        outcome=self.outcome)
        return df


def compare(reference: Profile, test: Profile, *, n_boot: int = N_BOOT, seed: int = 0,
            confidence: float = CONFIDENCE, bootstrap: bool = True,
            prediction: bool = False) -> Comparison:
    """f1/f2 of ``test`` against ``reference`` under the FDA rules, and Shah's bootstrap
    when either has replicate units (module doc); ``prediction``: the test is a model's
    curve, so the 12-unit rule applies to the reference alone."""
    same_grid(reference, test)
    if not (1000 <= n_boot <= MAX_BOOT):
        raise ParameterError("n_boot", n_boot, f"1000 ... {MAX_BOOT} draws")
    if not (0.5 <= confidence < 1.0):
        raise ParameterError("confidence", confidence, "0.5 <= level < 1 (0.90: Shah's)")
    r, t = reference.mean, test.mean
    keep = points_used(reference.times, r, t)
    idx = np.nonzero(keep)[0]
    if idx.size == 0:
        raise ParameterError(reference.where(None), "no time after zero",
                             "time points after zero in both profiles")
    f1 = f1_value(r[keep], t[keep])
    f2 = f2_value(r[keep], t[keep])
    cond = _conditions(reference, test, keep, prediction)
    met = all(c["met"] for c in cond.values())
    words = (f"f2 = {f2:.2f}, between 50 and 100: the two dissolution profiles are similar "
             f"(FDA 1997: '{F2_WORDS}')" if f2 >= 50.0 else
             f"f2 = {f2:.2f}, below 50: the two dissolution profiles are not shown to be "
             f"similar (FDA 1997: '{F2_WORDS}')")
    boot = _bootstrap(reference, test, keep, n_boot, seed, confidence, f2) \
        if bootstrap else None
    if not met:
        failed = "; ".join(c["rule"] for c in cond.values() if not c["met"])
        words += (f". The guidance's conditions for f2 are not all met ({failed}): f2 alone "
                  "does not decide" + ("; see the bootstrap interval" if boot else ""))
    f1_words = (f"f1 = {f1:.2f}: " + ("within 0-15" if f1 <= 15 else "above 15") +
                " (FDA 1997: f1 values up to 15 and f2 values of 50-100 ensure sameness or "
                "equivalence of the two curves)")
    return Comparison(f1, f2, idx.tolist(), reference.times[keep].tolist(),
                      reference.time_unit, r.tolist(), t.tolist(), cond, met, words, f1_words,
                      boot, _side(reference), _side(test),
                      [f"points used: {', '.join(f'{x:g}' for x in reference.times[keep])} "
                       f"{reference.time_unit} (zero excluded; none after the first point at "
                       "which both exceed 85 %)"])


def _side(p: Profile) -> dict[str, Any]:
    sd = p.sd
    cv = _cv(p)
    return {"label": p.label, "n_units": p.n_units, "time": p.times.tolist(),
            "mean_percent": p.mean.tolist(),
            "sd_percent": None if sd is None else sd.tolist(),
            "cv_percent": None if cv is None else [None if not np.isfinite(c) else float(c)
                                                   for c in cv]}


def _conditions(ref: Profile, test: Profile, keep: np.ndarray,
                prediction: bool = False) -> dict[str, dict[str, Any]]:
    """The guidance's conditions, each with its rule, whether met, and what was found."""
    n_used = int(keep.sum())
    after = keep & (ref.mean > LIMIT_85) & (test.mean > LIMIT_85)
    out = {
        "points": {"rule": f"at least {MIN_POINTS} time points, zero excluded",
                   "met": n_used >= MIN_POINTS, "found": n_used},
        "one_after_85": {"rule": "only one measurement after 85 % dissolution of both "
                                 "products", "met": int(after.sum()) <= 1,
                         "found": int(after.sum()),
                         "dropped": int(np.sum((ref.times > 0) & ~keep))},
        "units": {"rule": f"{UNITS_REQUIRED} units of each product",
                  "met": ref.n_units >= UNITS_REQUIRED and test.n_units >= UNITS_REQUIRED,
                  "found": [ref.n_units, test.n_units]},
    }
    if prediction:
        out["units"] = {"rule": f"{UNITS_REQUIRED} units of the measured profile (the "
                                "prediction is one curve)",
                        "met": ref.n_units >= UNITS_REQUIRED, "found": ref.n_units}
    idx = np.nonzero(keep)[0]
    bad = []
    checked = False
    for p, who in ((ref, "reference"), (test, "test")):
        cv = _cv(p)
        if cv is None:
            continue
        checked = True
        for k, i in enumerate(idx):
            limit = CV_EARLY if k == 0 else CV_LATER
            if cv[i] > limit:
                bad.append(f"{who} at {p.times[i]:g} {p.time_unit}: CV "
                           f"{'inf' if not np.isfinite(cv[i]) else f'{cv[i]:.1f}'} % > "
                           f"{limit:g} %")
    out["cv"] = {"rule": f"CV of the units <= {CV_EARLY:g} % at the earlier point (the first "
                         f"used), <= {CV_LATER:g} % at the others",
                 "met": checked and not bad, "checked": checked,
                 "found": bad if checked else "no replicate units given"}
    return out


def jackknife_f2(ref_units: np.ndarray, test_units: np.ndarray) -> np.ndarray:
    """f2 with one unit left out of either product ('nt+nr'), units x points arrays; a
    product of one unit is not left out."""
    out = []
    for units, other, first in ((test_units, ref_units, False), (ref_units, test_units, True)):
        n = units.shape[0]
        if n < 2:
            continue
        total = units.sum(axis=0)
        loo = (total[None, :] - units) / (n - 1)
        om = other.mean(axis=0)[None, :]
        out.append(_f2_rows(loo, om) if first else _f2_rows(om, loo))
    return np.concatenate(out) if out else np.empty(0)


def bootstrap_draws(ref_units: np.ndarray, test_units: np.ndarray, n_boot: int,
                    seed: int) -> np.ndarray:
    """``n_boot`` f2 values of unit-resampled means (units x points arrays), vectorised in
    chunks; a product of one unit is held fixed."""
    rng = np.random.default_rng(seed)
    nr, nt = ref_units.shape[0], test_units.shape[0]
    per = max(nr, nt) * ref_units.shape[1]
    chunk = max(1, _CHUNK // max(per, 1))
    out = np.empty(n_boot)
    for start in range(0, n_boot, chunk):
        b = min(chunk, n_boot - start)
        rm = ref_units[rng.integers(0, nr, (b, nr))].mean(axis=1) if nr > 1 else \
            np.broadcast_to(ref_units[0], (b, ref_units.shape[1]))
        tm = test_units[rng.integers(0, nt, (b, nt))].mean(axis=1) if nt > 1 else \
            np.broadcast_to(test_units[0], (b, test_units.shape[1]))
        out[start:start + b] = _f2_rows(rm, tm)
    return out


def bca_interval(draws: np.ndarray, estimate: float, jack: np.ndarray,
                 confidence: float) -> tuple[list[float], float, float]:
    """The BCa interval (Efron & Tibshirani 1993; z0 and the jackknife acceleration as in
    Shah et al. 1998), with z0 and a."""
    b = draws.size
    share = (np.sum(draws < estimate) + 0.5 * np.sum(draws == estimate)) / b
    norm = NormalDist()
    z0 = norm.inv_cdf(float(np.clip(share, 0.5 / b, 1 - 0.5 / b)))
    d = jack.mean() - jack if jack.size else np.zeros(1)
    s2 = float(np.sum(d * d))
    a = float(np.sum(d**3) / (6.0 * s2**1.5)) if s2 > 0 else 0.0
    alpha = (1.0 - confidence) / 2.0
    qs = []
    for z in (norm.inv_cdf(alpha), norm.inv_cdf(1 - alpha)):
        qs.append(norm.cdf(z0 + (z0 + z) / (1.0 - a * (z0 + z))))
    return [float(v) for v in np.quantile(draws, qs)], z0, a


def _bootstrap(ref: Profile, test: Profile, keep: np.ndarray, n_boot: int, seed: int,
               confidence: float, f2: float) -> dict[str, Any] | None:
    if ref.n_units < 2 and test.n_units < 2:
        return None
    ru, tu = ref.units[keep].T, test.units[keep].T  # units x points
    draws = bootstrap_draws(ru, tu, n_boot, seed)
    jack = jackknife_f2(ru, tu)
    bca, z0, a = bca_interval(draws, f2, jack, confidence)
    alpha = (1.0 - confidence) / 2.0
    pct = [float(v) for v in np.quantile(draws, [alpha, 1 - alpha])]
    similar = bca[0] >= 50.0
    held = [w for p, w in ((ref, "reference"), (test, "test")) if p.n_units < 2]
    return {
        "n_boot": n_boot, "seed": seed, "confidence": confidence,
        "resampled": "units within each product, with replacement" + (
            f" ({' and '.join(held)} held fixed: one profile)" if held else ""),
        "f2": f2, "mean": float(draws.mean()), "median": float(np.median(draws)),
        "sd": float(draws.std(ddof=1)), "bias": float(draws.mean() - f2),
        "interval_bca": bca, "interval_percentile": pct, "z0": z0, "acceleration": a,
        "jackknife": "nt+nr (one unit of either product left out)",
        "similar": similar,
        "outcome": (f"bootstrap f2 {confidence:.0%} BCa interval {bca[0]:.2f}-{bca[1]:.2f}: "
                    + ("the lower bound is at least 50: similar" if similar else
                       "the lower bound is below 50: similarity not shown")
                    + " (Shah et al. 1998)"),
    }


def measured_against_predicted(measured: Profile, time_s: Any, predicted: Any, *,
                               n_boot: int = N_BOOT, seed: int = 0) -> dict[str, Any]:
    """A prediction (released fraction at ``time_s``, interpolated to the measured times)
    against a measured profile: f1/f2 under the FDA rules with the measured profile as the
    reference (a bootstrap over its units when it has several), beside the residuals and the
    chi-square under the units' standard error of the mean."""
    ts = np.asarray(time_s, float)
    yp = 100.0 * np.asarray(predicted, float)
    mt = measured.time_s
    beyond = np.nonzero(mt > ts.max() * (1 + 1e-9))[0]
    if beyond.size:
        i = int(beyond[0])
        raise ParameterError(measured.where(i), f"{measured.times[i]:g} {measured.time_unit}",
                             f"times within the prediction's horizon ({ts.max():.6g} s)",
                             "measured after the prediction ends")
    at = np.interp(mt, ts, yp)
    pred = Profile(measured.times, at[:, None], measured.time_unit, measured.seconds_per_unit,
                   "predicted")
    c = compare(measured, pred, n_boot=n_boot, seed=seed, prediction=True)
    resid = measured.mean - at
    out: dict[str, Any] = {
        "similarity": {**c.to_dict(), "meaning": "FDA similarity (1997 guidance rules) of "
                       "the prediction and the measured profile as two dissolution "
                       "profiles, the measured one the reference"},
        "time": measured.times.tolist(), "time_unit": measured.time_unit,
        "measured_percent": measured.mean.tolist(), "predicted_percent": at.tolist(),
        "residuals_percent": resid.tolist(),
        "rms_residual_percent": float(np.sqrt(np.mean(resid**2)))}
    sd = measured.sd
    if sd is not None:
        sem = np.maximum(sd / math.sqrt(measured.n_units), 1e-6)
        chi2 = float(np.sum((resid / sem) ** 2))
        out.update(chi2=chi2, chi2_dof=int(resid.size), chi2_reduced=chi2 / resid.size,
                   chi2_meaning="sum ((measured mean - prediction) / SEM of the units)^2 "
                                "over the measured times (no parameter fitted)")
    return out
