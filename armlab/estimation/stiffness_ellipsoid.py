"""Cartesian stiffness ellipsoids of a joint stiffness (seed paper 001, Fig. 3).

The paper does not give its mapping; the spec's choice: the wrist's translational compliance
C_x = J_t K_q^{-1} J_t^T (J_t the 3 x 5 translational rows of J_limb: the wrist may rotate freely,
as the forearm's pronation is not held), K_x = C_x^{-1}, and the ellipsoid
{K_x d : ||d|| = r} for displacements on a sphere of radius r = 5 mm (Fig. 3 caption), centred at
the pre-load force F.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError
from armlab.estimation.criteria import symmetric_part

__all__ = [
    "FIG3_RADIUS_M",
    "StiffnessEllipsoid",
    "axis_angle_deg",
    "ellipsoid_surface",
    "stiffness_ellipsoid",
]

FIG3_RADIUS_M = 0.005  # m: the displacement sphere of the paper's Fig. 3 (caption: r = 5 mm)


@dataclass(frozen=True, kw_only=True, eq=False)
class StiffnessEllipsoid:
    """Cartesian stiffness at the wrist.

    Attributes:
        K_x: (3, 3) N/m, C_x: (3, 3) m/N.
        semi_axes: (3,) N, descending: r times the eigenvalues of K_x (the force for a displacement
            of radius r along each principal direction).
        axes: (3, 3) unit principal directions as columns, in the order of ``semi_axes``
            (``axes[:, 0]`` the major axis).
        centre: (3,) N, the pre-load force the ellipsoid is drawn at.
        radius: m, the displacement sphere's radius.
    """

    K_x: np.ndarray
    C_x: np.ndarray
    semi_axes: np.ndarray
    axes: np.ndarray
    centre: np.ndarray
    radius: float

    @property
    def major_axis(self) -> np.ndarray:
        """(3,) unit direction of the largest stiffness."""
        return self.axes[:, 0]


def stiffness_ellipsoid(
    K_q: np.ndarray, J_limb: np.ndarray, centre: np.ndarray | None = None, radius: float = FIG3_RADIUS_M
) -> StiffnessEllipsoid:
    """The Fig. 3 ellipsoid of ``K_q`` (n, n) N·m/rad (SPD) through ``J_limb`` (6, n) or J_t (3, n).

    Args:
        K_q: (n, n) SPD joint stiffness.
        J_limb: (6, n) wrist Jacobian (rows v; omega) or its (3, n) translational rows, m/rad.
        centre: (3,) N pre-load force (default zero).
        radius: m, the displacement sphere (default 5 mm, Fig. 3).

    Raises:
        DataError: on shapes that do not fit, a K_q that is not SPD or a non-positive radius.
    """
    K_q = np.asarray(K_q, dtype=float)
    J = np.asarray(J_limb, dtype=float)
    n = K_q.shape[0]
    if K_q.shape != (n, n) or J.shape not in ((6, n), (3, n)):
        raise DataError(f"K_q must be (n, n) and J_limb (6, n) or (3, n), got {K_q.shape} and {J.shape}")
    if not radius > 0:
        raise DataError(f"radius must be positive (m), got {radius!r}")
    try:
        chol = np.linalg.cholesky(symmetric_part(K_q))
    except np.linalg.LinAlgError:
        raise DataError("K_q is not symmetric positive definite; estimate it with the SPD solver") from None
    jt = J[:3]
    half = np.linalg.solve(chol, jt.T)  # L^{-1} J_t^T, so C_x = half^T half
    C_x = half.T @ half
    K_x = np.linalg.inv(C_x)
    K_x = symmetric_part(K_x)
    lam, vec = np.linalg.eigh(K_x)
    order = np.argsort(lam)[::-1]
    c = np.zeros(3) if centre is None else np.asarray(centre, dtype=float)
    if c.shape != (3,):
        raise DataError(f"centre must be a (3,) force in N, got shape {c.shape}")
    return StiffnessEllipsoid(
        K_x=K_x, C_x=C_x, semi_axes=radius * lam[order], axes=vec[:, order], centre=c, radius=float(radius)
    )


def ellipsoid_surface(ellipsoid: StiffnessEllipsoid, n_lat: int = 16, n_lon: int = 32) -> np.ndarray:
    """Points F + K_x d on the ellipsoid for d on the sphere of its radius, (n_lat, n_lon, 3) N."""
    th = np.linspace(0.0, np.pi, n_lat)[:, None]
    ph = np.linspace(0.0, 2.0 * np.pi, n_lon)[None, :]
    d = ellipsoid.radius * np.stack(
        [np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th) * np.ones_like(ph)], axis=-1
    )
    return ellipsoid.centre + d @ ellipsoid.K_x.T


def axis_angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (...,) deg in [0, 90] between two axes (...,3) (sign-free: an axis has no direction)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c = np.abs(np.sum(a * b, axis=-1)) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(np.arccos(np.clip(c, 0.0, 1.0)))
