"""The EMG -> stiffness map of seed paper 001 (Sec. 2.5, Eqs. (20)-(21)) and its linear baseline.

The network (Eq. (20)): features x (n_features,) -> one hidden layer of softplus units
sigma(a) = ln(1 + e^a) (the paper: 100) -> l in R^15 -> L (5 x 5 lower-triangular, filled row by
row) -> K = L L^T, symmetric positive semi-definite by construction. Loss (Eq. (21)): the mean over
the windows of ||L L^T - Z||_F^2 against the perturbation-estimated K_q (Z), plus an L2 penalty
on the weights; trained by SciPy's L-BFGS-B with the analytic gradient (back-propagation, checked
against finite differences by its test). Eq. (20)'s factor 1/N on W_1 is a constant scale absorbed
in W_1 and left out. Hyper-parameters (weight decay, iterations, initial scale) by a seeded
random search on a validation set (:func:`search_network`), as the paper does.

Why NumPy/SciPy and no neural-network library: the network has ~2.6k parameters and trains on
~2000 windows of 8 features; one loss-and-gradient evaluation is two small matrix products each
way (well under a millisecond), L-BFGS is the full-batch optimiser suited to it, and a library
(PyTorch/JAX) would add a large install beyond the README's two commands for no speed-up.

The linear baseline (the paper's form is not given): ridge regression from the same
standardised features, with an unpenalised intercept, to the 15 unique entries of K (lower
triangle), the ridge parameter searched on the same validation set (:func:`search_linear`).

NRMSE (the paper's normalisation is not given; spec 001's proposal): per unique entry the RMSE
over the test windows divided by the std of that entry's targets over them, averaged over the
entries (:func:`nrmse`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from armlab.cpus import single_threaded_blas
from armlab.errors import DataError

__all__ = [
    "N_HIDDEN",
    "N_UNIQUE",
    "LinearMap",
    "NetworkMap",
    "SearchResult",
    "ValidationSplit",
    "fit_linear",
    "fit_network",
    "lower_entries",
    "network_loss",
    "nrmse",
    "search_linear",
    "search_network",
]

N_HIDDEN = 100  # softplus units of the hidden layer (paper Sec. 4.1: "100 soft rectified linear units")
N = 5  # joints
N_UNIQUE = N * (N + 1) // 2  # 15 outputs: the entries of the lower-triangular L (paper Sec. 2.5)
_TRIL = np.tril_indices(N)


def lower_entries(K: np.ndarray) -> np.ndarray:
    """The 15 unique entries (..., 15) of symmetric (..., 5, 5) matrices, lower triangle row by row."""
    return np.asarray(K)[..., _TRIL[0], _TRIL[1]]


def _to_lower(l: np.ndarray) -> np.ndarray:
    L = np.zeros((*l.shape[:-1], N, N))
    L[..., _TRIL[0], _TRIL[1]] = l
    return L


def _softplus(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sigma(a) = ln(1 + e^a) and its derivative 1 / (1 + e^-a), from one exp(-|a|) (no overflow)."""
    e = np.exp(-np.abs(a))
    inv = 1.0 / (1.0 + e)
    return np.maximum(a, 0.0) + np.log1p(e), np.where(a >= 0.0, inv, e * inv)


@dataclass(frozen=True, kw_only=True, eq=False)
class NetworkMap:
    """A trained Eq. (20) network on standardised features.

    Attributes:
        W2: (n_hidden, n_features), b2: (n_hidden,) the hidden layer; W1: (15, n_hidden), b1: (15,)
            the output (entries of L in N·m/rad^(1/2) units of sqrt(K)).
        weight_decay: the L2 penalty it was trained with; n_iter: L-BFGS iterations run;
        loss: the final training loss (N·m/rad)^2 per window.
    """

    W2: np.ndarray
    b2: np.ndarray
    W1: np.ndarray
    b1: np.ndarray
    weight_decay: float
    n_iter: int
    loss: float

    def predict(self, X: np.ndarray) -> np.ndarray:
        """K = L L^T (n, 5, 5) N·m/rad for standardised features X (n, n_features)."""
        L = _to_lower(_softplus(np.asarray(X) @ self.W2.T + self.b2)[0] @ self.W1.T + self.b1)
        return L @ np.swapaxes(L, -1, -2)


