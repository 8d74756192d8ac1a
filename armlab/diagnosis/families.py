"""Surrogate model families and their fitting: the generic core of every protocol's diagnosis.

A protocol's diagnosis describes each catalogue effect it can score as a :class:`Surrogate` (its
nonlinear parameters with bounds and start grids, and the linear parameters it adds) and composes
them into a regressor through its :class:`ModelFamily`. :func:`fit_model` fits a composed model
by variable projection: the linear parameters (one set per trial) are solved by least squares for
given nonlinear ones (delays, cut-offs, compliance ratios); the nonlinear ones start from a grid
and are refined by ``scipy.optimize.least_squares`` on the concentrated residual.

Also here: the signal transforms several families share (a causal 2nd-order low-pass, the force
channel's Butterworth low-pass, a continuous 2nd-order sensor of any natural frequency, an exact
fractional delay).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import optimize
from scipy.fft import next_fast_len

from armlab.dsp import lowpass_causal, second_order_lowpass, zero_phase

__all__ = [
    "FittedModel",
    "ModelFamily",
    "NLParam",
    "Surrogate",
    "active_params",
    "fit_model",
    "lowpass2",
    "padded_length",
    "sensor_lowpass",
    "sensor_response",
    "shift_columns",
]


@dataclass(frozen=True)
class NLParam:
    """A nonlinear parameter: name (unit in it), bounds, log scaling, start grid, discrete flag.

    ``active_when``: ``(name, value)`` of a discrete parameter of the same surrogate that selects
    a form in which this parameter acts; in the other forms it is kept at its first grid value,
    neither searched nor refined nor counted.
    """

    name: str
    lower: float
    upper: float
    grid: tuple[float, ...]
    log: bool = False
    discrete: bool = False
    active_when: tuple[str, float] | None = None

    def __post_init__(self) -> None:
        # a start outside the bounds would survive a refinement that does not improve on it
        if not self.lower <= self.upper or any(not self.lower <= g <= self.upper for g in self.grid):
            raise ValueError(f"{self.name}: start grid {self.grid} outside [{self.lower}, {self.upper}]")


@dataclass(frozen=True)
class Surrogate:
    """One effect's change to the joint model (see the module docstring)."""

    name: str
    # "additive" | "intrinsic" | "output" | "position" | "absorbed" | "low_band" (scored by the protocol
    # below its band)
    kind: str
    params: tuple[NLParam, ...] = ()
    linear: tuple[str, ...] = ()  # names of the linear parameters it adds (per trial)
    absorbed_by: str = "limb inertia"  # kind "absorbed": the nominal parameter that takes it up
    # the parameters it adds, as the selection counts them, where that is not the difference of
    # free parameters: an intrinsic surrogate that re-parametrises the nominal with ratios shared
    # by the trials has fewer free parameters than the nominal's per-trial ones, and that sharing,
    # not the effect, would earn it the penalty's credit over every other candidate
    counts_as: int | None = None


@dataclass(frozen=True)
class ModelFamily:
    """How a protocol composes surrogates into a regressor.

    Attributes:
        columns: ``(trial, model, theta) -> (n, k)`` regressor of one scoring set.
        linear_names: ``model -> names`` of the ``k`` linear parameters.
        start: optional ``(theta, surrogate_name, nominal_beta) -> None`` that seeds the
            nonlinear parameters of an intrinsic surrogate from the nominal fit.
    """

    columns: Callable
    linear_names: Callable
    start: Callable | None = None


def lowpass2(z: np.ndarray, fc: float, zeta: float, fs: float, axis: int = 0) -> np.ndarray:
    """Causal 2nd-order low-pass ``w²/(s² + 2ζws + w²)``, ``w = 2π fc``, started at rest, along ``axis``.

    :func:`armlab.dsp.second_order_lowpass` with this module's argument order.
    """
    return second_order_lowpass(z, fs, fc, zeta, axis=axis)


def sensor_lowpass(z: np.ndarray, cutoff_hz: float, fs: float, axis: int = 0) -> np.ndarray:
    """The force channel's 2nd-order Butterworth low-pass (causal), started at ``z``'s first value.

    Starting from the first sample (not from zero) matches a sensor that was at rest on that
    value before the record: no start-up step the data lack. :func:`armlab.dsp.lowpass_causal`
    with ``start="deviation"``.
    """
    return lowpass_causal(z, fs, cutoff_hz, 2, axis=axis, start="deviation")


