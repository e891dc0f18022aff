"""Python that works as pasted: every ```python block of the README runs as a script of its
own, without an ``if __name__ == "__main__"`` guard, and finishes (docs/ pages may sketch an
API with elisions; the README's blocks are the ones a new user pastes).

Blocks that talk to the service get a live ``thermogel serve`` on a free loopback port in
place of the documented http://127.0.0.1:8000.  Each block runs in a fresh directory with a
fresh cache, so it shows what a new user sees.  Slow: some blocks run the full solver.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from api_support import ROOT, serve

DOCUMENTED_URL = "http://127.0.0.1:8000"
PAGES = [ROOT / "README.md"]


def python_blocks() -> list[tuple[str, str]]:
    """(id, code) of every fenced ```python block of the pages."""
    out = []
    for page in PAGES:
        text = page.read_text()
        for m in re.finditer(r"^```python\n(.*?)^```", text, re.S | re.M):
            line = text[:m.start()].count("\n") + 1
            out.append((f"{page.name}:{line}", m.group(1)))
    return out


BLOCKS = python_blocks()


def test_the_readme_has_python_blocks() -> None:
    assert sum(name.startswith("README.md") for name, _ in BLOCKS) >= 5


def run_block(code: str, tmp_path: Path, url: str | None = None) -> subprocess.CompletedProcess:
    if url is not None:
        code = code.replace(DOCUMENTED_URL, url)
    script = tmp_path / "pasted.py"
    script.write_text(code)
    env = {**os.environ, "THERMOGEL_CACHE": str(tmp_path / "cache.sqlite"),
           "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          cwd=tmp_path, env=env, timeout=900)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "code"), BLOCKS, ids=[n for n, _ in BLOCKS])
def test_block_runs_as_a_script(name: str, code: str, tmp_path: Path) -> None:
    if DOCUMENTED_URL in code:
        with serve(tmp_path / "server-cache.sqlite") as url:
            done = run_block(code, tmp_path, url)
    else:
        done = run_block(code, tmp_path)
    assert done.returncode == 0, f"{name} failed:\n{done.stderr[-3000:]}"
    assert "Traceback" not in done.stderr
