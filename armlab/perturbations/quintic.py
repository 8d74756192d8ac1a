"""Minimum-jerk (fifth-order) point-to-point perturbations, Sec. III-B and IV-B of the conditioning paper.

The robot moves the arm in joint space from ``q0`` to ``q0 + amplitude`` along the fifth-order
polynomial of Eq. (16), the minimum-jerk solution of Eq. (15), with zero velocity and acceleration
at both ends. :func:`conditioning_ratio` evaluates Eq. (17), the paper's argument (Table I) for the
fifth- over the sixth-order profile. The protocol constants of Sec. IV-B (six directions, the
interpolation times ``T_k`` and the observation windows ``T_obs = T_k + 70 ms``) live here too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from armlab.errors import ConfigError

__all__ = [
    "PAPER_DIRECTIONS",
    "QuinticPerturbation",
    "conditioning_ratio",
    "observation_durations",
    "polynomial_coefficients",
    "quintic_profile",
    "window_durations",
]

Profile = Literal["quintic", "sextic"]
_PROFILES = ("quintic", "sextic")

#: The six joint-space amplitudes ``dq_f = q_f - q0`` of Sec. IV-B, rad (shoulder, elbow).
PAPER_DIRECTIONS: tuple[tuple[float, float], ...] = (
    (0.05, 0.0),
    (-0.05, 0.0),
    (0.0, 0.05),
    (0.0, -0.05),
    (0.05, -0.05),
    (-0.05, 0.05),
)


def quintic_profile(t: np.ndarray, duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalised fifth-order point-to-point profile, Eq. (16) of the conditioning paper.

    ``s(tau) = 10 tau³ - 15 tau⁴ + 6 tau⁵`` with ``tau = t / duration``: position, velocity and
    acceleration are 0, 0, 0 at ``t = 0`` and 1, 0, 0 at ``t = duration``. The profile is held at 0
    before the start and at 1 after the end.

    Args:
        t: (...) s, time from the start of the motion.
        duration: s, interpolation time ``T_k = t_f - t_p`` (> 0).

    Returns:
        ``(s, sd, sdd)``, each shaped like ``t``: position (1), velocity (1/s), acceleration (1/s²).

    Raises:
        ConfigError: if ``duration`` is not a positive finite number.
    """
    if not (np.isfinite(duration) and duration > 0):
        raise ConfigError(f"duration must be a positive finite number of seconds, got {duration!r}")
    tau = np.clip(np.asarray(t, dtype=float) / duration, 0.0, 1.0)
    u = 1.0 - tau
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    sd = 30.0 * tau**2 * u**2 / duration
    sdd = 60.0 * tau * u * (1.0 - 2.0 * tau) / duration**2
    return s, sd, sdd


