"""The virtual force sensor and the Cartesian impedance fits of the virtual-sensor paper (seeds/003).

* :func:`virtual_force`: Eq. (2), the force the hand exerts on the capstan robot from its joint
  motion and command torques, ``F_ext = (J^T)^-1 (I Theta_dd + C Theta_d + F_r - tau)`` (the sign
  of Eq. (1); the printed Eq. (2) has it reversed, see the function).
* :func:`fit_fixture`: Eqs. (5)-(6), the mass-spring fixture ``m X_dd + K (X - X0) = -F_ext``
  with ``M = m I`` and a symmetric ``K`` (Sec. III-B).
* :func:`fit_arm`: Eq. (9), the arm ``(M + Lambda I) X_dd + B X_d + K (X - Xv) = -F_ext`` with full
  2 x 2 ``M``, ``B``, ``K`` and the known handle mass ``Lambda`` (Sec. III-C).
* :func:`identify_robot`: the Appendix, ``tau = Y(Theta, Theta_d, Theta_dd) alpha`` per trial.

Every fit is one linear least squares on the first ``id_s`` seconds of a trial, validated by the
VAF of Eq. (8) on the last ``val_s`` seconds (the paper's 40 s / 10 s split of 50 s trials). The
regressor columns are scaled to unit norm and solved by SVD; a scaled condition number above
``1 / _RCOND`` is reported as rank deficiency. Standard errors are the white-residual ones,
``sqrt(diag(s² (A^T A)^-1))`` with ``s² = |r|² / (rows - unknowns)``; after the paper's low-pass
filtering the residuals are autocorrelated, so these understate the true spread (Table III's
across-trial standard deviations are the honest measure). Equilibria ``X0 = -K^-1 c`` get
first-order (delta-method) errors. Regressors are centred on the identification-window mean
position, which leaves ``M``, ``B``, ``K`` unchanged and keeps the constant column well conditioned.

Cartesian quantities are in whatever base frame ``CapstanDynamics.fk``/``jacobian`` use; nothing
here depends on that convention.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields

import numpy as np

from armlab.errors import ConfigError, DataError, EstimationError
from armlab.models.capstan_robot import (
    ALPHA_NAMES,
    HANDLE_MASS_KG,
    TABLE_VI_ALPHA,
    CapstanDynamics,
    CapstanParameters,
)

__all__ = [
    "ArmFit",
    "FixtureFit",
    "RobotIdentification",
    "fit_arm",
    "fit_fixture",
    "identify_robot",
    "table_vi",
    "vaf",
    "virtual_force",
]

_RCOND = 1e-10  # smallest / largest singular value of the column-scaled regressor: below, rank deficient
_SINGULAR_DET = 1e-6  # |det J| / (l1 l2) below which Eq. (2) is undefined (arm stretched or folded)
_FIXTURE_NAMES = ("m", "k_xx", "k_yy", "k_s", "c_x", "c_y")
_JOINT_NAMES = ("theta", "theta_dot", "theta_ddot", "tau")
_ARM_NAMES = ("m_i1", "m_i2", "b_i1", "b_i2", "k_i1", "k_i2", "c_i")


def _plain(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, CapstanParameters):
        return {"alpha": list(value.alpha), "std": None if value.std is None else list(value.std)}
    return float(value) if isinstance(value, (float, np.floating)) else value


class _AsDict:
    def as_dict(self) -> dict:
        """Plain floats, lists and dicts, ready for ``json.dump``."""
        return {f.name: _plain(getattr(self, f.name)) for f in fields(self)}


@dataclass(frozen=True, kw_only=True, eq=False)
class FixtureFit(_AsDict):
    """Eqs. (5)-(6) identified on one trial.

    Attributes:
        m: kg, payload mass (``M = m I``).
        k_xx, k_yy, k_s: N/m, the symmetric stiffness ``[[k_xx, k_s], [k_s, k_yy]]``.
        x0: (2,) m, spring equilibrium ``X0``.
        m_se, k_xx_se, k_yy_se, k_s_se: standard errors (white residuals), same units.
        x0_se: (2,) m, delta-method standard errors of ``x0``.
        vaf_pct: (2,) %, Eq. (8) for f_x, f_y on the validation window.
        cond: condition number of the column-scaled regressor.
    """

    m: float
    k_xx: float
    k_yy: float
    k_s: float
    x0: np.ndarray
    m_se: float
    k_xx_se: float
    k_yy_se: float
    k_s_se: float
    x0_se: np.ndarray
    vaf_pct: np.ndarray
    cond: float

    @property
    def K(self) -> np.ndarray:
        """(2, 2) N/m, the stiffness matrix of Eq. (6)."""
        return np.array([[self.k_xx, self.k_s], [self.k_s, self.k_yy]])


@dataclass(frozen=True, kw_only=True, eq=False)
class ArmFit(_AsDict):
    """Eq. (9) identified on one trial (the handle mass removed from ``M``).

    Attributes:
        M: (2, 2) kg, B: (2, 2) N·s/m, K: (2, 2) N/m; row i is the equation of axis i (x, y).
        xv: (2,) m, equilibrium ``Xv``.
        M_se, B_se, K_se: (2, 2) standard errors (white residuals), same units.
        xv_se: (2,) m, delta-method standard errors of ``xv``.
        vaf_pct: (2,) %, Eq. (8) for f_x, f_y on the validation window (handle term predicted too).
        cond: condition number of the column-scaled regressor.
    """

    M: np.ndarray
    B: np.ndarray
    K: np.ndarray
    xv: np.ndarray
    M_se: np.ndarray
    B_se: np.ndarray
    K_se: np.ndarray
    xv_se: np.ndarray
    vaf_pct: np.ndarray
    cond: float


@dataclass(frozen=True, kw_only=True, eq=False)
class RobotIdentification(_AsDict):
    """The Appendix identification over several trials.

    Attributes:
        alphas: (n_trials, 5) per-trial least-squares alphas (kg·m² for 1-3, N·m·s/rad for 4-5).
        alpha_se: (n_trials, 5) their white-residual standard errors.
        params: the mean alphas; ``std`` is the across-trial std (ddof=1), None for one trial.
        vaf_pct: (n_trials, 2) %, Eq. (8) for tau1, tau2 on each validation window.
        cond: (n_trials,) condition numbers of the column-scaled regressors.
    """

    alphas: np.ndarray
    alpha_se: np.ndarray
    params: CapstanParameters
    vaf_pct: np.ndarray
    cond: np.ndarray


def _finite(name: str, a: np.ndarray) -> None:
    bad = ~np.isfinite(a)
    if np.any(bad):
        raise DataError(f"{name} must be finite; NaN or inf at index {tuple(np.argwhere(bad)[0].tolist())}")


def _trial(names: Sequence[str], arrays: Sequence[np.ndarray], where: str = "") -> list[np.ndarray]:
    """Check one trial's signals: each (n_samples, 2), finite, all of one length."""
    out = [np.asarray(a, dtype=float) for a in arrays]
    n = out[0].shape[0] if out[0].ndim else None
    for name, a in zip((where + s for s in names), out, strict=True):
        if a.ndim != 2 or a.shape[1] != 2 or a.shape[0] != n:
            raise DataError(
                f"{name} must have shape (n_samples, 2) with n_samples={n} like the others, got {a.shape}"
            )
        _finite(name, a)
    return out


