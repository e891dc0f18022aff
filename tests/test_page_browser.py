"""The planner page in headless Chromium against a real ``thermogel serve`` (issue 17).

Chromium is Debian's (``.ci/run`` installs it when missing), driven by Playwright's Python
package with ``executable_path`` (no browser download).  The page must read back the JSON
route's time for ANB 302 -> 308 K, 80 %, 50 um; an out-of-range temperature must show a
message and send no request; a server error must be shown next to the field it names; a
design map runs as a sweep job; a saved custom gel is answered as the JSON route answers
its parameters; a validation's progress is polled to its result.  On the fake full solver
(tests/api_fake_server.py): a batch's dose shows the batch's own time as its headline (its
mean bead's beside it), and a schedule, a batch's too, is queued as a job and shown with its
corrected times, the rough hold reading labelled as such.
Screenshots go to tests/artifacts/ (or $THERMOGEL_ARTIFACTS).  Without Chromium the test
is skipped, except in CI (CI=true), where it fails.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx
import pytest
from api_support import ROOT, _server, fake_server, free_port

CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if Path("/usr/bin/chromium").exists()
                                        else None)
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]
FRONT = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.8,
         "dry_radius_um": 50.0}
FAKE_DELAY = 0.2  # s per fake full-solver run: a batch schedule's 31 runs stay queued a while


def _need_browser() -> object:
    """Playwright's sync API, or a skip (a failure in CI) when it cannot run here."""
    in_ci = os.environ.get("CI") == "true"
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        if in_ci:
            pytest.fail("playwright is not installed (the test extra brings it)")
        pytest.skip("playwright is not installed")
    if CHROMIUM is None:
        if in_ci:
            pytest.fail("chromium is not installed (.ci/run installs Debian's package)")
        pytest.skip("chromium is not installed (apt-get install chromium)")
    return sync_playwright


def _artifacts() -> Path:
    out = Path(os.environ.get("THERMOGEL_ARTIFACTS", ROOT / "tests" / "artifacts"))
    out.mkdir(parents=True, exist_ok=True)
    return out


@contextmanager
def _serve_gracefully(cache: Path) -> Iterator[str]:
    """``thermogel serve`` on a free loopback port, stopped with SIGINT (uvicorn's shutdown
    closes the planner and its worker processes; SIGKILL would orphan them)."""
    port = free_port()
    cmd = [sys.executable, "-m", "api.cli", "serve", "--port", str(port), "--cache", str(cache),
           "--log-level", "warning", "--no-warmup"]
    with _server(cmd, port, 240.0) as (url, proc):
        try:
            yield url
        finally:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                pass  # _server kills it


@contextmanager
def _serve_fake(cache: Path) -> Iterator[str]:
    """The service with its full-solver runs on the fake solver (tests/api_fake_server.py;
    threads only, so SIGKILL orphans nothing)."""
    with fake_server(cache, FAKE_DELAY) as (url, _):
        yield url


@contextmanager
def browser_page(tmp_path: Path, serve: Any = None
                 ) -> Iterator[tuple[str, Any, list[str], list[str]]]:
    """(url, page, page errors, /v1/ requests sent): a real ``thermogel serve`` (or
    ``serve(cache)``'s server) and the page loaded in headless Chromium, ready; closed
    after."""
    sync_playwright = _need_browser()
    with (serve or _serve_gracefully)(tmp_path / "cache.sqlite") as url, \
            tempfile.TemporaryDirectory() as profile, sync_playwright() as pw:
        ctx = pw.chromium.launch_persistent_context(
            profile, executable_path=CHROMIUM, args=FLAGS, headless=True,
            viewport={"width": 1400, "height": 1000})
        try:
            page = ctx.new_page()
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            sent: list[str] = []
            page.on("request", lambda r: sent.append(r.url) if "/v1/" in r.url else None)
            page.goto(url + "/")
            page.wait_for_selector("body[data-state=ready]", timeout=60_000)
            yield url, page, errors, sent
        finally:
            ctx.close()

def _fill(page, **fields: str) -> None:
    for name, value in fields.items():
        page.fill(f"#{name}", value)


