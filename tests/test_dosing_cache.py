"""The validation cache: SQLite WAL, atomic rows, restarts, SIGKILL mid-write, concurrency."""

import hashlib
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from dosing import ValidationCache
from dosing.runs.scenario import Trajectory

ROOT = Path(__file__).resolve().parents[1]


def _traj(seed: int, n: int = 50) -> Trajectory:
    rng = np.random.default_rng(seed)
    t = np.sort(rng.random(n))
    front = rng.random(n)
    front[-5:] = np.nan  # no front at the end
    return Trajectory(t=t, radius=2.0 - t, front=front, expelled_volume=t * 3.0,
                      temperature=np.full(n, 308.0), meta={"seed": seed, "horizon": float(t[-1])})


def test_round_trip_and_restart(tmp_path: Path) -> None:
    path = tmp_path / "c.sqlite"
    with ValidationCache(path) as cache:
        for s in range(3):
            cache.put_trajectory(f"k{s}", _traj(s))
        cache.put_validation("v1", {"keys": ["k0"], "fraction": 0.8})
        assert cache.get("missing") is None
    with ValidationCache(path) as again:  # a restart: a new object on the same file
        assert len(again) == 3 and again.keys() == ["k0", "k1", "k2"]
        got, want = again.get("k1"), _traj(1)
        for name in ("t", "radius", "front", "expelled_volume", "temperature"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name))
        assert got.meta["seed"] == 1
        assert again.get_validation("v1") == {"keys": ["k0"], "fraction": 0.8}
        journal = again._con().execute("PRAGMA journal_mode").fetchone()[0]
        assert journal == "wal"


def test_put_if_longer_never_shortens(tmp_path: Path) -> None:
    with ValidationCache(tmp_path / "c.sqlite") as cache:
        assert cache.put_if_longer("k", {"horizon": 4.0}, b"long")
        assert not cache.put_if_longer("k", {"horizon": 1.0}, b"short")
        assert cache.meta("k")["horizon"] == 4.0
        assert cache.put_if_longer("k", {"horizon": 16.0}, b"longer")


def test_default_path_from_environment(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("THERMOGEL_CACHE", str(tmp_path / "env" / "v.sqlite"))
    with ValidationCache() as cache:
        assert cache.path == tmp_path / "env" / "v.sqlite" and cache.path.exists()


_WRITER = textwrap.dedent("""
    import hashlib, sys
    import numpy as np
    from dosing.runs.cache import ValidationCache
    cache = ValidationCache(sys.argv[1])
    for i in range(1000):
        data = np.random.default_rng(i).bytes(int(sys.argv[2]))
        meta = {"i": i, "sha": hashlib.sha256(data).hexdigest()}
        print("begin", i, flush=True)
        cache.put(f"key{i}", meta, data)
        print("done", i, flush=True)
""")


def test_sigkill_mid_write_keeps_every_committed_row(tmp_path: Path) -> None:
    path = tmp_path / "killed.sqlite"
    size = 24 * 2**20  # 24 MiB rows: a write takes long enough to be interrupted
    proc = subprocess.Popen([sys.executable, "-c", _WRITER, str(path), str(size)],
                            stdout=subprocess.PIPE, text=True, cwd=ROOT)
    done: list[int] = []
    killed_during = None
    try:
        for line in proc.stdout:
            word, i = line.split()
            if word == "done":
                done.append(int(i))
            elif int(i) >= 2:
                time.sleep(0.005)  # inside cache.put of row i
                proc.send_signal(signal.SIGKILL)
                killed_during = int(i)
                break
    finally:
        proc.kill()
        rest = proc.communicate(timeout=30)[0]
    assert proc.returncode == -signal.SIGKILL
    done += [int(x.split()[1]) for x in rest.splitlines() if x.startswith("done")]
    assert done == list(range(len(done))) and len(done) >= 2
    assert killed_during not in done  # the kill landed before that write returned
    with ValidationCache(path) as cache:
        assert cache.integrity() == "ok"
        keys = set(cache.keys())
        assert {f"key{i}" for i in done} <= keys
        assert keys <= {f"key{i}" for i in range(killed_during + 1)}
        for key in keys:  # every row there is whole
            row = cache._con().execute("SELECT meta, data FROM trajectories WHERE key = ?",
                                       (key,)).fetchone()
            meta = __import__("json").loads(row[0])
            assert hashlib.sha256(bytes(row[1])).hexdigest() == meta["sha"]
        cache.put("after", {"i": -1}, b"x")  # and writable again
        assert "after" in cache


_WORKER = textwrap.dedent("""
    import sys
    from dosing.runs.cache import ValidationCache
    cache, me = ValidationCache(sys.argv[1]), int(sys.argv[2])
    seen = 0
    for i in range(15):
        cache.put(f"p{me}-{i}", {"me": me, "i": i}, bytes([me]) * 200_000)
        for k in cache.keys():
            row = cache.meta(k)
            assert row is not None
            seen += 1
    print(seen)
""")


@pytest.mark.slow
def test_concurrent_processes_and_threads(tmp_path: Path) -> None:
    path = tmp_path / "shared.sqlite"
    ValidationCache(path).close()
    procs = [subprocess.Popen([sys.executable, "-c", _WORKER, str(path), str(me)],
                              stdout=subprocess.PIPE, text=True, cwd=ROOT) for me in range(2)]
    cache = ValidationCache(path)
    errors: list[BaseException] = []

    def thread_work(me: int) -> None:
        try:
            for i in range(15):
                cache.put_trajectory(f"t{me}-{i}", _traj(i))
                assert cache.get(f"t{me}-{i}") is not None
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=thread_work, args=(me,)) for me in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    outs = [p.communicate(timeout=120) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], outs
    assert not errors
    assert len(cache) == 2 * 15 + 4 * 15
    assert cache.integrity() == "ok"
    cache.close()
    assert os.path.getsize(path) > 0


