"""The full-solver pool stays usable (issue 40, R1 and R2), against live servers.

R1: a protocol the grammar took and the solver refused broke the process pool for good
(the solver's ParameterError did not pickle back), and a restart that polled the poisoned
id broke the new pool again.  R2: 'Rest at 290 K until radius 130 um' after a hold at
308 K spun the compiled integrator for ever, starving every validation queued behind it,
and its worker outlived a kill -9 of the server.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import httpx
import psutil
import pytest
from api_support import serve_process

BEAD = {"gel": "ANB", "t_start": 302.0, "dry_radius_um": 50.0}
R1 = [["Bath at 308 K with a time constant of 1e6 tau"], ["Heat to 308 K at 1e-320 K/tau"]]
R2 = {**BEAD, "dose_fraction": 0.3,
      "protocol": ["Hold at 308 K for 1 min", "Rest at 290 K until radius 130 um"]}
SMOOTH = {"gel": "ANB", "t_start": 300.0, "t_end": 303.0, "dose_fraction": 0.2}


def _wait(c: httpx.Client, url: str, timeout: float = 240.0) -> tuple[dict, float]:
    """Poll until done or failed: (the last poll, seconds waited)."""
    t0 = time.monotonic()
    while True:
        got = c.get(url).json()
        if got["status"] in ("done", "failed") or time.monotonic() - t0 > timeout:
            return got, time.monotonic() - t0
        time.sleep(0.25)


def _validated(c: httpx.Client, body: dict) -> dict:
    r = c.post("/v1/dose-time", json=body)
    assert r.status_code == 202, r.text
    got, _ = _wait(c, r.json()["validation_url"])
    return got


def _poisoned_validation(cache: Path) -> str:
    """A validation stored by a server before the fix: one run whose program the solver
    refuses (an open bath of 1e6 tau: 40 time constants, 4e7 tau, past its 1e6 per step)."""
    from dosing import ValidationCache
    from dosing.runs.scenario import Scenario, SolverSettings
    from solver.gel import preset

    sc = Scenario(preset("ANB"), 302.0, program={"steps": [["bath", 308.0, 1e6, 4e7]],
                                                 "mobility": "kT", "reference": 308.0},
                  stop=2.0, settings=SolverSettings(grid="moving", n=100,
                                                    interfacial_length=1e-4))
    vid = "0123456789abcdef01234567"
    cache_ = ValidationCache(str(cache))
    try:
        cache_.put_validation(vid, {"scenarios": [sc.to_dict()], "keys": [sc.key()],
                                    "start_radius": 2.29, "target_radius": 2.0,
                                    "fraction": 0.5, "front_time": None})
    finally:
        cache_.close()
    return vid


@pytest.mark.slow
def test_r1_protocols_are_refused_and_a_poisoned_id_does_not_break_the_pool(
        tmp_path: Path) -> None:
    """The two protocols are a 422 naming the step and field, before anything is queued;
    a validation after them is done.  After a kill -9 and a restart, polling an id the old
    server stored (a run the solver refuses) fails it, naming the field, and a validation
    sent after it is done: the pool never broke."""
    cache = tmp_path / "c.sqlite"
    with serve_process(cache, "--no-warmup") as (url, proc), \
            httpx.Client(base_url=url, timeout=120) as c:
        for prot, field in zip(R1, ("time_constant", "rate"), strict=True):
            r = c.post("/v1/dose-time", json={**BEAD, "dose_fraction": 0.5, "protocol": prot})
            assert r.status_code == 422, r.text
            item = r.json()["detail"][0]
            assert item["loc"] == ["body", "protocol", 0, field], item
            assert "as the solver runs it" in item["msg"], item
        assert _validated(c, SMOOTH)["status"] == "done"
        proc.kill()
        proc.wait(30)
    vid = _poisoned_validation(cache)
    with serve_process(cache, "--no-warmup") as (url, _), \
            httpx.Client(base_url=url, timeout=120) as c:
        got, _ = _wait(c, f"/v1/validations/{vid}")
        assert got["status"] == "failed", got
        assert "steps[0].duration" in got["error"], got
        got, _ = _wait(c, f"/v1/validations/{vid}")  # polled again: failed, not re-run
        assert got["status"] == "failed"
        assert _validated(c, {**SMOOTH, "t_start": 300.5})["status"] == "done"
        health = c.get("/health").json()
        assert health["status"] == "ok", health
        assert health["planner"]["pool"] == {"status": "ok", "broken_because": None,
                                             "restarts": 0, "last_break": None}


@pytest.mark.slow
def test_r2_protocol_ends_within_its_budget_and_the_pool_keeps_serving(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """With a 3 s run budget (THERMOGEL_RUN_SECONDS), the protocol that spun for ever
    ends (answered, or failed naming its budget and settings) within its budget and a
    little, and a validation queued behind it on the one worker is done."""
    budget = 3.0
    monkeypatch.setenv("THERMOGEL_RUN_SECONDS", str(budget))
    with serve_process(tmp_path / "c.sqlite", "--no-warmup") as (url, _), \
            httpx.Client(base_url=url, timeout=120) as c:
        r = c.post("/v1/dose-time", json=R2)
        assert r.status_code == 202, r.text
        behind = c.post("/v1/dose-time", json=SMOOTH)
        assert behind.status_code == 202, behind.text
        got, waited = _wait(c, r.json()["validation_url"])
        print(f"R2: {got['status']} after {waited:.1f} s")
        assert got["status"] in ("done", "failed"), got
        if got["status"] == "failed":
            assert "budget" in got["error"] and "moving grid" in got["error"], got
        assert waited < 2 * budget + 60.0
        got, waited = _wait(c, behind.json()["validation_url"])
        print(f"behind it: {got['status']} after {waited:.1f} s more")
        assert got["status"] == "done", got


@pytest.mark.slow
def test_no_worker_outlives_a_kill_9_of_its_server_mid_run(tmp_path: Path) -> None:
    """A pool worker busy in a compiled run (the thread that watched for its parent could
    not run while numba held the GIL) is killed by its watchdog process within seconds of
    a kill -9 of the server; so are the watchdog and the resource tracker."""
    with serve_process(tmp_path / "c.sqlite", "--no-warmup") as (url, proc), \
            httpx.Client(base_url=url, timeout=120) as c:
        for body in (R2, *({**SMOOTH, "t_start": t} for t in (300.0, 300.5, 301.0))):
            r = c.post("/v1/dose-time", json=body)  # work for the one worker, queued
            assert r.status_code == 202, r.text
        server = psutil.Process(proc.pid)
        deadline = time.monotonic() + 120
        busy = None
        while busy is None and time.monotonic() < deadline:
            for p in server.children(recursive=True):
                try:
                    if (p.ppid() == proc.pid and p.cpu_times().user > 1.0
                            and p.status() == psutil.STATUS_RUNNING):
                        busy = p
                except psutil.NoSuchProcess:
                    continue
            time.sleep(0.1)
        assert busy is not None, "no pool worker got busy"
        children = [p.pid for p in server.children(recursive=True)]
        assert len(children) >= 3, children  # a worker, its watchdog, the resource tracker
        proc.kill()
        proc.wait(30)
        t0 = time.monotonic()
        left = children
        while left and time.monotonic() - t0 < 20:
            left = [pid for pid in children if _alive(pid)]
            time.sleep(0.1)
        print(f"{len(children)} descendants gone {time.monotonic() - t0:.1f} s after kill -9")
        assert left == [], [psutil.Process(p).cmdline() for p in left]
        assert time.monotonic() - t0 < 5.0


def _alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def test_a_worker_dies_with_its_parent_even_inside_a_compiled_loop() -> None:
    """dosing.runs.jobs.kill_with_parent: the watchdog process kills a process whose parent is
    gone while that process sits in a numba loop holding the GIL."""
    import subprocess
    import sys

    script = (
        "import os, sys, time\n"
        "from numba import njit\n"
        "from dosing.runs.jobs import kill_with_parent\n"
        "@njit\n"
        "def spin(n):\n"
        "    x = 0.0\n"
        "    for i in range(n):\n"
        "        x += (i % 7) * 1e-9\n"
        "    return x\n"
        "spin(10)\n"
        "pid = os.fork()\n"
        "if pid == 0:\n"
        "    kill_with_parent(os.getppid(), interval=0.2)\n"
        "    print(os.getpid(), flush=True)\n"
        "    spin(10**13)\n"
        "    os._exit(0)\n"
        "time.sleep(30)\n")
    root = Path(__file__).resolve().parents[1]
    parent = subprocess.Popen([sys.executable, "-c", script], cwd=root, stdout=subprocess.PIPE,
                              text=True, env={**os.environ, "PYTHONPATH": str(root)})
    try:
        child = int(parent.stdout.readline())
        time.sleep(1.0)
        assert _alive(child)
        parent.kill()
        parent.wait(10)
        t0 = time.monotonic()
        while _alive(child) and time.monotonic() - t0 < 10:
            time.sleep(0.05)
        assert not _alive(child), "the spinning child outlived its parent"
        assert time.monotonic() - t0 < 3.0
    finally:
        parent.kill()
        parent.stdout.close()
