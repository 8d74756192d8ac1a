"""A rigid (or any affine) change of frame of the quadratic stiffness field (paper 002, Appendix A).

Appendix A argues that recording in the robot's base frame instead of the shoulder frame keeps
the quadratic form of Eq. 2.2.4; its printed coefficients drop terms (``k₄*`` and ``k₀*`` miss the
cross and linear parts of ``bᵀHb`` and ``2bᵀH A q``). Here the transform is done with matrices.
Write one polynomial as ``K(q) = k₀ + gᵀq + qᵀHq``, ``g = (k₁, k₂)``, ``H = [[k₃, k₄], [k₄, k₅]]``.
New coordinates ``q* = A q + b`` give ``q = M (q* − b)`` with ``M = A⁻¹``, and

    K*(q*) = K(q) = k₀*  + g*ᵀq* + q*ᵀH*q*,
    H* = MᵀHM,   g* = Mᵀg − 2H*b,   k₀* = k₀ − gᵀMb + bᵀH*b.

That is the scalar statement (each entry stays quadratic). The stiffness *matrix* also turns:
with a rotation ``A``, forces and displacements map by ``A``, so ``K*(q*) = A K(q) Aᵀ``, full in
general but with every entry still quadratic in ``q*`` (:func:`matrix_field_in_new_frame`).
"""

from __future__ import annotations

import numpy as np

from armlab.errors import ConfigError
from armlab.models.cartesian_field import QuadraticImpedanceField, quadratic_basis

__all__ = [
    "evaluate_matrix_field",
    "matrix_field_in_new_frame",
    "polynomial_in_new_frame",
    "rotation",
]


def rotation(angle_rad: float) -> np.ndarray:
    """The 2-D rotation matrix of Appendix A, ``[[cos, −sin], [sin, cos]]`` (2, 2)."""
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    return np.array([[c, -s], [s, c]])


def _affine(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != (2, 2) or b.shape != (2,):
        raise ConfigError(f"a frame change needs A (2, 2) and b (2,), got {a.shape} and {b.shape}")
    if abs(np.linalg.det(a)) < 1e-12:
        raise ConfigError("the frame change matrix A must be invertible")
    return a, b


def polynomial_in_new_frame(k: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Coefficients ``k*`` with ``K*(A q + b) = K(q)`` for one Eq. 2.2.4 polynomial (Appendix A).

    Args:
        k: (..., 6) ``k₀ … k₅`` (order of :data:`armlab.models.cartesian_field.QUADRATIC_TERMS`).
        a: (2, 2) the frame change matrix (Appendix A: a rotation); b: (2,) m, its offset.

    Returns:
        (..., 6) the coefficients in the new coordinates, same units.
    """
    a, b = _affine(a, b)
    k = np.asarray(k, dtype=float)
    if k.shape[-1] != 6:
        raise ConfigError(f"coefficients must have a last axis of 6 (k0..k5), got {k.shape}")
    m = np.linalg.inv(a)
    g = k[..., 1:3]
    h = np.stack([np.stack([k[..., 3], k[..., 4]], -1), np.stack([k[..., 4], k[..., 5]], -1)], -2)
    h_new = m.T @ h @ m
    g_new = g @ m - 2 * h_new @ b
    k0_new = k[..., 0] - g @ (m @ b) + b @ h_new @ b
    return np.stack(
        [k0_new, g_new[..., 0], g_new[..., 1], h_new[..., 0, 0], h_new[..., 0, 1], h_new[..., 1, 1]], -1
    )


def matrix_field_in_new_frame(
    field: QuadraticImpedanceField, a: np.ndarray, b: np.ndarray, sigma: float = 0.0
) -> np.ndarray:
    """The stiffness matrix field seen in the frame ``q* = A q + b``: ``K*(q*) = A K(q) Aᵀ``.

    Args:
        field: the diagonal field (its coefficients at ``sigma``: ``field.coefficients_at(sigma)``).
        a: (2, 2) an orthogonal frame change (vectors map by ``A``); b: (2,) m.
        sigma: co-contraction index in [0, 1] (its ``k_σ·σ`` is part of K, Eq. 2.2.4).

    Returns:
        (2, 2, 6): entry ``[i, j]`` holds the Eq. 2.2.4-form coefficients of ``K*_ij(q*)``.
    """
    a, b = _affine(a, b)
    if not np.allclose(a @ a.T, np.eye(2), atol=1e-12):
        raise ConfigError("the matrix field transforms as A K Aᵀ only for an orthogonal A (a rotation)")
    diag_new = polynomial_in_new_frame(
        field.coefficients_at(sigma), a, b
    )  # (2, 6): K_xx*, K_yy* as polynomials
    return np.einsum("ic,jc,ck->ijk", a, a, diag_new)


def evaluate_matrix_field(coefficients: np.ndarray, q: np.ndarray) -> np.ndarray:
    """A matrix of Eq. 2.2.4 polynomials at positions: ``(2, 2, 6)``, ``(..., 2)`` → ``(..., 2, 2)``."""
    c = np.asarray(coefficients, dtype=float)
    if c.shape != (2, 2, 6):
        raise ConfigError(f"matrix field coefficients must be (2, 2, 6), got {c.shape}")
    return np.einsum("...k,ijk->...ij", quadratic_basis(q), c)
