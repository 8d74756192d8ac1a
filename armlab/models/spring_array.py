"""The mass-spring fixture of seeds/003 (Sec. II-A, Eqs. (5)-(6); Sec. II-C-1; Table I).

The robot's end effector carries a payload of mass ``m`` and is tied to a planar array of linear
tension springs anchored to the bench around the array's equilibrium ``X0``. About ``X0`` the
fixture obeys Eq. (5), ``M X'' + K (X - X0) = -F_ext`` with ``M = m I`` and the symmetric
``K = [[k_xx, k_s], [k_s, k_yy]]`` of Eq. (6).

A spring ``i`` with anchor ``a_i``, stiffness ``k_i`` and rest length ``l0_i`` pulls the end effector
at ``X`` with ``F_i = -k_i (l_i - l0_i) u_i`` (``l_i = |X - a_i|``, ``u_i = (X - a_i) / l_i``); its
linearised stiffness ``-dF_i/dX`` is ``k_i [u uᵀ + (1 - l0_i / l_i) (I - u uᵀ)]`` — the axial
spring plus the geometric stiffness of its tension ``T_i = k_i (l_i - l0_i)`` across it.

:func:`design_spring_array` lays out springs on a circle around ``X0`` and chooses their spring
constants and tensions by linear programming so that the net force at ``X0`` is zero and the
stiffness at ``X0`` equals a target ``K`` (both constraints are linear in ``k_i`` and ``T_i``).
:func:`fixture_mjcf` emits the fixture alone as MJCF: a body on x/y slide joints with the payload
mass and one spatial tendon spring (``stiffness``, ``springlength``) per spring.

Frames and units: SI throughout (m, N, N/m, kg); positions are in the robot's base frame, the
plane of motion is its horizontal x-y plane. Table I gives ``X0`` in mm; it is stored here in m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from armlab.errors import ConfigError

__all__ = [
    "StiffnessField",
    "TABLE_I_STIFFNESS",
    "TABLE_I_PAYLOADS_KG",
    "Spring",
    "SpringArray",
    "design_spring_array",
    "table_i_array",
    "fixture_mjcf",
]


@dataclass(frozen=True)
class StiffnessField:
    """One row of Table I: ``k_xx``, ``k_yy``, ``k_s`` (N/m) and the equilibrium ``x0``, ``y0`` (m)."""

    k_xx: float
    k_yy: float
    k_s: float
    x0: float
    y0: float

    @property
    def K(self) -> np.ndarray:
        """(2, 2) N/m, Eq. (6)."""
        return np.array([[self.k_xx, self.k_s], [self.k_s, self.k_yy]])

    @property
    def X0(self) -> np.ndarray:
        """(2,) m, equilibrium in the robot's base frame."""
        return np.array([self.x0, self.y0])


# Table I of seeds/003 ("theoretical impedance values for mass-spring system"): k_xx, k_yy, k_s in
# N/m (from measured spring constants, numerically linearised by the authors); x0, y0 converted
# from the table's mm to m (robot base frame).
TABLE_I_STIFFNESS: dict[str, StiffnessField] = {
    "K1": StiffnessField(k_xx=421.57, k_yy=213.35, k_s=-18.87, x0=0.364, y0=-0.009),
    "K2": StiffnessField(k_xx=476.38, k_yy=248.71, k_s=-16.02, x0=0.375, y0=-0.008),
    "K3": StiffnessField(k_xx=239.54, k_yy=421.29, k_s=-12.52, x0=0.394, y0=0.053),
    "K4": StiffnessField(k_xx=190.26, k_yy=406.39, k_s=-2.08, x0=0.390, y0=0.036),
    "K5": StiffnessField(k_xx=373.81, k_yy=377.10, k_s=73.16, x0=0.332, y0=-0.061),
}

# kg, payloads M1..M5 of Table I of seeds/003 (measured by weighing; M = m I, Eq. (6)).
TABLE_I_PAYLOADS_KG: dict[str, float] = {
    "M1": 0.539,
    "M2": 0.786,
    "M3": 1.031,
    "M4": 1.279,
    "M5": 1.527,
}

# N: largest net spring force at X0 accepted as "X0 is the equilibrium" (at K >= 100 N/m it moves
# the equilibrium by < 10 nm; a designed array is balanced to ~1e-13 N)
_FORCE_TOL_N = 1e-6
# relative: largest |K(X0) - K_target| / |K_target| (Frobenius) a design may leave after polishing
_DESIGN_TOL_REL = 1e-9
# relative: the polished design may break a layout bound by this much (the LP's own tolerance)
_BOUND_SLACK_REL = 1e-6

