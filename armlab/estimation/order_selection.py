"""Polynomial order selection by adjusted R² (paper 002, Exp. 5, thesis §3.5.2).

Each entry of the per-sequence K̂ and D̂ matrices is fitted, over the sequences' positions
``(u, v)`` (``(x, y)`` or ``(ρ, θ)``), by a polynomial with no cross terms,

    z ≈ c₀ + Σ_{i=1..a} c_i uⁱ + Σ_{j=1..b} d_j vʲ,      order (a, b), 1 + a + b parameters,

which is the counting the thesis's totals imply (§3.5.2: "first order in x and y" is 3 parameters
per coefficient, d₁₂'s (1, 2) is 4; 26 Cartesian and 28 polar in all). The quality is the
degree-of-freedom adjusted coefficient of determination
``R²_adj = 1 − (1 − R²)(n − 1)/(n − p − 1)`` with ``p = a + b`` regressors besides the constant.
The thesis gives no threshold; :func:`select_order` takes the lowest total order reaching one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError, DataError

__all__ = [
    "PolyFit",
    "fit_separable_polynomial",
    "parameter_count",
    "select_order",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class PolyFit:
    """A separable polynomial fit of one matrix entry over positions.

    Attributes:
        order: (a, b) orders in the first and second coordinate.
        coefficients: (1 + a + b,) ``[c₀, c₁…c_a, d₁…d_b]`` in the units of the standardised
            coordinates (see ``centre``/``spread``).
        centre: (2,) the coordinate means subtracted before fitting.
        spread: (2,) the coordinate standard deviations divided by.
        r2: coefficient of determination; r2_adj: its adjusted form (−inf when n − p − 1 <= 0).
        n: number of estimates fitted.
    """

    order: tuple[int, int]
    coefficients: np.ndarray
    centre: np.ndarray
    spread: np.ndarray
    r2: float
    r2_adj: float
    n: int

    @property
    def n_parameters(self) -> int:
        """1 + a + b."""
        return 1 + sum(self.order)

    def evaluate(self, positions: np.ndarray) -> np.ndarray:
        """The fitted polynomial at (m, 2) positions: (m,)."""
        return _design(positions, self.order, self.centre, self.spread) @ self.coefficients


def _design(pos: np.ndarray, order: tuple[int, int], centre: np.ndarray, spread: np.ndarray) -> np.ndarray:
    s = (np.asarray(pos, dtype=float) - centre) / spread
    cols = [np.ones(len(s))]
    cols += [s[:, 0] ** i for i in range(1, order[0] + 1)]
    cols += [s[:, 1] ** j for j in range(1, order[1] + 1)]
    return np.stack(cols, axis=1)


def fit_separable_polynomial(positions: np.ndarray, values: np.ndarray, order: tuple[int, int]) -> PolyFit:
    """Fit ``values`` over ``positions`` with the separable polynomial of ``order`` (§3.5.2).

    Args:
        positions: (n, 2) coordinates of each estimate (m, or m and rad).
        values: (n,) the estimates of one matrix entry.
        order: (a, b), non-negative integers.

    Raises:
        ConfigError: for a negative order; DataError: for mismatched or non-finite inputs.
    """
    pos, z = np.asarray(positions, dtype=float), np.asarray(values, dtype=float)
    if pos.ndim != 2 or pos.shape[1] != 2 or z.shape != (len(pos),):
        raise DataError(f"positions must be (n, 2) and values (n,), got {pos.shape}, {z.shape}")
    if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(z))):
        raise DataError("positions and values must be finite")
    a, b = (int(o) for o in order)
    if a < 0 or b < 0:
        raise ConfigError(f"polynomial orders must be non-negative, got {order!r}")
    centre = pos.mean(axis=0)
    spread = pos.std(axis=0)
    spread[spread == 0] = 1.0
    design = _design(pos, (a, b), centre, spread)
    coef, *_ = np.linalg.lstsq(design, z, rcond=None)
    res = z - design @ coef
    ss_tot = float(np.sum((z - z.mean()) ** 2))
    r2 = 1.0 - float(res @ res) / ss_tot if ss_tot > 0 else 1.0
    n, p = len(z), a + b
    r2_adj = 1.0 - (1.0 - r2) * (n - 1) / (n - p - 1) if n - p - 1 > 0 else -np.inf
    return PolyFit(order=(a, b), coefficients=coef, centre=centre, spread=spread, r2=r2, r2_adj=r2_adj, n=n)


def select_order(
    positions: np.ndarray, values: np.ndarray, *, threshold: float = 0.999, max_order: int = 3
) -> PolyFit:
    """The lowest-total-order separable fit whose ``R²_adj`` reaches ``threshold`` (§3.5.2).

    Ties in total order go to the higher ``R²_adj``; when no order up to ``max_order`` in each
    coordinate reaches the threshold, the best ``R²_adj`` is returned.

    Args:
        positions: (n, 2); values: (n,).
        threshold: R²_adj to reach (the thesis gives none; 0.999 is spec 002's acceptance level).
        max_order: highest order tried per coordinate.
    """
    if not (0 < threshold < 1):
        raise ConfigError(f"threshold must lie in (0, 1), got {threshold!r}")
    if not (isinstance(max_order, int) and max_order >= 0):
        raise ConfigError(f"max_order must be a non-negative integer, got {max_order!r}")
    fits = [
        fit_separable_polynomial(positions, values, (a, b))
        for a in range(max_order + 1)
        for b in range(max_order + 1)
    ]
    good = [f for f in fits if f.r2_adj >= threshold]
    if good:
        return min(good, key=lambda f: (sum(f.order), -f.r2_adj))
    return max(fits, key=lambda f: f.r2_adj)


def parameter_count(orders: dict[str, tuple[int, int]] | list[tuple[int, int]]) -> int:
    """Total parameters of a model whose entries have the given orders: ``Σ (1 + a + b)``.

    The thesis's Exp. 5 (§3.5.2): Cartesian K all (1, 1), D diagonal (1, 1), d₁₂ (1, 2), d₂₁ (2, 1)
    → 26; polar K and D diagonal (1, 1), anti-diagonal (1, 2) → 28.
    """
    items = orders.values() if isinstance(orders, dict) else orders
    return int(sum(1 + int(a) + int(b) for a, b in items))
