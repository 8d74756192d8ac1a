"""Measured 1-DoF joint trials prepared for the diagnosis: band-limited, decimated, split.

Every trial (position in, torque out, as imported by :mod:`armlab.data.joint_import`) becomes a
:class:`PreparedTrial` at the fitting rate:

1. velocity and acceleration by five-point central differences of the raw position at the recorded rate;
2. zero-phase 4th-order Butterworth low-pass at ``band_hz`` of position, velocity, acceleration
   and torque at the recorded rate (anti-alias; identical on every channel, so their relative
   timing is kept). Differentiating first keeps the filtered torque the same linear combination
   of the filtered x, v, a up to the trial's ends (filtering first and differentiating after
   does not, near an end where the joint is moving); the filter's edge padding is even, so the
   first and last samples are band-limited too (odd padding pins them to the raw, full-band
   noisy values);
3. decimation to ``fs_fit_hz`` (every q-th sample);
4. the slow torque ``m(t)``: the zero-phase low-pass at ``slow_hz`` of the torque, less its
   least-squares fit by the equally low-passed position and a constant (the joint's static
   stiffness acting on the perturbation's own slow content, which would otherwise dominate it),
   scaled to zero mean and unit rms: the subject's tonic contraction level, the covariate of the
   co-contraction candidate.

The gap is scored in the perturbation band ``[highpass_hz, band_hz]``: below ``highpass_hz`` the
torque is dominated by the subject's voluntary/tonic fluctuations, which no protocol model
predicts. Models are fitted on the first ``1 - holdout_fraction`` of every trial and scored on
the rest (the REKLAB lab's own 0-40 s / 40-60 s split).

Noise floor: the torque noise variance in the scoring band, from repeated trials (trials whose
positions correlate above 0.99 are repeats of one perturbation: ``var(y_i - y_j) / 2``) or, with
no repeats, from the second differences of the raw torque (Rice 1984, Ann. Statist. 12:1215:
``E[(Δ²y)²] = 6σ²`` for white noise on a signal slow compared with the sampling; the scale is
taken robustly as 1.4826·MAD; higher differences where the signal still shows in the second,
:func:`_difference_variance`), scaled to the band on the assumption that the sensor noise is
white. With repeats, the smaller of the two estimates is used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

from armlab.dsp import butterworth, five_point_derivatives, grid_step, lowpass_zero_phase, zero_phase
from armlab.errors import DataError
from armlab.protocols.joint_1dof.diagnosis.grid_error import GRID_DRAWS, GridRuns

__all__ = [
    "EDGE_SAMPLES",
    "NoiseFloor",
    "PreparedTrial",
    "band_power_gain",
    "derivatives",
    "fit_decimation",
    "highpass_sos",
    "noise_floor",
    "prepare_trials",
    "repeat_groups",
    "slow_lowpass",
]

_REPEAT_CORR = 0.99  # 1, position correlation above which two trials are repeats
_BAND_ORDER = 4  # order of the one-way Butterworth anti-alias low-pass at band_hz
_SLOW_ORDER = 2  # order of the one-way Butterworth low-pass of the slow (tonic) torque
# the anti-alias and slow low-passes pad the record's ends by mirroring (see the module docstring)
_PADTYPE = "even"


@dataclass(frozen=True, kw_only=True, eq=False)
class PreparedTrial:
    """One trial at the fitting rate; all arrays (n,).

    Attributes:
        name: the trial's name.
        t_s: s, time from the trial's start.
        x, v, a: rad, rad/s, rad/s², band-limited joint angle and its derivatives.
        y: N·m, band-limited measured torque.
        m: 1, slow torque (tonic level), zero mean and unit rms.
        train: bool mask of the fitting part (first ``1 - holdout_fraction``, edges excluded).
        held: bool mask of the held-out part (the rest, edges excluded).
        fs_hz: Hz, the fitting rate.
        raw_fs_hz: Hz, the recorded rate.
        x_raw, v_raw: (n_raw,) rad, rad/s, unfiltered angle and velocity at the recorded rate:
            nonlinear and resonant model columns are computed from them and then band-limited
            and decimated like the torque (:meth:`to_fit_rate`), since a nonlinearity of a
            band-limited signal is not the band-limited nonlinearity.
        band_hz: Hz, the anti-alias cut-off.
        op: (n,) rad, the operating angle of a time-varying trial (band-limited and decimated
            like the angle) less the mean over all trials' operating angles (:attr:`op_ref`);
            None for a stationary trial.
        op_ref: rad, that mean (0 for a stationary trial).
    """

    name: str
    t_s: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    y: np.ndarray
    m: np.ndarray
    train: np.ndarray
    held: np.ndarray
    fs_hz: float
    raw_fs_hz: float
    x_raw: np.ndarray
    v_raw: np.ndarray
    band_hz: float
    op: np.ndarray | None = None
    op_ref: float = 0.0

    def to_fit_rate(self, z_raw: np.ndarray) -> np.ndarray:
        """A raw-rate signal (n_raw,) or (n_raw, k) band-limited and decimated like the torque."""
        q = int(round(self.raw_fs_hz / self.fs_hz))
        z = lowpass_zero_phase(z_raw, self.raw_fs_hz, self.band_hz, _BAND_ORDER, axis=0, padtype=_PADTYPE)
        return z[::q]


#: Samples at each end of a record whose derivatives use one-sided stencils (:func:`derivatives`).
EDGE_SAMPLES = 2

# fourth-order one-sided stencils at the first two samples (Fornberg 1988, Math. Comp. 51:699),
# rows: sample 0, sample 1; columns: x[0..5]
_EDGE_V = np.array([[-25.0, 48.0, -36.0, 16.0, -3.0, 0.0], [-3.0, -10.0, 18.0, -6.0, 1.0, 0.0]]) / 12.0
_EDGE_A = np.array([[45.0, -154.0, 214.0, -156.0, 61.0, -10.0], [10.0, -15.0, -4.0, 14.0, -6.0, 1.0]]) / 12.0


def derivatives(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """(rad/s, rad/s²) of a raw angle record (n,) at ``fs`` Hz, fourth order everywhere.

    Interior: five-point central differences (:func:`armlab.dsp.five_point_derivatives`; the
    three-point stencil, ``np.gradient`` twice, misses (ωΔt)²/3 = 2 % of the acceleration at
    40 Hz, 1 kHz, which left clean referee recordings 13-24 % of the noise variance above the
    floor; five points leave 4e-5). The first and last :data:`EDGE_SAMPLES` samples use
    fourth-order one-sided stencils instead of ``np.gradient``'s second-order ones: an end
    sample's error passes the anti-alias low-pass and the 0.3 Hz zero-phase scoring high-pass,
    whose tails reach ~2 s into the scored part; with second-order ends a clean 500 Hz multisine
    kept a held-out gap of 2.6e-7 (95 % of it in the last 2 s scored), 200 times a 1e-4 noise
    floor.
    """
    v, a = five_point_derivatives(x, fs, axis=0)
    if x.size >= 6:
        head, tail = x[:6], x[::-1][:6]
        v[:2], a[:2] = _EDGE_V @ head * fs, _EDGE_A @ head * fs * fs
        # the mirrored stencils at the end: time runs backwards, so the first derivative flips sign
        v[-2:], a[-2:] = (-_EDGE_V @ tail * fs)[::-1], (_EDGE_A @ tail * fs * fs)[::-1]
    return v, a


def slow_lowpass(z: np.ndarray, fs_hz: float, slow_hz: float) -> np.ndarray:
    """The tonic level's zero-phase low-pass at ``slow_hz`` along axis 0 (order :data:`_SLOW_ORDER`,
    mirrored ends): what :class:`PreparedTrial`'s ``m`` and the checks on it read as slow."""
    return lowpass_zero_phase(z, fs_hz, slow_hz, _SLOW_ORDER, axis=0, padtype=_PADTYPE)


