"""Levy's complex-curve fit of commensurate-order transfer functions, Sec. II of the fractional paper.

A commensurate model of order ``alpha`` (Eqs. (1), (23) of the fractional-elbow paper) is

    G(s) = sum_k b_k s^(k alpha) / (1 + sum_k a_k s^(k alpha)),

integer when ``alpha = 1``. Levy's method replaces the nonlinear error ``|G - N/D|²`` by the
linear equation error ``|G D - N|²`` of Eq. (2), summed over the measured frequencies. Setting its
gradient to zero gives the normal equations (3)-(17); here the same minimiser is computed from the
stacked real and imaginary rows by a column-scaled SVD least squares, which avoids squaring the
condition number (the ``s^(k alpha)`` columns span many decades). A :class:`LevyStructure` says
which coefficients are free (e.g. a numerator constant only); all others are zero, ``a_0 = 1``.
The order ``alpha`` is found by a sweep over ``]0, 2[`` in steps of 0.1 (Sec. IV-A), keeping the
best fit by one of the indices of Eqs. (24)-(26).

Readings of the paper: the third terms of Eqs. (7) and (9) multiply by ``Re[G]`` where the
derivative of Eq. (2) gives ``Im[G]`` (the test suite checks the corrected normal equations against
this solver). Eq. (24) squares a real difference, so the indices default to magnitudes ``|G|`` in
linear units (Table I's MSE ~1e-7 fits rad/N, not dB); ``indices_on="complex"`` uses complex
differences instead. The parameter count is the number of free coefficients, ``alpha`` excluded,
which reproduces Table I for (28), (29), A and B; for (27) it gives 6 where Table I prints 5.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from armlab.config.schema import alpha_grid  # the one grid rule, with FrfConfig that checks by it
from armlab.errors import ConfigError, EstimationError
from armlab.models.tf_structures import CommensurateTF, check_alpha, s_power

__all__ = [
    "PAPER_STRUCTURES",
    "FitIndices",
    "LevyFit",
    "LevyStructure",
    "LevySweep",
    "alpha_grid",
    "fit_indices",
    "levy_fit",
    "levy_sweep",
]

IndexOn = Literal["magnitude", "complex"]
Criterion = Literal["mse", "mad", "r2"]
# Singular values of the column-scaled Levy matrix below this fraction of the largest one mean the
# frequency data do not determine every free coefficient.
_SINGULAR_RCOND = 1e-12


@dataclass(frozen=True, kw_only=True)
class LevyStructure:
    """Which coefficients of Eq. (23) are free; the others are zero and ``a_0 = 1``.

    Attributes:
        num_powers: exponents ``k`` (in units of ``alpha``) of the free numerator coefficients
            ``b_k``, distinct, >= 0.
        den_powers: exponents ``k`` of the free denominator coefficients ``a_k``, distinct, >= 1
            (may be empty: a polynomial model such as an impedance ``K + B s + I s²``).
        alpha: commensurate order in ``]0, 2[``; ``None`` leaves it to :func:`levy_sweep`.
        name: label for reports.
    """

    num_powers: tuple[int, ...]
    den_powers: tuple[int, ...]
    alpha: float | None = None
    name: str = ""

    def __post_init__(self) -> None:
        for what, powers, low in (("num_powers", self.num_powers, 0), ("den_powers", self.den_powers, 1)):
            p = list(powers)
            if any(isinstance(k, bool) or int(k) != k or k < low for k in p) or len(set(p)) != len(p):
                raise ConfigError(f"{what} must be distinct integers >= {low}, got {powers!r}")
        if not self.num_powers:
            raise ConfigError("num_powers must name at least one numerator coefficient, e.g. (0,)")
        if self.alpha is not None:
            check_alpha(self.alpha)

    @classmethod
    def full(cls, m: int, n: int, alpha: float | None = None, name: str = "") -> LevyStructure:
        """All coefficients free: numerator order ``m >= 0``, denominator order ``n >= 0``."""
        if isinstance(m, bool) or isinstance(n, bool) or int(m) != m or int(n) != n or m < 0 or n < 0:
            raise ConfigError(f"orders must be integers m >= 0, n >= 0; got m={m!r}, n={n!r}")
        return cls(num_powers=tuple(range(m + 1)), den_powers=tuple(range(1, n + 1)), alpha=alpha, name=name)

    @property
    def n_params(self) -> int:
        """Number of free coefficients (``alpha`` not counted, as in Table I)."""
        return len(self.num_powers) + len(self.den_powers)


#: Model structures of the fractional paper: Eqs. (27)-(29) and models A, B of Table I.
PAPER_STRUCTURES: dict[str, LevyStructure] = {
    "27": LevyStructure.full(2, 3, alpha=1.0, name="(27) integer, 2 zeros 3 poles"),
    "28": LevyStructure(num_powers=(0, 1), den_powers=(1, 2), name="(28) fractional, 1 zero 2 poles"),
    "29": LevyStructure(num_powers=(0,), den_powers=(1, 2), name="(29) fractional, 2 poles"),
    "A": LevyStructure(num_powers=(0,), den_powers=(1, 2), alpha=1.0, name="A: integer, 2 poles"),
    "B": LevyStructure(num_powers=(0, 1), den_powers=(1, 2), alpha=1.0, name="B: integer, 1 zero 2 poles"),
}


@dataclass(frozen=True)
class FitIndices:
    """Goodness of fit, Eqs. (24)-(26) of the fractional paper.

    Attributes:
        mse: mean square error, in (units of G)².
        mad: mean absolute deviation, in units of G.
        r2: coefficient of determination, dimensionless (1 for a perfect fit).
        on: ``"magnitude"`` (indices of ``|G|``) or ``"complex"`` (moduli of complex differences).
    """

    mse: float
    mad: float
    r2: float
    on: str


def fit_indices(g: np.ndarray, g_hat: np.ndarray, on: IndexOn = "magnitude") -> FitIndices:
    """MSE, MAD and R² of Eqs. (24)-(26) between measured ``g`` and modelled ``g_hat``.

    Args:
        g: (N,) complex measured frequency response.
        g_hat: (N,) complex model response at the same frequencies.
        on: ``"magnitude"`` compares ``|g|`` with ``|g_hat|`` (Eq. (24) squares a real difference);
            ``"complex"`` uses ``|g - g_hat|`` and the complex mean.

    Returns:
        The :class:`FitIndices`.
    """
    g, g_hat = np.asarray(g), np.asarray(g_hat)
    if g.shape != g_hat.shape or g.ndim != 1 or g.size == 0:
        raise EstimationError(f"g and g_hat must be equal non-empty 1-D arrays, got {g.shape}, {g_hat.shape}")
    if on == "magnitude":
        g, g_hat = np.abs(g), np.abs(g_hat)
    elif on != "complex":
        raise ConfigError(f"on must be 'magnitude' or 'complex', got {on!r}")
    err = np.abs(g - g_hat)
    ss_tot = float(np.sum(np.abs(g - g.mean()) ** 2))
    r2 = 1.0 - float(np.sum(err**2)) / ss_tot if ss_tot > 0 else float("nan")
    return FitIndices(mse=float(np.mean(err**2)), mad=float(np.mean(err)), r2=r2, on=on)


@dataclass(frozen=True, kw_only=True, eq=False)
class LevyFit:
    """One Levy fit.

    Attributes:
        model: the fitted :class:`CommensurateTF` (coefficients ascending in ``s^alpha``).
        structure: the free-coefficient pattern that was fitted.
        indices: Eqs. (24)-(26) on the fitting band.
        n_freq: number of frequencies fitted.

    Derived: ``n_params`` (Table I's "# param"), ``stable`` (Matignon's condition) and
    ``bandwidth_hz`` (computed once, on first use: sweeps discard most fits unread).
    """

    model: CommensurateTF
    structure: LevyStructure
    indices: FitIndices
    n_freq: int

    @property
    def alpha(self) -> float:
        return self.model.alpha

    @property
    def n_params(self) -> int:
        """Number of free coefficients (Table I's "# param")."""
        return self.structure.n_params

    @property
    def stable(self) -> bool:
        """Whether :attr:`model` is stable (Matignon's condition)."""
        return self.model.is_stable

    @functools.cached_property
    def bandwidth_hz(self) -> float | None:
        """Hz, -3 dB bandwidth of :attr:`model`; None when ``|G|`` does not fall 3 dB below its
        low-frequency value up to 1 kHz (or has no finite low-frequency value)."""
        try:
            return self.model.bandwidth_hz()
        except EstimationError:
            return None

    def summary(self) -> dict:
        """Plain-dict record of the fit (coefficients, order, indices, bandwidth) for results files."""
        m = self.model
        return {
            "structure": self.structure.name,
            "alpha": float(m.alpha),
            "b": np.asarray(m.b).tolist(),
            "a": np.asarray(m.a).tolist(),
            "mse": self.indices.mse,
            "mad": self.indices.mad,
            "r2": self.indices.r2,
            "n_params": self.n_params,
            "bandwidth_hz": self.bandwidth_hz,
            "stable": bool(self.stable),
        }

    def response(self, f_hz: np.ndarray) -> np.ndarray:
        """Model frequency response at ``f_hz`` (Hz), complex, same shape."""
        return self.model.response(f_hz)


@dataclass(frozen=True, kw_only=True, eq=False)
class LevySweep:
    """An ``alpha`` sweep (Sec. IV-A): one fit per order, and the best by ``criterion``.

    Attributes:
        best: the selected fit.
        alphas: (n,) orders tried.
        fits: n fits, one per ``alpha``.
        criterion: ``"mse"``, ``"mad"`` (smallest wins) or ``"r2"`` (largest wins).
    """

    best: LevyFit
    alphas: np.ndarray
    fits: tuple[LevyFit, ...]
    criterion: str

    def stable_choice(self) -> tuple[LevyFit, LevyFit | None]:
        """(the best *stable* fit by :attr:`criterion`, the better unstable fit it displaced or None).

        Never drops an unstable fit silently: when the overall best is unstable it is returned
        second, to be reported as rejected. With no stable fit at all, the overall best is kept
        (its ``stable`` is False, for the caller to mark).
        """
        score = np.array([getattr(ft.indices, self.criterion) for ft in self.fits])
        score = -score if self.criterion == "r2" else score
        ok = np.array([ft.stable for ft in self.fits]) & np.isfinite(score)
        if not np.any(ok):
            return self.best, None
        kept = self.fits[int(np.flatnonzero(ok)[np.argmin(score[ok])])]
        return kept, (None if self.best is kept or self.best.stable else self.best)


def _check_data(f_hz, G, n_params: int) -> tuple[np.ndarray, np.ndarray]:
    f = np.asarray(f_hz, dtype=float)
    G = np.asarray(G, dtype=complex)
    if f.ndim != 1 or f.shape != G.shape:
        raise EstimationError(f"f_hz and G must be 1-D of equal length, got {f.shape} and {G.shape}")
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(G))):
        raise EstimationError("f_hz and G must be finite (no NaN or inf)")
    if np.any(f < 0):
        raise EstimationError(f"frequencies must be >= 0 Hz, got minimum {f.min():g} Hz")
    if f.size < n_params:
        raise EstimationError(
            f"{f.size} frequency points for {n_params} free coefficients; at least {n_params} are needed"
        )
    return f, G


