"""Level C of paper 002's Cartesian protocol: the planar Hill arm's force on the handle as the truth.

The robot plays the thesis's stops and perturbations (an ideal position source, as in the
thesis and level A) on the hand of the conditioning lab's planar Hill arm
(:mod:`armlab.models.hill_arm_field`). At every logged sample the robot's force on the hand is
the arm's quasi-static restoring force (no inertia: the thesis's model has none),

    F(t) = −J(q)^-T · (τ(q, q̇) − τ(q_r, 0)),   q = IK(q_h), q̇ = J(q)^-1 q̇_h,

``τ`` the muscles' joint torques at frozen activation evaluated by MuJoCo for the whole batch in
compiled code (:func:`armlab.sim._mujoco_calls.joint_forces`), ``q_r`` the posture of the stop.
The sign is level A's: the force the robot applies, ``+K q_p`` for a small displacement.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError
from armlab.models.hill_arm_field import HillArm
from armlab.perturbations.cartesian_timeline import StopTimeline
from armlab.sim._mujoco_calls import joint_forces

__all__ = [
    "LevelCRecord",
    "hill_arm_force",
    "simulate_level_c",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class LevelCRecord:
    """What :func:`simulate_level_c` produced.

    Attributes:
        timeline: the stops and perturbations played (q_h = q_r + q_p: the robot is ideal).
        force: (n, 2) N, the robot's force on the hand with noise; zero where nothing is logged.
        force_clean: (n, 2) N, without noise.
        k_true, d_true: (n_stops, 2, 2) N/m, N·s/m, the arm's Cartesian impedance at each stop
            (:meth:`~armlab.models.hill_arm_field.HillArm.cartesian_impedance`).
        noise_std_n: N, std of the white force noise added per axis.
    """

    timeline: StopTimeline
    force: np.ndarray
    force_clean: np.ndarray
    k_true: np.ndarray
    d_true: np.ndarray
    noise_std_n: float

    def stiffness_true(self) -> np.ndarray:
        """(n, 4) N/m: the true K at each sample's stop, flattened (xx, xy, yx, yy); NaN where the
        path moves (no stop)."""
        out = np.full((len(self.timeline.t), 4), np.nan)
        at = self.timeline.stop >= 0
        out[at] = self.k_true[self.timeline.stop[at]].reshape(-1, 4)
        return out

    @property
    def logged(self) -> np.ndarray:
        """(n,) bool: samples logged (during a perturbation, thesis §3.2.2)."""
        return self.timeline.perturbation >= 0


def hill_arm_force(arm: HillArm, q_h: np.ndarray, qd_h: np.ndarray, q_r: np.ndarray) -> np.ndarray:
    """The robot's force on the hand of ``arm`` (module docstring), for a batch of samples.

    Args:
        q_h: (n, 2) m, hand positions; qd_h: (n, 2) m/s, hand velocities; q_r: (n, 2) m, the
            reference each sample's subject holds.

    Returns:
        (n, 2) N.
    """
    sc = arm.scene
    q, q_ref = arm.joint_angles(q_h), arm.joint_angles(q_r)
    jac = arm.jacobian(q)
    qd = np.linalg.solve(jac, np.asarray(qd_h, float)[..., None])[..., 0]
    data = arm.frozen_data()
    tau = joint_forces(sc.model, data, sc.arm_qpos, sc.arm_dof, q, qd)
    # the references are a few stop points held over many samples: each distinct one once (every
    # row is computed alone, so the values are those of a call on all rows)
    refs, which = np.unique(q_ref, axis=0, return_inverse=True)
    tau_ref = joint_forces(sc.model, data, sc.arm_qpos, sc.arm_dof, refs, np.zeros_like(refs))
    tau_ref = tau_ref[which.reshape(-1)]
    # static balance of the massless arm: τ_net + Jᵀ F_robot = 0
    return -np.linalg.solve(np.swapaxes(jac, -1, -2), (tau - tau_ref)[..., None])[..., 0]


def simulate_level_c(
    arm: HillArm,
    timeline: StopTimeline,
    *,
    noise_std_n: float = 0.0,
    rng: np.random.Generator | None = None,
) -> LevelCRecord:
    """The Hill arm's forces on the logged samples of ``timeline`` (module docstring).

    Args:
        arm: the arm (:func:`~armlab.models.hill_arm_field.build_hill_arm`).
        timeline: stops and perturbations on a path within the arm's reach (m, arm frame).
        noise_std_n: N, white force noise per axis (0: none).
        rng: the noise's generator (required when ``noise_std_n > 0``).

    Raises:
        ConfigError: noise without a generator, or a point outside the arm's reach.
    """
    if noise_std_n < 0 or (noise_std_n > 0 and rng is None):
        raise ConfigError("noise_std_n must be >= 0 N, and a positive one needs rng (numpy Generator)")
    logged = timeline.perturbation >= 0
    clean = np.zeros((len(timeline.t), 2))
    clean[logged] = hill_arm_force(arm, timeline.q_h[logged], timeline.qd_h[logged], timeline.q_r[logged])
    force = clean.copy()
    if noise_std_n > 0:
        force[logged] += noise_std_n * rng.standard_normal((int(logged.sum()), 2))
    k, d = arm.cartesian_impedance(timeline.stop_position)
    return LevelCRecord(
        timeline=timeline, force=force, force_clean=clean, k_true=k, d_true=d, noise_std_n=float(noise_std_n)
    )