def refused_in_the_page(page, sent: list[str], button: str, state: str,
                        **fields: str) -> str:
    """Fill ``fields``, click ``button``: the page marks ``state`` invalid without sending a
    request; returns the first field's message (``#err-<field>``)."""
    sent.clear()
    _fill(page, **fields)
    page.click(button)
    page.wait_for_selector(f"body[{state}=invalid]")
    msg = page.inner_text(f"#err-{next(iter(fields))}")
    page.wait_for_timeout(500)
    assert sent == []
    return msg


@pytest.mark.slow  # a real server, a browser, and one coarse full-solver validation
def test_page_in_headless_chromium(tmp_path: Path) -> None:
    with browser_page(tmp_path) as (url, page, errors, sent):

        # the acceptance request, read back against the JSON route
        page.select_option("#gel", "ANB")
        _fill(page, t_start="302", t_end="308", doses="80", dry_radius_um="50")
        page.click("#plan")
        page.wait_for_selector("body[data-state=answered]", timeout=120_000)
        want = httpx.post(f"{url}/v1/dose-time", json=FRONT, timeout=60).json()
        assert float(page.get_attribute("#answer-time", "data-value")) == want["time"]
        assert float(page.get_attribute("#answer-seconds", "data-value")) == want["seconds"]
        assert page.inner_text("#answer-seconds") == f"{want['seconds']:.4g} s"
        assert want["error_explanation"] in page.inner_text("#answer-error-parts")
        assert page.locator("#curve-radius").count() == 1  # the front curve is drawn
        assert page.locator(".dose-mark").count() == 1
        assert page.locator("#timeline-release").count() == 1
        page.wait_for_function("document.getElementById('phase-map').complete && "
                               "document.getElementById('phase-map').naturalWidth > 0")
        page.screenshot(path=str(_artifacts() / "page.png"), full_page=True)

        # out of range: a message naming the field, and no request at all
        msg = refused_in_the_page(page, sent, "#plan", "data-state", t_end="400")
        assert "T_end" in msg and "373.15" in msg

        # within the page's bounds but refused by the server: shown at the field
        _fill(page, t_end="308", interfacial_length="0.00001")  # below the direct range
        page.click("#plan")
        page.wait_for_selector("body[data-state=server-error]", timeout=60_000)
        assert page.inner_text("#err-interfacial_length").startswith("interfacial_length:")
        assert page.inner_text("#err-t_end") == ""

        # a design map of the default axes (9 x 9 x 4): the table the sweep route gives
        _fill(page, interfacial_length="0.005")
        page.click("#sweep")
        page.wait_for_selector("body[data-sweep=done]", timeout=120_000)
        page.wait_for_function("document.getElementById('sweep-plot').complete && "
                               "document.getElementById('sweep-plot').naturalWidth > 0")
        csv_url = page.get_attribute("#sweep-links a", "href")  # /v1/sweeps/{id}/table.csv
        assert csv_url.endswith("/table.csv")
        csv = httpx.get(url + csv_url, timeout=60)
        assert csv.headers["content-type"].startswith("text/csv")
        assert len(csv.text.strip().splitlines()) == 1 + 9 * 9 * 4  # a header and the rows
        table = httpx.get(url + csv_url.removesuffix("/table.csv"), timeout=60).json()["result"]
        assert len(table["rows"]) == 9 * 9 * 4 and table["grid"]["t_ends"][0] == 307.5
        assert "324 answered" in page.inner_text("#sweep-status")
        assert "373.15" in refused_in_the_page(page, sent, "#sweep", "data-sweep",
                                               sweep_t_end="300, 380, 5")
        _fill(page, sweep_t_end="307.5, 311.5, 9")

        # a saved custom gel: checked in the page, kept in the browser, sent as parameters
        page.click("#custom-gel summary")
        _fill(page, gel_name="soft ANB", gel_omega="-1")
        sent.clear()
        page.click("#save-gel")
        assert "Omega" in page.inner_text("#err-gel_omega") and sent == []
        _fill(page, gel_omega="120")
        page.click("#save-gel")
        page.wait_for_selector("body[data-gel=saved]")
        assert page.input_value("#gel") == "saved:soft ANB"
        page.click("#plan")
        page.wait_for_selector("body[data-state=answered]", timeout=120_000)
        soft = {"base": "ANB", "omega": 120.0, "a0": -12.947, "b0": 0.04496, "a1": 17.92,
                "b1": -0.0569}
        want = httpx.post(f"{url}/v1/dose-time", json={**FRONT, "gel": soft}, timeout=60).json()
        assert float(page.get_attribute("#answer-time", "data-value")) == want["time"]
        page.click("#custom-gel summary")
        page.select_option("#gel", "ANB")

        # a validation, polled to its result (the coarsest ladder: ell = 0.01)
        _fill(page, interfacial_length="0.01")
        page.check("#validate")
        page.click("#plan")
        page.wait_for_selector("#validation-panel[data-status=done]", timeout=600_000)
        assert "Truth (regularized)" in page.inner_text("#validation-result")
        page.wait_for_selector("body[data-validated]", timeout=60_000)  # asked again
        ell = {**FRONT, "interfacial_length": 0.01}
        again = httpx.post(f"{url}/v1/dose-time", json=ell, timeout=60).json()
        assert again["validation"] is not None  # now answered with the verdict
        assert page.inner_text("#answer-error") == f"± {100 * again['error_estimate']:.3g} %"
        page.screenshot(path=str(_artifacts() / "page-validated.png"), full_page=True)
        assert errors == []


