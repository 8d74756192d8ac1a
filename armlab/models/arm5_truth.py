"""Ground truth of the seated 5-DoF arm (seed paper 001), computed from the compiled model.

- The intrinsic 5 x 5 joint stiffness K_q and damping D_q at a working point with activations frozen
  (central finite differences, :func:`armlab.models.ground_truth.impedance_fd`) and, for the linear
  muscles of ``models/arm_5dof``, its analytic form K_q = sum_i a_i k_i r_i r_i^T + K_passive.
- The static gravity torque G(q) (the joint torque that holds the arm still, Eq. (14)'s
  Gamma(q, xi_red)) and the gravitational stiffness dG/dq.
- The reduced inertial parameters xi_red (Eq. (22)): masses and first moments, as the
  combinations a static base-wrench regression identifies (:class:`InertialTruth`).
- The true joint centres and their offsets in the marker frames (Eqs. (7)-(8)).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.errors import DataError, ModelError
from armlab.models.arm_5dof import Arm5Dof, limb_kinematics
from armlab.models.ground_truth import impedance_fd

__all__ = [
    "XI_RED_NAMES",
    "InertialTruth",
    "JointCentreTruth",
    "analytic_damping",
    "analytic_stiffness",
    "gravity_stiffness",
    "gravity_torque",
    "inertial_truth",
    "joint_centre_truth",
    "stiffness_fd",
]

_FD_EPS_G = 1e-6  # rad: central-difference step for dG/dq (ENGINE_NOTES: eps ~ 1e-6)
# Names of the identifiable combinations (Eq. (22)), in the order of InertialTruth.xi_red.
XI_RED_NAMES = ("m_total", "c_x", "c_y", "u_x", "u_y", "u_z", "s_x", "s_y", "s_z")


def _check_act(arm: Arm5Dof, act: np.ndarray) -> np.ndarray:
    act = np.asarray(act, dtype=float)
    if act.shape[-1:] != (len(arm.muscle_act),):
        raise DataError(
            f"act must have shape (..., {len(arm.muscle_act)}) (one activation per muscle), got {act.shape}"
        )
    return act


def analytic_stiffness(arm: Arm5Dof, act: np.ndarray) -> np.ndarray:
    """K_q = sum_i a_i k_i r_i r_i^T + K_passive of the linear muscles, (..., 5, 5) N·m/rad.

    Args:
        act: (..., 12) activations in ``ARM5_MUSCLES`` order.
    """
    w = _check_act(arm, act) * arm.muscle_stiffness
    return np.einsum("...i,ij,ik->...jk", w, arm.moment_arms, arm.moment_arms) + np.diag(
        arm.passive_stiffness
    )


def analytic_damping(arm: Arm5Dof, act: np.ndarray) -> np.ndarray:
    """D_q = sum_i a_i b_i r_i r_i^T + D_passive, (..., 5, 5) N·m·s/rad."""
    w = _check_act(arm, act) * arm.muscle_damping
    return np.einsum("...i,ij,ik->...jk", w, arm.moment_arms, arm.moment_arms) + np.diag(arm.passive_damping)


def stiffness_fd(arm: Arm5Dof, q: np.ndarray, act: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Intrinsic (K_q (5, 5) N·m/rad, D_q (5, 5) N·m·s/rad) by finite differences at posture ``q``
    (5,) rad, zero velocity and frozen activations ``act`` (12,) (the reflex acts through
    activation, so it is excluded)."""
    data = arm.data_at(q, _check_act(arm, act))
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(arm.model, spec))
    mujoco.mj_getState(arm.model, data, state, spec)
    return impedance_fd(arm.model, state, arm.qpos, arm.dof)


def gravity_torque(arm: Arm5Dof, q: np.ndarray) -> np.ndarray:
    """G(q): the joint torque (..., 5) N·m that holds the arm still at ``q`` (..., 5) rad (MuJoCo's
    bias force at zero velocity; positive along each hinge axis)."""
    q = np.asarray(q, dtype=float)
    flat = q.reshape(-1, 5)
    data = mujoco.MjData(arm.model)
    out = np.empty_like(flat)
    for i, qi in enumerate(flat):  # one MuJoCo forward pass per posture (no batched bias call)
        data.qpos[arm.qpos] = qi
        data.qvel[:] = 0.0
        mujoco.mj_forward(arm.model, data)
        out[i] = data.qfrc_bias[arm.dof]
    return out.reshape(q.shape)


def gravity_stiffness(arm: Arm5Dof, q: np.ndarray) -> np.ndarray:
    """dG/dq (5, 5) N·m/rad at ``q`` (5,) rad by central differences (symmetric: the Hessian of the
    potential energy). With the restoring-sign K_q of Eq. (4), ignoring G in Eq. (14) shifts the
    estimate by +dG/dq."""
    q = np.asarray(q, dtype=float)
    steps = np.eye(5) * _FD_EPS_G
    g = gravity_torque(arm, np.concatenate([q + steps, q - steps]))
    return ((g[:5] - g[5:]) / (2 * _FD_EPS_G)).T


