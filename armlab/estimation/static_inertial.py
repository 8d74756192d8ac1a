"""Static inertial regression from the base wrench (seed paper 001, Eqs. (11)-(13), (22)).

At rest the Newton-Euler recursion of Eqs. (11)-(13) projected to the base sensor reduces to
gravity acting on the masses and first moments (Eq. (22)): with S(q) = c + R_u(q) u + R_f(q) s the
first moment (kg·m, world axes, origin at the sensor) of everything the sensor carries, the wrench
the base exerts on the seat is f = (0, 0, g m_total) and n = (g S_y, -g S_x, 0). So F_z, M_x and M_y
(the paper's components 3, 4, 5) are linear in xi_red = (m_total, c_x, c_y, u, s) (names in
``armlab.models.arm5_truth.XI_RED_NAMES``); c (the fixed bodies and the arm's mass at the shoulder)
is the intercept of the torso and seat. The sensor axes are taken aligned with the world (z up).

The gravity torque on the arm follows from the same parameters: the potential is V = g S_z(q), so
G_j(q) = g [w_j x (R_u u)]_z (shoulder joints) + g [w_j x (R_f s)]_z (every joint), with w_j the
world axis of joint j.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError, EstimationError
from armlab.estimation.least_squares import least_squares
from armlab.models.limb_kinematics import LimbKinematics

__all__ = [
    "GRAVITY_MS2",
    "StaticInertialFit",
    "gravity_stiffness_from_fit",
    "gravity_torque_from_fit",
    "static_inertial_regression",
    "static_regressor",
]

GRAVITY_MS2 = 9.81  # m/s², as the MJCF's <option gravity="0 0 -9.81"/> (models/arm_5dof)
_FD_EPS = 1e-6  # rad: central-difference step of dG/dq


@dataclass(frozen=True, kw_only=True, eq=False)
class StaticInertialFit:
    """Least-squares xi_red of Eq. (22).

    Attributes:
        xi_red: (9,) (m_total kg, c_x, c_y, u_x, u_y, u_z, s_x, s_y, s_z kg·m).
        covariance: (9, 9) from the residual variance (Gauss-Markov).
        rms_residual: (3,) RMS residual of F_z N, M_x N·m, M_y N·m.
        condition: 2-norm condition number of the column-scaled regressor.
    """

    xi_red: np.ndarray
    covariance: np.ndarray
    rms_residual: np.ndarray
    condition: float


def static_regressor(kin: LimbKinematics, q: np.ndarray, g: float = GRAVITY_MS2) -> np.ndarray:
    """Regressor Y(q) with (F_z, M_x, M_y) = Y(q) xi_red, (..., 3, 9) (Eq. (22))."""
    pose = kin.pose(q)
    ru, rf = pose.upper_rot, pose.forearm_rot
    shape = ru.shape[:-2]
    zero3 = np.zeros((*shape, 3))
    one = np.ones(shape)
    zero = np.zeros(shape)
    fz = np.concatenate([np.stack([one, zero, zero], -1), zero3, zero3], axis=-1)
    mx = np.concatenate([np.stack([zero, zero, one], -1), ru[..., 1, :], rf[..., 1, :]], axis=-1)
    my = -np.concatenate([np.stack([zero, one, zero], -1), ru[..., 0, :], rf[..., 0, :]], axis=-1)
    return g * np.stack([fz, mx, my], axis=-2)


def static_inertial_regression(
    kin: LimbKinematics, q: np.ndarray, wrench: np.ndarray, g: float = GRAVITY_MS2
) -> StaticInertialFit:
    """Eq. (22): xi_red from mean postures and mean base wrenches of static configurations.

    Args:
        kin: the (calibrated) kinematic chain.
        q: (N, 5) rad, mean joint angles of each held configuration (IK of the markers).
        wrench: (N, 6) mean base wrench (f N, n N·m) the base exerts on the seat, sensor axes = world.
        g: m/s².

    Returns:
        :class:`StaticInertialFit`.

    Raises:
        DataError: on mismatched or non-finite input.
        EstimationError: on fewer than 3 configurations or a rank-deficient regressor.
    """
    q = np.asarray(q, dtype=float)
    wrench = np.asarray(wrench, dtype=float)
    if q.ndim != 2 or q.shape[1] != 5 or wrench.shape != (len(q), 6):
        raise DataError(f"q must be (N, 5) and wrench (N, 6), got {q.shape} and {wrench.shape}")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(wrench))):
        raise DataError("q or wrench contains NaN or inf")
    if len(q) < 3:
        raise EstimationError(f"the static regression needs at least 3 configurations, got {len(q)}")
    y = static_regressor(kin, q, g).reshape(-1, 9)
    b = wrench[:, [2, 3, 4]].reshape(-1)
    ls = least_squares(y, b, scale_columns=True)
    if ls.rank < 9:
        raise EstimationError(
            f"the static regressor has rank {ls.rank} < 9: the configurations must rotate the upper arm and "
            "the forearm about independent axes"
        )
    xi = ls.x
    res = (y @ xi - b).reshape(-1, 3)
    cov = ls.inv_normal * ls.residual_variance  # NaN with 3 configurations (no dof)
    return StaticInertialFit(
        xi_red=xi,
        covariance=cov,
        rms_residual=np.sqrt(np.mean(res**2, axis=0)),
        condition=ls.condition,
    )


def gravity_torque_from_fit(
    kin: LimbKinematics, xi_red: np.ndarray, q: np.ndarray, g: float = GRAVITY_MS2
) -> np.ndarray:
    """G(q, xi_red) of Eq. (14): the joint torque (..., 5) N·m holding the arm at ``q`` (..., 5) rad."""
    xi_red = np.asarray(xi_red, dtype=float)
    if xi_red.shape != (9,):
        raise DataError(f"xi_red must have shape (9,), got {xi_red.shape}")
    pose = kin.pose(q)
    su = pose.upper_rot @ xi_red[3:6]
    sf = pose.forearm_rot @ xi_red[6:9]
    w = pose.axes
    tu = np.cross(w, su[..., None, :])[..., 2]
    tf = np.cross(w, sf[..., None, :])[..., 2]
    tu[..., 3:] = 0.0  # elbow and pronation do not move the upper arm
    return g * (tu + tf)


def gravity_stiffness_from_fit(
    kin: LimbKinematics, xi_red: np.ndarray, q: np.ndarray, g: float = GRAVITY_MS2
) -> np.ndarray:
    """dG/dq (5, 5) N·m/rad at ``q`` (5,) rad by central differences of :func:`gravity_torque_from_fit`."""
    q = np.asarray(q, dtype=float)
    steps = np.eye(5) * _FD_EPS
    gp = gravity_torque_from_fit(kin, xi_red, q + steps, g)
    gm = gravity_torque_from_fit(kin, xi_red, q - steps, g)
    return ((gp - gm) / (2 * _FD_EPS)).T