def _windows(n: int, fs_hz: float, id_s: float, val_s: float, n_unknowns: int) -> tuple[slice, slice]:
    """Identification (first ``id_s``) and validation (last ``val_s``) slices of an n-sample trial."""
    for name, v in (("fs_hz", fs_hz), ("id_s", id_s), ("val_s", val_s)):
        if not (np.isfinite(v) and v > 0):
            raise ConfigError(f"{name} must be a finite number > 0, got {v!r}")
    n_id, n_val = round(id_s * fs_hz), round(val_s * fs_hz)
    if n_id > n or n_val > n:
        raise DataError(
            f"the trial lasts {n / fs_hz:.3f} s ({n} samples at {fs_hz} Hz); the identification window "
            f"(id_s={id_s} s) and the validation window (val_s={val_s} s) must each fit in it"
        )
    if n_id <= n_unknowns or n_val < 2:
        raise EstimationError(
            f"{n_id} identification and {n_val} validation samples are too few: more than {n_unknowns} "
            "and at least 2 are needed; lengthen id_s / val_s"
        )
    return slice(0, n_id), slice(n - n_val, n)


def _lstsq(A: np.ndarray, b: np.ndarray, names: Sequence[str], what: str):
    """Column-scaled SVD least squares of ``A p = b``, A (r, c), b (r,) or (r, k).

    Returns ``p`` (c,) or (c, k), ``(A^T A)^-1`` (c, c), the residual variance (k,) or scalar, and
    the scaled condition number.
    """
    scale = np.linalg.norm(A, axis=0)
    if np.any(scale == 0):
        dead = [names[i] for i in np.flatnonzero(scale == 0)]
        raise EstimationError(
            f"{what}: the data do not excite {dead} (their regressor columns are zero; no motion?)"
        )
    U, S, Vt = np.linalg.svd(A / scale, full_matrices=False)
    if S[-1] < _RCOND * S[0]:
        raise EstimationError(
            f"{what}: the regressor is rank deficient (scaled condition number {S[0] / S[-1]:.3g} > "
            f"{1 / _RCOND:.0e}); the motion does not separate {list(names)}: excite more frequencies "
            "and directions"
        )
    Vs = Vt.T / S / scale[:, None]
    p = Vs @ (U.T @ b)
    s2 = np.sum((b - A @ p) ** 2, axis=0) / (A.shape[0] - A.shape[1])
    return p, Vs @ Vs.T, s2, float(S[0] / S[-1])


