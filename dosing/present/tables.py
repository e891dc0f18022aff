"""Results as tables: pandas DataFrames (``to_dataframe``) and compact notebook HTML
(``_repr_html_``) for answers, schedules, sweeps, fits and runs.

Column names are ``name [unit]`` (dosing.present.export.header); pandas is imported inside the
functions only.  The HTML is a small table built without pandas: the answer, its
uncertainty parts and the truth, nothing else (the full record stays in ``to_dict()``).
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from .export import PARAMETER_UNITS, header

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from solver.fit import FitResult
    from solver.full import FullResult

    from ..answers import DoseAnswer
    from ..question.schedule import ScheduleAnswer
    from ..studies.sweep import SweepResult


def _frame(columns: dict[str, Sequence[Any]], units: dict[str, str],
           attrs: dict[str, Any] | None = None) -> pd.DataFrame:
    import pandas as pd

    df = pd.DataFrame({header(k, units.get(k)): list(v) for k, v in columns.items()})
    df.attrs.update(attrs or {})
    return df


# ---------------------------------------------------------------------------- answers
ANSWER_UNITS = {"time": "1", "seconds": "s", "timescale_seconds": "s", "start_radius": "1",
                "final_radius": "1", "final_radius_um": "um", "expelled_volume": "1",
                "expelled_volume_ul": "uL", "stored_volume": "1", "stored_volume_ul": "uL",
                "dose_fraction": "1", "error_estimate": "1", "interfacial_length": "1",
                "bead_dry_radius_um": "um", "numerical": "1",
                "interfacial_length_range": "1", "model_form": "1"}
_ANSWER_FIELDS = ("model", "method", "time", "seconds", "timescale_seconds", "dose_fraction",
                  "final_radius_um", "expelled_volume_ul", "stored_volume_ul",
                  "error_estimate", "interfacial_length", "bead_dry_radius_um", "truth")
_PARTS = ("numerical", "interfacial_length_range", "model_form")


def _parts(ans: DoseAnswer) -> dict[str, float | None]:
    u = ans.uncertainty
    return {p: None if u is None else getattr(u, p).relative for p in _PARTS}


def answer_frame(ans: DoseAnswer) -> pd.DataFrame:
    """One row: the answer (time, seconds, dose, volumes), its error and uncertainty parts
    (relative: numerical, interfacial-length range, model form) and the truth."""
    cols = {k: [getattr(ans, k)] for k in _ANSWER_FIELDS}
    cols.update({k: [v] for k, v in _parts(ans).items()})
    return _frame(cols, ANSWER_UNITS, {"note": ans.note, "scenario_key": ans.scenario_key})


def _fmt(v: Any) -> str:
    if v is None:
        return "&ndash;"
    if isinstance(v, float):
        return f"{v:.4g}"
    return html.escape(str(v))


def _table(title: str, rows: Sequence[tuple[str, Any, str]], foot: str = "") -> str:
    body = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
                   f"<td style='text-align:right'>{_fmt(v)}</td><td>{html.escape(u)}</td></tr>"
                   for k, v, u in rows)
    foot_html = (f"<tr><td colspan='3' style='text-align:left;font-size:smaller'>"
                 f"{html.escape(foot)}</td></tr>") if foot else ""
    return (f"<table><caption style='text-align:left'><b>{html.escape(title)}</b></caption>"
            f"{body}{foot_html}</table>")


def answer_html(ans: DoseAnswer) -> str:
    """A compact table: time (tau and s), dose, the error and its parts, and the truth."""
    rows = [("time", ans.time, "tau"), ("time", ans.seconds, "s"),
            ("dose fraction", ans.dose_fraction, ""),
            ("released volume", ans.expelled_volume_ul, "uL"),
            ("final radius", ans.final_radius_um, "um"),
            ("error estimate", ans.error_estimate, "relative")]
    for k, v in _parts(ans).items():
        if v is not None:
            rows.append((f"  {k.replace('_', ' ')}", v, "relative"))
    rows.append(("model", ans.model, ""))
    return _table("thermogel dose answer", rows, f"truth: {ans.truth}")


# ---------------------------------------------------------------------------- the one answer
# (dosing.question.result: every cell's DoseResult and ScheduleResult, led by its envelope)
def _lead(res: Any, what: str) -> list[str]:
    """The lines the CLI's text answer leads with (the envelope's), else the headline."""
    env = res.envelope
    return env.lines(what) if env is not None else [res.headline]


def _envelope_rows(res: Any) -> list[tuple[str, Any, str]]:
    """Each part of the envelope, widest first: its factors, counted or listed only."""
    env = res.envelope
    if env is None:
        return []
    return [(f"  {p.name.replace('_', ' ')}", f"x{p.low:.3g} to x{p.high:.3g}",
             "" if p.counted else "listed, not counted")
            for p in sorted(env.parts, key=lambda p: -p.factor)]


def _lead_html(lines: list[str]) -> str:
    return "<br>".join(html.escape(x) for x in lines)


def result_frame(res: Any) -> pd.DataFrame:
    """Any dose (every cell): one row leading with what cannot be ruled out (the envelope
    in s and tau, its dominant part), then the point, the model, each part's factors and
    the cell's own scalar fields (dose, volumes, radii, ...)."""
    d = res.to_dict()
    env = d.get("envelope_seconds") or [None, None]
    env_t = d.get("envelope_time") or [None, None]
    cols: dict[str, list[Any]] = {
        "cell": [res.cell], "envelope_low_s": [env[0]], "envelope_high_s": [env[1]],
        "envelope_low": [env_t[0]], "envelope_high": [env_t[1]],
        "dominant_uncertainty": [(d.get("dominant_uncertainty") or {}).get("name")],
        "seconds": [res.seconds], "time": [res.time], "model": [res.model]}
    for p in ([] if res.envelope is None else res.envelope.parts):
        cols[f"{p.name}_low"], cols[f"{p.name}_high"] = [p.low], [p.high]
    words = ("headline", "truth", "note", "question")
    cols.update({k: [v] for k, v in d.items() if k not in cols and k not in words
                 and (v is None or isinstance(v, (bool, int, float, str)))})
    units = {**ANSWER_UNITS, "envelope_low_s": "s", "envelope_high_s": "s",
             "envelope_low": "1", "envelope_high": "1"}
    return _frame(cols, units, {k: d.get(k) for k in words})