# Design defaults (a bench build like Fig. 1a of seeds/003; our choice, not given by the paper):
_N_SPRINGS = 8  # springs, evenly spaced around X0 (opposite pairs balance each other's tension)
_RADIUS_M = 0.20  # m, anchor distance from X0 (a 0.4 m wide frame around the end effector)
_K_MIN_N_PER_M = 20.0  # N/m, softest stock extension spring used
_K_MAX_N_PER_M = 400.0  # N/m, stiffest stock extension spring used
# m, least stretch at X0: the springs stay in tension over the paper's 5 cm-diameter perturbation
# region (Sec. II-C-1), i.e. |X - X0| <= 25 mm, with margin
_MIN_STRETCH_M = 0.04
_MIN_REST_FRACTION = 0.5  # rest length >= half the stretched length (extension <= 100 % of l0)
_TOTAL_K_WEIGHT = 1e-3  # (dimensionless) weight of sum(k) against max(k) in the design objective


def _finite_vector(name: str, value, size: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (size,) or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} must be {size} finite numbers, got {value!r}")
    return arr


def _positive_finite(name: str, value: float, unit: str) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise ConfigError(f"{name} must be a finite number > 0 {unit}, got {value!r}")
    return v


@dataclass(frozen=True)
class Spring:
    """A linear extension spring from a bench anchor to the end effector.

    Attributes:
        anchor: (x, y) m, fixed end in the robot's base frame.
        stiffness: N/m, spring constant (> 0).
        rest_length: m, unstretched length (>= 0).
    """

    anchor: tuple[float, float]
    stiffness: float
    rest_length: float

    def __post_init__(self) -> None:
        anchor = _finite_vector("Spring.anchor", self.anchor, 2)
        object.__setattr__(self, "anchor", (float(anchor[0]), float(anchor[1])))
        object.__setattr__(self, "stiffness", _positive_finite("Spring.stiffness", self.stiffness, "N/m"))
        rest = float(self.rest_length)
        if not math.isfinite(rest) or rest < 0:
            raise ConfigError(f"Spring.rest_length must be a finite number >= 0 m, got {self.rest_length!r}")
        object.__setattr__(self, "rest_length", rest)

    def _geometry(self, X: np.ndarray) -> tuple[np.ndarray, float]:
        d = X - np.asarray(self.anchor)
        length = float(np.hypot(d[0], d[1]))
        if length == 0.0:
            raise ConfigError(f"X = {X.tolist()} m lies on the anchor {self.anchor} m of a spring")
        return d / length, length

    def length(self, X) -> float:
        """m, spring length with the end effector at ``X``."""
        return self._geometry(_finite_vector("X", X, 2))[1]

    def tension(self, X) -> float:
        """N, ``k (l - l0)`` (negative when compressed)."""
        return self.stiffness * (self.length(X) - self.rest_length)

    def force(self, X) -> np.ndarray:
        """(2,) N, force of this spring on the end effector at ``X``."""
        u, length = self._geometry(_finite_vector("X", X, 2))
        return -self.stiffness * (length - self.rest_length) * u

    def stiffness_matrix(self, X) -> np.ndarray:
        """(2, 2) N/m, ``-dF/dX`` of this spring at ``X``."""
        u, length = self._geometry(_finite_vector("X", X, 2))
        uu = np.outer(u, u)
        return self.stiffness * (uu + (1.0 - self.rest_length / length) * (np.eye(2) - uu))


