"""The work between two reflex chunks of :func:`armlab.sim.rollout.simulate`, compiled (numba).

Between chunks the lab writes the next chunk's controls (robot targets gathered from the paths
table, muscle commands from the delayed stretch) and files the stepped chunk (its muscle lengths
and velocities into the reflex history, a check that every state stays finite and on the clock).
In NumPy that was about 0.6 CPU-s of temporaries for the default conditioning run (780 trials,
25 chunks), taken from the two cores MuJoCo steps on; these loops write each value once, without
the GIL.

The arithmetic is :func:`armlab.sim.rollout.reflex_command`'s, term by term and in its order,
without fast-math, so the commands are bit-identical to it (tests/test_rollout.py compares the
pipelined simulation with a plain NumPy loop bit for bit).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["first_bad_step", "load", "muscle_commands", "robot_targets", "store_history"]


@njit(nogil=True, cache=True)
def robot_targets(ctrl: np.ndarray, cols: np.ndarray, table: np.ndarray, rows: np.ndarray, c0: int) -> None:
    """``ctrl[i, s, cols[a]] = table[rows[i], c0 + s, a]`` for every trial i, step s of the chunk and
    robot actuator a (``ctrl`` (n, m, nu); ``table`` (n_paths, n_steps, 7))."""
    for i in range(ctrl.shape[0]):
        r = rows[i]
        for s in range(ctrl.shape[1]):
            for a in range(cols.size):
                ctrl[i, s, cols[a]] = table[r, c0 + s, a]


@njit(nogil=True, cache=True)
def muscle_commands(
    ctrl: np.ndarray,
    cols: np.ndarray,
    base: np.ndarray,
    hold: int,
    c0: int,
    hist: np.ndarray,
    lag_s: int,
    lag_sp: int,
    ref: np.ndarray,
    scale: float,
    stretch_gain: float,
    velocity_gain: float,
    spinal_gain: float,
) -> None:
    """The reflex commands of chunk [c0, c0 + m) into ``ctrl[:, :, cols]``.

    ``base``: (1 or n, 1 or ceil(n_steps / hold), n_muscles) commands without reflex (one row / one
    step broadcast), each row held over ``hold`` physics steps (step t reads row t // hold).
    ``hist``: (n, h, 2 n_muscles) ring of the muscle lengths then velocities of the last ``h`` >=
    ``lag_sp`` steps stepped (step j in row j % h, :func:`store_history`); a lagged
    index before step 0 reads the steady state (length ``ref``, velocity 0).

    The command is ``clip(base + g_s [stretch]_+ + g_v [rate]_+ + g_sp [spinal stretch]_+, 0, 1)``;
    stretch and rate are read ``lag_s`` steps back, spinal stretch ``lag_sp`` steps back, each
    normalised by ``scale`` (m).
    """
    nm = cols.size
    h = hist.shape[1]
    per_trial = base.shape[0] > 1
    per_step = base.shape[1] > 1
    for i in range(ctrl.shape[0]):
        bi = i if per_trial else 0
        for s in range(ctrl.shape[1]):
            t = c0 + s
            bs = t // hold if per_step else 0
            j1 = t - lag_s
            j2 = t - lag_sp
            for k in range(nm):
                if j1 >= 0:
                    length = hist[i, j1 % h, k]
                    velocity = hist[i, j1 % h, nm + k]
                else:
                    length = ref[k]
                    velocity = 0.0
                length_sp = hist[i, j2 % h, k] if j2 >= 0 else ref[k]
                stretch = (length - ref[k]) / scale
                rate = velocity / scale
                stretch_sp = (length_sp - ref[k]) / scale
                u = (
                    base[bi, bs, k]
                    + stretch_gain * max(stretch, 0.0)
                    + velocity_gain * max(rate, 0.0)
                    + spinal_gain * max(stretch_sp, 0.0)
                )
                ctrl[i, s, cols[k]] = min(max(u, 0.0), 1.0)


@njit(nogil=True, cache=True)
def store_history(hist: np.ndarray, sd: np.ndarray, cols: np.ndarray, c0: int) -> None:
    """Sensor columns ``cols`` of the chunk's sensordata ``sd`` (n, m, nsd), step c0 + s, into row
    (c0 + s) % h of the ring ``hist`` (n, h, cols.size)."""
    h = hist.shape[1]
    for i in range(sd.shape[0]):
        for s in range(sd.shape[1]):
            row = (c0 + s) % h
            for k in range(cols.size):
                hist[i, row, k] = sd[i, s, cols[k]]


@njit(nogil=True, cache=True)
def first_bad_step(time_in: np.ndarray, states: np.ndarray, dt: float) -> int:
    """``i * m + s`` of the first trial i (then step s) whose state after step s is not finite or
    whose clock (column 0) is not ``time_in[i] + (s + 1) dt`` within dt/2 (MuJoCo reset it); -1
    when every state is sound. ``states``: (n, m, nstate)."""
    n, m, k = states.shape
    for i in range(n):
        for s in range(m):
            if abs(states[i, s, 0] - (time_in[i] + dt * (s + 1))) > 0.5 * dt:
                return i * m + s
            for c in range(k):
                if not np.isfinite(states[i, s, c]):
                    return i * m + s
    return -1


def load() -> None:
    """Load every kernel, for the argument types and layouts :func:`armlab.sim.rollout.simulate`
    passes, from numba's cache (compiled there on a first use), by calling each on one tiny chunk."""
    ctrl, ring = np.zeros((1, 1, 2)), np.zeros((1, 2, 2))
    one = np.zeros(1, dtype=np.intp)
    robot_targets(ctrl, one, np.zeros((1, 1, 1)), one, 0)
    muscle_commands(ctrl, one, np.zeros((1, 1, 1)), 1, 0, ring, 1, 1, np.zeros(1), 1.0, 0.0, 0.0, 0.0)
    store_history(ring, np.zeros((1, 1, 2)), np.arange(2, dtype=np.intp), 0)
    first_bad_step(np.ones(1), np.ones((1, 1, 2)), 1.0)