def _old_blob(arrays: dict[str, np.ndarray]) -> bytes:
    """A trajectory blob as the cache wrote it before the one run record (issue 16): the
    arrays t, radius, front, expelled_volume, temperature, step_* only, no diagnostics."""
    import io

    buf = io.BytesIO()
    np.savez_compressed(buf, **{k: np.asarray(v, dtype=float) for k, v in arrays.items()})
    return buf.getvalue()


def test_blobs_of_the_old_format_still_load(tmp_path: Path) -> None:
    """A row written by an earlier version loads as the one run record: arrays from the
    blob, diagnostics and the spinodal flag from the row's metadata."""
    from solver.full import FullResult

    t = np.linspace(0.0, 1.0, 11)
    step_t = np.linspace(0.0, 1.0, 101)
    old = {"t": t, "radius": 2.0 - t, "front": np.full(t.size, np.nan),
           "expelled_volume": 3.0 * t, "temperature": np.full(t.size, 308.0),
           "step_t": step_t, "step_radius": 2.0 - step_t, "step_rate": -np.ones(step_t.size),
           "step_edge": 0.9 - 0.5 * step_t}
    meta = {"key": "k", "horizon": 1.0, "wall_seconds": 0.5,
            "diagnostics": {"spinodal": True, "message": "spinodal collapse", "steps": 100}}
    with ValidationCache(tmp_path / "c.sqlite") as cache:
        cache.put("k", meta, _old_blob(old))
        got = cache.get("k")
    assert isinstance(got, FullResult) and got.meta == meta
    for name, want in old.items():
        np.testing.assert_array_equal(getattr(got, name), want)
    assert got.spinodal and got.diagnostics["message"] == "spinodal collapse"
    assert got.horizon == 1.0 and got.phi.size == 0
    # a(t) = 2 - t exactly: the Hermite crossing between steps is exact for a line
    assert got.time_to_radius(1.5) == pytest.approx(0.5, abs=1e-12)
    assert got.time_to_radius(1.2, after=0.55) == pytest.approx(0.8, abs=1e-12)
    assert got.nucleation_time(0.65) == pytest.approx(0.5, abs=1e-12)  # edge 0.9 - t/2
    assert got.nucleation_time(0.1) is None  # never: None, not NaN
    back = FullResult.from_npz(got.to_npz(), got.meta)  # and the new format round-trips
    assert back.spinodal and back.diagnostics == got.diagnostics
    np.testing.assert_array_equal(back.step_edge, got.step_edge)


def test_stored_runs_decode_one_at_a_time(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                          ) -> None:
    """numpy reads an npz header with ast.literal_eval, which CPython 3.11 can fail with a
    spurious SystemError when threads compile at once (python/cpython#106905; seen here as
    a batch node's run failing): the cache and the store decode under one lock, so eight
    threads reading never overlap in the decoder, and every row survives."""
    from dosing.runs import scenario

    inside, most = [0], [0]
    real = Trajectory.from_npz.__func__

    def counting(cls, blob, meta):
        inside[0] += 1
        most[0] = max(most[0], inside[0])
        time.sleep(0.002)
        try:
            return real(cls, blob, meta)
        finally:
            inside[0] -= 1

    monkeypatch.setattr(scenario.Trajectory, "from_npz", classmethod(counting))
    with ValidationCache(tmp_path / "c.sqlite") as cache:
        for s in range(8):
            cache.put_trajectory(f"k{s}", _traj(s))
        got: list[Trajectory | None] = [None] * 8
        threads = [threading.Thread(target=lambda i=i: got.__setitem__(i, cache.get(f"k{i}")))
                   for i in range(8)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
    assert most[0] == 1 and all(g is not None and g.meta["seed"] == i for i, g in enumerate(got))
