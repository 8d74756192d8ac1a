"""Reference hand paths of paper 002's simulations (thesis Ch. 3), as functions of *path time*.

Path time ``s`` runs only while the reference moves (the reference stops during every perturbation,
§3.1.1 and §3.2.1); :mod:`armlab.perturbations.cartesian_timeline` maps wall time to path time.

- :func:`table_3_3_path`: the piecewise-linear motion of Exp. 1 (Table 3.3 waypoints);
- :func:`circle_path`: Exps. 2 and 4, centre (0.95, 0.1) m, R = 0.1 m, 100 s (one revolution is an
  assumption: the thesis gives no angular speed);
- :func:`sinusoid_path`: Exp. 3, ``x = 0.95 + 0.1 sin(ω s)``, ``y = 0``, with ω the golden angle per
  perturbation spacing by default (see :func:`golden_omega`);
- :func:`spiral_path`: Exp. 5, the circle with its radius shrinking linearly from 100 % to 10 %.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from armlab.errors import ConfigError

__all__ = [
    "CIRCLE_CENTRE_M",
    "CIRCLE_RADIUS_M",
    "MOTION_DURATION_S",
    "TABLE_3_3",
    "ReferencePath",
    "circle_path",
    "golden_omega",
    "sinusoid_path",
    "spiral_path",
    "table_3_3_path",
]

#: Thesis §3.2.1: circle centre O{0.95, 0.1}, m (shoulder frame).
CIRCLE_CENTRE_M: tuple[float, float] = (0.95, 0.1)
#: Thesis §3.2.1: circle radius R, m.
CIRCLE_RADIUS_M = 0.1
#: Thesis §3.1.1 (Table 3.3) and §3.2.1: motion duration, s.
MOTION_DURATION_S = 100.0
#: Table 3.3 waypoints: (x m, y m, t s).
TABLE_3_3: tuple[tuple[float, float, float], ...] = (
    (0.95, 0.10, 0.0),
    (0.95, 0.20, 12.5),
    (0.95, 0.00, 37.5),
    (0.95, 0.10, 50.0),
    (1.10, 0.10, 62.5),
    (0.80, 0.10, 87.5),
    (0.95, 0.10, 100.0),
)

Kind = Literal["waypoints", "circle", "sinusoid", "spiral"]


@dataclass(frozen=True, kw_only=True)
class ReferencePath:
    """A planar reference path ``q_r(s)`` over path time ``s ∈ [0, duration_s]``.

    Attributes:
        kind: which family (``waypoints``, ``circle``, ``sinusoid``, ``spiral``).
        duration_s: s, path-time length (> 0).
        centre: (2,) m, centre of the circle/spiral, or bias of the sinusoid (x, y).
        radius_m: m, circle radius, sinusoid amplitude, or the spiral's initial radius.
        omega_rad_s: rad/s, angular rate (circle, spiral) or sinusoid frequency.
        end_radius_fraction: spiral radius at the end as a fraction of ``radius_m`` (1 otherwise).
        waypoints: ((x, y, s), ...) m, m, s for ``waypoints`` (increasing s from 0 to duration).
    """

    kind: Kind
    duration_s: float = MOTION_DURATION_S
    centre: tuple[float, float] = CIRCLE_CENTRE_M
    radius_m: float = CIRCLE_RADIUS_M
    omega_rad_s: float = 2 * np.pi / MOTION_DURATION_S
    end_radius_fraction: float = 1.0
    waypoints: tuple[tuple[float, float, float], ...] = ()

    def __post_init__(self) -> None:
        kinds = ("waypoints", "circle", "sinusoid", "spiral")
        if self.kind not in kinds:
            raise ConfigError(f"unknown reference path kind {self.kind!r}; valid: {', '.join(kinds)}")
        if not (np.isfinite(self.duration_s) and self.duration_s > 0):
            raise ConfigError(f"duration_s must be positive, got {self.duration_s!r}")
        if not (np.isfinite(self.radius_m) and self.radius_m >= 0 and np.isfinite(self.omega_rad_s)):
            raise ConfigError(
                "radius_m must be a non-negative number and omega_rad_s finite, "
                f"got radius_m={self.radius_m!r}, omega_rad_s={self.omega_rad_s!r}"
            )
        c = np.asarray(self.centre, dtype=float)
        if c.shape != (2,) or not np.all(np.isfinite(c)):
            raise ConfigError(f"centre must be two finite numbers (x, y) m, got {self.centre!r}")
        if not (0 < self.end_radius_fraction <= 1):
            raise ConfigError(f"end_radius_fraction must lie in (0, 1], got {self.end_radius_fraction!r}")
        if self.kind != "spiral" and self.end_radius_fraction != 1:
            raise ConfigError(
                f"end_radius_fraction={self.end_radius_fraction!r} is read by kind 'spiral' only; "
                f"a {self.kind!r} path needs 1"
            )
        if self.kind == "waypoints":
            w = np.asarray(self.waypoints, dtype=float)
            if w.ndim != 2 or w.shape[1] != 3 or len(w) < 2:
                raise ConfigError("waypoints must be at least two (x, y, s) rows")
            if w[0, 2] != 0 or not np.all(np.diff(w[:, 2]) > 0) or not np.isclose(w[-1, 2], self.duration_s):
                raise ConfigError(f"waypoint times must increase from 0 to duration_s = {self.duration_s} s")

    def position(self, s: np.ndarray) -> np.ndarray:
        """Reference position at path times ``s`` (clipped to ``[0, duration_s]``).

        Args:
            s: (...) s.

        Returns:
            (..., 2) m.
        """
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.duration_s)
        cx, cy = self.centre
        if self.kind == "waypoints":
            w = np.asarray(self.waypoints, dtype=float)
            return np.stack([np.interp(s, w[:, 2], w[:, 0]), np.interp(s, w[:, 2], w[:, 1])], axis=-1)
        if self.kind == "sinusoid":
            return np.stack([cx + self.radius_m * np.sin(self.omega_rad_s * s), np.full_like(s, cy)], axis=-1)
        r = self.radius_m * (1.0 - (1.0 - self.end_radius_fraction) * s / self.duration_s)
        phase = self.omega_rad_s * s
        return np.stack([cx + r * np.cos(phase), cy + r * np.sin(phase)], axis=-1)

    def velocity(self, s: np.ndarray) -> np.ndarray:
        """Path-time derivative ``dq_r/ds`` at ``s`` (one-sided at waypoint corners).

        Args:
            s: (...) s.

        Returns:
            (..., 2) m/s; 0 outside ``[0, duration_s)``.
        """
        s = np.asarray(s, dtype=float)
        inside = ((s >= 0) & (s < self.duration_s))[..., None]
        if self.kind == "waypoints":
            w = np.asarray(self.waypoints, dtype=float)
            seg = np.clip(np.searchsorted(w[:, 2], s, side="right") - 1, 0, len(w) - 2)
            slope = np.diff(w[:, :2], axis=0) / np.diff(w[:, 2])[:, None]
            return np.where(inside, slope[seg], 0.0)
        if self.kind == "sinusoid":
            vx = self.radius_m * self.omega_rad_s * np.cos(self.omega_rad_s * s)
            return np.where(inside, np.stack([vx, np.zeros_like(s)], axis=-1), 0.0)
        rate = -self.radius_m * (1.0 - self.end_radius_fraction) / self.duration_s
        r = self.radius_m + rate * s
        phase = self.omega_rad_s * s
        c, sn = np.cos(phase), np.sin(phase)
        v = np.stack([rate * c - r * self.omega_rad_s * sn, rate * sn + r * self.omega_rad_s * c], axis=-1)
        return np.where(inside, v, 0.0)


def table_3_3_path() -> ReferencePath:
    """Exp. 1's piecewise-linear motion through the Table 3.3 waypoints (100 s)."""
    return ReferencePath(kind="waypoints", waypoints=TABLE_3_3, duration_s=TABLE_3_3[-1][2])