def _tonic_torque(position: np.ndarray, torque: np.ndarray, slow_hz: float, fs: float) -> np.ndarray:
    """Slow torque not explained by the slow position: ``lp(τ) − (c0 + c1·lp(θ))``, least squares."""
    slow_t, slow_x = (slow_lowpass(z, fs, slow_hz) for z in (torque, position))
    basis = np.stack([np.ones_like(slow_x), slow_x], axis=1)
    coef, *_ = np.linalg.lstsq(basis, slow_t, rcond=None)
    return slow_t - basis @ coef


def fit_decimation(fs_hz: float, fs_fit_hz: float) -> int:
    """The integer decimation of a recorded rate that fits at ``fs_fit_hz`` or just above it.

    The largest q with ``fs_hz / q >= fs_hz_fit`` (1 for data recorded below it): rounding to the
    nearest q instead fitted 660 Hz data at 220 Hz, whose Nyquist frequency (110 Hz) cannot carry
    the sensor-bandwidth candidate's cut-offs, and the whole diagnosis was refused.
    """
    return max(1, int(np.floor(fs_hz / fs_fit_hz + 1e-9)))


def prepare_trials(
    records,
    *,
    fs_fit_hz: float,
    band_hz: float,
    holdout_fraction: float,
    slow_hz: float,
    min_duration_s: float,
    edge_s: float = 2.0,
) -> tuple[PreparedTrial, ...]:
    """Band-limit, differentiate, decimate and split imported trials.

    Args:
        records: sequence of objects with ``name``, ``position`` (n,) rad, ``torque`` (n,) N·m and
            ``fs_hz`` (e.g. :class:`armlab.data.joint_import.JointRecord`).
        fs_fit_hz: Hz, rate the models are fitted at, at least (:func:`fit_decimation`).
        band_hz: Hz, upper edge of the analysed band; below 0.45 of the fitting rate.
        holdout_fraction: the last fraction of every trial held out for scoring.
        slow_hz: Hz, cut-off of the slow (tonic) torque.
        min_duration_s: s, shortest acceptable trial.
        edge_s: s, excluded at both ends of every trial from fitting and scoring: the zero-phase
            filters (and any start-up transient of the record) disturb the first and last
            samples; 2 s is four time constants of the 0.3 Hz scoring high-pass.

    Raises:
        DataError: no trials, sample rates that differ, a trial too short, or a band the
            sample rate cannot carry.
    """
    records = list(records)
    if not records:
        raise DataError("no trials to diagnose")
    rates = {r.name: float(r.fs_hz) for r in records}
    fs = next(iter(rates.values()))
    if any(abs(f - fs) > 1e-6 * fs for f in rates.values()):
        raise DataError(f"trials have different sample rates {rates}; resample them to one rate first")
    q = fit_decimation(fs, fs_fit_hz)
    fs_fit = fs / q
    if band_hz >= 0.45 * fs_fit:
        raise DataError(
            f"diagnosis.band_hz={band_hz:g} Hz needs a fitting rate above {band_hz / 0.45:.0f} Hz; the data "
            f"({fs:g} Hz) with diagnosis.fs_fit_hz={fs_fit_hz:g} give {fs_fit:g} Hz; valid: band_hz < "
            f"{0.45 * fs_fit:.3g} Hz, or a higher fs_fit_hz (up to the data's rate)"
        )
    # a time-varying group: every trial carries its operating angle (else none is used)
    ops = [getattr(r, "operating_point", None) for r in records]
    varying = all(o is not None for o in ops)
    op_ref = float(np.mean(np.concatenate([np.asarray(o, float) for o in ops]))) if varying else 0.0
    out = []
    for r, op_raw in zip(records, ops, strict=True):
        n = np.asarray(r.position).size
        if n / fs < min_duration_s:
            raise DataError(
                f"trial {r.name!r} lasts {n / fs:.2f} s; the diagnosis needs at least {min_duration_s:g} s "
                "(training part, held-out part and the filter edges)"
            )
        xr = np.asarray(r.position, float)
        vr, ar = derivatives(xr, fs)
        x, v, a, y = (
            lowpass_zero_phase(z, fs, band_hz, _BAND_ORDER, axis=0, padtype=_PADTYPE)
            for z in (xr, vr, ar, np.asarray(r.torque, float))
        )
        slow = _tonic_torque(xr, np.asarray(r.torque, float), slow_hz, fs)[::q]
        slow = slow - slow.mean()
        rms = float(np.sqrt(np.mean(slow**2)))
        m = slow / rms if rms > 0 else slow
        nd = x[::q].size
        idx = np.arange(nd)
        inner = (idx >= edge_s * fs_fit) & (idx < nd - edge_s * fs_fit)
        first = idx < int(round((1.0 - holdout_fraction) * nd))
        if inner.sum() < 0.5 * nd:
            raise DataError(
                f"trial {r.name!r} lasts {n / fs:.2f} s; {edge_s:g} s at each end are not scored, "
                "which leaves less than half of it"
            )
        train, held = inner & first, inner & ~first
        op = None
        if varying:
            op = lowpass_zero_phase(
                np.asarray(op_raw, float), fs, band_hz, _BAND_ORDER, axis=0, padtype=_PADTYPE
            )
            op = op[::q] - op_ref
        out.append(
            PreparedTrial(
                name=r.name,
                t_s=np.arange(nd) / fs_fit,
                x=x[::q],
                v=v[::q],
                a=a[::q],
                y=y[::q],
                m=m,
                train=train,
                held=held,
                fs_hz=fs_fit,
                raw_fs_hz=fs,
                x_raw=xr,
                v_raw=vr,
                band_hz=band_hz,
                op=op,
                op_ref=op_ref,
            )
        )
    return tuple(out)