@dataclass(frozen=True)
class SpringArray:
    """A planar array of springs acting on the end effector, in equilibrium at ``X0``.

    Validated on construction: at least one spring, no anchor at ``X0``, net force at ``X0`` below
    1 µN, and a positive-definite stiffness at ``X0``. A spring shorter than its rest length pushes
    (a compression spring) and its transverse stiffness ``k (1 - l0 / l)`` is negative, which is how
    an array in equilibrium can be unstable; arrays of stretched springs are always stable.

    Attributes:
        springs: the springs.
        X0: (x0, y0) m, equilibrium in the robot's base frame.
    """

    springs: tuple[Spring, ...]
    X0: tuple[float, float]

    def __post_init__(self) -> None:
        springs = tuple(self.springs)
        if not springs or not all(isinstance(s, Spring) for s in springs):
            raise ConfigError(f"SpringArray.springs must be a non-empty sequence of Spring, got {springs!r}")
        object.__setattr__(self, "springs", springs)
        x0 = _finite_vector("SpringArray.X0", self.X0, 2)
        object.__setattr__(self, "X0", (float(x0[0]), float(x0[1])))
        for i, s in enumerate(springs):
            if np.array_equal(np.asarray(s.anchor), x0):
                raise ConfigError(
                    f"spring {i} is anchored at X0 = {x0.tolist()} m; its direction is undefined"
                )
        residual = self.force(x0)
        if np.hypot(*residual) > _FORCE_TOL_N:
            raise ConfigError(
                f"X0 = {x0.tolist()} m is not the spring array's equilibrium: net force there is "
                f"{residual.tolist()} N (|F| must be <= {_FORCE_TOL_N:g} N)"
            )
        eig = np.linalg.eigvalsh(self.stiffness(x0))
        if eig[0] <= 0:
            raise ConfigError(
                f"the spring array's stiffness at X0 is not positive definite: eigenvalues "
                f"{eig.tolist()} N/m (both must be > 0)"
            )

    def force(self, X) -> np.ndarray:
        """(2,) N, net spring force on the end effector at ``X`` (m, base frame)."""
        X = _finite_vector("X", X, 2)
        return np.sum([s.force(X) for s in self.springs], axis=0)

    def stiffness(self, X=None) -> np.ndarray:
        """(2, 2) N/m, linearised stiffness ``-dF/dX`` at ``X`` (default ``X0``)."""
        X = _finite_vector("X", self.X0 if X is None else X, 2)
        return np.sum([s.stiffness_matrix(X) for s in self.springs], axis=0)

    def tensions(self) -> np.ndarray:
        """(n,) N, spring tensions at ``X0``."""
        return np.array([s.tension(self.X0) for s in self.springs])

    def lengths(self) -> np.ndarray:
        """(n,) m, spring lengths at ``X0``."""
        return np.array([s.length(self.X0) for s in self.springs])


def _target_K(k_xx: float, k_yy: float, k_s: float) -> np.ndarray:
    vals = [float(v) for v in (k_xx, k_yy, k_s)]
    if not all(math.isfinite(v) for v in vals):
        raise ConfigError(f"k_xx, k_yy, k_s must be finite numbers (N/m), got {vals}")
    K = np.array([[vals[0], vals[2]], [vals[2], vals[1]]])
    eig = np.linalg.eigvalsh(K)
    if eig[0] <= 0:
        raise ConfigError(
            f"stiffness K = [[{vals[0]:g}, {vals[2]:g}], [{vals[2]:g}, {vals[1]:g}]] N/m is not positive "
            f"definite (eigenvalues {eig.tolist()} N/m): a passive spring array in equilibrium needs "
            f"k_xx > 0 and k_xx k_yy > k_s²"
        )
    return K