def _equilibrium(K: np.ndarray, c: np.ndarray, x_mean: np.ndarray, what: str) -> np.ndarray:
    """``X = x_mean - K^-1 c``, the equilibrium of a model fitted on positions centred at ``x_mean``."""
    if not np.all(np.isfinite(K)) or np.linalg.cond(K) > 1 / _RCOND:
        raise EstimationError(
            f"{what}: the identified K={K.tolist()} N/m is singular; the equilibrium is undefined"
        )
    return x_mean - np.linalg.solve(K, c)


def vaf(measured: np.ndarray, predicted: np.ndarray) -> float | np.ndarray:
    """Eq. (8): ``100 (1 - var(f - f_hat) / var(f))`` in %, per column.

    Args:
        measured, predicted: (n,) or (n, k), same shape.

    Returns:
        A float for 1-D input, else a (k,) array.
    """
    f, f_hat = np.asarray(measured, dtype=float), np.asarray(predicted, dtype=float)
    if f.shape != f_hat.shape or f.ndim not in (1, 2):
        raise DataError(
            f"measured and predicted must share a shape (n,) or (n, k), got {f.shape} and {f_hat.shape}"
        )
    _finite("measured", f)
    _finite("predicted", f_hat)
    var = np.var(f, axis=0)
    if np.any(var == 0):
        raise DataError("the measured signal is constant (zero variance); its VAF is undefined")
    out = 100.0 * (1.0 - np.var(f - f_hat, axis=0) / var)
    return float(out) if out.ndim == 0 else out


def virtual_force(
    dyn: CapstanDynamics, theta: np.ndarray, theta_dot: np.ndarray, theta_ddot: np.ndarray, tau: np.ndarray
) -> np.ndarray:
    """Eq. (2) with the sign of Eq. (1): ``F_ext = (J^T)^-1 (I Theta_dd + C Theta_d + F_r - tau)``.

    ``F_ext`` is the force the hand (or fixture) exerts on the robot, so Eq. (1),
    ``I Theta_dd + C Theta_d + F_r = tau + J^T F_ext``, is Newton's law for the robot and Eq. (5)
    reads ``F_ext = -(m X_dd + K (X - X0))``. The paper's printed Eq. (2) (and the ``-J^T F_ext + tau``
    of Sec. III) has the opposite sign, which contradicts Eqs. (1) and (5); this follows Eq. (1).

    Args:
        dyn: the robot model (dynamics of Eqs. (11)-(13), Jacobian ``J = dX/dTheta``).
        theta, theta_dot, theta_ddot: (..., 2) rad, rad/s, rad/s²; ``theta_ddot`` typically from
            ``dyn.joint_acceleration(theta, theta_dot, x_ddot)``, Eq. (7).
        tau: (..., 2) N·m, command torques ``tau_r``.

    Returns:
        (..., 2) N, ``F_ext`` in the base frame of ``dyn.jacobian``.
    """
    arrays = {"theta": theta, "theta_dot": theta_dot, "theta_ddot": theta_ddot, "tau": tau}
    arrays = {k: np.asarray(v, dtype=float) for k, v in arrays.items()}
    for name, a in arrays.items():
        if a.shape != arrays["theta"].shape or a.shape[-1:] != (2,):
            raise DataError(
                f"{name} must have the shape (..., 2) of theta {arrays['theta'].shape}, got {a.shape}"
            )
        _finite(name, a)
    theta, theta_dot, theta_ddot, tau = arrays.values()
    J = dyn.jacobian(theta)
    bad = np.abs(np.linalg.det(J)) < _SINGULAR_DET * dyn.l1 * dyn.l2
    if np.any(bad):
        i = tuple(np.argwhere(bad)[0].tolist())
        raise DataError(
            f"theta={theta[i].tolist()} rad at index {i} is a kinematic singularity; Eq. (2) needs an "
            "invertible J"
        )
    rhs = dyn.inverse_dynamics(theta, theta_dot, theta_ddot) - tau
    return np.linalg.solve(np.swapaxes(J, -1, -2), rhs[..., None])[..., 0]