def repeat_groups(records) -> list[list[int]]:
    """Indices of trials that repeat one perturbation (position correlation > 0.99), groups of >= 2."""
    pos = [np.asarray(r.position, float) for r in records]
    groups: list[list[int]] = []
    used: set[int] = set()
    for i in range(len(pos)):
        if i in used:
            continue
        g = [i]
        for j in range(i + 1, len(pos)):
            if (
                j not in used
                and pos[j].size == pos[i].size
                and np.corrcoef(pos[i], pos[j])[0, 1] > _REPEAT_CORR
            ):
                g.append(j)
        if len(g) > 1:
            groups.append(g)
            used.update(g)
    return groups


@dataclass(frozen=True, kw_only=True)
class NoiseFloor:
    """Torque noise in the scoring band.

    Attributes:
        variance_Nm2: N·m², per-sample noise variance in the band.
        psd: (n_f,) N·m²/Hz one-sided noise spectral density on ``f_hz`` (flat when estimated
            from second differences).
        f_hz: (n_f,) Hz.
        source: ``"repeats"``, ``"second differences (white noise assumed)"`` (or a higher order),
            or the raw torque's grid (``q²/12``) where the noise measured beside a grid reads less.
    """

    variance_Nm2: float
    psd: np.ndarray
    f_hz: np.ndarray
    source: str