def result_html(res: Any) -> str:
    """Any dose (every cell): the envelope's lead lines as the caption, the point, the
    model, each part's factors, and the truth."""
    rows = [("time", res.time, "tau"), ("time", res.seconds, "s"), ("model", res.model, ""),
            *_envelope_rows(res)]
    truth = getattr(res, "truth", "") or ""
    body = _table(f"thermogel dose ({res.cell})", rows, f"truth: {truth}" if truth else "")
    return f"<div><p>{_lead_html(_lead(res, 'the dose after'))}</p>{body}</div>"


def schedule_result_frame(res: Any) -> pd.DataFrame:
    """Any schedule (every cell): its events, one row per step, the envelope and the
    headline in the attributes."""
    df = schedule_frame(res.answer)
    df.attrs.update(headline=res.headline, reading=res.reading,
                    lead=_lead(res, f"heat for ({res.reading} times)"))
    return df


def schedule_result_html(res: Any) -> str:
    """Any schedule (every cell): the envelope's lead lines, its parts, then the events."""
    parts = _envelope_rows(res)
    table = _table("uncertainty parts (factors of every time)", parts) if parts else ""
    return (f"<div><p>{_lead_html(_lead(res, f'heat for ({res.reading} times)'))}</p>"
            f"{table}{schedule_html(res.answer)}</div>")


# ---------------------------------------------------------------------------- schedules
def events_frame(events: Sequence[dict[str, Any]], attrs: dict[str, Any] | None = None
                 ) -> Any:
    """The events as a pandas DataFrame, one row per step, columns ``name [unit]``."""
    from ..question.events import EVENT_COLUMNS

    return _frame({name: [e.get(name) for e in events] for name in EVENT_COLUMNS},
                  {name: unit for name, (unit, _) in EVENT_COLUMNS.items()}, attrs)


def schedule_frame(ans: ScheduleAnswer) -> pd.DataFrame:
    """Any schedule (fluid or drug, one bead or a batch) as a lab runs it: one row per step
    (heat, rest), the corrected times when it was corrected, else the hold reading marked
    rough (:mod:`dosing.question.events`; every reading's table is ``to_xarray``)."""
    return events_frame(ans.events, {"model": ans.model, "truth": ans.truth,
                                     "note": ans.note})


_HTML_EVENTS = ("step", "kind", "start_s", "duration_s", "temperature_K", "dose_fraction",
                "released_fraction", "amount_ul", "dose_error")