def circle_path(revolutions: float = 1.0) -> ReferencePath:
    """Exps. 2 and 4: the §3.2.1 circle over 100 s (*assumption*: one revolution by default)."""
    if not (np.isfinite(revolutions) and revolutions > 0):
        raise ConfigError(f"revolutions must be positive, got {revolutions!r}")
    return ReferencePath(kind="circle", omega_rad_s=2 * np.pi * revolutions / MOTION_DURATION_S)


def spiral_path(end_radius_fraction: float = 0.1, revolutions: float = 1.0) -> ReferencePath:
    """Exp. 5 (§3.5.1): the circle with its radius decaying linearly 100 % → ``end_radius_fraction``."""
    if not (np.isfinite(revolutions) and revolutions > 0):
        raise ConfigError(f"revolutions must be positive, got {revolutions!r}")
    return ReferencePath(
        kind="spiral",
        omega_rad_s=2 * np.pi * revolutions / MOTION_DURATION_S,
        end_radius_fraction=end_radius_fraction,
    )


def golden_omega(spacing_s: float) -> float:
    """Sinusoid frequency whose phase advances by the golden angle between perturbations, rad/s.

    With stops every ``spacing_s`` of path time, the phase at the k-th stop is ``k·ω·spacing_s``
    mod 2π. A period that divides a small multiple of the spacing (e.g. 20 s for 5 s spacing: 4
    phases, two x-values, spec 002's trap) leaves the quadratic of Exp. 3 unidentifiable. The
    golden angle 2π(1 − 1/φ) ≈ 2.400 rad is the rotation whose multiples stay most evenly spread
    on the circle for any count (three-distance theorem), so every stop sees a distinct phase
    and no two consecutive stops land near each other. For 5 s spacing: ω ≈ 0.480 rad/s
    (period ≈ 13.1 s, peak reference speed 0.048 m/s at 0.1 m amplitude).

    Args:
        spacing_s: s, path time between perturbations (> 0).
    """
    if not (np.isfinite(spacing_s) and spacing_s > 0):
        raise ConfigError(f"spacing_s must be positive, got {spacing_s!r}")
    golden_angle = 2 * np.pi * (1 - 2 / (1 + np.sqrt(5)))
    return float(golden_angle / spacing_s)


def sinusoid_path(omega_rad_s: float | None = None, spacing_s: float = 5.0) -> ReferencePath:
    """Exp. 3 (§3.3.1): ``x = 0.95 + 0.1 sin(ω s)``, ``y = 0``, over 100 s.

    Args:
        omega_rad_s: rad/s; default :func:`golden_omega` of ``spacing_s`` (the thesis gives none).
        spacing_s: s, path time between perturbations, used for the default ω.
    """
    omega = golden_omega(spacing_s) if omega_rad_s is None else omega_rad_s
    return ReferencePath(kind="sinusoid", centre=(CIRCLE_CENTRE_M[0], 0.0), omega_rad_s=omega)