def sensor_response(z: np.ndarray, natural_hz: float, damping_ratio: float, fs: float) -> np.ndarray:
    """A continuous 2nd-order sensor ``w²/(s² + 2ζws + w²)``, ``w = 2π natural_hz``, on columns along axis 0.

    Applied as its exact frequency response on the spectrum of ``z`` padded with its end values
    (the sensor at rest on the first value before the record, as :func:`sensor_lowpass`), so that
    the natural frequency may lie anywhere, at or above the Nyquist frequency of ``z`` too: a
    force sensor of a few hundred Hz to kHz seen at a 250 Hz fitting rate is, in band, a delay
    ``2ζ/w`` plus a gain change of order ``(1 - 2ζ²)(f/natural_hz)²`` that a digital filter at
    that rate cannot represent. Exact for a band-limited ``z`` (the fitting columns are low-passed
    before decimation); the pad covers 10 of the response's decay times ``1/(ζw)``.
    """
    w = 2.0 * np.pi * natural_hz
    pad = int(np.ceil(10.0 / (damping_ratio * w) * fs)) + 8
    n = padded_length(z.shape[0], pad)
    s = 2j * np.pi * np.fft.rfftfreq(n, 1.0 / fs)
    h = w * w / (s * s + 2.0 * damping_ratio * w * s + w * w)
    if z.ndim > 1:
        h = h.reshape((-1,) + (1,) * (z.ndim - 1))
    out = np.fft.irfft(_padded_spectrum(z, pad) * h, n=n, axis=0)
    return out[pad : pad + z.shape[0]]


def shift_columns(t: np.ndarray, z: np.ndarray, delay: float) -> np.ndarray:
    """z(t - delay), held at its first value before the start (columns along axis 0).

    Holding (not zeroing) matches a recorded channel: before the trial it read its resting value;
    a zero there would add a step at the start that the data lack.
    """
    # exact fractional delay of a band-limited signal: a linear phase in the frequency domain
    # (linear interpolation between samples would low-pass the delayed signal); the signal is
    # padded with its end values so the circular wrap stays outside the record
    fs = 1.0 / (t[1] - t[0])
    pad = int(np.ceil(abs(delay) * fs)) + 8
    n = padded_length(z.shape[0], pad)
    f = np.fft.rfftfreq(n, 1.0 / fs)
    phase = np.exp(-2j * np.pi * f * delay)
    if z.ndim > 1:
        phase = phase[:, None]
    out = np.fft.irfft(_padded_spectrum(z, pad) * phase, n=n, axis=0)
    return out[pad : pad + z.shape[0]]


# The last spectra of padded signals, most recently used last: (signal copy, pad, spectrum). A fit
# shifts the same signal (a trial's velocity; the stacked regressor of a delay search whose other
# columns are fixed) by many delays, and delays a finite difference apart share the pad, hence
# the spectrum. A hit needs an equal signal (a stored copy, compared exactly), so it cannot go
# stale. Only signals up to _SPECTRUM_MAX_BYTES are kept: the joint fits' 1-D signals hit (1582 of
# 1640 look-ups on the referee); the conditioning diagnosis's stacked (850, 660) regressors hit 54
# of 185 and held ~220 MB at no gain in time (measured in review), so they are not cached.
_SPECTRA: list[tuple[np.ndarray, int, np.ndarray]] = []
_SPECTRA_LOCK = threading.Lock()
_SPECTRA_KEPT = 24  # a few pads of each trial's signals in a fit (6 trials in the REKLAB folder)
_SPECTRUM_MAX_BYTES = 1 << 20  # bytes of signal: a 30 s trial at 1 kHz in float64 is 240 kB


def padded_length(n: int, pad: int) -> int:
    """Length of a signal of ``n`` samples held at its end values for at least ``pad`` samples on
    each side, lengthened at its end to a product of small primes.

    The FFT's cost per sample depends on the length's prime factors: ``n + 2·pad`` for a 106 s
    trial at the 1 kHz recorded rate is 4·31·859 (16 ms an inverse transform, against 0.9 ms at
    the next 5-smooth length), and the diagnosis runs thousands of them. Holding the end value
    longer changes nothing but where the circular wrap falls, further outside the record.
    """
    return int(next_fast_len(n + 2 * pad, real=True))


