"""Analytic planar two-link arm: kinematics and rigid-body dynamics in base parameters.

Conventions (shoulder frame): the shoulder is at the origin, x points lateral, y anterior.
``q1`` is the shoulder angle of the upper arm from the +x axis (counter-clockwise positive) and
``q2`` the elbow angle of the forearm relative to the upper arm; ``l1`` is the upper-arm length
(shoulder to elbow) and ``l2`` the forearm length (elbow to hand). The arm moves in the
transversal plane, so gravity does not act (Sec. III-A of the conditioning paper).

The dynamics are written in the three base inertial parameters ``xi = (xi1, xi2, xi3)`` implied by
the regressor of Eq. (13) of the conditioning paper::

    M11 = xi1 + 2 xi2 cos q2,   M12 = M21 = xi3 + xi2 cos q2,   M22 = xi3.

Every function broadcasts over leading dimensions (trials, samples, ...).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from armlab.errors import DataError

__all__ = [
    "forward",
    "jacobian",
    "inverse",
    "xi_from_segments",
    "mass_matrix",
    "coriolis_matrix",
    "coriolis_torque",
    "inverse_dynamics",
]

Elbow = Literal["flexed", "extended"]
_ELBOWS = ("flexed", "extended")
# Points whose cos(q2) overshoots [-1, 1] by at most this much (rounding in FK -> IK round trips)
# are clipped onto the workspace boundary instead of being rejected.
_REACH_TOL = 1e-9


def forward(q: np.ndarray, l1: float, l2: float) -> np.ndarray:
    """Hand position from joint angles.

    Args:
        q: (..., 2) rad, shoulder and elbow angles.
        l1: upper-arm length, m.
        l2: forearm length (elbow to hand), m.

    Returns:
        (..., 2) m, hand position (x lateral, y anterior) in the shoulder frame.
    """
    q = np.asarray(q, dtype=float)
    q1, q12 = q[..., 0], q[..., 0] + q[..., 1]
    return np.stack(
        [l1 * np.cos(q1) + l2 * np.cos(q12), l1 * np.sin(q1) + l2 * np.sin(q12)],
        axis=-1,
    )


def jacobian(q: np.ndarray, l1: float, l2: float) -> np.ndarray:
    """Hand Jacobian ``J = dx/dq`` used in ``tau_ext = J^T F`` (Sec. IV-C of the conditioning paper).

    Args:
        q: (..., 2) rad.
        l1: upper-arm length, m.
        l2: forearm length, m.

    Returns:
        (..., 2, 2) m/rad, ``J[..., i, j] = d x_i / d q_j``.
    """
    q = np.asarray(q, dtype=float)
    q1, q12 = q[..., 0], q[..., 0] + q[..., 1]
    s1, c1, s12, c12 = np.sin(q1), np.cos(q1), np.sin(q12), np.cos(q12)
    row_x = np.stack([-l1 * s1 - l2 * s12, -l2 * s12], axis=-1)
    row_y = np.stack([l1 * c1 + l2 * c12, l2 * c12], axis=-1)
    return np.stack([row_x, row_y], axis=-2)


def inverse(x: np.ndarray, l1: float, l2: float, elbow: Elbow = "flexed") -> np.ndarray:
    """Analytic inverse kinematics (the bijection ``x = f(q)`` of Sec. IV-C of the conditioning paper).

    Args:
        x: (..., 2) m, hand position in the shoulder frame.
        l1: upper-arm length, m.
        l2: forearm length, m.
        elbow: ``"flexed"`` picks ``q2`` in [0, pi] (the human elbow), ``"extended"`` the mirror
            branch ``q2`` in [-pi, 0].

    Returns:
        (..., 2) rad, joint angles with ``forward(inverse(x)) == x``.

    Raises:
        DataError: on an unknown ``elbow`` or a point outside the annulus
            ``|l1 - l2| <= |x| <= l1 + l2``.
    """
    if elbow not in _ELBOWS:
        raise DataError(f"elbow must be one of {_ELBOWS}, got {elbow!r}")
    if not (l1 > 0 and l2 > 0):
        raise DataError(f"segment lengths must be positive, got l1={l1!r}, l2={l2!r}")
    x = np.asarray(x, dtype=float)
    if x.shape[-1:] != (2,):
        raise DataError(f"x must have shape (..., 2), got {x.shape}")
    r2 = np.sum(x * x, axis=-1)
    c2 = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    bad = ~(np.abs(c2) <= 1.0 + _REACH_TOL)  # also catches NaN
    if np.any(bad):
        r = np.sqrt(r2[bad])
        raise DataError(
            f"{int(np.sum(bad))} hand position(s) unreachable: distance from the shoulder "
            f"{r.min():.4g}..{r.max():.4g} m, valid range [{abs(l1 - l2):.4g}, {l1 + l2:.4g}] m"
        )
    q2 = np.arccos(np.clip(c2, -1.0, 1.0))
    if elbow == "extended":
        q2 = -q2
    q1 = np.arctan2(x[..., 1], x[..., 0]) - np.arctan2(l2 * np.sin(q2), l1 + l2 * np.cos(q2))
    q1 = (q1 + np.pi) % (2.0 * np.pi) - np.pi
    return np.stack([q1, q2], axis=-1)


def xi_from_segments(
    m1: float, lc1: float, I1: float, m2: float, lc2: float, I2: float, l1: float
) -> np.ndarray:
    """Base inertial parameters of the planar arm from segment properties.

    This is the parametrisation implied by the regressor of Eq. (13) of the conditioning paper.

    Args:
        m1, m2: upper-arm and forearm(+hand) masses, kg.
        lc1, lc2: distance from the proximal joint to the segment's centre of mass, m.
        I1, I2: moment of inertia about the segment's centre of mass, vertical axis, kg·m².
        l1: upper-arm length, m.

    Returns:
        (3,) kg·m², ``xi1 = I1 + m1 lc1² + I2 + m2 (l1² + lc2²)``, ``xi2 = m2 l1 lc2``,
        ``xi3 = I2 + m2 lc2²``.
    """
    xi1 = I1 + m1 * lc1**2 + I2 + m2 * (l1**2 + lc2**2)
    xi2 = m2 * l1 * lc2
    xi3 = I2 + m2 * lc2**2
    return np.array([xi1, xi2, xi3], dtype=float)


def _xi(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    xi = np.asarray(xi, dtype=float)
    if xi.shape[-1:] != (3,):
        raise DataError(f"xi must have shape (..., 3) (xi1, xi2, xi3), got {xi.shape}")
    return xi[..., 0], xi[..., 1], xi[..., 2]


def mass_matrix(q: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Mass matrix ``M(q, xi)`` of Eq. (1)/(9) of the conditioning paper.

    Args:
        q: (..., 2) rad.
        xi: (3,) or (..., 3) kg·m², base inertial parameters.

    Returns:
        (..., 2, 2) kg·m², symmetric positive definite for physical ``xi``.
    """
    xi1, xi2, xi3 = _xi(xi)
    c2 = np.cos(np.asarray(q, dtype=float)[..., 1])
    m11 = xi1 + 2.0 * xi2 * c2
    m12 = xi3 + xi2 * c2
    m22 = np.broadcast_to(xi3, m12.shape)
    return np.stack([np.stack([m11, m12], -1), np.stack([m12, m22], -1)], -2)