BATH_CSV = "time (s),T (degC)\n0,28.85\n10,31.0\n20,32.5\n40,34.0\n80,34.8\n120,34.85\n"


def _protocol_answered(page) -> None:
    """Wait for the protocol's answer, or its error (which fails at once, with the page's
    message: CI once waited 15 minutes on a poll that had answered 500)."""
    page.wait_for_selector("body[data-protocol=answered], body[data-protocol=error]",
                           timeout=900_000)
    state = page.evaluate("document.body.dataset.protocol")
    assert state == "answered", page.inner_text("#protocol-error")


@pytest.mark.slow  # a real server, a browser and the full solver's protocol runs (issue 24)
def test_protocol_editor_in_headless_chromium(tmp_path: Path) -> None:
    """The protocol editor: the ramp preset, a bad step named at its row, the answer read
    back against the JSON route (the temperature and the released fraction drawn on one
    time axis), and a measured trace in degC and seconds uploaded and answered."""
    sync_playwright = _need_browser()
    with _serve_gracefully(tmp_path / "cache.sqlite") as url, \
            tempfile.TemporaryDirectory() as profile, sync_playwright() as pw:
        ctx = pw.chromium.launch_persistent_context(
            profile, executable_path=CHROMIUM, args=FLAGS, headless=True,
            viewport={"width": 1400, "height": 1000})
        try:
            page = ctx.new_page()
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url + "/")
            page.wait_for_selector("body[data-state=ready]", timeout=60_000)
            _fill(page, t_start="302", t_end="308", doses="30", dry_radius_um="50")
            page.click("#preset-ramp")
            steps = page.locator("#protocol-steps .step-text")
            assert steps.count() == 1 and steps.nth(0).input_value() == "Heat to 308 K at 5 K/min"

            page.click("#add-step")
            steps.nth(1).fill("Hold at 308 K for 2 parsecs")
            page.click("#plan-protocol")
            page.wait_for_selector("body[data-protocol=error]", timeout=60_000)
            assert "for" in page.locator(".step-err").nth(1).inner_text()
            assert page.locator(".step-err").nth(0).inner_text() == ""
            page.locator(".remove-step").nth(1).click()

            body = {"gel": "ANB", "t_start": 302.0, "dose_fraction": 0.3, "dry_radius_um": 50.0,
                    "protocol": ["Heat to 308 K at 5 K/min"]}
            page.click("#plan-protocol")
            _protocol_answered(page)
            want = httpx.post(f"{url}/v1/dose-time", json=body, timeout=60)
            assert want.status_code == 200  # cached by the page's request
            want = want.json()
            assert float(page.get_attribute("#protocol-seconds", "data-value")) == want["seconds"]
            assert page.inner_text("#protocol-seconds") == f"{want['seconds']:.4g} s"
            # which model answered, and why (the JSON's model and model_reason)
            assert page.get_attribute("#protocol-model", "data-value") == want["model"]
            assert want["model_reason"] and want["model_reason"] in page.inner_text(
                "#protocol-model")
            assert page.locator("#protocol-temperature").count() == 1
            assert page.locator("#protocol-release").count() == 1
            assert page.locator(".protocol-dose-mark").count() == 1
            page.screenshot(path=str(_artifacts() / "page-protocol.png"), full_page=True)

            trace = tmp_path / "bath.csv"
            trace.write_text(BATH_CSV)
            page.set_input_files("#trace-file", str(trace))
            assert steps.count() == 1 and steps.nth(0).input_value() == "Trace from bath.csv"
            page.click("#plan-protocol")
            _protocol_answered(page)
            structured = {**body, "protocol": [{"step": "trace", "name": "bath.csv",
                                                "csv": BATH_CSV}]}
            want = httpx.post(f"{url}/v1/dose-time", json=structured, timeout=60).json()
            assert float(page.get_attribute("#protocol-seconds", "data-value")) == want["seconds"]
            assert errors == []
        finally:
            ctx.close()


