"""Level B of paper 002 stepped in compiled code: the human's field before every MuJoCo step.

The field of Eqs. 2.2.1-2.2.4 (thesis Ch. 3) depends nonlinearly on the hand's state, so it is
recomputed from each trial's ``qpos``/``qvel`` before every physics step and written as the
control of the hand's two force motors (:mod:`armlab.sim.cartesian_level_b`). Here that loop runs
in one numba kernel per thread over a batch of ``MjData`` (one per trial): the kernel reads and
writes each trial's ``qpos``, ``qvel``, ``ctrl`` and ``sensordata`` through their addresses and
calls MuJoCo's own ``mj_step`` from its shared library, without the GIL and without a Python call
per step. Each trial runs from its start to its end inside the kernel (the trials do not
interact), so a trial's result does not depend on the number of threads or on its neighbours.

The field's arithmetic is :meth:`~armlab.models.cartesian_field.QuadraticImpedanceField.force`'s,
term by term and in its order, without fast-math, so the commanded forces equal NumPy's bit for
bit (tests/test_cartesian_level_b.py steps the same trials by a per-step Python reference).
"""

from __future__ import annotations

import numpy as np
from numba import carray, njit

from armlab.sim._mujoco_calls import call, f64_pointer

__all__ = [
    "NEGATIVE_STIFFNESS",
    "NON_FINITE",
    "load",
    "step_trials",
]

#: status codes of :func:`step_trials` per trial (0: stepped to the end)
NEGATIVE_STIFFNESS = 1
NON_FINITE = 2


@njit(nogil=True, cache=True)
def _field(x: float, y: float, v: float, p: float, c: np.ndarray, kc: float, sigma: float, delta: float):
    """One axis of the human's force, ``-(δ√K·v + K·p)`` with ``K`` of Eq. 2.2.4, summed as
    :meth:`~armlab.models.cartesian_field.QuadraticImpedanceField.stiffness` sums it
    (``0 + b_0 c_0 + ... + b_5 c_5 + σ k_σ``). Returns ``(force N, K N/m)``."""
    k = 0.0 + 1.0 * c[0]
    k = k + x * c[1]
    k = k + y * c[2]
    k = k + (x * x) * c[3]
    k = k + (2.0 * x * y) * c[4]
    k = k + (y * y) * c[5]
    k = k + sigma * kc
    return -(delta * np.sqrt(k) * v + k * p), k