def _unpack(theta: np.ndarray, n_features: int, n_hidden: int):
    i = 0
    W2 = theta[i : i + n_hidden * n_features].reshape(n_hidden, n_features)
    i += W2.size
    b2 = theta[i : i + n_hidden]
    i += n_hidden
    W1 = theta[i : i + N_UNIQUE * n_hidden].reshape(N_UNIQUE, n_hidden)
    i += W1.size
    return W2, b2, W1, theta[i : i + N_UNIQUE]


def network_loss(
    theta: np.ndarray, X: np.ndarray, Z: np.ndarray, n_hidden: int, weight_decay: float
) -> tuple[float, np.ndarray]:
    """Eq. (21) with an L2 penalty, and its gradient by back-propagation.

    loss = (1/n) sum_i ||L_i L_i^T - Z_i||_F^2 + weight_decay (||W_1||^2 + ||W_2||^2)

    Args:
        theta: the parameters, flattened (W_2, b_2, W_1, b_1).
        X: (n, n_features) standardised features; Z: (n, 5, 5) N·m/rad target stiffness.
        n_hidden: hidden units; weight_decay: the penalty (>= 0).

    Returns:
        (loss (N·m/rad)^2, gradient like ``theta``).
    """
    n, n_features = X.shape
    W2, b2, W1, b1 = _unpack(theta, n_features, n_hidden)
    a = X @ W2.T + b2  # (n, H)
    h, dh = _softplus(a)
    L = _to_lower(h @ W1.T + b1)  # (n, 5, 5)
    R = L @ np.swapaxes(L, -1, -2) - Z  # symmetric residual
    loss = float(np.sum(R * R)) / n + weight_decay * (float(np.sum(W1 * W1)) + float(np.sum(W2 * W2)))
    dL = (4.0 / n) * (R @ L)  # d/dL ||L L^T - Z||^2 = 2 (R + R^T) L = 4 R L
    dl = dL[:, _TRIL[0], _TRIL[1]]  # (n, 15)
    da = (dl @ W1) * dh  # (n, H): softplus' = sigmoid
    grad = np.concatenate(
        [
            (da.T @ X + 2.0 * weight_decay * W2).ravel(),
            da.sum(axis=0),
            (dl.T @ h + 2.0 * weight_decay * W1).ravel(),
            dl.sum(axis=0),
        ]
    )
    return loss, grad


def _check_xz(X: np.ndarray, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    X, Z = np.asarray(X, dtype=float), np.asarray(Z, dtype=float)
    if X.ndim != 2 or Z.shape != (X.shape[0], N, N) or X.shape[0] < 2:
        raise DataError(
            f"need features (n >= 2, n_features) and targets (n, 5, 5), got {X.shape} and {Z.shape}"
        )
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Z))):
        raise DataError("EMG features and target stiffness must be finite")
    return X, Z