def levy_fit(
    f_hz: np.ndarray,
    G: np.ndarray,
    structure: LevyStructure,
    alpha: float | None = None,
    weights: np.ndarray | None = None,
    iterations: int = 0,
    indices_on: IndexOn = "magnitude",
) -> LevyFit:
    """Levy's least-squares fit, Eqs. (1)-(17) of the fractional paper.

    Each frequency gives the complex equation ``sum b_k S_k - G sum a_k S_k = G`` with
    ``S_k = (j omega)^(k alpha)`` (Eq. (2) with ``a_0 = 1`` moved to the right).

    Args:
        f_hz: (f,) Hz, frequencies (>= 0).
        G: (f,) complex measured frequency response.
        structure: which coefficients are free.
        alpha: commensurate order in ``]0, 2[``; defaults to ``structure.alpha``.
        weights: (f,) >= 0, optional frequency weights multiplying each equation (e.g. to curb the
            dominance of high frequencies); the paper found no gain and used none.
        iterations: Sanathanan-Koerner refinements that divide each equation by ``|D(j omega)|``
            of the previous fit, approaching ``min |G - N/D|²`` (Sec. III-B; the paper used 0).
        indices_on: how :attr:`LevyFit.indices` compare responses (see :func:`fit_indices`).

    Returns:
        The :class:`LevyFit`.
    """
    alpha = structure.alpha if alpha is None else alpha
    if alpha is None:
        raise ConfigError("alpha is not set: pass alpha in ]0, 2[ or use levy_sweep")
    alpha = check_alpha(alpha)
    f, G = _check_data(f_hz, G, structure.n_params)
    w = np.ones(f.size) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != f.shape or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ConfigError(f"weights must be {f.shape} finite values >= 0, got shape {w.shape}")
    if isinstance(iterations, bool) or int(iterations) != iterations or iterations < 0:
        raise ConfigError(f"iterations must be an integer >= 0, got {iterations!r}")
    num, den = list(structure.num_powers), list(structure.den_powers)
    S = s_power(f, np.arange(max(num + den) + 1) * alpha)  # (f, K)
    cols = np.concatenate([S[:, num], -G[:, None] * S[:, den]], axis=1)  # (f, q) complex
    model = None
    for _ in range(int(iterations) + 1):
        wk = w if model is None else w / np.abs(S[:, : model.a.size] @ model.a)
        A = np.concatenate([(wk[:, None] * cols).real, (wk[:, None] * cols).imag])
        y = np.concatenate([(wk * G).real, (wk * G).imag])
        scale = np.linalg.norm(A, axis=0)
        if np.any(scale == 0):
            raise EstimationError("a free coefficient has an all-zero column (all weights or data zero)")
        U, sv, Vt = np.linalg.svd(A / scale, full_matrices=False)
        if sv[-1] <= sv[0] * _SINGULAR_RCOND:
            raise EstimationError(
                f"the Levy system is rank deficient (scaled condition number {sv[0] / sv[-1]:.3g}); "
                "use more or wider-spread frequencies, or fewer free coefficients"
            )
        x = Vt.T @ ((U.T @ y) / sv) / scale
        b = np.zeros(max(num) + 1)
        a = np.zeros(max(den, default=0) + 1)
        b[num], a[0], a[den] = x[: len(num)], 1.0, x[len(num) :]
        model = CommensurateTF(b=b, a=a, alpha=alpha, name=structure.name)
    return LevyFit(
        model=model,
        structure=structure,
        indices=fit_indices(G, model.response(f), on=indices_on),
        n_freq=int(f.size),
    )


