"""Sparse filtering (Ngiam, Koh, Chen, Bhaskar and Ng, NIPS 2011): the unsupervised feature layers
of seed paper 001's phi (Sec. 4.1: "two layers of unsupervised feature extraction using the
approach of [9]").

One layer with weights W (k, d) maps examples x (d,) to features by

    f = W x,   f~ = sqrt(f^2 + eps)                       soft absolute value
    f^_j = f~_j / ||f~_j||   (over the examples)           each feature to unit norm
    f^^_i = f^_i / ||f^_i||  (over the features)           each example to unit norm

and W minimises sum_i ||f^^_i||_1 (sparse features, each used equally), by L-BFGS with the
analytic gradient (checked against finite differences by its test). Layers are stacked greedily:
each is trained on the previous layer's output. On new examples a layer uses the per-feature norms
of its training set (as the rms over the examples), so one example's features do not depend on the
others it is transformed with. The paper gives neither the number of features per layer nor the
training; they are arguments here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from armlab.cpus import single_threaded_blas
from armlab.errors import DataError

__all__ = [
    "SPARSE_EPS",
    "SparseFilter",
    "fit_sparse_filter",
    "sparse_filter_loss",
]

SPARSE_EPS = 1e-8  # the soft absolute value's epsilon (Ngiam et al. 2011, Sec. 3: "e.g. 1e-8")


def _unit(v: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    norm = np.sqrt(np.sum(v * v, axis=axis, keepdims=True))
    return v / norm, norm


def sparse_filter_loss(w: np.ndarray, X: np.ndarray, k: int) -> tuple[float, np.ndarray]:
    """The sparse-filtering objective sum |f^^| of one layer and its gradient.

    Args:
        w: (k * d,) the weights W flattened. X: (n, d) the examples. k: features.

    Returns:
        (objective, gradient (k * d,)).
    """
    W = w.reshape(k, X.shape[1])
    F = X @ W.T  # (n, k)
    Fs = np.sqrt(F * F + SPARSE_EPS)
    Fr, nr = _unit(Fs, 0)  # each feature over the examples
    Fc, nc = _unit(Fr, 1)  # each example over the features
    g = np.ones_like(Fc)  # d sum(Fc) / d Fc (Fc > 0)
    # through y = x / ||x||: dx = (g - y (y . g)) / ||x||, per example, then per feature
    gr = (g - Fc * np.sum(Fc * g, axis=1, keepdims=True)) / nc
    gs = (gr - Fr * np.sum(Fr * gr, axis=0, keepdims=True)) / nr
    gF = gs * F / Fs
    return float(Fc.sum()), (gF.T @ X).ravel()


@dataclass(frozen=True, kw_only=True, eq=False)
class SparseFilter:
    """Trained sparse-filtering layers.

    Attributes:
        weights: per layer W (k_l, d_l); rms: per layer (k_l,) the training features' rms over the
            examples (the per-feature normaliser applied to new examples).
    """

    weights: tuple[np.ndarray, ...]
    rms: tuple[np.ndarray, ...]

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """The last layer's features (n, k_last) of examples X (n, d)."""
        out = np.asarray(X, dtype=float)
        for W, rms in zip(self.weights, self.rms, strict=True):
            out = _unit(np.sqrt((out @ W.T) ** 2 + SPARSE_EPS) / rms, 1)[0]
        return out


def fit_sparse_filter(
    X: np.ndarray, sizes: tuple[int, ...], rng: np.random.Generator, max_iter: int = 200
) -> SparseFilter:
    """Train the layers greedily on examples X (n, d) (module docstring).

    Args:
        X: (n, d) training examples (e.g. standardised EMG maxima). sizes: features per layer.
        rng: draws each layer's initial weights, N(0, 1). max_iter: L-BFGS iterations per layer.

    Raises:
        DataError: fewer than 2 examples, or a layer size < 1.
    """
    out = np.asarray(X, dtype=float)
    if out.ndim != 2 or out.shape[0] < 2:
        raise DataError(f"sparse filtering needs examples (n >= 2, d), got shape {out.shape}")
    if not sizes or min(sizes) < 1:
        raise DataError(f"sparse filtering needs at least one layer of >= 1 feature, got sizes {sizes}")
    weights, norms = [], []
    for k in sizes:
        w0 = rng.standard_normal(k * out.shape[1])
        with single_threaded_blas():  # many small BLAS calls (armlab.cpus)
            res = minimize(
                sparse_filter_loss,
                w0,
                args=(out, k),
                jac=True,
                method="L-BFGS-B",
                options={"maxiter": max_iter},
            )
        W = res.x.reshape(k, out.shape[1])
        Fs = np.sqrt((out @ W.T) ** 2 + SPARSE_EPS)
        rms = np.sqrt(np.mean(Fs * Fs, axis=0))
        weights.append(W)
        norms.append(rms)
        out = _unit(Fs / rms, 1)[0]
    return SparseFilter(weights=tuple(weights), rms=tuple(norms))
