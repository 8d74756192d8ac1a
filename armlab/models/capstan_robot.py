"""Analytic dynamics and kinematics of the capstan-driven 2-DoF planar rehabilitation robot.

The Quanser robot of the virtual-sensor paper (seeds/003) in its absolute link angles
``Theta = (theta1, theta2)`` (rad), Eq. (1) without the external force::

    tau = I(Theta) Theta_dd + C(Theta, Theta_d) Theta_d + F_r(Theta_d)

with Eqs. (11)-(13) of the Appendix::

    I = [[a1, -a2/2 sin(t1 - t2)], [-a2/2 sin(t1 - t2), a3]]
    C = [[0, a2/2 cos(t1 - t2) t2_d], [-a2/2 cos(t1 - t2) t1_d, 0]]
    F_r = (a4 t1_d, a5 t2_d)

The paper prints ``C21 = +a2/2 cos(t1 - t1) t1_d``; the ``t1 - t1`` is a typo and the sign follows
from the Lagrangian of ``I``: with ``I12 = -a2/2 sin(t1 - t2)`` the centrifugal torque on joint 2
is ``-a2/2 cos(t1 - t2) t1_d^2``, which makes ``dI/dt - 2C`` skew-symmetric. This module uses the
consistent ``C``; ``models/capstan_planar`` realises exactly this rigid model (README there).

Kinematics (frames of ``models/capstan_planar``): the shoulder axis is the origin, x forward
(towards the subject; the paper's x, along which Table I's ``X0`` lies at 0.33-0.39 m), y to the
left. Link 1 points along ``(cos t1, sin t1)`` and link 2 along ``(sin t2, -cos t2)``, so
``X = l1 (cos t1, sin t1) + l2 (sin t2, -cos t2)``; the 90 degree offset of link 2 is what turns
the serial arm's coupling into the ``sin(t1 - t2)`` of Eq. (11).

Every function broadcasts over leading dimensions (trials, samples, ...).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from armlab.errors import ConfigError, DataError

__all__ = [
    "ALPHA_NAMES",
    "CABLE_DAMPING_NMS_PER_RAD",
    "CABLE_STIFFNESS_NM_PER_RAD",
    "CAPSTAN_RATIO",
    "HANDLE_MASS_KG",
    "LINK1_LENGTH_M",
    "LINK2_LENGTH_M",
    "ROTOR_INERTIA_KGM2",
    "TABLE_VI_ALPHA",
    "CapstanDynamics",
    "CapstanParameters",
]

ALPHA_NAMES = ("alpha1", "alpha2", "alpha3", "alpha4", "alpha5")
# Mirrored in models/capstan_planar/capstan_planar.xml (tests/test_capstan_robot.py ties them).
LINK1_LENGTH_M = 0.35  # m, shoulder to elbow (assumption: desktop rehabilitation robot)
LINK2_LENGTH_M = 0.35  # m, elbow to end effector (assumption)
CAPSTAN_RATIO = 10.0  # motor turns per link turn (assumption, capstan drum ratio)
ROTOR_INERTIA_KGM2 = 1.34e-5  # kg·m², motor rotor (assumption: Maxon RE40 class, 134 g·cm²)
CABLE_STIFFNESS_NM_PER_RAD = 200.0  # N·m/rad, link side (assumption: locked-rotor modes 8.6/10.9 Hz)
CABLE_DAMPING_NMS_PER_RAD = 0.05  # N·m·s/rad, link side (assumption: lightly damped steel cable)
HANDLE_MASS_KG = 0.135  # kg, the handle Lambda (paper Sec. II-C, Eq. (9)); not part of Table VI


@dataclass(frozen=True, kw_only=True)
class CapstanParameters:
    """The dynamic parameters of Eqs. (11)-(13).

    Attributes:
        alpha: ``(alpha1, alpha2, alpha3)`` kg·m² and ``(alpha4, alpha5)`` N·m·s/rad.
        std: one standard deviation of each, same units (None when unknown).
    """

    alpha: tuple[float, float, float, float, float]
    std: tuple[float, float, float, float, float] | None = None

    def __post_init__(self) -> None:
        alpha = tuple(float(a) for a in self.alpha)
        if len(alpha) != 5 or not np.all(np.isfinite(alpha)):
            raise ConfigError(f"alpha must be 5 finite values {ALPHA_NAMES}, got {self.alpha!r}")
        a1, a2, a3, a4, a5 = alpha
        if a1 <= 0 or a3 <= 0 or a1 * a3 <= 0.25 * a2**2:
            raise ConfigError(
                f"alpha1, alpha3 > 0 and alpha1 alpha3 > alpha2²/4 are needed for a positive definite "
                f"I(Theta), Eq. (11); got alpha1={a1}, alpha2={a2}, alpha3={a3}"
            )
        if a4 < 0 or a5 < 0:
            raise ConfigError(f"viscous friction alpha4, alpha5 must be >= 0, got {a4}, {a5}")
        object.__setattr__(self, "alpha", alpha)
        if self.std is not None:
            std = tuple(float(s) for s in self.std)
            if len(std) != 5 or not all(s >= 0 for s in std):
                raise ConfigError(f"std must be 5 values >= 0 (one per alpha), got {self.std!r}")
            object.__setattr__(self, "std", std)

    @classmethod
    def from_array(cls, alpha: np.ndarray, std: np.ndarray | None = None) -> CapstanParameters:
        """Parameters from a (5,) array (e.g. a least-squares solution of ``regressor``)."""
        return cls(
            alpha=tuple(np.asarray(alpha, float).ravel()),
            std=None if std is None else tuple(np.asarray(std, float).ravel()),
        )

    def as_array(self) -> np.ndarray:
        """(5,) the alphas, in the order of :data:`ALPHA_NAMES`."""
        return np.array(self.alpha)


# Table VI of the paper: identified parameters with their standard deviations over six trials.
TABLE_VI_ALPHA = CapstanParameters(
    alpha=(0.06929, 0.04217, 0.04416, 0.06510, 0.07389),
    std=(0.00003, 0.00007, 0.00004, 0.00176, 0.00072),
)


def _pair(x: np.ndarray, name: str) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.shape[-1:] != (2,):
        raise DataError(f"{name} must have shape (..., 2) (theta1, theta2), got {x.shape}")
    return x


def _mat(a11: np.ndarray, a12: np.ndarray, a21: np.ndarray, a22: np.ndarray) -> np.ndarray:
    return np.stack([np.stack([a11, a12], axis=-1), np.stack([a21, a22], axis=-1)], axis=-2)


@dataclass(frozen=True, kw_only=True)
class CapstanDynamics:
    """Rigid-body model of the robot in its absolute link angles.

    Attributes:
        params: the alphas of Eqs. (11)-(13) (default Table VI).
        l1, l2: m, link lengths (defaults mirror the MJCF).
    """

    params: CapstanParameters = field(default_factory=lambda: TABLE_VI_ALPHA)
    l1: float = LINK1_LENGTH_M
    l2: float = LINK2_LENGTH_M

    def __post_init__(self) -> None:
        if not (self.l1 > 0 and self.l2 > 0):
            raise ConfigError(f"link lengths must be > 0 m, got l1={self.l1}, l2={self.l2}")

    def inertia(self, theta: np.ndarray) -> np.ndarray:
        """Eq. (11): (..., 2) rad -> (..., 2, 2) kg·m²."""
        theta = _pair(theta, "theta")
        a1, a2, a3 = self.params.alpha[:3]
        off = -0.5 * a2 * np.sin(theta[..., 0] - theta[..., 1])
        return _mat(np.full_like(off, a1), off, off, np.full_like(off, a3))

    def coriolis(self, theta: np.ndarray, theta_dot: np.ndarray) -> np.ndarray:
        """Eq. (12) made consistent with Eq. (11) (module docstring): -> (..., 2, 2) kg·m²/s."""
        theta, theta_dot = _pair(theta, "theta"), _pair(theta_dot, "theta_dot")
        h = 0.5 * self.params.alpha[1] * np.cos(theta[..., 0] - theta[..., 1])
        zero = np.zeros_like(h)
        return _mat(zero, h * theta_dot[..., 1], -h * theta_dot[..., 0], zero)

    def friction(self, theta_dot: np.ndarray) -> np.ndarray:
        """Eq. (13): (..., 2) rad/s -> (..., 2) N·m."""
        theta_dot = _pair(theta_dot, "theta_dot")
        return theta_dot * np.array(self.params.alpha[3:])

    def inverse_dynamics(
        self, theta: np.ndarray, theta_dot: np.ndarray, theta_ddot: np.ndarray
    ) -> np.ndarray:
        """Eq. (1) with F_ext = 0: joint torques (..., 2) N·m from (..., 2) rad, rad/s, rad/s²."""
        theta_ddot = _pair(theta_ddot, "theta_ddot")
        return (
            np.einsum("...ij,...j->...i", self.inertia(theta), theta_ddot)
            + np.einsum("...ij,...j->...i", self.coriolis(theta, theta_dot), theta_dot)
            + self.friction(theta_dot)
        )

    def forward_dynamics(self, theta: np.ndarray, theta_dot: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Joint accelerations (..., 2) rad/s² under torques ``tau`` (..., 2) N·m, Eq. (1)."""
        bias = self.inverse_dynamics(theta, theta_dot, np.zeros_like(_pair(theta_dot, "theta_dot")))
        rhs = _pair(tau, "tau") - bias
        return np.linalg.solve(self.inertia(theta), rhs[..., None])[..., 0]

    @staticmethod
    def regressor(theta: np.ndarray, theta_dot: np.ndarray, theta_ddot: np.ndarray) -> np.ndarray:
        """``Y`` with ``tau = Y @ alpha``, linear in the alphas (Appendix least squares).

        Args:
            theta, theta_dot, theta_ddot: (..., 2) rad, rad/s, rad/s².

        Returns:
            (..., 2, 5): rows tau1, tau2; columns alpha1..alpha5 (N·m per unit alpha).
        """
        theta, theta_dot = _pair(theta, "theta"), _pair(theta_dot, "theta_dot")
        theta_ddot = _pair(theta_ddot, "theta_ddot")
        d = theta[..., 0] - theta[..., 1]
        s, c = 0.5 * np.sin(d), 0.5 * np.cos(d)
        v1, v2 = theta_dot[..., 0], theta_dot[..., 1]
        a1, a2 = theta_ddot[..., 0], theta_ddot[..., 1]
        z = np.zeros_like(d)
        row1 = np.stack([a1, -s * a2 + c * v2**2, z, v1, z], axis=-1)
        row2 = np.stack([z, -s * a1 - c * v1**2, a2, z, v2], axis=-1)
        return np.stack([row1, row2], axis=-2)

    def fk(self, theta: np.ndarray) -> np.ndarray:
        """End-effector position X (..., 2) m in the base frame (x forward, y left)."""
        theta = _pair(theta, "theta")
        t1, t2 = theta[..., 0], theta[..., 1]
        return np.stack(
            [self.l1 * np.cos(t1) + self.l2 * np.sin(t2), self.l1 * np.sin(t1) - self.l2 * np.cos(t2)],
            axis=-1,
        )

    def ik(self, x: np.ndarray) -> np.ndarray:
        """Joint angles Theta (..., 2) rad placing the end effector at ``x`` (..., 2) m.

        The branch with the elbow bent to the right of link 1 (the MJCF's elbow joint
        ``theta2 - theta1`` in (-pi/2, pi/2) over the usable workspace), so ``fk(ik(x)) == x``.

        Raises:
            DataError: a point outside the annulus ``|l1 - l2| < |x| < l1 + l2``.
        """
        x = _pair(x, "x")
        r2 = np.sum(x * x, axis=-1)
        c = (r2 - self.l1**2 - self.l2**2) / (2 * self.l1 * self.l2)
        if np.any(~(np.abs(c) < 1.0)):
            r = np.sqrt(r2)
            raise DataError(
                f"end-effector position(s) out of reach: distance {np.min(r):.4g}..{np.max(r):.4g} m from "
                f"the shoulder axis; reachable ({abs(self.l1 - self.l2):.4g}, {self.l1 + self.l2:.4g}) m"
            )
        delta = -np.arccos(c)  # angle from link 1 to link 2 (link directions theta1, theta2 - pi/2)
        t1 = np.arctan2(x[..., 1], x[..., 0]) - np.arctan2(
            self.l2 * np.sin(delta), self.l1 + self.l2 * np.cos(delta)
        )
        return np.stack([t1, t1 + delta + 0.5 * np.pi], axis=-1)

    def jacobian(self, theta: np.ndarray) -> np.ndarray:
        """``J = dX/dTheta`` (..., 2, 2) m/rad, the Jacobian of Eqs. (1), (2) and (7)."""
        theta = _pair(theta, "theta")
        t1, t2 = theta[..., 0], theta[..., 1]
        return _mat(-self.l1 * np.sin(t1), self.l2 * np.cos(t2), self.l1 * np.cos(t1), self.l2 * np.sin(t2))

    def jacobian_dot(self, theta: np.ndarray, theta_dot: np.ndarray) -> np.ndarray:
        """``dJ/dt`` (..., 2, 2) m/(rad·s), for Eq. (7)."""
        theta, theta_dot = _pair(theta, "theta"), _pair(theta_dot, "theta_dot")
        t1, t2 = theta[..., 0], theta[..., 1]
        w1, w2 = theta_dot[..., 0], theta_dot[..., 1]
        return _mat(
            -self.l1 * np.cos(t1) * w1,
            -self.l2 * np.sin(t2) * w2,
            -self.l1 * np.sin(t1) * w1,
            self.l2 * np.cos(t2) * w2,
        )

    def joint_acceleration(self, theta: np.ndarray, theta_dot: np.ndarray, x_ddot: np.ndarray) -> np.ndarray:
        """Eq. (7): ``Theta_dd = J^-1 (X_dd - J_dot Theta_d)`` from the end-effector acceleration.

        Args:
            theta, theta_dot: (..., 2) rad, rad/s.
            x_ddot: (..., 2) m/s², end-effector acceleration in the base frame (an ee-mounted
                accelerometer reads it rotated by theta2, see models/capstan_planar/README.md).

        Returns:
            (..., 2) rad/s².
        """
        rhs = _pair(x_ddot, "x_ddot") - np.einsum(
            "...ij,...j->...i", self.jacobian_dot(theta, theta_dot), _pair(theta_dot, "theta_dot")
        )
        return np.linalg.solve(self.jacobian(theta), rhs[..., None])[..., 0]