def _job_result(url: str, vid: str) -> dict:
    v = httpx.get(f"{url}/v1/validations/{vid}", timeout=60).json()
    assert v["status"] == "done", v
    return v["result"]


def _schedule_shown(page) -> list[float]:
    """The schedule panel's headline seconds, checked against its table's first column."""
    shown = json.loads(page.get_attribute("#schedule-headline", "data-value"))
    cells = page.locator("#schedule-table td.heat-for")
    assert [float(cells.nth(k).get_attribute("data-value")) for k in range(cells.count())] \
        == shown
    return shown


@pytest.mark.slow  # a browser and a server whose full-solver runs are the fake's
def test_batch_dose_and_schedules_in_headless_chromium(tmp_path: Path) -> None:
    """A batch's dose: the headline is the batch's own seconds (the HTTP answer's), its mean
    bead's secondary.  A schedule: queued as a job, then led by its corrected times with the
    rough hold reading beside them; a batch's schedule likewise, saying it is the batch's."""
    with browser_page(tmp_path, _serve_fake) as (url, page, errors, sent):
        batch = {"kind": "lognormal", "cv": 0.2}
        page.select_option("#gel", "ANB")
        _fill(page, t_start="302", t_end="308", doses="60", dry_radius_um="50", size_cv="0.2")
        page.click("#plan")
        page.wait_for_selector("body[data-state=answered]", timeout=120_000)
        want = httpx.post(f"{url}/v1/dose-time", json={
            **FRONT, "dose_fraction": 0.6, "size_distribution": batch}, timeout=60).json()
        assert want["seconds"] == want["batch"]["seconds"] != want["reference_bead"]["seconds"]
        assert float(page.get_attribute("#answer-seconds", "data-value")) == want["seconds"]
        assert page.inner_text("#answer-seconds") == f"{want['seconds']:.4g} s"
        assert float(page.get_attribute("#answer-time", "data-value")) == want["time"]
        assert page.inner_text("#answer-headline") == want["headline"]
        assert float(page.get_attribute("#answer-reference", "data-value")) == \
            want["reference_bead"]["seconds"]
        assert page.locator(".batch-mark").count() == 1
        assert page.inner_text("#schedule-table td.heat-for") == f"{want['seconds']:.4g} s"

        # a schedule of one bead: the job's corrected times lead, the hold reading beside
        _fill(page, doses="30, 30", size_cv="")
        page.click("#plan")
        page.wait_for_selector("body[data-schedule=corrected]", timeout=120_000)
        assert page.get_attribute("body", "data-schedule-batch") == "false"
        one = _job_result(url, page.get_attribute("body", "data-schedule-job"))
        assert one["reading"] == "corrected" and one.get("batch") is None
        assert _schedule_shown(page) == one["actuation_seconds"] == \
            one["corrected"]["actuation_seconds"]
        assert one["actuation_seconds"] != [r["actuation_seconds"] for r in one["hold"]]
        assert "rough hold reading" in page.inner_text("#schedule-table")
        assert "corrected" in page.inner_text("#schedule-headline")

        # a batch's schedule: queued (always a job), then the batch's corrected times
        _fill(page, size_cv="0.2")
        page.click("#plan")
        page.wait_for_selector("body[data-schedule=queued], body[data-schedule=running]",
                               timeout=120_000)
        assert "batch's schedule (size CV 0.2) is queued" in page.inner_text(
            "#schedule-headline")
        vid = page.get_attribute("body", "data-schedule-job")
        assert page.get_attribute("body", "data-schedule-batch") == "true"
        body = {k: v for k, v in FRONT.items() if k != "dose_fraction"}
        again = httpx.post(f"{url}/v1/schedule", json={**body, "doses": [0.3, 0.3],
                                                       "size_distribution": batch}, timeout=60)
        assert again.status_code == 202 and again.json()["validation_id"] == vid  # the same
        page.screenshot(path=str(_artifacts() / "page-batch-schedule-queued.png"),
                        full_page=True)
        page.wait_for_selector("body[data-schedule=corrected]", timeout=300_000)
        res = _job_result(url, vid)
        assert res["batch"] is True and res["reading"] == "corrected"
        assert _schedule_shown(page) == res["actuation_seconds"] == \
            res["corrected"]["actuation_seconds"]
        assert res["actuation_seconds"] != one["actuation_seconds"]
        words = page.inner_text("#schedule-batch")
        assert "size CV 0.2" in words and "50 µm" in words
        assert page.inner_text("#schedule-headline").startswith("The batch's schedule: heat for")
        assert "rough hold reading" in page.inner_text("#schedule-table")
        page.screenshot(path=str(_artifacts() / "page-batch-schedule.png"), full_page=True)
        assert errors == []


