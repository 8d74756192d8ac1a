"""The force task of seed paper 001's stiffness trials: the subject holds a displayed force.

"4 levels in Cartesian X and Z direction each" (paper Sec. 3), read as 4 levels in X plus 4 in Z:
8 pre-load conditions whose values the paper does not give (spec 001 assumption: +-5, +-10 N).
The simulated subject holds the default posture q0 against gravity while pushing that force on the
robot, with the least-effort activations: a >= a_min minimising ||a||^2 subject to the static
torque balance of Eq. (14),

    tau_m(a) + tau_passive(q0) + J_limb(q0)^T w = G(q0),   w = (-F, 0) the wrench on the limb,

solved by ``scipy.optimize.lsq_linear`` (the balance as a heavily weighted row block, the effort
as the rest) and then made exact on the muscles off their bound. Different pushes recruit different
muscles, so K_q = sum_i a_i k_i r_i r_i^T + K_passive differs per condition (spec 001, design).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from armlab.errors import ConfigError
from armlab.models.arm5_truth import gravity_torque
from armlab.models.arm_5dof import Arm5Dof, limb_kinematics

__all__ = [
    "A_MIN",
    "PRELOAD_CONDITIONS",
    "ForceTask",
    "force_task_activations",
    "muscle_torque_matrix",
    "preload_conditions",
]

# Minimum activation of every muscle (assumption: a resting co-contraction tone; with it the
# intrinsic K_q of models/arm_5dof has eigenvalues of ~1-13 N m/rad, the order of human arm joint
# stiffness, Shadmehr and Mussa-Ivaldi 1994; the paper gives no figure).
A_MIN = 0.1
# N, the displayed force levels (spec 001 assumption: +-5, +-10 N; the paper: "4 levels in
# Cartesian X and Z direction each", values not given), in the world frame of models/arm_5dof
# (x lateral, z up). Name -> force the subject exerts on the robot.
PRELOAD_CONDITIONS: dict[str, tuple[float, float, float]] = {
    "X-10": (-10.0, 0.0, 0.0),
    "X-5": (-5.0, 0.0, 0.0),
    "X+5": (5.0, 0.0, 0.0),
    "X+10": (10.0, 0.0, 0.0),
    "Z-10": (0.0, 0.0, -10.0),
    "Z-5": (0.0, 0.0, -5.0),
    "Z+5": (0.0, 0.0, 5.0),
    "Z+10": (0.0, 0.0, 10.0),
}
_BALANCE_WEIGHT = 1e3  # weight of the torque rows against the effort rows (then polished exactly)


def preload_conditions() -> tuple[tuple[str, ...], np.ndarray]:
    """The condition names and their forces (8, 3) N (:data:`PRELOAD_CONDITIONS`)."""
    return tuple(PRELOAD_CONDITIONS), np.array(list(PRELOAD_CONDITIONS.values()))


@dataclass(frozen=True, kw_only=True, eq=False)
class ForceTask:
    """The held activations of one condition.

    Attributes:
        activation: (12,) muscle activations in ``ARM5_MUSCLES`` order, in [a_min, 1].
        force: (3,) N the force the subject exerts on the robot (world).
        tau_required: (5,) N·m the muscle torque the balance needs.
        residual: N·m, max |tau_m(a) - tau_required| (rounding only).
    """

    activation: np.ndarray
    force: np.ndarray
    tau_required: np.ndarray
    residual: float


def muscle_torque_matrix(arm: Arm5Dof, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint torques of the muscles at rest at ``q`` (5,) rad: (M (5, 12) N·m per unit activation,
    tau_passive (5,) N·m), so that qfrc_actuator + qfrc_passive = M a + tau_passive (linear
    muscles, read from MuJoCo's forces, not the file's numbers)."""
    n = len(arm.muscle_act)
    base = arm.data_at(q, np.zeros(n))
    tau0 = base.qfrc_actuator[arm.dof].copy()
    cols = [arm.data_at(q, e).qfrc_actuator[arm.dof] - tau0 for e in np.eye(n)]
    return np.stack(cols, axis=1), tau0 + base.qfrc_passive[arm.dof]


def force_task_activations(arm: Arm5Dof, q: np.ndarray, force: np.ndarray, a_min: float = A_MIN) -> ForceTask:
    """Least-effort activations that hold posture ``q`` (5,) rad while pushing ``force`` (3,) N.

    Args:
        arm: the 5-DoF arm.
        q: (5,) rad the held posture.
        force: (3,) N the force the wrist exerts on the robot (world frame), no moment.
        a_min: the lower bound of every activation.

    Raises:
        ConfigError: ``a_min`` outside [0, 1) or the push needs activations above 1.
    """
    if not 0.0 <= a_min < 1.0:
        raise ConfigError(f"a_min must lie in [0, 1), got {a_min!r}")
    q = np.asarray(q, dtype=float)
    f = np.asarray(force, dtype=float)
    if f.shape != (3,):
        raise ConfigError(f"force must be a (3,) vector in N, got shape {f.shape}")
    M, tau_p = muscle_torque_matrix(arm, q)
    jac = limb_kinematics(arm).jacobian(q)
    wrench = np.r_[-f, 0.0, 0.0, 0.0]  # on the limb: the robot pushes back
    tau_req = gravity_torque(arm, q) - tau_p - jac.T @ wrench
    n = M.shape[1]
    C = np.vstack([_BALANCE_WEIGHT * M, np.eye(n)])
    d = np.r_[_BALANCE_WEIGHT * tau_req, np.zeros(n)]
    a = lsq_linear(C, d, bounds=(a_min, 1.0), method="bvls", tol=1e-12).x
    # exact balance on the muscles off their bound: the least-norm correction of those
    free = a > a_min + 1e-9
    if np.linalg.matrix_rank(M[:, free]) == M.shape[0]:
        a[free] += np.linalg.pinv(M[:, free]) @ (tau_req - M @ a)
    residual = float(np.max(np.abs(M @ a - tau_req)))
    if residual > 1e-6 or a.max() > 1.0 + 1e-9 or a.min() < a_min - 1e-9:
        raise ConfigError(
            f"the push {f.tolist()} N at posture {np.round(q, 3).tolist()} rad needs more than full "
            f"activation (torque residual {residual:.3g} N m at a <= 1); lower the force level"
        )
    return ForceTask(activation=np.clip(a, a_min, 1.0), force=f, tau_required=tau_req, residual=residual)