@dataclass(frozen=True, kw_only=True, eq=False)
class InertialTruth:
    """Reduced inertial parameters of the seat subtree (Eq. (22)), relative to the base F/T site.

    The first moment of everything the base sensor carries is
    S(q) = c + R_u(q) u + R_f(q) s (kg·m, world axes, origin at the sensor), where R_u, R_f are the
    upper-arm and forearm orientations; a static base wrench sees m_total (through F_z) and the
    horizontal components of S(q) (through M_x, M_y); c_z is not identifiable.

    Attributes:
        xi_red: (9,) in :data:`XI_RED_NAMES` order: m_total kg; c_x, c_y kg·m (fixed bodies plus
            the arm's mass at the shoulder); u (3,) kg·m = m_u c_u + m_f l_u (upper-arm frame, about
            the shoulder); s (3,) kg·m = m_f c_f (forearm frame, about the elbow).
        masses: (3,) kg of (fixed bodies, upper arm, forearm); first_moments: (3, 3) kg·m of the
            same about (sensor [world axes], shoulder [upper-arm frame], elbow [forearm frame]).
    """

    xi_red: np.ndarray
    masses: np.ndarray
    first_moments: np.ndarray


def inertial_truth(arm: Arm5Dof) -> InertialTruth:
    """Masses, first moments and the identifiable combinations of :class:`InertialTruth`."""
    m = arm.model
    kin = limb_kinematics(arm)
    data = mujoco.MjData(m)
    mujoco.mj_kinematics(m, data)
    joints = m.dof_jntid[arm.dof]
    upper, forearm = int(m.jnt_bodyid[joints[0]]), int(m.jnt_bodyid[joints[3]])
    site = arm.sites["base_ft"]
    seat = int(m.site_bodyid[site])
    p_s = data.site_xpos[site]
    sub = [b for b in range(m.nbody) if b != 0 and _in_subtree(m, b, seat)]
    fixed = [b for b in sub if not _in_subtree(m, b, upper)]
    moving = [b for b in sub if _in_subtree(m, b, upper)]
    if sorted(moving) != sorted([upper, forearm]):
        raise ModelError("arm_5dof: the arm must be exactly two bodies (upper arm, forearm)")
    m_fix = float(m.body_mass[fixed].sum())
    s_fix = (m.body_mass[fixed, None] * (data.xipos[fixed] - p_s)).sum(axis=0)
    m_u, m_f = float(m.body_mass[upper]), float(m.body_mass[forearm])
    s_u = m_u * m.body_ipos[upper]
    s_f = m_f * m.body_ipos[forearm]
    c = s_fix + (m_u + m_f) * (kin.shoulder - p_s)
    u = s_u + m_f * kin.elbow_offset
    xi = np.concatenate([[m_fix + m_u + m_f], c[:2], u, s_f])
    return InertialTruth(
        xi_red=xi, masses=np.array([m_fix, m_u, m_f]), first_moments=np.stack([s_fix, s_u, s_f])
    )


def _in_subtree(m: mujoco.MjModel, body: int, root: int) -> bool:
    while body != 0:
        if body == root:
            return True
        body = int(m.body_parentid[body])
    return root == 0


@dataclass(frozen=True, kw_only=True, eq=False)
class JointCentreTruth:
    """True joint centres and their offsets d_k in the adjacent marker frames (Eqs. (7)-(8)).

    Attributes:
        shoulder: (3,) m (world; the torso is belted, so it is fixed).
        elbow: (..., 3) m (world) at the postures asked for.
        d_shoulder: (2, 3) m, the shoulder centre in the torso and upper-arm marker frames.
        d_elbow: (2, 3) m, the elbow centre in the upper-arm and forearm marker frames.
    """

    shoulder: np.ndarray
    elbow: np.ndarray
    d_shoulder: np.ndarray
    d_elbow: np.ndarray


def joint_centre_truth(arm: Arm5Dof, q: np.ndarray) -> JointCentreTruth:
    """True joint centres at postures ``q`` (..., 5) rad and their marker-frame offsets."""
    m = arm.model
    data = mujoco.MjData(m)
    mujoco.mj_kinematics(m, data)

    def local(point: np.ndarray, site: str) -> np.ndarray:
        s = arm.sites[site]
        return data.site_xmat[s].reshape(3, 3).T @ (point - data.site_xpos[s])

    sh = data.site_xpos[arm.sites["shoulder_centre"]].copy()
    el = data.site_xpos[arm.sites["elbow_centre"]].copy()
    return JointCentreTruth(
        shoulder=sh,
        elbow=limb_kinematics(arm).pose(q).elbow,
        d_shoulder=np.stack([local(sh, "torso_marker"), local(sh, "upper_arm_marker")]),
        d_elbow=np.stack([local(el, "upper_arm_marker"), local(el, "forearm_marker")]),
    )
