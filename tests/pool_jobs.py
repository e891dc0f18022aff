"""Jobs for the process-pool tests (importable by name in spawned workers)."""

from __future__ import annotations

import os
import signal
import time

from solver.errors import ParameterError


class Unpicklable(Exception):
    """An error whose constructor pickle cannot call again (two arguments, one message)."""

    def __init__(self, a: int, b: int) -> None:
        super().__init__(f"{a}/{b}")


def bad_parameter() -> None:
    raise ParameterError("steps[0].duration", 4e7, "0 < duration <= 1e6 (tau)", "why")


def bad_local() -> None:
    raise Unpicklable(1, 2)


def die() -> None:
    os.kill(os.getpid(), signal.SIGKILL)


def slow(x: object, seconds: float = 0.3) -> object:
    time.sleep(seconds)
    return x


def spin() -> None:
    while True:
        pass


def dying_solver(*args: object, **kwargs: object) -> None:
    """A stand-in for solver.full.simulate whose worker dies (as under the OOM killer); it
    appends a line to $THERMOGEL_TEST_CALLS first."""
    with open(os.environ["THERMOGEL_TEST_CALLS"], "a") as fh:
        fh.write(f"{os.getpid()}\n")
    die()