def highpass_sos(fs_hz: float, highpass_hz: float) -> np.ndarray:
    """Second-order sections of the scoring high-pass (2nd-order Butterworth, applied zero-phase)."""
    return butterworth(highpass_hz, fs_hz, 2, btype="high")


def noise_floor(records, prepared, *, band_hz: float, highpass_hz: float, nperseg: int = 512) -> NoiseFloor:
    """The noise floor in the scoring band (see the module docstring).

    Args:
        records: the imported trials (raw rate).
        prepared: their :class:`PreparedTrial` versions.
        band_hz: Hz, the anti-alias cut-off used by :func:`prepare_trials`.
        highpass_hz: Hz, the scoring high-pass.
        nperseg: Welch segment length at the fitting rate.
    """
    hp = highpass_sos(prepared[0].fs_hz, highpass_hz)
    floor = _measured_floor(records, prepared, band_hz, hp, nperseg)
    grid = _grid_floor(records, prepared, band_hz, hp, nperseg)
    return grid if grid is not None and grid.variance_Nm2 > floor.variance_Nm2 else floor


def _measured_floor(records, prepared, band_hz: float, hp: np.ndarray, nperseg: int) -> NoiseFloor:
    """The floor from the repeats' differences, or from the torque's own k-th differences."""
    fs = prepared[0].fs_hz
    groups = repeat_groups(records)
    if groups:
        # over the scored samples only (``train | held``): the excluded ends carry the filters'
        # start and end transients, which the scores never see
        diffs = [
            ((zero_phase(hp, prepared[g[k]].y) - zero_phase(hp, prepared[g[0]].y)) / np.sqrt(2.0))[
                prepared[g[0]].train | prepared[g[0]].held
            ]
            for g in groups
            for k in range(1, len(g))
        ]
        var = float(np.mean([np.var(d) for d in diffs]))
        # groups of repeats may differ in length: one Welch segment length for all, then average
        nper = min(nperseg, min(d.size for d in diffs))
        f = signal.welch(diffs[0], fs=fs, nperseg=nper)[0]
        p = np.mean([signal.welch(d, fs=fs, nperseg=nper)[1] for d in diffs], axis=0)
        white = _difference_floor(records, prepared, band_hz, hp, nperseg)
        if white.variance_Nm2 < var:
            # the repeats also differ by the subject's trial-to-trial variability (e.g. its
            # co-contraction level), which a candidate can explain from a covariate
            return NoiseFloor(
                variance_Nm2=white.variance_Nm2,
                psd=white.psd,
                f_hz=white.f_hz,
                source=f"{white.source}; below the repeats' estimate {var:.3g} N·m²",
            )
        return NoiseFloor(variance_Nm2=var, psd=p, f_hz=f, source="repeats")
    return _difference_floor(records, prepared, band_hz, hp, nperseg)