def fit_network(
    X: np.ndarray,
    Z: np.ndarray,
    rng: np.random.Generator,
    *,
    n_hidden: int = N_HIDDEN,
    weight_decay: float = 1e-3,
    max_iter: int = 300,
    init_scale: float = 1.0,
) -> NetworkMap:
    """Train Eq. (20) on (X, Z) by L-BFGS (module docstring).

    Initialisation: W_2 ~ N(0, init_scale^2 / n_features), b_2 ~ N(0, init_scale^2), W_1 ~
    N(0, 0.01 / n_hidden) and b_1 the Cholesky factor of the mean target, so training starts at
    the mean stiffness.

    Args:
        X: (n, n_features) standardised features. Z: (n, 5, 5) N·m/rad SPD targets.
        rng: draws the initial weights.
        n_hidden, weight_decay, max_iter, init_scale: the hyper-parameters.
    """
    X, Z = _check_xz(X, Z)
    f = X.shape[1]
    try:
        b1 = lower_entries(np.linalg.cholesky(Z.mean(axis=0)))
    except np.linalg.LinAlgError:
        raise DataError("the mean target stiffness is not positive definite") from None
    theta0 = np.concatenate(
        [
            rng.normal(0.0, init_scale / np.sqrt(f), n_hidden * f),
            rng.normal(0.0, init_scale, n_hidden),
            rng.normal(0.0, 0.1 / np.sqrt(n_hidden), N_UNIQUE * n_hidden),
            b1,
        ]
    )
    with single_threaded_blas():  # many tiny BLAS calls: threads cost more than they give (armlab.cpus)
        res = minimize(
            network_loss,
            theta0,
            args=(X, Z, n_hidden, weight_decay),
            jac=True,
            method="L-BFGS-B",
            options={"maxiter": int(max_iter), "maxfun": 2 * int(max_iter)},
        )
    W2, b2, W1, b1 = _unpack(res.x, f, n_hidden)
    return NetworkMap(
        W2=W2.copy(),
        b2=b2.copy(),
        W1=W1.copy(),
        b1=b1.copy(),
        weight_decay=float(weight_decay),
        n_iter=int(res.nit),
        loss=float(res.fun),
    )


@dataclass(frozen=True, kw_only=True, eq=False)
class LinearMap:
    """Ridge regression from standardised features to the 15 unique entries of K.

    Attributes:
        coef: (n_features, 15) N·m/rad per unit feature; intercept: (15,) N·m/rad; ridge: its penalty.
    """

    coef: np.ndarray
    intercept: np.ndarray
    ridge: float

    def predict(self, X: np.ndarray) -> np.ndarray:
        """K (n, 5, 5) N·m/rad, the predicted entries mirrored (symmetric, not necessarily SPD)."""
        K = _to_lower(np.asarray(X) @ self.coef + self.intercept)
        return K + np.swapaxes(np.tril(K, -1), -1, -2)


def fit_linear(X: np.ndarray, Z: np.ndarray, ridge: float = 1e-3) -> LinearMap:
    """min_B ||X B + 1 c^T - lower(Z)||^2 + ridge n ||B||^2 (the intercept unpenalised), closed form."""
    X, Z = _check_xz(X, Z)
    y = lower_entries(Z)
    xm, ym = X.mean(axis=0), y.mean(axis=0)
    Xc = X - xm
    A = Xc.T @ Xc + ridge * X.shape[0] * np.eye(X.shape[1])
    coef = np.linalg.solve(A, Xc.T @ (y - ym))
    return LinearMap(coef=coef, intercept=ym - xm @ coef, ridge=float(ridge))


def nrmse(
    pred: np.ndarray, target: np.ndarray, entries: np.ndarray | None = None, scale: np.ndarray | None = None
) -> float:
    """Mean over the unique entries of RMSE / std of the targets (spec 001's proposal).

    Args:
        pred, target: (n, 5, 5) N·m/rad.
        entries: (15,) bool, the unique entries averaged (default all). An entry whose targets do
            not vary over the set has no std to normalise by: leave it out here.
        scale: (15,) N·m/rad, the normaliser of each entry in place of the targets' std over the
            set (for a set of one condition, e.g. a validation condition: the training set's std).

    Raises:
        DataError: an averaged entry's normaliser is zero.
    """
    p, t = lower_entries(pred), lower_entries(target)
    keep = np.ones(N_UNIQUE, bool) if entries is None else np.asarray(entries, bool)
    std = t[:, keep].std(axis=0) if scale is None else np.asarray(scale, float)[keep]
    if np.any(std <= 0):
        raise DataError(
            "NRMSE: an averaged entry of K is constant over the set (no std to normalise by); "
            "pass entries= without it, a scale=, or test on several conditions"
        )
    rmse = np.sqrt(np.mean((p[:, keep] - t[:, keep]) ** 2, axis=0))
    return float(np.mean(rmse / std))