def levy_sweep(
    f_hz: np.ndarray,
    G: np.ndarray,
    structure: LevyStructure,
    alphas: Sequence[float] | np.ndarray | None = None,
    criterion: Criterion = "mse",
    stable_only: bool = True,
    **fit_kwargs,
) -> LevySweep:
    """Fit ``structure`` for each ``alpha`` and keep the best (Sec. IV-A of the fractional paper).

    Args:
        f_hz: (f,) Hz.
        G: (f,) complex measured response.
        structure: free-coefficient pattern (its ``alpha`` is ignored).
        alphas: orders to try, each in ``]0, 2[``; default 0.1, 0.2, ..., 1.9.
        criterion: index that selects the best fit: ``"mse"``, ``"mad"`` (min) or ``"r2"`` (max).
        stable_only: skip unstable fits when choosing (they stay in :attr:`LevySweep.fits`).
        **fit_kwargs: ``weights``, ``iterations``, ``indices_on`` passed to :func:`levy_fit`.

    Returns:
        The :class:`LevySweep`.
    """
    if criterion not in ("mse", "mad", "r2"):
        raise ConfigError(f"criterion must be 'mse', 'mad' or 'r2', got {criterion!r}")
    grid = alpha_grid(0.1) if alphas is None else np.asarray(alphas, dtype=float)
    if grid.ndim != 1 or grid.size == 0:
        raise ConfigError(f"alphas must be a non-empty 1-D sequence in ]0, 2[, got shape {grid.shape}")
    for al in grid:
        check_alpha(al)
    fits = tuple(levy_fit(f_hz, G, structure, alpha=float(al), **fit_kwargs) for al in grid)
    score = np.array([getattr(ft.indices, criterion) for ft in fits])
    score = -score if criterion == "r2" else score
    ok = np.array([ft.stable or not stable_only for ft in fits]) & np.isfinite(score)
    if not np.any(ok):
        raise EstimationError(
            f"no stable fit with a finite {criterion} among alphas {grid.tolist()}; "
            "try another structure or stable_only=False"
        )
    best = int(np.flatnonzero(ok)[np.argmin(score[ok])])
    return LevySweep(best=fits[best], alphas=grid, fits=fits, criterion=criterion)