@njit(nogil=True, cache=True)
def step_trials(
    step_fn: int,
    model: int,
    data: np.ndarray,
    addr: np.ndarray,
    rows: np.ndarray,
    idx: np.ndarray,
    sensor_cols: np.ndarray,
    robot_qpos: np.ndarray,
    robot_act: np.ndarray,
    ref: np.ndarray,
    coef: np.ndarray,
    k_sigma: np.ndarray,
    sigma: float,
    delta: np.ndarray,
    q0: np.ndarray,
    targets: np.ndarray,
    n_settle: int,
    substeps: int,
    out_pos: np.ndarray,
    out_vel: np.ndarray,
    out_q: np.ndarray,
    out_sensor: np.ndarray,
    out_field: np.ndarray,
    status: np.ndarray,
) -> None:
    """Step trials ``rows`` from their initial state (set by the caller) through their perturbation.

    Before every physics step the human's force ``F = -(K(q_h)·(q_h - q_r) + δ√K(q_h)·q̇_h)``
    (Eqs. 2.2.1, 2.2.2, 2.2.4) of trial ``i`` is written to its field motors and the robot's
    servo targets to the sample being moved to (``q0`` while settling); then ``mj_step``. Sample
    ``j`` is the state at the start of step ``n_settle + j·substeps`` and the sensors of that step.

    Args:
        step_fn, model: addresses of ``mj_step`` and of the ``mjModel``.
        data: (n,) int64 ``mjData`` addresses, one per trial.
        addr: (n, 4) int64 addresses of each trial's ``qpos``, ``qvel``, ``ctrl``, ``sensordata``.
        rows: (r,) int64, the trials this call steps.
        idx: (10,) int64: hand x, y qpos addresses; hand x, y dof addresses; field motor x, y
            actuator ids; nq, nv, nu, nsensordata.
        sensor_cols: (k,) int64, the ``sensordata`` entries recorded.
        robot_qpos, robot_act: (7,) int64 robot joint qpos addresses and servo actuator ids.
        ref: (n, 2) m stop positions ``q_r``; coef: (2, 6) N/m per power of m (Eq. 2.2.4, times
            ``stiffness_scale``); k_sigma: (2,) N/m, ``k_σ·stiffness_scale``; sigma: σ in [0, 1];
            delta: (2,) √kg.
        q0: (n, 7) rad servo targets at the stop; targets: (n, n_s, 7) rad, per sample.
        n_settle: steps before the perturbation; substeps: physics steps per sample.
        out_pos, out_vel: (n, n_s, 2) m, m/s; out_q: (n, n_s, 7) rad; out_sensor: (n, n_s, k);
            out_field: (n, n_s, 2) N: filled for ``rows``.
        status: (n,) int64, set for ``rows`` to 0 (stepped to the end), :data:`NEGATIVE_STIFFNESS`
            or :data:`NON_FINITE` (the trial stops there).
    """
    n_s = targets.shape[1]
    n_robot = robot_qpos.size
    for i in rows:
        qpos = carray(f64_pointer(addr[i, 0]), (idx[6],))
        qvel = carray(f64_pointer(addr[i, 1]), (idx[7],))
        ctrl = carray(f64_pointer(addr[i, 2]), (idx[8],))
        sd = carray(f64_pointer(addr[i, 3]), (idx[9],))
        status[i] = 0
        for step in range(n_settle + n_s * substeps):
            x, y = qpos[idx[0]], qpos[idx[1]]
            vx, vy = qvel[idx[2]], qvel[idx[3]]
            fx, kx = _field(x, y, vx, x - ref[i, 0], coef[0], k_sigma[0], sigma, delta[0])
            fy, ky = _field(x, y, vy, y - ref[i, 1], coef[1], k_sigma[1], sigma, delta[1])
            if kx < 0.0 or ky < 0.0:
                status[i] = NEGATIVE_STIFFNESS
                break
            if not (np.isfinite(fx) and np.isfinite(fy)):
                status[i] = NON_FINITE
                break
            ctrl[idx[4]] = fx
            ctrl[idx[5]] = fy
            k_rel = step - n_settle
            if k_rel >= 0:  # servo target: the sample being moved to (held at the last one)
                s_next = min(k_rel // substeps + 1, n_s - 1)
                for a in range(n_robot):
                    ctrl[robot_act[a]] = targets[i, s_next, a]
            else:
                for a in range(n_robot):
                    ctrl[robot_act[a]] = q0[i, a]
            sample = k_rel // substeps if k_rel >= 0 and k_rel % substeps == 0 else -1
            if sample >= 0:
                out_pos[i, sample, 0] = x
                out_pos[i, sample, 1] = y
                out_vel[i, sample, 0] = vx
                out_vel[i, sample, 1] = vy
                for a in range(n_robot):
                    out_q[i, sample, a] = qpos[robot_qpos[a]]
                out_field[i, sample, 0] = fx
                out_field[i, sample, 1] = fy
            call(step_fn, model, data[i])
            if sample >= 0:
                for c in range(sensor_cols.size):
                    out_sensor[i, sample, c] = sd[sensor_cols[c]]


def load() -> None:
    """Load :func:`step_trials` from numba's cache (compiled there on a first use) by stepping
    nothing: an empty batch with the real argument types."""
    z2, z3, zi = np.zeros((0, 2)), np.zeros((0, 1, 2)), np.zeros(0, dtype=np.int64)
    step_trials(
        0, 0, zi, np.zeros((0, 4), dtype=np.int64), zi, np.zeros(10, dtype=np.int64), zi, zi, zi,
        z2, np.zeros((2, 6)), np.zeros(2), 0.0, np.zeros(2), np.zeros((0, 7)),
        np.zeros((0, 1, 7)), 0, 1, z3, z3, np.zeros((0, 1, 7)), z3, z3, zi,
    )  # fmt: skip