def design_spring_array(
    k_xx: float,
    k_yy: float,
    k_s: float,
    x0: float,
    y0: float,
    *,
    n_springs: int = _N_SPRINGS,
    radius_m: float = _RADIUS_M,
    angle_offset_rad: float = 0.0,
    k_min: float = _K_MIN_N_PER_M,
    k_max: float = _K_MAX_N_PER_M,
    min_stretch_m: float = _MIN_STRETCH_M,
    min_rest_fraction: float = _MIN_REST_FRACTION,
) -> SpringArray:
    """Design a spring array whose stiffness at ``X0 = (x0, y0)`` m is ``[[k_xx, k_s], [k_s, k_yy]]`` N/m.

    The ``n_springs`` anchors sit on a circle of ``radius_m`` around ``X0`` at angles
    ``angle_offset_rad + 2 pi i / n``. With ``u_i`` the unit vector from anchor ``i`` to ``X0`` and
    ``T_i`` its tension, the stiffness ``sum k_i u uᵀ + (T_i / r)(I - u uᵀ)`` and the net force
    ``-sum T_i u_i`` are linear in ``(k, T)``; a linear program (``scipy.optimize.linprog``, HiGHS)
    finds the array with the smallest largest spring constant (then the least total) such that the
    force is zero, the stiffness is the target, ``k_min <= k_i <= k_max``, each spring is stretched
    by at least ``min_stretch_m`` and its rest length is at least ``min_rest_fraction`` of its
    length. The
    solution is then polished onto the equality constraints by a minimum-norm correction, so the
    stiffness matches to ~1e-13 relative.

    Raises:
        ConfigError: K not positive definite, bad layout values, or no array within the bounds.
    """
    K = _target_K(k_xx, k_yy, k_s)
    X0 = _finite_vector("(x0, y0)", (x0, y0), 2)
    if int(n_springs) != n_springs or n_springs < 3:
        raise ConfigError(
            f"n_springs must be an integer >= 3 (to balance tensions in 2-D), got {n_springs!r}"
        )
    n = int(n_springs)
    r = _positive_finite("radius_m", radius_m, "m")
    k_min = _positive_finite("k_min", k_min, "N/m")
    k_max = _positive_finite("k_max", k_max, "N/m")
    if k_max < k_min:
        raise ConfigError(f"k_max ({k_max:g} N/m) must be >= k_min ({k_min:g} N/m)")
    stretch = _positive_finite("min_stretch_m", min_stretch_m, "m")
    rho = float(min_rest_fraction)
    if not 0.0 <= rho < 1.0:
        raise ConfigError(f"min_rest_fraction must be in [0, 1), got {min_rest_fraction!r}")
    if stretch > (1.0 - rho) * r:
        raise ConfigError(
            f"min_stretch_m ({stretch:g} m) exceeds the largest stretch (1 - min_rest_fraction) * "
            f"radius_m = {(1.0 - rho) * r:g} m"
        )
    offset = float(angle_offset_rad)
    if not math.isfinite(offset):
        raise ConfigError(f"angle_offset_rad must be finite, got {angle_offset_rad!r}")

    phi = offset + 2.0 * np.pi * np.arange(n) / n
    anchors = X0 + r * np.column_stack([np.cos(phi), np.sin(phi)])
    u = (X0 - anchors) / r  # unit vectors anchor -> X0
    uu = np.einsum("ni,nj->nij", u, u)
    nn = np.eye(2) - uu
    # unknowns z = [k_1..k_n, T_1..T_n, t]; equality rows: K_xx, K_yy, K_xy, F_x, F_y
    A_eq = np.zeros((5, 2 * n + 1))
    A_eq[0, :n], A_eq[1, :n], A_eq[2, :n] = uu[:, 0, 0], uu[:, 1, 1], uu[:, 0, 1]
    A_eq[0, n:-1], A_eq[1, n:-1], A_eq[2, n:-1] = nn[:, 0, 0] / r, nn[:, 1, 1] / r, nn[:, 0, 1] / r
    A_eq[3, n:-1], A_eq[4, n:-1] = u[:, 0], u[:, 1]
    b_eq = np.array([K[0, 0], K[1, 1], K[0, 1], 0.0, 0.0])
    eye, zero, ones = np.eye(n), np.zeros((n, 1)), np.ones((n, 1))
    # T_i >= k_i stretch;  T_i <= (1 - rho) r k_i (rest length >= rho r);  k_i <= t
    A_ub = np.block([[stretch * eye, -eye, zero], [-(1.0 - rho) * r * eye, eye, zero], [eye, 0 * eye, -ones]])
    b_ub = np.zeros(3 * n)
    # minimise the stiffest spring t (spreads the load, gives identical opposite pairs), then the
    # total spring constant (small weight: picks the cheapest of the minimax solutions)
    cost = np.concatenate([np.full(n, _TOTAL_K_WEIGHT), np.zeros(n), [1.0]])
    bounds = [(k_min, k_max)] * n + [(0.0, None)] * n + [(0.0, None)]
    res = linprog(cost, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")
    if res.status != 0:
        raise ConfigError(
            f"no array of {n} springs at {r:g} m with {k_min:g} <= k <= {k_max:g} N/m, stretch >= "
            f"{stretch:g} m and rest length >= {rho:g} x length realises K = {K.tolist()} N/m "
            f"({res.message.strip()}); try more springs, other k bounds or another radius"
        )
    z = res.x + np.linalg.lstsq(A_eq, b_eq - A_eq @ res.x, rcond=None)[0]
    k, T = z[:n], z[n:-1]
    slack = _BOUND_SLACK_REL * max(k_max, 1.0)
    if np.any(k < k_min - slack) or np.any(k > k_max + slack) or np.any(A_ub[: 2 * n] @ z > slack):
        raise ConfigError(
            f"polishing the spring design broke its bounds (k = {k.tolist()} N/m, T = {T.tolist()} N)"
        )
    springs = tuple(
        Spring(anchor=(float(a[0]), float(a[1])), stiffness=float(ki), rest_length=float(r - Ti / ki))
        for a, ki, Ti in zip(anchors, k, T, strict=True)
    )
    array = SpringArray(springs=springs, X0=(float(X0[0]), float(X0[1])))
    err = np.linalg.norm(array.stiffness() - K) / np.linalg.norm(K)
    if err > _DESIGN_TOL_REL:
        raise ConfigError(
            f"designed spring array misses K by {err:.3g} (relative); the layout is ill-conditioned"
        )
    return array


def table_i_array(label: str, **layout) -> SpringArray:
    """:func:`design_spring_array` for the Table I stiffness field ``label`` ("K1".."K5")."""
    if label not in TABLE_I_STIFFNESS:
        raise ConfigError(f"unknown Table I stiffness field {label!r}; valid: {sorted(TABLE_I_STIFFNESS)}")
    f = TABLE_I_STIFFNESS[label]
    return design_spring_array(f.k_xx, f.k_yy, f.k_s, f.x0, f.y0, **layout)


def _num(v: float) -> str:
    return repr(float(v))  # shortest round-trip form: MuJoCo reads back the exact double


def fixture_mjcf(
    array: SpringArray,
    payload_kg: float,
    *,
    model_name: str = "spring_array",
    timestep_s: float = 0.001,
) -> str:
    """MJCF of the fixture alone: the payload on x/y slide joints, tied to the array's springs.

    The body ``payload`` sits at ``X0`` (z = 0) with slide joints ``x`` and ``y`` along the base
    frame's horizontal axes, so ``qpos = X - X0`` (m) and gravity (-z) does no work in the plane.
    Its mass is ``payload_kg``; its rotational inertia is nominal (1e-4 kg·m²: the body cannot
    rotate). Sites ``anchor_i`` (worldbody) and ``ee`` (on the payload) carry one spatial tendon
    ``spring_i`` each, with ``stiffness`` = k_i and ``springlength`` = l0_i: MuJoCo's tendon
    spring pulls with ``-k (L - L0)``, so ``qfrc_passive`` is the array's :meth:`SpringArray.force`
    and vanishes at ``qpos = 0``. The default 1 ms step matches the paper's 1 kHz loop.

    Raises:
        ConfigError: payload not a finite mass > 0, or a bad timestep.
    """
    if not isinstance(array, SpringArray):
        raise ConfigError(f"array must be a SpringArray, got {type(array).__name__}")
    try:
        m = float(payload_kg)
    except (TypeError, ValueError):
        raise ConfigError(f"payload_kg must be a finite mass > 0 kg, got {payload_kg!r}") from None
    if not math.isfinite(m) or m <= 0:
        raise ConfigError(
            f"payload_kg must be a finite mass > 0 kg, got {payload_kg!r} "
            f"(Table I payloads: {sorted(TABLE_I_PAYLOADS_KG.values())} kg)"
        )
    dt = _positive_finite("timestep_s", timestep_s, "s")
    x0, y0 = array.X0
    anchors = "\n".join(
        f'    <site name="anchor_{i}" pos="{_num(s.anchor[0])} {_num(s.anchor[1])} 0" size="0.005"/>'
        for i, s in enumerate(array.springs)
    )
    tendons = "\n".join(
        f'    <spatial name="spring_{i}" stiffness="{_num(s.stiffness)}" '
        f'springlength="{_num(s.rest_length)}" width="0.002">\n'
        f'      <site site="anchor_{i}"/>\n      <site site="ee"/>\n    </spatial>'
        for i, s in enumerate(array.springs)
    )
    return f"""<mujoco model="{model_name}">
  <!-- generated by armlab.models.spring_array.fixture_mjcf (seeds/003 Table I mass-spring fixture) -->
  <compiler angle="radian"/>
  <option timestep="{_num(dt)}" integrator="implicitfast"/>
  <worldbody>
{anchors}
    <body name="payload" pos="{_num(x0)} {_num(y0)} 0">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="y" type="slide" axis="0 1 0"/>
      <inertial pos="0 0 0" mass="{_num(m)}" diaginertia="1e-4 1e-4 1e-4"/>
      <geom type="cylinder" size="0.03 0.01" contype="0" conaffinity="0" mass="0"/>
      <site name="ee" pos="0 0 0" size="0.005"/>
    </body>
  </worldbody>
  <tendon>
{tendons}
  </tendon>
</mujoco>
"""