def schedule_html(ans: ScheduleAnswer) -> str:
    """The events in HTML (one row per step), with the reading and the truth below."""
    from ..question.events import EVENT_COLUMNS

    ev = ans.events
    cols = _HTML_EVENTS
    head = "".join(f"<th>{html.escape(header(c, EVENT_COLUMNS[c][0] or None))}</th>"
                   for c in cols)
    body = "".join("<tr>" + "".join(f"<td>{_fmt(e.get(c))}</td>" for c in cols) + "</tr>"
                   for e in ev)
    reading = ev[0]["reading"] if ev else "hold"
    rough = " (rough: the hold reading, not checked)" if ev and ev[0]["rough"] else ""
    return (f"<table><caption style='text-align:left'><b>thermogel schedule "
            f"({html.escape(ans.model)}), {reading} times{rough}</b></caption><tr>{head}</tr>"
            f"{body}<tr><td colspan='{len(cols)}' style='text-align:left;font-size:smaller'>"
            f"truth: {html.escape(ans.truth)}</td></tr></table>")


# ---------------------------------------------------------------------------- sweeps
def sweep_frame(sw: SweepResult) -> pd.DataFrame:
    """The sweep's rows, one per point, columns ``name [unit]`` (dosing.studies.sweep.COLUMNS)."""
    COLUMNS = sw.COLUMNS
    cols = {n: [r.get(n) for r in sw.rows] for n in COLUMNS}
    units = {n: ("1" if u == "tau" else u) for n, (u, _) in COLUMNS.items()}
    return _frame(cols, units, {"grid": sw.grid})


# ---------------------------------------------------------------------------- fits
def fit_frame(fit: FitResult) -> pd.DataFrame:
    """One row per fitted parameter: estimate, 95% interval, standard error, unit."""
    names = list(fit.names)
    iv = [fit.intervals.get(n) or [None, None] for n in names]
    return _frame({"parameter": names, "estimate": [fit.parameters[n] for n in names],
                   "lower_95": [v[0] for v in iv], "upper_95": [v[1] for v in iv],
                   "stderr": [fit.stderr.get(n) for n in names],
                   "unit": [PARAMETER_UNITS.get(n.removeprefix("log_"), "") for n in names]},
                  {}, {"warnings": list(fit.warnings), "chi2_reduced": fit.chi2_reduced})


def fit_html(fit: FitResult) -> str:
    """Estimates with their 95% intervals, the fit's quality and its warnings."""
    rows = []
    for n in fit.names:
        iv = fit.interval(n)
        text = "" if iv is None else f"[{iv[0]:.4g}, {iv[1]:.4g}]"
        rows.append((n, fit.parameters[n], f"{PARAMETER_UNITS.get(n, '')} 95% {text}"))
    rows += [("points", fit.n_points, ""), ("rms residual", fit.rms_residual, ""),
             ("reduced chi^2", fit.chi2_reduced, "")]
    return _table("thermogel fit" + ("" if fit.success else " (not converged)"), rows,
                  "; ".join(fit.warnings))


# ---------------------------------------------------------------------------- runs
def run_frame(res: FullResult, dry_radius_um: float | None = None,
              timescale_seconds: float | None = None) -> pd.DataFrame:
    """One row per output time: t (and s), a (and um), R_f, jump, T, expelled volume."""
    from .export import dataset_frame, run_dataset

    ds = run_dataset(res, dry_radius_um, timescale_seconds)
    keep = [v for v in ds.data_vars if ds[v].dims == ("time",)]
    return dataset_frame(ds[keep])


def run_html(res: FullResult) -> str:
    """The run's grid, size, final state and cost."""
    d = res.diagnostics
    last = len(res.t) - 1
    rows = [("grid", res.grid, ""), ("cells", d.get("n"), ""),
            ("outputs", len(res.t), ""), ("t end", float(res.t[last]), "tau"),
            ("final radius", float(res.radius[last]), "dry radii"),
            ("front", float(res.front[last]), "dry radii"),
            ("steps", d.get("steps"), ""), ("wall time", d.get("wall_time"), "s")]
    gel = (d.get("gel") or {}).get("name", "")
    ell = d.get("interfacial_length")
    truth = f"gel {gel}, " + (f"interfacial length {ell:g}" if ell else "the paper's model")
    return _table("thermogel full run" + (" (spinodal)" if res.spinodal else ""), rows, truth)

