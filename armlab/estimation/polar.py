"""The polar form of paper 002's hand impedance (thesis §2.2.2, Eqs. 2.2.11–2.2.15; Exp. 5).

Positions become ``q_pol = (ρ, θ)`` about a polar origin (Eqs. 2.2.12–13), the perturbation is the
polar position of the hand minus that of the unperturbed reference (§2.2.2: "a motion without
perturbations ... transformed ... and then subtracted"), the velocity is ``(ρ̇, θ̇)`` by the chain
rule, and the force becomes a radial force and a moment about the origin (Eqs. 2.2.14–15):

    |F| = √(F_x² + F_y²),  ψ = atan2(F_y, F_x) − θ,  F_ρ = |F| cos ψ,  M = |F| ρ sin ψ.

The thesis does not state the polar origin; the default is the origin of the coordinates (the
shoulder frame of Tables 3.1 and 3.3), and any other point may be given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError

__all__ = [
    "PolarSignals",
    "polar_force",
    "polar_signals",
    "to_polar",
]


def _xy(a: np.ndarray, name: str) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.ndim < 1 or a.shape[-1] != 2:
        raise DataError(f"{name} must have a last axis of length 2 (x, y), got shape {a.shape}")
    return a


def to_polar(q: np.ndarray, origin: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """Eqs. 2.2.12–13: ``(ρ, θ)`` of positions about ``origin``.

    Args:
        q: (..., 2) m.
        origin: (2,) m, the polar origin (default the shoulder-frame origin).

    Returns:
        (..., 2): ρ in m, θ in rad in [−π, π].
    """
    d = _xy(q, "q") - np.asarray(origin, dtype=float)
    return np.stack([np.hypot(d[..., 0], d[..., 1]), np.arctan2(d[..., 1], d[..., 0])], axis=-1)


def polar_force(force: np.ndarray, q: np.ndarray, origin: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """Eqs. 2.2.14–15: radial force and moment ``(F_ρ, M)`` at positions ``q``.

    Args:
        force: (..., 2) N, Cartesian force.
        q: (..., 2) m, where it acts.
        origin: (2,) m, polar origin.

    Returns:
        (..., 2): F_ρ in N, M in N·m.
    """
    f = _xy(force, "force")
    pol = to_polar(q, origin)
    mag = np.hypot(f[..., 0], f[..., 1])
    psi = np.arctan2(f[..., 1], f[..., 0]) - pol[..., 1]
    return np.stack([mag * np.cos(psi), mag * pol[..., 0] * np.sin(psi)], axis=-1)


@dataclass(frozen=True, kw_only=True, eq=False)
class PolarSignals:
    """Logged signals in polar form.

    Attributes:
        q_pol: (n, 2) hand ``(ρ m, θ rad)``.
        q_p: (n, 2) perturbation ``(ρ_p m, θ_p rad)`` = hand minus reference in polar form.
        qd: (n, 2) ``(ρ̇ m/s, θ̇ rad/s)`` of the hand.
        force: (n, 2) ``(F_ρ N, M N·m)``.
    """

    q_pol: np.ndarray
    q_p: np.ndarray
    qd: np.ndarray
    force: np.ndarray


def polar_signals(
    q_h: np.ndarray,
    q_r: np.ndarray,
    qd_h: np.ndarray,
    force: np.ndarray,
    origin: tuple[float, float] = (0.0, 0.0),
) -> PolarSignals:
    """Transform logged Cartesian samples to the polar model's inputs and outputs (§2.2.2).

    Args:
        q_h: (n, 2) m, hand positions; q_r: (n, 2) m, the unperturbed reference at the same samples;
            qd_h: (n, 2) m/s, hand velocities; force: (n, 2) N.
        origin: (2,) m, polar origin.

    Returns:
        The :class:`PolarSignals`; ``θ_p`` is wrapped to (−π, π].
    """
    q_h, q_r, qd_h = _xy(q_h, "q_h"), _xy(q_r, "q_r"), _xy(qd_h, "qd_h")
    hand = to_polar(q_h, origin)
    ref = to_polar(q_r, origin)
    dp = hand - ref
    dp[..., 1] = np.angle(np.exp(1j * dp[..., 1]))
    d = q_h - np.asarray(origin, dtype=float)
    rho = hand[..., 0]
    rho_dot = (d[..., 0] * qd_h[..., 0] + d[..., 1] * qd_h[..., 1]) / rho
    theta_dot = (d[..., 0] * qd_h[..., 1] - d[..., 1] * qd_h[..., 0]) / rho**2
    return PolarSignals(
        q_pol=hand,
        q_p=dp,
        qd=np.stack([rho_dot, theta_dot], axis=-1),
        force=polar_force(force, q_h, origin),
    )