def _padded_spectrum(z: np.ndarray, pad: int) -> np.ndarray:
    """``rfft`` along axis 0 of ``z`` held at its first value for ``pad`` samples before it and at
    its last one after it up to :func:`padded_length`."""
    kept = z.nbytes <= _SPECTRUM_MAX_BYTES
    if kept:
        with _SPECTRA_LOCK:  # the candidates of a diagnosis step are fitted on threads
            for i in range(len(_SPECTRA) - 1, -1, -1):
                zc, pc, spec = _SPECTRA[i]
                if pc == pad and zc.shape == z.shape and zc.dtype == z.dtype and np.array_equal(zc, z):
                    _SPECTRA.append(_SPECTRA.pop(i))
                    return spec
    back = padded_length(z.shape[0], pad) - z.shape[0] - pad
    zz = np.concatenate([np.repeat(z[:1], pad, axis=0), z, np.repeat(z[-1:], back, axis=0)], axis=0)
    spec = np.fft.rfft(zz, axis=0)
    spec.flags.writeable = False
    if kept:
        with _SPECTRA_LOCK:
            _SPECTRA.append((z.copy(), pad, spec))
            del _SPECTRA[:-_SPECTRA_KEPT]
    return spec


@dataclass(frozen=True, eq=False)
class FittedModel:
    """A composed model fitted on the training parts.

    Attributes:
        effects: the effect names, in the order they were added.
        theta: nonlinear parameters, ``"<effect>.<param>"`` -> value.
        beta: per trial, the linear parameters (first the intrinsic ones, then each effect's).
        linear_names: names of the entries of each ``beta``.
        predictions: per trial, (n,) N·m model torque in the scoring band.
        residuals: per trial, (n,) N·m measured minus model torque in the scoring band.
        n_params: free parameters in all (linear per trial plus shared nonlinear).
    """

    effects: tuple[str, ...]
    theta: dict[str, float]
    beta: tuple[np.ndarray, ...]
    linear_names: tuple[str, ...]
    predictions: tuple[np.ndarray, ...]
    residuals: tuple[np.ndarray, ...]
    n_params: int


