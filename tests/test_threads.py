"""Trials run concurrently on threads (armlab.sim.threads)."""

from __future__ import annotations

import threading
import time

import pytest

from armlab.errors import SimulationError
from armlab.sim.threads import run_trials


def test_results_come_back_in_trial_order_at_any_thread_count():
    def square(i: int) -> int:
        time.sleep(0.002 * (5 - i))  # later trials finish first
        return i * i

    for nthread in (1, 2, 5, 16):
        assert run_trials(square, 5, nthread) == [0, 1, 4, 9, 16]


def test_trials_run_on_several_threads():
    seen: set[str] = set()
    barrier = threading.Barrier(2, timeout=5.0)  # both trials must be running at once to pass

    def trial(i: int) -> int:
        seen.add(threading.current_thread().name)
        barrier.wait()
        return i

    assert run_trials(trial, 2, 2) == [0, 1]
    assert len(seen) == 2


def test_the_lowest_failing_trial_is_the_one_raised():
    # serially trial 1 fails first and trial 3 is never reached; threaded, trial 3 may fail
    # earlier in time, but the error raised must still be trial 1's
    def trial(i: int) -> int:
        if i == 3:
            raise SimulationError("trial 3 failed")
        if i == 1:
            time.sleep(0.05)
            raise SimulationError("trial 1 failed")
        return i

    for nthread in (1, 2, 4):
        with pytest.raises(SimulationError, match="trial 1 failed"):
            run_trials(trial, 4, nthread)