def band_power_gain(f_hz: np.ndarray, *, fs_hz: float, raw_fs_hz: float, band_hz: float, hp: np.ndarray):
    """(n_f,) 1: the power gain of the scoring band on white noise at ``f_hz``: the anti-alias
    low-pass at the recorded rate and the scoring high-pass at the fitting rate, each zero-phase
    (forward-backward: its power gain applied twice)."""
    _, h_lp = signal.sosfreqz(butterworth(band_hz, raw_fs_hz, _BAND_ORDER), worN=f_hz, fs=raw_fs_hz)
    _, h_hp = signal.sosfreqz(hp, worN=f_hz, fs=fs_hz)
    return np.abs(h_lp) ** 4 * np.abs(h_hp) ** 4


def _difference_floor(records, prepared, band_hz, hp, nperseg: int) -> NoiseFloor:
    """Noise floor from k-th differences of the raw torque (white noise assumed)."""
    fs = prepared[0].fs_hz
    raw_fs = prepared[0].raw_fs_hz

    order, s2 = _difference_variance([np.asarray(r.torque, float) for r in records])
    f = np.fft.rfftfreq(nperseg, 1.0 / fs)
    # white noise of variance s2 over 0..raw_fs/2 has the one-sided density 2*s2/raw_fs; the
    # zero-phase (forward-backward) filters apply their power gain twice
    psd = 2.0 * s2 / raw_fs * band_power_gain(f, fs_hz=fs, raw_fs_hz=raw_fs, band_hz=band_hz, hp=hp)
    return NoiseFloor(
        variance_Nm2=float(np.trapezoid(psd, f)),
        psd=psd,
        f_hz=f,
        source=f"{_ORDINAL[order]} differences of the raw torque (white noise assumed)",
    )