def _lstsq(a: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least squares by column-scaled normal equations (15x faster than SVD on tall regressors).

    Squaring the condition number is harmless while the scaled Gram matrix stays well
    conditioned; beyond ``1e10`` the SVD solver takes over.
    """
    scale = np.linalg.norm(a, axis=0)
    scale[scale == 0] = 1.0
    b = a / scale
    gram = b.T @ b
    if np.linalg.cond(gram) > 1e10:
        return np.linalg.lstsq(a, y, rcond=None)[0]
    return np.linalg.solve(gram, b.T @ y) / scale


class _Problem:
    """Concentrated (variable-projection) residual of a composed model over the training parts."""

    def __init__(self, trials, y_band, model, hp, family):
        self.trials, self.y_band, self.model, self.hp, self.family = trials, y_band, model, hp, family
        # (trial, column) -> (last unfiltered column, its filtered form): most columns (the
        # nominal a, v, x; effects whose parameters the search is not moving) repeat unchanged
        # from one evaluation to the next, and filtering is the costliest step of an evaluation
        self._filtered: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}

    def design(self, theta):
        cols = [self.family.columns(tr, self.model, theta) for tr in self.trials]
        if self.hp is None:
            return cols
        return [self._high_pass(i, c) for i, c in enumerate(cols)]

    def _high_pass(self, i: int, phi: np.ndarray) -> np.ndarray:
        """``zero_phase(hp, phi, axis=0)``, filtering only the columns that changed (the filter
        treats each column on its own, so the result is the same to the bit)."""
        # laid out as sosfiltfilt lays out its result (time reversed in a column-major buffer),
        # so that products with it take the same NumPy/BLAS path, hence the same roundings
        out = np.empty(phi.shape[::-1])[:, ::-1].T
        todo = []
        for j in range(phi.shape[1]):
            hit = self._filtered.get((i, j))
            if hit is not None and np.array_equal(hit[0], phi[:, j]):
                out[:, j] = hit[1]
            else:
                todo.append(j)
        if todo:
            fresh = zero_phase(self.hp, phi[:, todo], axis=0)
            out[:, todo] = fresh
            for k, j in enumerate(todo):
                self._filtered[i, j] = (phi[:, j].copy(), fresh[:, k].copy())
        return out

    def solve(self, theta):
        phis = self.design(theta)
        betas, res = [], []
        for tr, y, phi in zip(self.trials, self.y_band, phis, strict=True):
            beta = _lstsq(phi[tr.train], y[tr.train])
            betas.append(beta)
            res.append(y - phi @ beta)
        return phis, betas, res

    def train_residual(self, theta):
        _, _, res = self.solve(theta)
        return np.concatenate([r[tr.train] for tr, r in zip(self.trials, res, strict=True)])


def fit_model(
    trials: tuple,
    y_band: list[np.ndarray],
    model: tuple[Surrogate, ...],
    hp: np.ndarray,
    *,
    theta0: dict[str, float] | None = None,
    nominal_beta: tuple[np.ndarray, ...] | None = None,
    family: ModelFamily,
) -> FittedModel:
    """Fit a composed model: grid over the parameters not in ``theta0``, then a joint refinement.

    Args:
        trials: prepared trials (the family's; each has boolean ``train`` and ``held`` masks).
        y_band: per trial, (n,) measured torque in the scoring band.
        model: the surrogates, the newest last.
        hp: second-order sections of the scoring high-pass.
        theta0: nonlinear parameters already fitted (kept as the start of the refinement).
        nominal_beta: the nominal fit's linear parameters (start of compliance time constants).
        family: the protocol's model family; ``hp`` None scores the columns unfiltered.
    """
    theta = dict(theta0 or {})
    for s in model:
        if s.kind == "intrinsic" and nominal_beta is not None and family.start is not None:
            family.start(theta, s.name, nominal_beta)
    prob = _Problem(trials, y_band, model, hp, family)
    todo = [(f"{s.name}.{p.name}", p) for s in model for p in s.params if f"{s.name}.{p.name}" not in theta]
    gridded = [(k, p) for k, p in todo if p.grid]
    for k, p in todo:
        if not p.grid:
            theta[k] = float(np.sqrt(p.lower * p.upper)) if p.log else 0.5 * (p.lower + p.upper)
    all_params = {f"{s.name}.{p.name}": p for s in model for p in s.params}
    if gridded:
        keys = [k for k, _ in gridded]
        mesh = np.array(np.meshgrid(*[p.grid for _, p in gridded], indexing="ij")).reshape(len(keys), -1).T
        best, seen = (np.inf, None), set()
        for row in mesh:
            trial_theta = _canonical({**theta, **dict(zip(keys, map(float, row), strict=True))}, all_params)
            row_key = tuple(trial_theta[k] for k in keys)
            if row_key in seen:  # a row that differs only in a parameter its form does not use
                continue
            seen.add(row_key)
            cost = float(np.sum(prob.train_residual(trial_theta) ** 2))
            if cost < best[0]:
                best = (cost, trial_theta)
        theta = best[1]
    free = [k for k, p in all_params.items() if not p.discrete and _active(k, p, theta)]
    if free:
        theta = _refine(prob, theta, free, all_params)
    phis, betas, res = prob.solve(theta)
    n_lin = phis[0].shape[1]
    return FittedModel(
        effects=tuple(s.name for s in model),
        theta=theta,
        beta=tuple(betas),
        linear_names=family.linear_names(model),
        predictions=tuple(y - r for y, r in zip(y_band, res, strict=True)),
        residuals=tuple(res),
        n_params=n_lin * len(trials) + len(free),
    )


def _active(key: str, p: NLParam, theta: dict[str, float]) -> bool:
    """Whether ``p`` (full name ``key``) acts in the form ``theta`` selects (:class:`NLParam`)."""
    if p.active_when is None:
        return True
    name, value = p.active_when
    return theta[f"{key.rsplit('.', 1)[0]}.{name}"] == value


def active_params(theta: dict[str, float], model: tuple[Surrogate, ...]) -> dict[str, float]:
    """``theta`` less the parameters of the forms ``model`` did not take (what a report shows)."""
    params = {f"{s.name}.{p.name}": p for s in model for p in s.params}
    return {k: v for k, v in theta.items() if k not in params or _active(k, params[k], theta)}


def _canonical(theta: dict[str, float], params: dict[str, NLParam]) -> dict[str, float]:
    """``theta`` with every parameter its form does not use at its first grid value."""
    for k, p in params.items():
        if k in theta and not _active(k, p, theta):
            theta[k] = float(p.grid[0])
    return theta


def _past_grid_end(u0: float, cost0: float, grid_u: list[float], lo: float, hi: float, cost) -> float:
    """Where the one-parameter search centres its window: ``u0``, or, where ``u0`` is the grid's
    first or last point, the best of the grid continued at its end spacing out to the bound
    (``cost``: the concentrated cost at a point, ``cost0`` its value at ``u0``).

    The grid spans less than the declared bounds (a channel delay's grid -20...40 ms, its bounds
    -30...60 ms), and a window of one grid spacing about the grid's end cannot reach past it: a
    50 ms delay was fitted at 42.9 ms, the window's edge.
    """
    g = np.unique(np.asarray(grid_u, dtype=float))
    if g.size < 2:
        return u0
    tol = 1e-9 * max(hi - lo, 1e-300)
    if abs(u0 - g[-1]) <= tol and hi - g[-1] > tol:
        edge, spacing = hi, g[-1] - g[-2]
    elif abs(u0 - g[0]) <= tol and g[0] - lo > tol:
        edge, spacing = lo, g[0] - g[1]
    else:
        return u0
    n = int(np.ceil((edge - u0) / spacing - 1e-9))
    points = [u0 + k * spacing for k in range(1, n)] + [edge]
    costs = [cost0, *(cost(x) for x in points)]
    return [u0, *points][int(np.argmin(costs))]


def _refine(prob: _Problem, theta: dict, free: list[str], params: dict[str, NLParam]) -> dict:
    """Bounded least squares over the free nonlinear parameters (log coordinates where marked)."""

    def to_u(k, v):
        return np.log(v) if params[k].log else v

    def from_u(k, u):
        return float(np.exp(u)) if params[k].log else float(u)

    lo = np.array([to_u(k, params[k].lower) for k in free])
    hi = np.array([to_u(k, params[k].upper) for k in free])
    u0 = np.clip(np.array([to_u(k, theta[k]) for k in free]), lo + 1e-9, hi - 1e-9)

    def resid(u):
        return prob.train_residual({**theta, **{k: from_u(k, x) for k, x in zip(free, u, strict=True)}})

    cost0 = float(np.sum(resid(u0) ** 2))
    if len(free) == 1:
        # one parameter: a bounded scalar search on the concentrated cost (a few dozen solves,
        # where the trust-region solver spends most of its evaluations on finite differences)
        def cost1(x: float) -> float:
            return float(np.sum(resid(np.array([x])) ** 2))

        step = (hi[0] - lo[0]) / max(len(params[free[0]].grid), 4)
        grid_u = [to_u(free[0], g) for g in params[free[0]].grid]
        centre = _past_grid_end(u0[0], cost0, grid_u, lo[0], hi[0], cost1)
        a, b = max(lo[0], centre - step), min(hi[0], centre + step)
        sol1 = optimize.minimize_scalar(
            cost1,
            bounds=(a, b),
            method="bounded",
            # 1e-6 of the range: a channel delay's range is 90 ms and the ODE referee's sub-sample
            # delays are ~10 µs, where 1e-4 of it (9 µs) left a residual of the order of the floor
            options={"xatol": 1e-6 * (hi[0] - lo[0]), "maxiter": 60},
        )
        if sol1.fun <= cost0:
            return {**theta, free[0]: from_u(free[0], float(sol1.x))}
        return theta
    sol = optimize.least_squares(resid, u0, bounds=(lo, hi), x_scale="jac", diff_step=1e-3, max_nfev=60)
    cand = {**theta, **{k: from_u(k, x) for k, x in zip(free, sol.x, strict=True)}}
    return cand if np.sum(sol.fun**2) <= cost0 else theta
