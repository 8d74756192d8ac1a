"""The position-dependent Cartesian hand impedance of paper 002 (thesis §2.2, Eqs. 2.2.2–2.2.4).

Each diagonal stiffness entry is a quadratic polynomial of the hand position ``q_h = (x, y)`` in
the shoulder frame (Eq. 2.2.4),

    K_**(x, y) = k_0 + k_1 x + k_2 y + k_3 x² + 2 k_4 x y + k_5 y²,

plus an optional co-contraction part ``k_σ·σ`` (Eq. 2.2.4, ``K_cont``), and the damping is
``D = diag(δ_xx √K_xx, δ_yy √K_yy)`` (Eq. 2.2.2). The thesis's values are Tables 3.1 and 3.2;
:data:`THESIS_FIELD` holds them. They are 10–100× physiological hand stiffness (spec 002), so the
field carries a ``stiffness_scale`` that multiplies every stiffness coefficient (damping follows
through ``√K``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from armlab.errors import ConfigError

__all__ = [
    "QUADRATIC_TERMS",
    "THESIS_FIELD",
    "QuadraticImpedanceField",
    "quadratic_basis",
]

#: The six monomials of Eq. 2.2.4 in the order of Table 3.1 (k_0 … k_5); ``2xy`` carries the factor 2.
QUADRATIC_TERMS: tuple[str, ...] = ("1", "x", "y", "x^2", "2xy", "y^2")


def quadratic_basis(q: np.ndarray) -> np.ndarray:
    """The monomials of Eq. 2.2.4 at positions ``q``.

    Args:
        q: (..., 2) m, positions (x, y) in the frame of the coefficients.

    Returns:
        (..., 6): ``[1, x, y, x², 2xy, y²]`` (units 1, m, m, m², m², m²).
    """
    q = np.asarray(q, dtype=float)
    if q.shape[-1] != 2:
        raise ConfigError(f"positions must have a last axis of length 2 (x, y), got shape {q.shape}")
    x, y = q[..., 0], q[..., 1]
    return np.stack([np.ones_like(x), x, y, x * x, 2.0 * x * y, y * y], axis=-1)


@dataclass(frozen=True, kw_only=True)
class QuadraticImpedanceField:
    """A diagonal, position-dependent hand stiffness and damping (Eqs. 2.2.2–2.2.4).

    Attributes:
        coefficients: (2, 6) N/m per power of metres; row 0 the ``K_xx`` polynomial, row 1 ``K_yy``,
            columns ``k_0 … k_5`` in the order of :data:`QUADRATIC_TERMS`.
        k_sigma: (2,) N/m, the co-contraction stiffness ``k_σxx, k_σyy`` multiplied by ``σ``.
        delta: (2,) √kg, the damping factors ``δ_xx, δ_yy`` of Eq. 2.2.2 (D = δ√K is in N·s/m
            when K is in N/m).
        stiffness_scale: dimensionless factor on every stiffness coefficient (> 0); 1 is the thesis.
    """

    coefficients: tuple[tuple[float, ...], tuple[float, ...]]
    k_sigma: tuple[float, float] = (0.0, 0.0)
    delta: tuple[float, float] = (1.0, 1.0)
    stiffness_scale: float = 1.0
    _c: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        c = np.asarray(self.coefficients, dtype=float)
        if c.shape != (2, 6) or not np.all(np.isfinite(c)):
            raise ConfigError(
                f"coefficients must be a finite (2, 6) table (K_xx, K_yy rows; k_0..k_5), got {c.shape}"
            )
        for name in ("k_sigma", "delta"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (2,) or not np.all(np.isfinite(v)) or np.any(v < 0):
                raise ConfigError(
                    f"{name} must be two finite non-negative numbers (x, y), got {getattr(self, name)!r}"
                )
        if not (np.isfinite(self.stiffness_scale) and self.stiffness_scale > 0):
            raise ConfigError(
                f"stiffness_scale must be a positive finite number, got {self.stiffness_scale!r}"
            )
        object.__setattr__(self, "_c", c * self.stiffness_scale)

    @property
    def scaled_coefficients(self) -> np.ndarray:
        """(2, 6) N/m per power of metres: the coefficients times ``stiffness_scale`` (a copy)."""
        return self._c.copy()

    def coefficients_at(self, sigma: float = 0.0) -> np.ndarray:
        """(2, 6) N/m per power of metres: the Eq. 2.2.4 polynomials of ``K_xx, K_yy`` at one σ.

        ``K_cont = diag(k_σ)·σ`` (Eq. 2.2.4) is constant in q, so it adds ``k_σ·stiffness_scale·σ``
        to the constant column ``k_0``; at σ = 0 this is :attr:`scaled_coefficients`.

        Args:
            sigma: co-contraction index in [0, 1].

        Raises:
            ConfigError: where ``sigma`` lies outside [0, 1].
        """
        if not (np.isfinite(sigma) and 0.0 <= sigma <= 1.0):
            raise ConfigError(f"sigma (co-contraction index) must lie in [0, 1], got {sigma!r}")
        c = self._c.copy()
        c[:, 0] += np.asarray(self.k_sigma) * self.stiffness_scale * sigma
        return c

    def scaled(self, stiffness_scale: float) -> QuadraticImpedanceField:
        """The same field with another ``stiffness_scale``."""
        return QuadraticImpedanceField(
            coefficients=self.coefficients,
            k_sigma=self.k_sigma,
            delta=self.delta,
            stiffness_scale=stiffness_scale,
        )

    def stiffness(self, q: np.ndarray, sigma: float | np.ndarray = 0.0) -> np.ndarray:
        """Diagonal stiffness ``(K_xx, K_yy)``, Eq. 2.2.4 with ``K_cont = diag(k_σ)·σ``.

        Args:
            q: (..., 2) m, hand positions in the shoulder frame.
            sigma: co-contraction index in [0, 1], scalar or broadcastable to ``q[..., 0]``.

        Returns:
            (..., 2) N/m.
        """
        sig = np.asarray(sigma, dtype=float)
        if np.any((sig < 0) | (sig > 1)):
            raise ConfigError("sigma (co-contraction index) must lie in [0, 1]")
        k_cont = np.asarray(self.k_sigma) * self.stiffness_scale
        # a sum over the 6 terms: a (n, 6) @ (6, 2) matmul goes through BLAS and is ~10× slower here
        b = quadratic_basis(q)
        k = sum(b[..., j, None] * self._c[:, j] for j in range(6))
        return k + sig[..., None] * k_cont

    def damping(self, q: np.ndarray, sigma: float | np.ndarray = 0.0) -> np.ndarray:
        """Diagonal damping ``(D_xx, D_yy) = δ·√K``, Eq. 2.2.2.

        Args:
            q: (..., 2) m.
            sigma: co-contraction index in [0, 1].

        Returns:
            (..., 2) N·s/m.

        Raises:
            ConfigError: where the stiffness is negative (√K undefined), naming the first position.
        """
        return self._root(self.stiffness(q, sigma), q)

    def _root(self, k: np.ndarray, q: np.ndarray) -> np.ndarray:
        if np.any(k < 0):
            bad = np.atleast_2d(np.asarray(q, dtype=float))[np.atleast_1d(np.any(k < 0, axis=-1))][0]
            raise ConfigError(f"the stiffness field is negative at q = {bad} m: D = δ√K is undefined there")
        return np.asarray(self.delta) * np.sqrt(k)

    def force(
        self, q_h: np.ndarray, qd_h: np.ndarray, q_p: np.ndarray, sigma: float | np.ndarray = 0.0
    ) -> np.ndarray:
        """Hand force ``F = D(q_h)·q̇_h + K(q_h)·q_p``, Eq. 2.2.1 without inertia (thesis Ch. 3).

        Args:
            q_h: (..., 2) m, hand position; qd_h: (..., 2) m/s, hand velocity; q_p: (..., 2) m,
                perturbation displacement.
            sigma: co-contraction index in [0, 1].

        Returns:
            (..., 2) N.
        """
        k = self.stiffness(q_h, sigma)
        return self._root(k, q_h) * np.asarray(qd_h) + k * np.asarray(q_p)


#: Tables 3.1 (k_x*, k_y*, N/m per power of m; k_σ in N/m) and 3.2 (δ = 1) of the thesis (paper 002).
THESIS_FIELD = QuadraticImpedanceField(
    coefficients=(
        # k_x0, k_x1, k_x2, k_x3, k_x4, k_x5: Table 3.1, N/m, N/m², N/m², N/m³, N/m³, N/m³
        (5.381e3, 1.186e4, -1.060e4, 5.195e3, -2.164e4, -5.539e3),
        # k_y0, k_y1, k_y2, k_y3, k_y4, k_y5: Table 3.1, same units
        (4.497e3, 1.357e4, -1.011e4, 1.226e4, -2.380e4, 6.562e3),
    ),
    k_sigma=(10.2912, 19.809),  # k_σxx, k_σyy: Table 3.1, N/m (per unit σ)
    delta=(1.0, 1.0),  # δ_xx, δ_yy: Table 3.2 (D = δ√K, Eq. 2.2.2)
)