def fit_fixture(
    x: np.ndarray,
    x_ddot: np.ndarray,
    f_ext: np.ndarray,
    fs_hz: float,
    *,
    id_s: float = 40.0,
    val_s: float = 10.0,
) -> FixtureFit:
    """Eqs. (5)-(6) by one least squares over both axes (Sec. III-B).

    Unknowns ``(m, k_xx, k_yy, k_s, c_x, c_y)``; x rows ``-f_x = m x_dd + k_xx x + k_s y + c_x``,
    y rows ``-f_y = m y_dd + k_s x + k_yy y + c_y``; ``X0 = -K^-1 c``.

    Args:
        x, x_ddot: (n, 2) m, m/s², end-effector position and acceleration.
        f_ext: (n, 2) N, force on the robot (virtual or physical sensor).
        fs_hz: Hz, sample rate.
        id_s, val_s: s, identification (first) and validation (last) windows.

    Returns:
        The :class:`FixtureFit`.
    """
    x, x_ddot, f_ext = _trial(("x", "x_ddot", "f_ext"), (x, x_ddot, f_ext))
    ident, valid = _windows(len(x), fs_hz, id_s, val_s, 6)
    x_mean = x[ident].mean(axis=0)
    dx = x - x_mean
    A = np.zeros((len(x), 2, 6))
    A[:, :, 0] = x_ddot
    A[:, 0, 1], A[:, 1, 2] = dx[:, 0], dx[:, 1]
    A[:, 0, 3], A[:, 1, 3] = dx[:, 1], dx[:, 0]
    A[:, 0, 4] = A[:, 1, 5] = 1.0
    p, cov_unit, s2, cond = _lstsq(
        A[ident].reshape(-1, 6), -f_ext[ident].reshape(-1), _FIXTURE_NAMES, "fit_fixture"
    )
    cov = s2 * cov_unit
    K = np.array([[p[1], p[3]], [p[3], p[2]]])
    x0 = _equilibrium(K, p[4:], x_mean, "fit_fixture")
    d = x0 - x_mean  # K d = -c, so dX0 = -K^-1 (dK d + dc) to first order
    G = -np.linalg.solve(K, np.array([[0, d[0], 0, d[1], 1, 0], [0, 0, d[1], d[0], 0, 1]]))
    se = np.sqrt(np.diag(cov))
    return FixtureFit(
        m=float(p[0]),
        k_xx=float(p[1]),
        k_yy=float(p[2]),
        k_s=float(p[3]),
        x0=x0,
        m_se=float(se[0]),
        k_xx_se=float(se[1]),
        k_yy_se=float(se[2]),
        k_s_se=float(se[3]),
        x0_se=np.sqrt(np.diag(G @ cov @ G.T)),
        vaf_pct=vaf(f_ext[valid], -(A[valid] @ p)),
        cond=cond,
    )


def fit_arm(
    x: np.ndarray,
    x_dot: np.ndarray,
    x_ddot: np.ndarray,
    f_ext: np.ndarray,
    fs_hz: float,
    *,
    handle_mass_kg: float = HANDLE_MASS_KG,
    id_s: float = 40.0,
    val_s: float = 10.0,
) -> ArmFit:
    """Eq. (9), ``(M + Lambda I) X_dd + B X_d + K (X - Xv) = -F_ext``, one LS per axis (Sec. III-C).

    Row i: ``-f_i - Lambda x_dd_i = M_i· X_dd + B_i· X_d + K_i· X + c_i`` (7 unknowns); ``Xv = -K^-1 c``.

    Args:
        x, x_dot, x_ddot: (n, 2) m, m/s, m/s², end-effector position, velocity, acceleration.
        f_ext: (n, 2) N, force on the robot.
        fs_hz: Hz, sample rate.
        handle_mass_kg: kg, the known handle mass ``Lambda`` (0 fits ``M + Lambda I`` as ``M``).
        id_s, val_s: s, identification (first) and validation (last) windows.

    Returns:
        The :class:`ArmFit`.
    """
    if not (np.isfinite(handle_mass_kg) and handle_mass_kg >= 0):
        raise ConfigError(f"handle_mass_kg must be a finite mass >= 0 kg, got {handle_mass_kg!r}")
    x, x_dot, x_ddot, f_ext = _trial(("x", "x_dot", "x_ddot", "f_ext"), (x, x_dot, x_ddot, f_ext))
    ident, valid = _windows(len(x), fs_hz, id_s, val_s, 7)
    x_mean = x[ident].mean(axis=0)
    A = np.column_stack([x_ddot, x_dot, x - x_mean, np.ones(len(x))])
    b = -f_ext - handle_mass_kg * x_ddot
    p, cov_unit, s2, cond = _lstsq(A[ident], b[ident], _ARM_NAMES, "fit_arm")  # p (7, 2): column i = row i
    K = p[4:6].T
    xv = _equilibrium(K, p[6], x_mean, "fit_arm")
    g = np.array([0, 0, 0, 0, *(xv - x_mean), 1.0])  # dXv = -K^-1 e_i (dK_i· d + dc_i) for row i
    K_inv = np.linalg.inv(K)
    xv_cov = K_inv @ np.diag(s2 * (g @ cov_unit @ g)) @ K_inv.T
    se = np.sqrt(np.outer(np.diag(cov_unit), s2))  # (7, 2)
    return ArmFit(
        M=p[0:2].T,
        B=p[2:4].T,
        K=K,
        xv=xv,
        M_se=se[0:2].T,
        B_se=se[2:4].T,
        K_se=se[4:6].T,
        xv_se=np.sqrt(np.diag(xv_cov)),
        vaf_pct=vaf(f_ext[valid], -(A[valid] @ p + handle_mass_kg * x_ddot[valid])),
        cond=cond,
    )


