"""A delayed stretch reflex for the 5-DoF arm's muscles (seed paper 001, spec check 7).

The paper's model (Eq. (14)) freezes activation; a real arm answers a held stretch with a reflex,
so a static estimate measures an *effective* stiffness above the intrinsic one. The reflex law is
the conditioning lab's (:func:`armlab.sim.rollout.reflex_command`, paper 000 Sec. II-B, its gains
and latencies in :class:`armlab.config.schema.ReflexConfig`): each muscle's command is its
held activation plus the gains times its lengthening (and lengthening rate), read a latency
earlier, normalised by :data:`armlab.sim.rollout.REFLEX_LENGTH_SCALE_M`, half-wave rectified and
clipped to [0, 1]. The compiled chunk kernels of :mod:`armlab.sim._chunk_kernel` compute it
between rollout chunks no longer than the shortest latency (exact, no per-step Python).

The 5-DoF arm's muscles run on fixed tendons: a muscle's lengthening is R (q - q_ref) with R the
constant (12, 5) length Jacobian, and its rate R q̇; so the reflex's history is built from the
state's joint angles and velocities (no length sensors needed).

Effective truth (:func:`reflex_stiffness_fd`): the static part of the reflex (velocity zero, the
stretch and spinal pathways settled) adds to the joint torque tau_r(q) = tau_m(q, a(q)) -
tau_m(q, a0) with a(q) = clip(a0 + (g_s + g_sp) [R (q - q_ref)]_+ / L_s, 0, 1). That torque is not
linear in the displacement: half-wave rectified, and the extra activation pulls with the force of
the stretched length (a k ΔL on top of T0, ~16 % more at 0.08 rad here: quadratic in the
displacement). So the effective stiffness is the secant the paper's protocol measures: the
central difference over the perturbation's own amplitude, ±A along each joint, which is the
average of the two one-sided secants that the static estimate of Eq. (15) fits from displacements
of equal size both ways (an infinitesimal step would give the tangent, 15-25 % below the measured
secant here).
"""

from __future__ import annotations

import mujoco
import numpy as np

from armlab.config.schema import ReflexConfig
from armlab.sim.rollout import REFLEX_LENGTH_SCALE_M

__all__ = [
    "muscle_length_jacobian",
    "reflex_history",
    "reflex_stiffness_fd",
]

_FD_EPS = 1e-6  # rad: central-difference step (ENGINE_NOTES: eps ~ 1e-6; the law is piecewise linear)


def muscle_length_jacobian(
    model: mujoco.MjModel, muscle_act: np.ndarray, qpos_adr: np.ndarray, q: np.ndarray
) -> np.ndarray:
    """R = dL/dq (n_muscles, 5) m/rad of the muscles ``muscle_act`` (actuator ids) in the joints at
    ``qpos_adr``, by central differences of MuJoCo's ``actuator_length`` at ``q`` (5,) rad (exact
    for fixed tendons: lengths are linear in q)."""
    data = mujoco.MjData(model)
    cols = []
    for j in range(len(qpos_adr)):
        lengths = []
        for sign in (1.0, -1.0):
            data.qpos[:] = model.qpos0
            data.qpos[qpos_adr] = q
            data.qpos[qpos_adr[j]] += sign * _FD_EPS
            mujoco.mj_fwdPosition(model, data)
            lengths.append(data.actuator_length[muscle_act].copy())
        cols.append((lengths[0] - lengths[1]) / (2 * _FD_EPS))
    return np.stack(cols, axis=1)


def reflex_history(
    hist: np.ndarray,
    states: np.ndarray,
    c0: int,
    q_cols: np.ndarray,
    qd_cols: np.ndarray,
    q_ref: np.ndarray,
    R: np.ndarray,
) -> None:
    """File a stepped chunk into the reflex ring ``hist`` (n, h, 2 n_muscles) as
    :func:`armlab.sim._chunk_kernel.store_history` would from length sensors: step c0 + s in row
    (c0 + s) % h, the muscles' lengthening R (q - q_ref) m then its rate R q̇ m/s.

    Args:
        states: (n, m, nstate) full-physics states of the chunk; q_cols, qd_cols: the arm's
            joint angles' and velocities' columns in them.
        q_ref: (n, 5) rad each trial's reference posture (its state at the onset's hold).
        R: (n_muscles, 5) m/rad from :func:`muscle_length_jacobian`.
    """
    nm = R.shape[0]
    rows = (c0 + np.arange(states.shape[1])) % hist.shape[1]
    hist[:, rows, :nm] = (states[:, :, q_cols] - q_ref[:, None, :]) @ R.T
    hist[:, rows, nm:] = states[:, :, qd_cols] @ R.T


def reflex_stiffness_fd(
    model: mujoco.MjModel,
    muscle_act: np.ndarray,
    muscle_actadr: np.ndarray,
    qpos_adr: np.ndarray,
    dof_adr: np.ndarray,
    q: np.ndarray,
    act: np.ndarray,
    reflex: ReflexConfig,
    step_rad: float,
) -> np.ndarray:
    """The static reflex's joint stiffness (5, 5) N·m/rad at the held posture ``q`` (5,) rad with
    held activations ``act`` (n_muscles,), restoring sign: the secant over ``step_rad`` (the
    perturbation amplitude, rad) both ways along each joint (module docstring); zero when the
    reflex is off. Add it to the intrinsic K_q (linear: its tangent is its secant) for the
    effective truth."""
    if not reflex.enabled:
        return np.zeros((len(dof_adr), len(dof_adr)))
    R = muscle_length_jacobian(model, muscle_act, qpos_adr, q)
    gain = (reflex.stretch_gain + reflex.spinal_gain) / REFLEX_LENGTH_SCALE_M
    data = mujoco.MjData(model)

    def reflex_torque(qi: np.ndarray) -> np.ndarray:
        out = []
        for a in (np.clip(act + gain * np.maximum(R @ (qi - q), 0.0), 0.0, 1.0), act):
            data.qpos[:] = model.qpos0
            data.qpos[qpos_adr] = qi
            data.qvel[:] = 0.0
            data.act[muscle_actadr] = a
            mujoco.mj_forward(model, data)
            out.append(data.qfrc_actuator[dof_adr].copy())
        return out[0] - out[1]

    steps = np.eye(len(qpos_adr)) * step_rad
    cols = [-(reflex_torque(q + e) - reflex_torque(q - e)) / (2 * step_rad) for e in steps]
    return np.stack(cols, axis=1)