@dataclass(frozen=True, kw_only=True, eq=False)
class ValidationSplit:
    """One training set and its validation set, features standardised.

    Attributes:
        X, Z: (n, n_features) training features, (n, 5, 5) N·m/rad targets.
        X_val, Z_val: the validation set's.
        scale: (15,) N·m/rad the NRMSE normaliser (:func:`nrmse`); None: the validation targets'
            std (needs several conditions among them).
    """

    X: np.ndarray
    Z: np.ndarray
    X_val: np.ndarray
    Z_val: np.ndarray
    scale: np.ndarray | None = None


@dataclass(frozen=True, kw_only=True, eq=False)
class SearchResult:
    """The random search's pick.

    Attributes:
        model: the map trained with the best hyper-parameters on the first split; params: them;
        val_nrmse: their validation NRMSE (mean over the splits); tried: (params, validation
        NRMSE) of every draw.
    """

    model: NetworkMap | LinearMap
    params: dict
    val_nrmse: float
    tried: tuple[tuple[dict, float], ...]


def _search(fit, draws, splits, entries) -> SearchResult:
    if not splits:
        raise DataError("the search needs at least one validation split")
    tried, best = [], None
    for params in draws:
        models = [fit(sp, params) for sp in splits]
        score = float(
            np.mean(
                [
                    nrmse(m.predict(sp.X_val), sp.Z_val, entries, sp.scale)
                    for m, sp in zip(models, splits, strict=True)
                ]
            )
        )
        tried.append((params, score))
        if best is None or score < best[2]:
            best = (models[0], params, score)
    return SearchResult(model=best[0], params=best[1], val_nrmse=best[2], tried=tuple(tried))


def search_network(
    splits: list[ValidationSplit],
    rng: np.random.Generator,
    n_draws: int,
    *,
    n_hidden: int = N_HIDDEN,
    entries: np.ndarray | None = None,
) -> SearchResult:
    """Random search of the network's hyper-parameters on validation sets (paper Sec. 4.1).

    Each draw: weight_decay log-uniform in [1e-5, 1e-1], max_iter log-uniform in [30, 300],
    init_scale log-uniform in [0.3, 3] (assumption: the paper gives neither the hyper-parameters
    nor their ranges), trained on every split; the draw with the lowest validation NRMSE
    (:func:`nrmse` with ``entries`` and the split's ``scale``, averaged over the splits) is kept.
    """

    def draws():
        for _ in range(n_draws):
            yield {
                "weight_decay": float(10 ** rng.uniform(-5.0, -1.0)),
                "max_iter": int(round(10 ** rng.uniform(np.log10(30.0), np.log10(300.0)))),
                "init_scale": float(10 ** rng.uniform(np.log10(0.3), np.log10(3.0))),
            }

    return _search(
        lambda sp, params: fit_network(sp.X, sp.Z, rng, n_hidden=n_hidden, **params), draws(), splits, entries
    )


def search_linear(
    splits: list[ValidationSplit],
    entries: np.ndarray | None = None,
    ridges: tuple[float, ...] = tuple(10.0 ** np.arange(-6, 3)),
) -> SearchResult:
    """The ridge parameter on the validation sets, over a grid (1e-6 ... 1e2: closed form, so the
    whole grid is cheaper than one network)."""
    return _search(
        lambda sp, params: fit_linear(sp.X, sp.Z, params["ridge"]),
        ({"ridge": float(r)} for r in ridges),
        splits,
        entries,
    )
