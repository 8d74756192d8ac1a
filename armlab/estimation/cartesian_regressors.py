"""Regressors of paper 002's Cartesian identification, Exps. 1–5 (thesis §3.1.2–3.5.2).

Each returns the rows ``φᵀ`` (n, p) of the model ``F_a = φᵀ θ`` for one force axis ``a`` (0 = x,
1 = y) and the names of ``θ``. Inputs are the logged samples: hand position ``q_h`` (n, 2) m,
perturbation displacement ``q_p`` (n, 2) m and hand velocity ``qd_h`` (n, 2) m/s.

====  ==========================================  =========================================
exp   φ for axis a                                θ
====  ==========================================  =========================================
1     [p_a, v_a]                                  K_aa, D_aa
2     [x_p, y_p, v_a]                             K_ax, K_ay, D_aa
3     [x_p, x x_p, x² x_p, ẋ]                     k_x0, k_x1, k_x3, D_xx
4     [1, x, y, x², 2xy, y²]·p_a, ẋ, ẏ (3.4.1)    k_a0 … k_a5, D_ax, D_ay
5     [p_1, p_2, v_1, v_2]                        K_a1, K_a2, D_a1, D_a2 (any coordinates)
full  [basis·x_p, basis·y_p, ẋ, ẏ]                a full quadratic K row (rotated frames)
====  ==========================================  =========================================
"""

from __future__ import annotations

import numpy as np

from armlab.errors import ConfigError, DataError
from armlab.models.cartesian_field import QUADRATIC_TERMS, quadratic_basis

__all__ = [
    "full_quadratic_regressor",
    "linear_axis_regressor",
    "linear_coupled_regressor",
    "linear_full_regressor",
    "quadratic_field_regressor",
    "quadratic_x_regressor",
]

_AXES = "xy"


def _inputs(*arrays: np.ndarray) -> list[np.ndarray]:
    out = [np.asarray(a, dtype=float) for a in arrays]
    n = out[0].shape[0]
    for a in out:
        if a.shape != (n, 2):
            raise DataError(f"positions, displacements and velocities must be (n, 2), got {a.shape}")
    return out


def _axis(axis: int) -> int:
    if axis not in (0, 1):
        raise ConfigError(f"axis must be 0 (x) or 1 (y), got {axis!r}")
    return axis


def linear_axis_regressor(q_p: np.ndarray, qd_h: np.ndarray, axis: int) -> tuple[np.ndarray, tuple[str, ...]]:
    """Exp. 1 (§3.1.2): ``φ_a = [a_p, ȧ_h]`` → ``(K_aa, D_aa)``; returns (n, 2) and names."""
    q_p, qd_h = _inputs(q_p, qd_h)
    a = _axis(axis)
    c = _AXES[a]
    return np.stack([q_p[:, a], qd_h[:, a]], axis=1), (f"K_{c}{c}", f"D_{c}{c}")


def linear_coupled_regressor(
    q_p: np.ndarray, qd_h: np.ndarray, axis: int
) -> tuple[np.ndarray, tuple[str, ...]]:
    """Exp. 2 (§3.2.2): ``φ_a = [x_p, y_p, ȧ_h]`` → ``(K_ax, K_ay, D_aa)``; (n, 3) and names."""
    q_p, qd_h = _inputs(q_p, qd_h)
    a = _axis(axis)
    c = _AXES[a]
    return np.stack([q_p[:, 0], q_p[:, 1], qd_h[:, a]], axis=1), (f"K_{c}x", f"K_{c}y", f"D_{c}{c}")


def linear_full_regressor(q_p: np.ndarray, qd: np.ndarray, axis: int) -> tuple[np.ndarray, tuple[str, ...]]:
    """Exp. 5 (§3.5.2): ``φ = [p_1, p_2, v_1, v_2]`` → row ``a`` of a full K and D (n, 4).

    The thesis's Exp. 5 reports off-diagonal damping, so both velocities enter; the coordinates
    may be Cartesian or polar (``(ρ_p, θ_p)``, ``(ρ̇, θ̇)``).
    """
    q_p, qd = _inputs(q_p, qd)
    a = _axis(axis) + 1
    names = (f"K_{a}1", f"K_{a}2", f"D_{a}1", f"D_{a}2")
    return np.concatenate([q_p, qd], axis=1), names


def quadratic_x_regressor(
    q_h: np.ndarray, q_p: np.ndarray, qd_h: np.ndarray
) -> tuple[np.ndarray, tuple[str, ...]]:
    """Exp. 3 (§3.3.2): ``φ = [x_p, x_h x_p, x_h² x_p, ẋ_h]`` → ``(k_x0, k_x1, k_x3, D_xx)``; (n, 4)."""
    q_h, q_p, qd_h = _inputs(q_h, q_p, qd_h)
    x, xp = q_h[:, 0], q_p[:, 0]
    return np.stack([xp, x * xp, x * x * xp, qd_h[:, 0]], axis=1), ("k_x0", "k_x1", "k_x3", "D_xx")


def quadratic_field_regressor(
    q_h: np.ndarray, q_p: np.ndarray, qd_h: np.ndarray, axis: int
) -> tuple[np.ndarray, tuple[str, ...]]:
    """Exp. 4, Eq. 3.4.1: ``φ_a = [1, x, y, x², 2xy, y²]·a_p, ẋ_h, ẏ_h`` → ``k_a0 … k_a5, D_ax, D_ay``.

    Returns:
        (n, 8) rows and the names; ``φ_aᵀ[:6]`` is the Eq. 2.2.4 polynomial times ``a_p``, so
        ``φᵀθ`` is exactly the model force when ``θ[:6]`` are Table 3.1's row and ``D`` is
        evaluated where the hand is.
    """
    q_h, q_p, qd_h = _inputs(q_h, q_p, qd_h)
    a = _axis(axis)
    c = _AXES[a]
    phi = np.concatenate([quadratic_basis(q_h) * q_p[:, a : a + 1], qd_h], axis=1)
    return phi, tuple(f"k_{c}{i}" for i in range(6)) + (f"D_{c}x", f"D_{c}y")


def full_quadratic_regressor(
    q_h: np.ndarray, q_p: np.ndarray, qd_h: np.ndarray, axis: int
) -> tuple[np.ndarray, tuple[str, ...]]:
    """A full-matrix quadratic stiffness row: ``F_a = Σ_b K_ab(q_h) b_p + D_ax ẋ + D_ay ẏ`` (n, 14).

    Needed after a frame *rotation* (Appendix A): ``A K Aᵀ`` is no longer diagonal, but each
    entry is still a quadratic polynomial of the position, so Eq. 3.4.1 extends to both
    displacement components. Parameter order: the six ``K_ax`` terms, the six ``K_ay`` terms, then
    ``D_ax, D_ay``.
    """
    q_h, q_p, qd_h = _inputs(q_h, q_p, qd_h)
    a = _axis(axis)
    c = _AXES[a]
    b = quadratic_basis(q_h)
    phi = np.concatenate([b * q_p[:, :1], b * q_p[:, 1:], qd_h], axis=1)
    names = tuple(f"k_{c}x[{t}]" for t in QUADRATIC_TERMS) + tuple(f"k_{c}y[{t}]" for t in QUADRATIC_TERMS)
    return phi, names + (f"D_{c}x", f"D_{c}y")
