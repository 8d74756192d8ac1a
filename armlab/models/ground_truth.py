"""Ground truth of the simulated arm, computed from the compiled model (never from the config).

- Intrinsic joint stiffness K and damping D (n x n; 2 x 2 for the planar arm) at the operating
  point: central finite differences of the arm's actuator + passive joint forces with respect to
  the arm's joint positions and velocities, with muscle activations frozen (``mj_forward`` does not integrate
  ``act``). Reflexes are excluded by construction: they act through activation.
- Base inertial parameters xi of eq. (13) of the conditioning paper from the body inertias of
  the arm and the bodies welded to it (the cuff shell, with its own inertia), plus, for a rigid
  cuff, the robot-side bodies beyond the force sensor as point masses at the hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.errors import ModelError
from armlab.models.scene import Scene, named_id

__all__ = [
    "GroundTruth",
    "base_inertial_parameters",
    "ground_truth",
    "impedance_fd",
    "joint_impedance",
]

_FD_EPS = 1e-6  # rad, rad/s; central differences (ENGINE_NOTES: eps ~ 1e-6)


@dataclass(frozen=True, kw_only=True, eq=False)
class GroundTruth:
    """Ground truth at the operating point.

    Attributes:
        K: (2, 2) N·m/rad intrinsic joint stiffness, restoring sign (tau = -K dq).
        D: (2, 2) N·m·s/rad intrinsic joint damping.
        xi: (3,) kg·m² base inertial parameters, eq. (13) of the conditioning paper.
        q_op: (2,) rad the operating point (settled posture).
    """

    K: np.ndarray
    D: np.ndarray
    xi: np.ndarray
    q_op: np.ndarray

    def as_dict(self) -> dict:
        return {
            "K": self.K.tolist(),
            "D": self.D.tolist(),
            "xi": self.xi.tolist(),
            "q_op": self.q_op.tolist(),
        }


def impedance_fd(
    model: mujoco.MjModel, state: np.ndarray, qpos_idx: np.ndarray, dof_idx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Intrinsic n x n stiffness and damping of the joints ``dof_idx`` at a full-physics ``state``.

    Central differences (step ``_FD_EPS``) of the actuator + passive joint forces with respect to
    the joints' positions (``qpos_idx``, hinges/slides) and velocities, activations frozen
    (``mj_forward`` does not integrate ``act``; reflexes act through activation, so they are
    excluded by construction).

    Returns:
        (K (n, n), D (n, n)), restoring sign (tau = -K dq - D dqd), in the joints' units
        (N·m/rad, N·m·s/rad for hinges).
    """
    qpos_idx = np.asarray(qpos_idx)
    dof_idx = np.asarray(dof_idx)
    n = len(dof_idx)
    data = mujoco.MjData(model)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    mujoco.mj_setState(model, data, np.asarray(state, float), spec)
    qpos0 = data.qpos.copy()
    qvel0 = data.qvel.copy()

    def torque(dq: np.ndarray, dv: np.ndarray) -> np.ndarray:
        data.qpos[:] = qpos0
        data.qvel[:] = qvel0
        data.qpos[qpos_idx] += dq
        data.qvel[dof_idx] += dv
        mujoco.mj_forward(model, data)
        return (data.qfrc_actuator + data.qfrc_passive)[dof_idx].copy()

    eye = np.eye(n) * _FD_EPS
    zero = np.zeros(n)
    K = -np.stack([(torque(e, zero) - torque(-e, zero)) / (2 * _FD_EPS) for e in eye], axis=1)
    D = -np.stack([(torque(zero, e) - torque(zero, -e)) / (2 * _FD_EPS) for e in eye], axis=1)
    return K, D


def joint_impedance(scene: Scene, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Intrinsic K and D of the planar arm at a full-physics ``state`` (activations frozen).

    Returns:
        (K (2, 2) N·m/rad, D (2, 2) N·m·s/rad).
    """
    return impedance_fd(scene.model, state, scene.arm_qpos, scene.arm_dof)


def _composite(model: mujoco.MjModel, bodies: list[int], frame: int) -> tuple[float, np.ndarray, float]:
    """Mass kg, first moment (3,) kg·m and inertia about ``frame``'s z axis kg·m² of rigid bodies.

    ``bodies`` must be welded to ``frame`` (no joints in between); positions are taken at qpos0.
    """
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    r_f = data.xmat[frame].reshape(3, 3)
    mass, first, inertia = 0.0, np.zeros(3), 0.0
    for b in bodies:
        com = r_f.T @ (data.xipos[b] - data.xpos[frame])
        r_i = r_f.T @ data.ximat[b].reshape(3, 3)
        i_zz = (r_i @ np.diag(model.body_inertia[b]) @ r_i.T)[2, 2]
        m = float(model.body_mass[b])
        mass += m
        first += m * com
        inertia += i_zz + m * (com[0] ** 2 + com[1] ** 2)
    return mass, first, inertia


def _welded_subtree(model: mujoco.MjModel, root: int) -> list[int]:
    out = [root]
    for b in range(model.nbody):
        if b != root and model.body_parentid[b] in out and model.body_jntnum[b] == 0:
            out.append(b)
    return out


def base_inertial_parameters(scene: Scene, rigid_cuff: bool) -> np.ndarray:
    """xi = (xi1, xi2, xi3) kg·m² of the arm, its welded cuff shell and, for a rigid cuff, the
    robot-side cuff bodies beyond the F/T sensor (point masses at the hand), eq. (13).

    xi1 = J1 + J2 + m2 l1², xi2 = l1 s2, xi3 = J2 with J the segments' inertia about their joint,
    s2 the forearm's first moment along the link and m2 its mass (cuff included).
    """
    model = scene.model
    forearm = model.site_bodyid[scene.hand_site]
    upper = model.body_parentid[forearm]
    _, s1, j1 = _composite(model, [upper], upper)  # the upper arm alone (its subtree holds the forearm)
    m2, s2, j2 = _composite(model, _welded_subtree(model, forearm), forearm)
    if abs(s1[1]) > 1e-9 or abs(s2[1]) > 1e-9:
        raise ModelError("arm segments must have their centres of mass on the link axes (x)")
    if rigid_cuff:
        for name in ("lwr/cuff/ft_sensor", "lwr/cuff/mount"):
            b = named_id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            m = float(model.body_mass[b])
            m2 += m
            s2 = s2 + m * np.array([scene.l2, 0.0, 0.0])
            j2 += m * scene.l2**2
    return np.array([j1 + j2 + m2 * scene.l1**2, scene.l1 * s2[0], j2])


def ground_truth(scene: Scene, state: np.ndarray, rigid_cuff: bool) -> GroundTruth:
    """K, D at ``state`` and xi from the model's inertias."""
    K, D = joint_impedance(scene, state)
    q_op = np.asarray(state)[1 + scene.arm_qpos]
    return GroundTruth(K=K, D=D, xi=base_inertial_parameters(scene, rigid_cuff), q_op=q_op)
