"""Joint-space least squares of the conditioning paper, Eqs. (9)-(14), and its reduced form, Eqs. (23)-(25).

The partially linearised arm model, Eq. (9),
``M(q, xi) qdd + (C(q, qd, xi) + D) qd + K dq = dtau_ext``, is linear in
``zeta = [xi1, xi2, xi3, D11, D12, D21, D22, K11, K12, K21, K22]`` (Eq. (10)). Each sample gives
two rows ``X zeta = dtau`` (Eq. (13)); stacking the samples of an observation window of several
trials gives ``W zeta = y`` (Eqs. (11), (12)). With the inertial parameters known, the reduced model
keeps the eight impedance parameters (Eq. (23)) and moves the rigid-body torque to the output
(Eq. (24)).

:func:`estimate` solves one window by a column-scaled QR + SVD (no normal equations).
:func:`estimate_windows` solves many windows at once through accumulated normal equations
``H = W^T W``, ``g = W^T y``; this squares the condition number, which in float64 costs about
``cond(W)² · 1e-16`` relative accuracy — harmless for ``cond(W) ≲ 1e4`` after the column scaling
applied here (the test suite compares both solvers).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import as_strided

from armlab.errors import EstimationError
from armlab.estimation.processing import JointSignals
from armlab.models.planar_arm import inverse_dynamics

__all__ = [
    "PARAM_NAMES",
    "REDUCED_PARAM_NAMES",
    "LSEstimate",
    "ValidationFit",
    "estimate",
    "estimate_windows",
    "regressor",
    "validate",
]

#: Order of the parameter vector ``zeta`` of Eq. (10).
PARAM_NAMES: tuple[str, ...] = ("xi1", "xi2", "xi3", "D11", "D12", "D21", "D22", "K11", "K12", "K21", "K22")
#: Order of the reduced parameter vector ``zeta_red`` of Eq. (23).
REDUCED_PARAM_NAMES: tuple[str, ...] = PARAM_NAMES[3:]
# Below this ratio of smallest to largest eigenvalue of the column-scaled Hessian the problem is
# treated as singular (the data do not excite some parameter combination).
_SINGULAR_RCOND = 1e-13


def regressor(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """Matrix of independent variables ``X = dPsi/dzeta``, Eq. (13) of the conditioning paper.

    Args:
        q: (..., 2) rad.
        qd: (..., 2) rad/s (the full velocity, Eq. (8): ``dq0/dt = 0``).
        qdd: (..., 2) rad/s².
        dq: (..., 2) rad, displacement from the pre-onset posture.

    Returns:
        (..., 2, 11), columns in the order of :data:`PARAM_NAMES`.
    """
    q, qd, qdd, dq = (np.asarray(a, dtype=float) for a in (q, qd, qdd, dq))
    shape = np.broadcast_shapes(q.shape, qd.shape, qdd.shape, dq.shape)[:-1]
    out = np.zeros((*shape, 2, 11))
    _fill_regressor(out, q, qd, qdd, dq, full=True)
    return out


def _fill_regressor(
    out: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, dq: np.ndarray, full: bool
) -> None:
    """Write the nonzero entries of Eq. (13) into the zeroed ``out`` (..., 2, >= 8 or 11).

    With ``full=False`` only the eight D, K columns of Eq. (25) are written, at columns 0..7.
    """
    qd1, qd2, qdd1, qdd2 = qd[..., 0], qd[..., 1], qdd[..., 0], qdd[..., 1]
    o = 3 if full else 0
    if full:
        s2, c2 = np.sin(q[..., 1]), np.cos(q[..., 1])
        out[..., 0, 0] = qdd1
        out[..., 0, 1] = (2 * qdd1 + qdd2) * c2 - (2 * qd1 * qd2 + qd2 * qd2) * s2
        out[..., 0, 2] = qdd2
        out[..., 1, 1] = qdd1 * c2 + qd1 * qd1 * s2
        out[..., 1, 2] = qdd1 + qdd2
    out[..., 0, o + 0] = qd1
    out[..., 0, o + 1] = qd2
    out[..., 1, o + 2] = qd1
    out[..., 1, o + 3] = qd2
    out[..., 0, o + 4] = dq[..., 0]
    out[..., 0, o + 5] = dq[..., 1]
    out[..., 1, o + 6] = dq[..., 0]
    out[..., 1, o + 7] = dq[..., 1]


# Signals of one sample from which both rows of Eq. (13) and of its reduced form are linear maps:
# u = [qdd1, qdd2, qd1, qd2, dq1, dq2, a, b, dtau1, dtau2] with
# a = (2 qdd1 + qdd2) cos q2 - (2 qd1 qd2 + qd2²) sin q2 and b = qdd1 cos q2 + qd1² sin q2.
# Sums of u u^T (10 x 10) carry the normal equations of both models at a third of the cost of
# forming the two (11 + 1)-column rows per sample.
_N_BASIS = 10


def _after_onset(a: np.ndarray, idx: np.ndarray, on: np.ndarray, length: int) -> np.ndarray:
    """``length`` samples of ``a`` (n_trials, n_samples, k) from ``on[i]`` in trial ``idx[i]``:
    (n, k, length), a copy. Sample windows are a read-only strided view (what NumPy's
    ``sliding_window_view`` makes, without its argument checks, which cost more than the gather
    for the windows' small groups); the caller checks that the windows fit in the records."""
    n, n_samples, k = a.shape
    s0, s1, s2 = a.strides
    shape = (n, n_samples - length + 1, k, length)
    return as_strided(a, shape=shape, strides=(s0, s1, s2, s1), writeable=False)[idx, on]


def _basis(signals: JointSignals, idx: np.ndarray, length: int) -> np.ndarray:
    """The signal basis ``u`` over ``length`` samples after onset of trials ``idx``: (n, 10, length).

    Component-major, so each trial's ``u u^T`` is one contiguous matrix product. The caller
    checks that the window fits in the records.
    """
    on = signals.onset_index[idx]
    q, qd, qdd, dq, dtau = (
        _after_onset(a, idx, on, length)  # (n, 2, length) copies
        for a in (signals.q, signals.qd, signals.qdd, signals.dq, signals.dtau)
    )
    s2, c2 = np.sin(q[:, 1]), np.cos(q[:, 1])
    qd1, qd2, qdd1, qdd2 = qd[:, 0], qd[:, 1], qdd[:, 0], qdd[:, 1]
    u = np.empty((idx.size, _N_BASIS, length))
    u[:, 0:2] = qdd
    u[:, 2:4] = qd
    u[:, 4:6] = dq
    u[:, 6] = (2 * qdd1 + qdd2) * c2 - (2 * qd1 + qd2) * qd2 * s2
    u[:, 7] = qdd1 * c2 + qd1 * qd1 * s2
    u[:, 8:10] = dtau
    return u


def _make_row_maps() -> np.ndarray:
    """(2, 10, 12): ``[X | y]`` row r = ``u @ maps[r]``, columns of :data:`PARAM_NAMES` then y."""
    m = np.zeros((2, _N_BASIS, 12))
    for col, src in enumerate((0, 6, 1, 2, 3, None, None, 4, 5, None, None, 8)):  # row 0
        if src is not None:
            m[0, src, col] = 1.0
    for col, src in enumerate((None, 7, 0, None, None, 2, 3, None, None, 4, 5, 9)):  # row 1
        if src is not None:
            m[1, src, col] = 1.0
    m[1, 1, 2] = 1.0  # qdd1 + qdd2
    return m


_ROW_MAPS = _make_row_maps()


@dataclass(frozen=True, kw_only=True, eq=False)
class LSEstimate:
    """Least-squares estimate of the arm parameters for one observation window.

    Attributes:
        zeta: (c,) estimated parameters, order :attr:`names` (c = 11 full, 8 reduced); units
            kg·m² (xi), N·m·s/rad (D), N·m/rad (K).
        names: (c,) parameter names.
        cov: (c, c) parameter covariance ``sigma² H⁻¹`` with ``sigma² = |y - W zeta|² / (r - c)``.
        std: (c,) standard deviations, ``sqrt(diag(cov))``.
        cond: condition number of ``W``, Eq. (19) (unscaled columns, as in the paper).
        K: (2, 2) N·m/rad, stiffness.
        D: (2, 2) N·m·s/rad, damping.
        xi: (3,) kg·m², estimated (full model) or given (reduced model) base inertial parameters.
        rms_residual: N·m, ``sqrt(|y - W zeta|² / r)``.
        n_rows: r, number of scalar equations (2 per sample).
        reduced: True for the reduced model of Eqs. (23)-(25).
    """

    zeta: np.ndarray
    names: tuple[str, ...]
    cov: np.ndarray
    std: np.ndarray
    cond: float
    K: np.ndarray
    D: np.ndarray
    xi: np.ndarray
    rms_residual: float
    n_rows: int
    reduced: bool

    def predict(
        self, signals: JointSignals, window_samples: int, trials: np.ndarray | None = None
    ) -> np.ndarray:
        """Model prediction of ``dtau_ext`` over the window after onset, Eq. (9).

        Args:
            signals: joint signals.
            window_samples: samples after each onset.
            trials: bool mask or indices of trials; all when None.

        Returns:
            (n_selected, window_samples, 2) N·m.
        """
        q, qd, qdd, dq, _ = _window(signals, _trial_indices(trials, signals.n_trials), window_samples)
        return inverse_dynamics(q, qd, qdd, self.xi) + qd @ self.D.T + dq @ self.K.T


@dataclass(frozen=True, kw_only=True, eq=False)
class ValidationFit:
    """Prediction of ``dtau_ext`` on a trial not used for training (Fig. 6 of the conditioning paper).

    Attributes:
        trial_index: index of the validation trial.
        t: (n,) s, time from onset.
        dtau: (n, 2) N·m, measured.
        dtau_hat: (n, 2) N·m, predicted.
        vaf: (2,) %, variance accounted for, ``100 (1 - var(dtau - dtau_hat) / var(dtau))``.
        rmse: (2,) N·m.
    """

    trial_index: int
    t: np.ndarray
    dtau: np.ndarray
    dtau_hat: np.ndarray
    vaf: np.ndarray
    rmse: np.ndarray


def _trial_indices(trials: np.ndarray | None, n_trials: int) -> np.ndarray:
    if trials is None:
        return np.arange(n_trials)
    trials = np.asarray(trials)
    if trials.dtype == bool:
        if trials.shape != (n_trials,):
            raise EstimationError(f"a boolean trial mask must have shape ({n_trials},), got {trials.shape}")
        idx = np.flatnonzero(trials)
    else:
        idx = np.atleast_1d(trials).astype(np.intp)
        if np.any((idx < 0) | (idx >= n_trials)):
            raise EstimationError(
                f"trial indices must lie in [0, {n_trials - 1}], got {idx.min()}..{idx.max()}"
            )
    if idx.size == 0:
        raise EstimationError("no trial selected; the trial mask must select at least one trial")
    return idx


def _check_window(signals: JointSignals, idx: np.ndarray, window_samples: int) -> int:
    if isinstance(window_samples, bool) or int(window_samples) != window_samples or window_samples < 1:
        raise EstimationError(f"window_samples must be a positive integer, got {window_samples!r}")
    max_allowed = int(np.min(signals.n_samples - signals.onset_index[idx]))
    if window_samples > max_allowed:
        raise EstimationError(
            f"window of {int(window_samples)} samples runs past the end of a trial; the maximum allowed "
            f"for the selected trials is {max_allowed} samples ({max_allowed / signals.fs_hz:.3f} s)"
        )
    return int(window_samples)


def _window(
    signals: JointSignals, idx: np.ndarray, window_samples: int, length: int | None = None
) -> tuple[np.ndarray, ...]:
    """Samples after onset of trials ``idx``: (q, qd, qdd, dq, dtau), each (n, length, 2).

    ``window_samples`` (checked against the record ends) defaults ``length``; a longer ``length``
    pads with the last sample, for callers that ignore the padding.
    """
    w = _check_window(signals, idx, window_samples)
    n = signals.n_samples
    t = np.minimum(signals.onset_index[idx][:, None] + np.arange(w if length is None else length), n - 1)
    # a gather of the selected samples only: the filtered signals are strided views, which a
    # reshape would first copy whole (~10 MB each for a 780-trial run) on every call
    return tuple(a[idx[:, None], t] for a in (signals.q, signals.qd, signals.qdd, signals.dq, signals.dtau))


def _augmented(q, qd, qdd, dq, dtau, xi_known) -> np.ndarray:
    """``Z = [X | y]`` of Eq. (13) with ``y = dtau`` (full) or Eqs. (24)-(25) (reduced): (..., 2, c + 1)."""
    full = xi_known is None
    c = 11 if full else 8
    Z = np.zeros((*q.shape[:-1], 2, c + 1))
    _fill_regressor(Z, q, qd, qdd, dq, full=full)
    Z[..., c] = dtau if full else dtau - inverse_dynamics(q, qd, qdd, xi_known)
    return Z


def _xi_known(xi_known: np.ndarray | None) -> np.ndarray | None:
    if xi_known is None:
        return None
    xi = np.asarray(xi_known, dtype=float)
    if xi.shape != (3,) or not np.all(np.isfinite(xi)):
        raise EstimationError(f"xi_known must be 3 finite values (xi1, xi2, xi3) kg·m², got {xi_known!r}")
    return xi


def _assemble(zeta, cov, cond, rss, n_rows, xi_known) -> LSEstimate:
    c = zeta.shape[-1]
    reduced = xi_known is not None
    xi = xi_known if reduced else zeta[:3]
    D, K = zeta[c - 8 : c - 4].reshape(2, 2), zeta[c - 4 :].reshape(2, 2)
    return LSEstimate(
        zeta=zeta,
        names=REDUCED_PARAM_NAMES if reduced else PARAM_NAMES,
        cov=cov,
        std=np.sqrt(np.clip(np.diag(cov), 0.0, None)),
        cond=float(cond),
        K=K,
        D=D,
        xi=np.array(xi),
        rms_residual=float(np.sqrt(max(rss, 0.0) / n_rows)),
        n_rows=int(n_rows),
        reduced=reduced,
    )


def _check_rows(n_rows: int, c: int, what: str) -> None:
    if n_rows <= c:
        raise EstimationError(
            f"{what}: {n_rows} scalar equations for {c} parameters; at least {c + 1} "
            f"rows (2 per sample) are needed to estimate the parameters and their covariance"
        )


def estimate(
    signals: JointSignals,
    trials_mask: np.ndarray | None,
    window_samples: int,
    xi_known: np.ndarray | None = None,
) -> LSEstimate:
    """Least-squares estimate over one observation window, Eqs. (11)-(14) or (23)-(25).

    Rows come from samples ``[onset, onset + window_samples)`` of each selected trial (the window
    ``T_obs`` starts at the perturbation onset ``t_p``). The columns of ``W`` are scaled to unit
    norm and the system is solved by Householder QR of ``[W | y]`` and an SVD of the triangular
    factor, which avoids forming ``H = W^T W`` of Eq. (14).

    Args:
        signals: processed joint signals of all trials.
        trials_mask: (n_trials,) bool or index array of the training trials; None for all.
        window_samples: samples per trial, ``round(T_obs · fs)``.
        xi_known: (3,) kg·m², known inertial parameters for the reduced model; None estimates the
            full 11-parameter model.

    Returns:
        The :class:`LSEstimate`.
    """
    xi_known = _xi_known(xi_known)
    idx = _trial_indices(trials_mask, signals.n_trials)
    Z = _augmented(*_window(signals, idx, window_samples), xi_known)
    c = Z.shape[-1] - 1
    W, Y = Z[..., :c].reshape(-1, c), Z[..., c].reshape(-1)
    _check_rows(W.shape[0], c, "estimate")
    names = REDUCED_PARAM_NAMES if xi_known is not None else PARAM_NAMES
    scale = np.linalg.norm(W, axis=0)
    if np.any(scale == 0):
        dead = [names[i] for i in np.flatnonzero(scale == 0)]
        raise EstimationError(f"the data do not excite parameter(s) {dead}: their regressor columns are zero")
    # Householder QR of the scaled, augmented [W | y] = Q R: R[:c, :c] carries W's singular values,
    # R[:c, c] = Q^T y, and |R[c, c]| is the residual norm -- no squared condition number, no
    # cancellation in the residual.
    R = np.linalg.qr(np.column_stack([W / scale, Y]), mode="r")
    U, S, Vt = np.linalg.svd(R[:c, :c])
    if S[-1] <= S[0] * np.sqrt(_SINGULAR_RCOND):
        raise EstimationError(
            f"the regressor is rank deficient (scaled condition number {S[0] / S[-1]:.3g}); "
            "use more perturbation directions or a longer window"
        )
    zeta = Vt.T @ ((U.T @ R[:c, c]) / S) / scale
    rss = float(R[c, c] ** 2)
    Vs = Vt.T / S / scale[:, None]
    cov = rss / (W.shape[0] - c) * (Vs @ Vs.T)
    sv = np.linalg.svd(R[:c, :c] * scale, compute_uv=False)  # singular values of W itself
    return _assemble(zeta, cov, sv[0] / sv[-1], rss, W.shape[0], xi_known)


def estimate_windows(
    signals: JointSignals,
    trial_masks: np.ndarray,
    window_samples: Sequence[int] | np.ndarray,
    xi_known: np.ndarray | None = None,
) -> list[LSEstimate]:
    """Estimates for many observation windows at once (Sec. IV-C/IV-D of the conditioning paper).

    Window ``k`` uses the trials selected by ``trial_masks[k]`` (in the protocol, the trials whose
    ``group == k``) over samples ``[onset, onset + window_samples[k])``. Both rows of ``[X | y]``
    of a sample are linear maps of ten signals ``u`` (see :func:`_basis`), so the normal equations
    ``H = W^T W``, ``g = W^T y`` of every window follow from sums of ``u u^T``. Each sample's ``u``
    is built once, however many windows contain it: trials are grouped by the longest window that
    uses them, each group's samples are cut into blocks between the window lengths that use it, and
    each block's per-trial ``u u^T`` (one batched product) is added to every window containing it.
    All windows thus cost one pass over the data used by any window; with nested windows (the same
    trials for all windows) about one estimate of the longest window, with disjoint trial groups
    (the paper's design) one pass over all groups.

    Each system is solved after Jacobi (column) scaling by an eigendecomposition; see the module
    docstring for the accuracy of this route. The residual sum of squares is ``y^T y - g^T zeta``,
    accurate to about ``1e-16 · |y|²``, so ``std`` is meaningful only for residuals well above that.

    Args:
        signals: processed joint signals of all trials.
        trial_masks: (n_windows, n_trials) bool, training trials of each window.
        window_samples: (n_windows,) int, window length of each window in samples.
        xi_known: (3,) kg·m² for the reduced model; None for the full model.

    Returns:
        One :class:`LSEstimate` per window, in order; equal to :func:`estimate` on the same data
        up to the round-off of the normal equations.
    """
    xi_known = _xi_known(xi_known)
    masks = np.asarray(trial_masks)
    wins = np.asarray(window_samples)
    if masks.ndim != 2 or masks.shape[1] != signals.n_trials or masks.dtype != bool:
        raise EstimationError(
            f"trial_masks must be a bool array (n_windows, {signals.n_trials}), "
            f"got {masks.dtype} {masks.shape}"
        )
    if wins.shape != (masks.shape[0],):
        raise EstimationError(f"window_samples must have shape ({masks.shape[0]},), got {wins.shape}")
    empty = np.flatnonzero(~masks.any(axis=1))
    if empty.size:
        raise EstimationError(f"window(s) {empty.tolist()} select no trial; every mask needs at least one")
    for k in range(masks.shape[0]):  # O(n_windows) validation, no per-sample work
        _check_window(signals, _trial_indices(masks[k], signals.n_trials), wins[k])
    wins = wins.astype(np.intp)
    c = 8 if xi_known is not None else 11
    for k in range(masks.shape[0]):
        _check_rows(2 * int(wins[k]) * int(masks[k].sum()), c, f"window {k}")

    # Trials grouped by the longest window that uses them: each group's basis is computed once
    # over that length and cut into blocks between the window lengths that use the group.
    longest = np.max(np.where(masks, wins[:, None], 0), axis=0)  # (n_trials,), 0 if unused
    weight = masks.astype(float)
    S = np.zeros((wins.size, _N_BASIS * _N_BASIS))
    for length in np.unique(longest[longest > 0]):
        idx = np.flatnonzero(longest == length)
        u = _basis(signals, idx, int(length))
        lo = 0
        for hi in np.unique(wins[masks[:, idx].any(axis=1)]):
            ub = u[:, :, lo:hi]
            blocks = np.matmul(ub, ub.transpose(0, 2, 1)).reshape(idx.size, -1)  # per-trial u u^T
            S += (weight[:, idx] * (wins >= hi)[:, None]) @ blocks
            lo = int(hi)
    maps = _ROW_MAPS
    if xi_known is not None:  # Eqs. (24)-(25): keep the D, K columns, move the xi terms to y
        maps = np.concatenate(
            [maps[:, :, 3:11], maps[:, :, 11:] - maps[:, :, :3] @ xi_known[:, None]], axis=2
        )
    S = S.reshape(-1, _N_BASIS, _N_BASIS)
    G = sum(maps[r].T @ S @ maps[r] for r in range(2))  # (n_windows, c + 1, c + 1) = [X | y]^T [X | y]
    H, g, yy = G[:, :c, :c], G[:, :c, c], G[:, c, c]

    diag = np.diagonal(H, axis1=1, axis2=2)
    names = REDUCED_PARAM_NAMES if xi_known is not None else PARAM_NAMES
    if np.any(diag <= 0):
        k, i = np.argwhere(diag <= 0)[0]
        raise EstimationError(
            f"window {k}: the data do not excite parameter {names[i]} (zero regressor column)"
        )
    d = 1.0 / np.sqrt(diag)
    lam, V = np.linalg.eigh(H * d[:, :, None] * d[:, None, :])
    bad = lam[:, 0] <= lam[:, -1] * _SINGULAR_RCOND
    if np.any(bad):
        raise EstimationError(
            f"window(s) {np.flatnonzero(bad).tolist()}: the regressor is rank deficient; "
            "use more perturbation directions or a longer window"
        )
    Vs = V / np.sqrt(lam)[:, None, :] * d[:, :, None]  # H⁻¹ = Vs Vs^T
    zeta = np.einsum("kij,kj->ki", Vs, np.einsum("kji,kj->ki", Vs, g))
    rss = np.maximum(yy - np.einsum("ki,ki->k", g, zeta), 0.0)
    n_rows = 2 * wins * masks.sum(axis=1)
    cov = (rss / (n_rows - c))[:, None, None] * np.matmul(Vs, Vs.transpose(0, 2, 1))
    lam_h = np.linalg.eigvalsh(H)
    cond = np.sqrt(lam_h[:, -1] / np.maximum(lam_h[:, 0], np.finfo(float).tiny))
    return [_assemble(zeta[k], cov[k], cond[k], rss[k], n_rows[k], xi_known) for k in range(len(wins))]


def validate(
    estimate: LSEstimate, signals: JointSignals, trial_index: int, window_samples: int
) -> ValidationFit:
    """Predict ``dtau_ext`` of one held-out trial and score it (Fig. 6 of the conditioning paper).

    Args:
        estimate: the estimate to validate.
        signals: joint signals containing the validation trial.
        trial_index: index of the validation trial.
        window_samples: samples after onset to compare.

    Returns:
        The :class:`ValidationFit` with VAF (%) and RMSE (N·m) per joint.
    """
    idx = _trial_indices(np.array([trial_index]), signals.n_trials)
    dtau = _window(signals, idx, window_samples)[4][0]
    dtau_hat = estimate.predict(signals, window_samples, idx)[0]
    var = np.var(dtau, axis=0)
    if np.any(var == 0):
        raise EstimationError(
            f"measured dtau of trial {trial_index} is constant on joint(s) "
            f"{np.flatnonzero(var == 0).tolist()} over the window; VAF is undefined"
        )
    err = dtau - dtau_hat
    return ValidationFit(
        trial_index=int(trial_index),
        t=np.arange(int(window_samples)) / signals.fs_hz,
        dtau=dtau,
        dtau_hat=dtau_hat,
        vaf=100.0 * (1.0 - np.var(err, axis=0) / var),
        rmse=np.sqrt(np.mean(err**2, axis=0)),
    )