def coriolis_matrix(q: np.ndarray, qd: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Coriolis/centrifugal matrix ``C(q, qd, xi)`` of Eq. (1), chosen so ``dM/dt - 2C`` is skew.

    Args:
        q: (..., 2) rad.
        qd: (..., 2) rad/s.
        xi: (3,) or (..., 3) kg·m².

    Returns:
        (..., 2, 2) kg·m²/s, ``C = h [[-qd2, -(qd1 + qd2)], [qd1, 0]]`` with ``h = xi2 sin q2``.
    """
    _, xi2, _ = _xi(xi)
    qd = np.asarray(qd, dtype=float)
    h = xi2 * np.sin(np.asarray(q, dtype=float)[..., 1])
    qd1, qd2 = qd[..., 0], qd[..., 1]
    zero = np.zeros_like(h * qd1)
    row1 = np.stack([-h * qd2, -h * (qd1 + qd2)], -1)
    row2 = np.stack([h * qd1, zero], -1)
    return np.stack([row1, row2], -2)


def coriolis_torque(q: np.ndarray, qd: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Coriolis/centrifugal torque ``C(q, qd, xi) qd`` of Eq. (1) of the conditioning paper.

    Args:
        q: (..., 2) rad.
        qd: (..., 2) rad/s.
        xi: (3,) or (..., 3) kg·m².

    Returns:
        (..., 2) N·m, ``(-h (2 qd1 qd2 + qd2²), h qd1²)`` with ``h = xi2 sin q2``.
    """
    _, xi2, _ = _xi(xi)
    qd = np.asarray(qd, dtype=float)
    h = xi2 * np.sin(np.asarray(q, dtype=float)[..., 1])
    qd1, qd2 = qd[..., 0], qd[..., 1]
    return np.stack([-h * (2.0 * qd1 * qd2 + qd2 * qd2), h * qd1 * qd1], axis=-1)


def inverse_dynamics(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Rigid-body inverse dynamics ``M(q) qdd + C(q, qd) qd`` (Eq. (1) without gravity).

    Args:
        q: (..., 2) rad.
        qd: (..., 2) rad/s.
        qdd: (..., 2) rad/s².
        xi: (3,) or (..., 3) kg·m².

    Returns:
        (..., 2) N·m, joint torques needed to produce ``qdd`` (no impedance terms).
    """
    M = mass_matrix(q, xi)
    qdd = np.asarray(qdd, dtype=float)
    return np.einsum("...ij,...j->...i", M, qdd) + coriolis_torque(q, qd, xi)