@dataclass(frozen=True, kw_only=True)
class QuinticPerturbation:
    """A joint-space minimum-jerk perturbation, Eq. (16) and Sec. IV-B of the conditioning paper.

    Attributes:
        amplitude: (dof,) rad, final displacement ``q_f - q0`` of each joint.
        duration_s: s, interpolation time ``T_k`` (> 0).
        onset_s: s, perturbation onset ``t_p`` from the start of the record (>= 0).
    """

    amplitude: tuple[float, ...]
    duration_s: float
    onset_s: float = 0.0

    def __post_init__(self) -> None:
        try:
            amp = tuple(float(a) for a in np.ravel(np.asarray(self.amplitude, dtype=float)))
        except (TypeError, ValueError):
            raise ConfigError(
                f"amplitude must be a sequence of numbers (rad), got {self.amplitude!r}"
            ) from None
        if not amp or not all(np.isfinite(amp)):
            raise ConfigError(f"amplitude must be a non-empty sequence of finite rad values, got {amp!r}")
        object.__setattr__(self, "amplitude", amp)
        if not (np.isfinite(self.duration_s) and self.duration_s > 0):
            raise ConfigError(f"duration_s must be a positive finite number, got {self.duration_s!r}")
        if not (np.isfinite(self.onset_s) and self.onset_s >= 0):
            raise ConfigError(f"onset_s must be a finite number >= 0, got {self.onset_s!r}")

    @property
    def dof(self) -> int:
        """Number of perturbed joints."""
        return len(self.amplitude)

    @property
    def end_s(self) -> float:
        """s, time ``t_f = t_p + T_k`` at which the goal is reached."""
        return self.onset_s + self.duration_s

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Displacement, velocity and acceleration at the times ``t``.

        Args:
            t: (n,) s, time from the start of the record.

        Returns:
            ``(pos, vel, acc)``, each (n, dof): rad, rad/s, rad/s² relative to ``q0``.
        """
        t = np.asarray(t, dtype=float)
        if t.ndim != 1:
            raise ConfigError(f"t must be a 1-D array of times (s), got shape {t.shape}")
        s, sd, sdd = quintic_profile(t - self.onset_s, self.duration_s)
        amp = np.asarray(self.amplitude)
        return s[:, None] * amp, sd[:, None] * amp, sdd[:, None] * amp


def polynomial_coefficients(profile: Profile = "quintic") -> np.ndarray:
    """Coefficients of the normalised point-to-point polynomial on ``tau`` in [0, 1].

    Both profiles satisfy ``s(0) = s'(0) = s''(0) = 0`` and ``s(1) = 1, s'(1) = s''(1) = 0``
    (Eq. (16)); the ``"sextic"`` one adds the condition of Sec. III-B that the jerk vanishes at the
    goal, ``s'''(1) = 0``. The coefficients are found by solving the boundary-condition system.

    Args:
        profile: ``"quintic"`` (order 5) or ``"sextic"`` (order 6).

    Returns:
        (order + 1,) coefficients, lowest power first (``numpy.polynomial`` convention).
    """
    if profile not in _PROFILES:
        raise ConfigError(f"profile must be one of {_PROFILES}, got {profile!r}")
    order = 5 if profile == "quintic" else 6
    conditions = [(0.0, 0, 0.0), (0.0, 1, 0.0), (0.0, 2, 0.0), (1.0, 0, 1.0), (1.0, 1, 0.0), (1.0, 2, 0.0)]
    if profile == "sextic":
        conditions.append((1.0, 3, 0.0))
    basis = np.eye(order + 1)
    A = np.array(
        [
            [np.polynomial.polynomial.polyval(tau, np.polynomial.polynomial.polyder(b, d)) for b in basis]
            for tau, d, _ in conditions
        ]
    )
    rhs = np.array([v for _, _, v in conditions])
    return np.linalg.solve(A, rhs)


def conditioning_ratio(
    i: int, j: int, profile: Profile = "quintic", duration_s: float = 0.5, n_nodes: int = 16
) -> float:
    """Conditioning ratio ``C_ij`` of Eq. (17) of the conditioning paper.

    ``C_ij = mean(q^(i)(t)²) / mean(q^(j)(t)²)`` over ``0 <= t <= t_f``, the ratio of the squared
    mean values of the ``i``-th and ``j``-th time derivatives of the profile; values near 1 mean the
    columns of the observation matrix have similar magnitudes. The amplitude cancels. The means are
    computed by Gauss-Legendre quadrature with ``n_nodes`` nodes (exact for these polynomials when
    ``2 n_nodes - 1 >= 12``).

    Args:
        i, j: derivative orders in 0..4 (0: position, 1: velocity, 2: acceleration, 3: jerk).
        profile: ``"quintic"`` (Eq. (16)) or ``"sextic"`` (extra ``jerk(t_f) = 0``).
        duration_s: s, ``t_f`` (> 0); ``C_ij`` scales as ``t_f^(2 (j - i))``.
        n_nodes: quadrature nodes (>= 7).

    Returns:
        ``C_ij`` in s^(2 (j - i)).
    """
    for name, k in (("i", i), ("j", j)):
        if int(k) != k or not 0 <= k <= 4:
            raise ConfigError(f"{name} must be a derivative order in 0..4, got {k!r}")
    if not (np.isfinite(duration_s) and duration_s > 0):
        raise ConfigError(f"duration_s must be a positive finite number, got {duration_s!r}")
    if int(n_nodes) != n_nodes or n_nodes < 7:
        raise ConfigError(f"n_nodes must be an integer >= 7 (exact up to degree 13), got {n_nodes!r}")
    coef = polynomial_coefficients(profile)
    nodes, weights = np.polynomial.legendre.leggauss(int(n_nodes))
    tau, w = 0.5 * (nodes + 1.0), 0.5 * weights  # map [-1, 1] -> [0, 1]

    def mean_square(order: int) -> float:
        d = np.polynomial.polynomial.polyval(tau, np.polynomial.polynomial.polyder(coef, order))
        return float(np.sum(w * d * d)) / duration_s ** (2 * order)

    return mean_square(int(i)) / mean_square(int(j))


def window_durations(k_max: int = 26, base_s: float = 0.040, step_s: float = 0.010) -> np.ndarray:
    """Interpolation times ``T_k = 40 ms + k · 10 ms``, k = 1..k_max (Sec. IV-B of the conditioning paper).

    Returns:
        (k_max,) s.
    """
    if int(k_max) != k_max or k_max < 1:
        raise ConfigError(f"k_max must be a positive integer, got {k_max!r}")
    if not (base_s >= 0 and step_s > 0):
        raise ConfigError(f"need base_s >= 0 and step_s > 0, got base_s={base_s!r}, step_s={step_s!r}")
    return base_s + step_s * np.arange(1, int(k_max) + 1)


def observation_durations(
    k_max: int = 26, extra_s: float = 0.070, base_s: float = 0.040, step_s: float = 0.010
) -> np.ndarray:
    """Observation windows ``T_obs = T_k + 70 ms`` (Sec. IV-C of the conditioning paper).

    Args:
        k_max: number of windows.
        extra_s: s, observation time after the goal is reached (>= 0).
        base_s, step_s: s, passed to :func:`window_durations`.

    Returns:
        (k_max,) s.
    """
    if not (np.isfinite(extra_s) and extra_s >= 0):
        raise ConfigError(f"extra_s must be a finite number >= 0, got {extra_s!r}")
    return window_durations(k_max, base_s=base_s, step_s=step_s) + extra_s