def identify_robot(
    trials: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
    fs_hz: float,
    *,
    id_s: float = 40.0,
    val_s: float = 10.0,
    prefilter: Callable[[np.ndarray], np.ndarray] | None = None,
) -> RobotIdentification:
    """The Appendix: least squares of ``tau = Y(Theta, Theta_d, Theta_dd) alpha`` per trial.

    Args:
        trials: one ``(theta, theta_dot, theta_ddot, tau)`` per trial, each (n, 2) in rad, rad/s,
            rad/s², N·m (trials may differ in length).
        fs_hz: Hz, sample rate.
        id_s, val_s: s, identification (first) and validation (last) windows of each trial.
        prefilter: a linear filter along axis 0 applied to the regressor ``Y`` (n, 2, 5) and to
            ``tau`` (n, 2) alike before the fit (e.g. the paper's zero-phase low-pass): both
            sides of the regression filtered the same way leave ``alpha`` unbiased.

    Returns:
        The :class:`RobotIdentification`.
    """
    if len(trials) == 0:
        raise DataError("trials is empty; give at least one (theta, theta_dot, theta_ddot, tau) trial")
    alphas, ses, vafs, conds = [], [], [], []
    for k, trial in enumerate(trials):
        if len(trial) != 4:
            raise DataError(
                f"trial {k} must be a (theta, theta_dot, theta_ddot, tau) tuple, got {len(trial)} items"
            )
        theta, theta_dot, theta_ddot, tau = _trial(_JOINT_NAMES, trial, f"trial {k} ")
        ident, valid = _windows(len(theta), fs_hz, id_s, val_s, 5)
        Y = CapstanDynamics.regressor(theta, theta_dot, theta_ddot)  # (n, 2, 5)
        if prefilter is not None:
            Y, tau = prefilter(Y), prefilter(tau)
        p, cov_unit, s2, cond = _lstsq(
            Y[ident].reshape(-1, 5), tau[ident].reshape(-1), ALPHA_NAMES, f"identify_robot trial {k}"
        )
        alphas.append(p)
        ses.append(np.sqrt(s2 * np.diag(cov_unit)))
        vafs.append(vaf(tau[valid], Y[valid] @ p))
        conds.append(cond)
    alphas = np.array(alphas)
    std = alphas.std(axis=0, ddof=1) if len(alphas) > 1 else None
    try:
        params = CapstanParameters.from_array(alphas.mean(axis=0), std)
    except ConfigError as e:
        raise EstimationError(f"identify_robot: the mean alphas are not a physical robot model: {e}") from e
    return RobotIdentification(
        alphas=alphas, alpha_se=np.array(ses), params=params, vaf_pct=np.array(vafs), cond=np.array(conds)
    )


def table_vi(ident: RobotIdentification) -> list[tuple[str, float, float, float, float, float]]:
    """Rows ``(name, mean, std, paper, paper_std, (mean - paper) / paper)`` against Table VI.

    ``std`` is NaN for a single trial.
    """
    std = ident.params.std or (float("nan"),) * 5
    paper, paper_std = TABLE_VI_ALPHA.alpha, TABLE_VI_ALPHA.std
    return [
        (name, m, s, p, ps, (m - p) / p)
        for name, m, s, p, ps in zip(ALPHA_NAMES, ident.params.alpha, std, paper, paper_std, strict=True)
    ]