SIZES_CSV = "radius (um)\n40\n50\n60\n"


def _wait_schedule(page, url: str) -> dict:
    """Wait for the page's schedule job to be shown corrected; its result (the JSON)."""
    page.wait_for_selector("body[data-schedule=corrected], body[data-schedule=failed]",
                           timeout=300_000)
    assert page.get_attribute("body", "data-schedule") == "corrected", page.inner_text(
        "#schedule-note")
    return _job_result(url, page.get_attribute("body", "data-schedule-job"))


def _events_shown(page, res: dict) -> None:
    """The page's schedule is the answer's events: the headline, the answer panel and the
    table's heat rows read the corrected durations, the plot its release."""
    heats = [e["duration_s"] for e in res["events"] if e["kind"] == "heat"]
    assert heats == res["actuation_seconds"]
    assert _schedule_shown(page) == heats
    assert json.loads(page.get_attribute("#answer-seconds", "data-value")) == heats
    assert page.inner_text("#answer-heat-label") == "Heat for (corrected)"
    rows = page.locator("#schedule-table tbody tr, #schedule-table tr.heat, "
                        "#schedule-table tr.rest, #schedule-table tr.hold")
    kinds = [page.locator("#schedule-table tr").nth(k).get_attribute("class")
             for k in range(1, page.locator("#schedule-table tr").count())]
    assert kinds == [e["kind"] for e in res["events"]], rows.count()
    assert "shooting residual" in page.inner_text("#schedule-table")
    assert page.get_attribute("#timeline-release", "data-reading") == "corrected"
    assert "corrected" in page.inner_text("#schedule-caption")
    # the steps as CSV, as the CLI's --out writes them: a header with units, a row per step
    from urllib.parse import unquote

    href = page.get_attribute("#schedule-download", "href")
    lines = unquote(href.split(",", 1)[1]).strip().splitlines()
    assert lines[0].startswith("step [1],kind,start_s [s],duration_s [s],temperature_K [K]")
    assert [x.split(",")[1] for x in lines[1:]] == [e["kind"] for e in res["events"]]
    assert [float(x.split(",")[3]) for x in lines[1:]] == [e["duration_s"]
                                                           for e in res["events"]]


