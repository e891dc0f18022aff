"""``thermogel serve`` logs its warm-up as it goes and warms every kernel it lists
(issue 37): between uvicorn's "Waiting for application startup" and "startup complete" a
line per group of kernels and per call of the workload, with seconds; /health then lists
no kernel cold."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import httpx
import pytest
from api_support import ROOT, free_port, wait_healthy


@pytest.mark.slow
def test_serve_logs_its_warm_up_and_leaves_no_kernel_cold(tmp_path: Path) -> None:
    port = free_port()
    log = tmp_path / "serve.log"
    with log.open("w") as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "api.cli", "serve", "--port", str(port), "--cache",
             str(tmp_path / "c.sqlite")], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=err,
            env={**os.environ, "PYTHONUNBUFFERED": "1"})
        try:
            url = f"http://127.0.0.1:{port}"
            proc.stderr = open(log)  # wait_healthy reads it on failure
            wait_healthy(url, proc, 300)
            health = httpx.get(f"{url}/health").json()
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            proc.stderr.close()
    text = log.read_text()
    start = text.index("Waiting for application startup")
    done = text.index("Application startup complete")
    between = text[start:done]
    for group in ("solver.full", "solver.front", "solver.solute"):
        assert re.search(rf"warm-up: {re.escape(group)} +\d+ kernels, +\d+ cached signatures "
                         rf"loaded, +[\d.]+ s", between), between
    assert re.search(r"warm-up: tiny full runs +[\d.]+ s", between), between
    assert re.search(r"warm-up: done in [\d.]+ s: \d+ kernels warm .*, 0 cold", between)
    assert health["kernels_cold"] == [] and health["kernels_warm"] > 100
