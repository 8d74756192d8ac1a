"""Trials stepped from Python, run concurrently on threads (one MjData and one RNG each).

A closed loop that reads MuJoCo's state every control period (:mod:`armlab.sim.force_control`)
calls ``mujoco.mj_step`` from Python; MuJoCo releases Python's GIL inside ``mj_step`` (checked on
mujoco 3.17: a Python thread keeps running during a long ``mj_step`` call of another), so while
one trial's physics steps, another trial's controller runs, and trials use every core as
``mujoco.rollout`` does. Each trial owns its data and random generator, so the results are
bit-identical to a serial loop at any thread count; a failure raises the error of the
lowest-index failing trial, the one a serial loop would have raised.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

from armlab.cpus import usable_cpus

__all__ = ["run_trials"]

T = TypeVar("T")


def run_trials(
    simulate: Callable[[int], T],
    n_trials: int,
    nthread: int | None = None,
    done: Callable[[], None] | None = None,
) -> list[T]:
    """``[simulate(0), ..., simulate(n_trials - 1)]``, computed on up to ``nthread`` threads.

    Args:
        simulate: one trial by its index; it must not share mutable state with another trial.
        n_trials: how many trials.
        nthread: threads (default: the CPU count; 1 runs the trials in order on this thread).
        done: called on this thread as each trial's result is taken, in trial order (e.g.
            ``armlab.progress.advance``: the progress sink is this thread's context).

    Raises:
        Whatever ``simulate`` raised for the lowest failing index; trials after it that had not
        started are not run.
    """
    nthread = min(nthread or usable_cpus(), n_trials)
    tick = done or (lambda: None)
    if nthread <= 1:
        out = []
        for i in range(n_trials):
            out.append(simulate(i))
            tick()
        return out
    with ThreadPoolExecutor(max_workers=nthread, thread_name_prefix="armlab-trial") as pool:
        futures = [pool.submit(simulate, i) for i in range(n_trials)]
        out = []
        try:
            for fut in futures:  # in trial order: an earlier trial's error is raised first
                out.append(fut.result())
                tick()
        except BaseException:
            for fut in futures:
                fut.cancel()  # those not started; running ones finish before the pool closes
            raise
    return out