def _grid_floor(records, prepared, band_hz, hp, nperseg: int) -> NoiseFloor | None:
    """The floor of a torque recorded on a grid (a converter's step, or a file's rounding), or None.

    No model of the joint removes the grid's error, but where the noise beside it is small most of
    the torque's k-th differences are exactly 0 and their MAD reads no noise at all (and identical
    repeats differ by nothing), so this bounds the measured floor from below. The error is the
    angle's grid error model (:class:`~.grid_error.GridRuns`): a uniform ``q²/12`` per sample where
    the torque crosses a step every sample or two, a constant per hold where it holds still between
    moves (a smoothed PRBS's torque), which white ``q²/12`` underestimates many times over;
    :data:`~.grid_error.GRID_DRAWS` draws through the scoring filters, over the scored samples, and
    never less than white ``q²/12`` (Sheppard's correction).
    """
    steps = [grid_step(np.asarray(r.torque, float)) for r in records]
    if not all(q > 0 for q in steps):
        return None
    rng = np.random.default_rng(0)  # the draws are the estimate's own: fixed, bit-identical results
    parts = []
    for r, tr, q in zip(records, prepared, steps, strict=True):
        runs = GridRuns(np.asarray(r.torque, float), q)
        for _ in range(GRID_DRAWS):
            e = zero_phase(hp, tr.to_fit_rate(runs.error(rng.uniform(-0.5 * q, 0.5 * q, runs.length.size))))
            parts.append(e[tr.train | tr.held])
    q = float(np.mean(steps))
    fs, raw_fs = prepared[0].fs_hz, prepared[0].raw_fs_hz
    runs_var = float(np.mean([np.mean(e**2) for e in parts]))
    f = np.fft.rfftfreq(nperseg, 1.0 / fs)
    white = (
        2.0 * (q * q / 12.0) / raw_fs * band_power_gain(f, fs_hz=fs, raw_fs_hz=raw_fs, band_hz=band_hz, hp=hp)
    )
    if runs_var <= float(np.trapezoid(white, f)):
        # the runs' settling rounds off slow crossings (a sum of sines: 0.34-1.04 of the true
        # error for the angle, position_sensor): a grid's error is never whiter than uniform
        return NoiseFloor(
            variance_Nm2=float(np.trapezoid(white, f)),
            psd=white,
            f_hz=f,
            source=f"the raw torque's grid of {q:.3g} N·m, q²/12 white (the measured noise reads less)",
        )
    nper = min(nperseg, min(e.size for e in parts))
    f = signal.welch(parts[0], fs=fs, nperseg=nper)[0]
    psd = np.mean([signal.welch(e, fs=fs, nperseg=nper)[1] for e in parts], axis=0)
    return NoiseFloor(
        variance_Nm2=runs_var,
        psd=psd,
        f_hz=f,
        source=f"the raw torque's grid of {q:.3g} N·m, held between steps (the measured noise reads less)",
    )


_ORDINAL = {2: "second", 3: "third", 4: "fourth", 5: "fifth"}
_PLATEAU = 1.05  # 1, ratio of successive orders' estimates below which the signal no longer counts


def _difference_variance(torques: list[np.ndarray]) -> tuple[int, float]:
    """(difference order k, white-noise variance N·m²) from the k-th differences of the raw torques.

    For white noise of variance σ², ``E[(Δᵏy)²] = C(2k, k)·σ²`` (6σ² for k = 2: Rice 1984), and
    the scale is taken robustly as 1.4826·MAD (the signal's own differences are sparse spikes,
    acceleration steps of a pseudo-random perturbation, that a mean square would count as noise).
    The signal's share shrinks as hᵏ with the order while the noise's estimate does not, so the
    order rises from 2 while the estimate still falls by more than :data:`_PLATEAU` (up to 5):
    at noise 1e-4 of the torque's rms the second differences of a smoothed PRBS torque read 2.7x
    the noise variance, the fourth 1.03x; at 1e-2 and above the second differences are kept (no
    change). Noise that is not white (a sensor's low-pass) is underestimated by a higher order
    more than by the second, which is why the order stops at the plateau.
    """

    def mad(k: int) -> float:
        ests = []
        for z in torques:
            d = np.diff(z, k)
            ests.append((1.4826 * float(np.median(np.abs(d - np.median(d))))) ** 2 / math.comb(2 * k, k))
        return float(np.mean(ests))

    k, est = 2, mad(2)
    while k < 5:
        nxt = mad(k + 1)
        if est <= _PLATEAU * nxt:
            break
        k, est = k + 1, nxt
    return k, est