@pytest.mark.slow  # a browser and a server whose full-solver runs are the fake's
def test_lab_inputs_in_headless_chromium(tmp_path: Path) -> None:
    """The page for lab users (issue 37): temperatures in degC and rests in minutes (the
    server's one unit parser), a swollen bead size, drug inputs, a size table uploaded as
    CSV for a batch's schedule; every schedule shown as its events (the corrected times in
    the headline, the answer panel, the table and the plot)."""
    with browser_page(tmp_path, _serve_fake) as (url, page, errors, sent):
        page.select_option("#gel", "ANB")

        # degC and minutes: the same request as the JSON route with those strings
        _fill(page, t_start="29 degC", t_end="35 degC", doses="30, 30", rests="10 min",
              dry_radius_um="50")
        page.click("#plan")
        res = _wait_schedule(page, url)
        body = {"gel": "ANB", "t_start": "29 degC", "t_end": "35 degC", "dry_radius_um": 50.0,
                "doses": [0.3, 0.3], "rests_seconds": ["10 min"]}
        again = httpx.post(f"{url}/v1/schedule", json=body, timeout=60).json()
        assert again["validation_id"] == page.get_attribute("body", "data-schedule-job")
        assert res["request"]["t_start"] == pytest.approx(302.15)
        _events_shown(page, res)
        rest = [e for e in res["events"] if e["kind"] == "rest"]
        assert rest[0]["duration_s"] == pytest.approx(600.0)
        assert "600 s (10 min)" in page.inner_text("#schedule-table")
        assert "308.15 K (35 °C)" in page.inner_text("#schedule-table")
        page.wait_for_function("document.getElementById('phase-map').complete && "
                               "document.getElementById('phase-map').naturalWidth > 0")
        page.screenshot(path=str(_artifacts() / "page-lab-schedule.png"), full_page=True)

        # rests in tau and in minutes mixed: refused in the page, no request
        assert "not both" in refused_in_the_page(page, sent, "#plan", "data-state",
                                                 rests="0.5, 10 min", doses="30, 30, 30")
        # a temperature with a unit out of range: the server's message at the field
        _fill(page, t_end="120 degC", doses="30", rests="")
        page.click("#plan")
        page.wait_for_selector("body[data-state=server-error]", timeout=60_000)
        assert page.inner_text("#err-t_end").startswith("t_end")

        # a swollen size: sent as swollen_radius_um, answered as the JSON route answers it
        _fill(page, t_start="302", t_end="308", dry_radius_um="60")
        page.select_option("#size_kind", "swollen")
        page.click("#plan")
        page.wait_for_selector("body[data-state=answered]", timeout=120_000)
        want = httpx.post(f"{url}/v1/dose-time", json={
            "gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.3,
            "swollen_radius_um": 60.0}, timeout=60).json()
        assert float(page.get_attribute("#answer-seconds", "data-value")) == want["seconds"]
        assert want["bead_dry_radius_um"] < 60.0
        page.select_option("#size_kind", "dry")

        # drug inputs: D0, solute radius, mesh and load, sent as the drug
        page.click("#drug-inputs summary")
        _fill(page, dry_radius_um="50", drug_radius="2", drug_mesh="20", drug_load="2")
        page.click("#plan")  # a drug dose job on the fake solver, then answered
        page.wait_for_selector("body[data-state=answered]", timeout=120_000)
        drug = {"solute_radius_nm": 2.0, "mesh_size_nm": 20.0, "load_ug": 2.0}
        want = httpx.post(f"{url}/v1/dose-time", json={
            "gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.3,
            "dry_radius_um": 50.0, "drug": drug}, timeout=60).json()
        assert want["drug"] is True
        assert float(page.get_attribute("#answer-seconds", "data-value")) == want["seconds"]
        assert "drug load" in page.inner_text("#answer-release")
        # a bad drug field is named at its input
        msg = refused_in_the_page(page, sent, "#plan", "data-state", drug_d0="-1")
        assert msg.startswith("D0")
        _fill(page, drug_d0="")
        # a drug schedule: its events, doses of the load
        _fill(page, doses="30, 30", rests="0.5")
        page.click("#plan")
        res = _wait_schedule(page, url)
        assert res["drug"] is True
        _events_shown(page, res)
        assert "of the load" in page.inner_text("#schedule-table")
        for name in ("drug_radius", "drug_mesh", "drug_load"):
            _fill(page, **{name: ""})

        # a size table uploaded as CSV: a batch, its schedule corrected as the batch's
        table = tmp_path / "sizes.csv"
        table.write_text(SIZES_CSV)
        page.set_input_files("#size-file", str(table))
        page.wait_for_selector("body[data-size-table=loaded]")
        assert "3 sizes" in page.inner_text("#size-table-status")
        page.click("#plan")
        res = _wait_schedule(page, url)
        assert res["batch"] is True
        assert res["request"]["population"]["sizes"]["kind"] == "table"
        _events_shown(page, res)
        assert "The batch's schedule: heat for" in page.inner_text("#schedule-headline")
        page.screenshot(path=str(_artifacts() / "page-lab-batch.png"), full_page=True)
        bad = tmp_path / "bad.csv"
        bad.write_text("radius (um)\n40\nfifty\n")
        page.set_input_files("#size-file", str(bad))
        page.wait_for_selector("body[data-size-table=invalid]")
        assert "line 3" in page.inner_text("#err-size_table")
        assert errors == []
