"""Measured ``cartesian_online`` trials, prepared for the diagnosis.

Input is an armlab trial file (``trials.h5``, docs/trial_format.md) or the run folder holding
one. Only what a lab measures is read: the channels ``hand_pos`` (m, the robot's cuff position),
``ref_pos`` (m, the stopped reference the robot was commanded to) and ``hand_force`` (N, the F/T
reading in the thesis's frame), and the trial_meta ``case``, ``stop``, ``n_logged`` and
``t_start_s`` where present. Never ``true_*``, ``human_force``, ``pert_pos`` (it is recomputed as
``hand_pos - ref_pos``) or the ``truth_json`` attribute. The thesis logs one trial per perturbation
(Ch. 3, §3.2.2); a run folder holds several cases, of which the diagnosis takes Exp. 4's
(``exp4``: the circle, +x / −y / (+x, −y) sequences), or the only case a file holds.

Velocity is the file's ``hand_vel`` channel where it has one (level B writes the central
differences of its encoders' position; level A the generator's exact ``q̇_h``), else the central
differences of ``hand_pos``. It is low-passed where the position's own noise outgrows the
perturbation's spectrum below the band (:mod:`.position_noise`: the cut-off is read from the
data). Acceleration is the central differences of that velocity. Where it is smoothed, the
samples within the smoothed differentiator's response of a trial's ends are not scored (there the
filter's edge extension, not the record, sets the velocity; :func:`.position_noise.
edge_guard_samples`: 39 ms at a 25 Hz cut-off, none on ideal sensors). Scoring
rows are the remaining logged samples of every trial, both axes, after a zero-phase low-pass at ``band_hz``
(4th order forward-backward, the same filter on the force and on every model column, so a linear
model stays linear). Whole sequences are held
out: every third stop, starting with the second (the field is fitted on the others around the
circle and predicts the held-out ones).

Noise floor (:mod:`.noise_floor`): the white force noise of each axis from the second
differences of the raw force (a trimmed mean of their squares, so the triangle's corners do not
count and a quantised sensor's grid does not bias it), through the band's zero-phase filter (its
exact white-noise gain, the sum of its squared impulse response). A noise low-passed before it
is sampled (gauge noise through the sensor's filter) has second differences far below ``6σ²``
(2 % of the truth through a 125 Hz 2nd-order filter), so only the *white* part is read there.
It is never taken below :data:`MIN_FLOOR` of the force's power: on noise-free data (level A)
the gap is round-off, which no effect explains. The position sensor's white noise, read the same
way from ``hand_pos``, adds its share through the nominal field (:attr:`CartSet.row_noise_var`,
:mod:`.position_noise`), and so do per-trial force offsets (the F/T's residual tare, which a
held-out trial cannot predict: read from the trial means of the nominal field's residual beyond
a smooth function of the stop and time).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from armlab.dsp import lowpass_zero_phase
from armlab.errors import DataError, EstimationError
from armlab.estimation.sqrt_damping_fit import fit_sqrt_damping_field
from armlab.models.cartesian_field import quadratic_basis
from armlab.protocols.cartesian_online.diagnosis.noise_floor import (
    band_noise_gain,
    trial_offset_var,
    white_noise_var,
)
from armlab.protocols.cartesian_online.diagnosis.position_noise import (
    differentiated_gain,
    edge_guard_samples,
    smooth_velocity,
    snr_cutoff_hz,
)

__all__ = [
    "AXES",
    "MIN_FLOOR",
    "CartSet",
    "load_cart_trials",
    "prepare_cart",
]

AXES = ("x", "y")
_REQUIRED = ("hand_pos", "ref_pos", "hand_force")
_MAX_HAND_POS_M = 2.0  # m, the thesis's workspace lies within 1.2 m of its origin (Table 3.3)
_MAX_HAND_VEL_M_S = 10.0  # m/s, beyond the fastest human reaching (~2-5 m/s): the unit is not m/s
_MAX_HAND_FORCE_N = 2000.0  # N, ten times the JR3's rated 200 N: beyond, the unit is not N
_HELD_EVERY = 3  # every third sequence is held out
#: fewest logged samples a trial may have: a tenth of the thesis's 0.4 s perturbation at 1 kHz
#: (the differences, the periodogram and the edge guard need a stretch of samples)
_MIN_LOGGED = 40
#: the smallest noise variance, as a fraction of the force's mean square per axis: the 12 + 2 fit's
#: round-off on noise-free data (level A: gap ~1e-12 with the exact velocity) stays below it, and
#: the JR3's 0.0122 N steps alone (0.0035 N rms) are 3e-8 of a 20 N rms force
MIN_FLOOR = 1e-9


def load_cart_trials(path: Path):
    """Read a ``cartesian_online`` trial file (or the run folder that holds ``trials.h5``).

    Raises:
        DataError: no single ``.h5`` file, a missing channel, or values outside the units' ranges.
    """
    from armlab.data.h5io import read_trial_file

    path, trials = read_trial_file(path, _REQUIRED, "the cartesian_online diagnosis")
    checked = [("hand_pos", _MAX_HAND_POS_M), ("ref_pos", _MAX_HAND_POS_M), ("hand_force", _MAX_HAND_FORCE_N)]
    if "hand_vel" in trials.channels:
        checked.append(("hand_vel", _MAX_HAND_VEL_M_S))
    for name, bound in checked:
        a = np.asarray(trials.channels[name])
        if a.shape[-1] != 2:
            raise DataError(f"{path.name}: channel {name!r} must have the 2 axes (x, y), got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise DataError(f"{path.name}: channel {name!r} holds NaN or infinite values")
        if np.abs(a).max() > bound:
            unit = {"hand_force": "N", "hand_vel": "m/s"}.get(name, "m")
            raise DataError(
                f"{path.name}: channel {name!r} reaches {np.abs(a).max():.4g}, beyond {bound:g} {unit}; "
                f"the diagnosis computes in m and N (stored unit: {trials.units.get(name)!r})"
            )
    return trials


def _case_rows(trials) -> np.ndarray:
    """Indices of the trials of the case diagnosed (module docstring)."""
    case = trials.trial_meta.get("case")
    if case is None:
        return np.arange(np.shape(trials.channels["hand_pos"])[0])
    case = np.asarray(case).astype(str)
    names = list(dict.fromkeys(case))
    if "exp4" in names:
        return np.flatnonzero(case == "exp4")
    if len(names) == 1:
        return np.arange(len(case))
    raise DataError(
        f"the trial file holds the cases {names} but no 'exp4' (Exp. 4, the circle's sequences); "
        "valid: a file with an 'exp4' case or with one case only"
    )


@dataclass(frozen=True, eq=False)
class CartSet:
    """One dataset's trials as one scoring set (the field is shared by every trial).

    Attributes:
        fs_hz: Hz; band_hz: Hz, the zero-phase low-pass of the scoring rows.
        q, p, v, a: (m, n, 2) measured hand position m, perturbation ``q - q_ref`` m, velocity
            m/s, acceleration m/s² (central differences), unfiltered.
        force: (m, n, 2) N, measured force, unfiltered.
        u: (m, n, 2) N, the nominal field's force at the measured states, ``K̂₀(q)·p + δ₀√K̂₀(q)·v``
            (the cuff-compliance basis: a cuff stretches by ``F/k``, to first order by the
            nominal prediction's; built from the measured force instead, the basis would carry
            the output's own noise and "explain" it).
        t: (m, n) s, time of each sample from the first trial's start (drift basis).
        valid: (m, n) bool, logged samples (the padding of shorter trials excluded).
        scored: (m, n) bool, the scoring rows' samples: the logged ones less ``edge_guard`` at
            each end of a trial (:func:`.position_noise.edge_guard_samples`).
        edge_guard: samples not scored at each end of a trial (0 unless the velocity is
            smoothed).
        stop: (m,) int, the sequence (stop) of each trial, 0.. in time order.
        phase: (m,) str, the perturbation within its sequence: ``+x``, ``-y``, ``+x-y`` (from the
            measured excursion's axes and signs).
        held_trials: (m,) bool.
        centre: (2,) m and radius m: the stops' centroid and rms distance (the basis's scaling).
        k0: (2, 6) N/m per power of m, delta0 (2,): the nominal field fitted on the training
            sequences by the protocol's estimator (D = δ√K, 12 + 2 parameters).
        noise_var: (2,) N², white force-noise variance per axis (raw rate).
        noise_gain: the band filter's white-noise variance gain.
        offset_var: (2,) N², variance of the per-trial force offsets (the F/T's residual tare,
            :func:`.noise_floor.trial_offset_var`; constant within a trial, so the band passes it
            whole).
        pos_noise_var: (2,) m², white position-noise variance per axis (raw rate).
        vel_cutoff_hz: (2,) Hz, the velocity's smoothing cut-off per axis (``inf``: none; applied
            only below ``band_hz``).
        vel_gain: (2,) (m/s)² per m², white position noise's variance gain into the velocity
            column (central difference, smoothing, band).
        names: (m,) trial labels.
    """

    fs_hz: float
    band_hz: float
    q: np.ndarray
    p: np.ndarray
    v: np.ndarray
    a: np.ndarray
    force: np.ndarray
    u: np.ndarray
    t: np.ndarray
    valid: np.ndarray
    scored: np.ndarray
    edge_guard: int
    stop: np.ndarray
    phase: np.ndarray
    held_trials: np.ndarray
    centre: np.ndarray
    radius: float
    k0: np.ndarray
    delta0: np.ndarray
    noise_var: np.ndarray
    noise_gain: float
    offset_var: np.ndarray
    pos_noise_var: np.ndarray
    vel_cutoff_hz: np.ndarray
    vel_gain: np.ndarray
    names: tuple[str, ...]

    @property
    def n_trials(self) -> int:
        return self.q.shape[0]

    def band(self, z: np.ndarray) -> np.ndarray:
        """(m, n, ...) -> the same, zero-phase low-passed at ``band_hz`` along the samples."""
        return lowpass_zero_phase(z, self.fs_hz, self.band_hz, 4, axis=1, padtype="even")

    def rows(self, z: np.ndarray) -> np.ndarray:
        """(m, n, 2, ...) -> (rows, ...): the scored samples, both axes, trial-major."""
        return z[self.scored].reshape(-1, *z.shape[3:])

    @cached_property
    def row_trial(self) -> np.ndarray:
        idx = np.broadcast_to(np.arange(self.n_trials)[:, None, None], (*self.valid.shape, 2))
        return self.rows(idx)

    @cached_property
    def row_axis(self) -> np.ndarray:
        return self.rows(np.broadcast_to(np.arange(2), (*self.valid.shape, 2)))

    @cached_property
    def row_time_s(self) -> np.ndarray:
        """Time of each row after its perturbation's onset, s."""
        t = np.arange(self.valid.shape[1]) / self.fs_hz
        return self.rows(np.broadcast_to(t[None, :, None], (*self.valid.shape, 2)))

    @cached_property
    def held(self) -> np.ndarray:
        return self.held_trials[self.row_trial]

    @cached_property
    def train(self) -> np.ndarray:
        return ~self.held

    @cached_property
    def y(self) -> np.ndarray:
        """Measured force on the scoring rows, N (band-limited)."""
        return self.rows(self.band(self.force))

    @cached_property
    def row_noise_var(self) -> np.ndarray:
        """N², band-limited noise variance of each row: the force's white noise, plus the position's
        through the nominal field, ``σ_e²·(K̂₀(q)²·g_band + δ₀²K̂₀(q)·g_v)`` (:mod:`.position_noise`;
        the cross term is zero: one impulse response is even, the other odd), plus the per-trial
        offsets' variance (:mod:`.noise_floor`)."""
        k = self.rows(np.maximum(quadratic_basis(self.q) @ self.k0.T, 0.0))  # (rows,) N/m, K̂₀ at q
        ax = self.row_axis
        eiv = self.pos_noise_var[ax] * (k**2 * self.noise_gain + self.delta0[ax] ** 2 * k * self.vel_gain[ax])
        return self.noise_var[ax] * self.noise_gain + eiv + self.offset_var[ax]


def _phase_labels(p: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """'+x', '-y', '+x-y' (or another sign pattern) from each trial's largest excursion."""
    peak = np.where(valid[..., None], p, 0.0)
    idx = np.argmax(np.abs(peak), axis=1)  # (m, 2)
    ext = np.take_along_axis(peak, idx[:, None, :], axis=1)[:, 0]  # (m, 2) signed peak
    moved = np.abs(ext) > 0.25 * np.abs(ext).max(axis=1, keepdims=True)
    out = []
    for e, mv in zip(ext, moved, strict=True):
        out.append("".join(("+" if e[j] > 0 else "-") + AXES[j] for j in range(2) if mv[j]))
    return np.array(out)


def _nominal_force(k: np.ndarray, p: np.ndarray, v: np.ndarray, fits) -> np.ndarray:
    """(m, n, 2) N: the fitted field's force ``K(q)·p + δ√K(q)·v`` at the measured states, with
    ``k`` = K̂(q) (m, n, 2) N/m."""
    root = np.sqrt(np.maximum(k, 0.0))
    return k * p + np.array([f.delta for f in fits]) * root * v


def _white_var(k, valid, noise_var, pos_noise_var) -> np.ndarray:
    """(m, 2) N², per trial, the white noise's variance per sample in the nominal's raw residual,
    as far as its trial mean goes: the force's, plus the position's through the fitted stiffness,
    ``mean(K̂(q)²)·σ_e²``. The damping column's share is left out (a derivative of noise averages
    to its end values over a trial, but the smoothed one's are correlated: 23-33 % of the
    stiffness term on the thesis's field at a 25 Hz cut-off, measured), so the offsets read ~3 %
    high in variance on the default lab. ``k``: (m, n, 2) N/m, the fitted stiffness K̂(q)."""
    n = np.maximum(valid.sum(axis=1), 1)[:, None]
    k2 = np.where(valid[..., None], np.maximum(k, 0.0) ** 2, 0.0).sum(axis=1) / n
    return noise_var[None, :] + k2 * pos_noise_var[None, :]


def prepare_cart(trials, *, band_hz: float) -> CartSet:
    """The scoring set of a ``cartesian_online`` trial file (module docstring).

    Args:
        trials: a :class:`armlab.data.trial.TrialSet` (see :func:`load_cart_trials`).
        band_hz: Hz, the scoring band's top (below fs/2).

    Raises:
        DataError: fewer than 4 sequences (two to fit the field, one to hold out, one more), or a
            nominal field the training sequences cannot determine.
    """
    fs = float(trials.fs_hz)
    if not 0 < band_hz < 0.5 * fs:
        raise DataError(
            f"diagnosis.band_hz must lie in (0, {0.5 * fs:g}) Hz at fs = {fs:g} Hz, got {band_hz}"
        )
    rows = _case_rows(trials)
    ch = {k: np.asarray(trials.channels[k], float)[rows] for k in _REQUIRED}
    meta = {k: np.asarray(v)[rows] for k, v in trials.trial_meta.items()}
    m, n, _ = ch["hand_pos"].shape
    n_logged = np.minimum(meta.get("n_logged", np.full(m, n)).astype(int), n)  # at most the stored
    short = np.flatnonzero(n_logged < _MIN_LOGGED)
    if short.size:
        raise DataError(
            f"trial_meta 'n_logged' must be at least {_MIN_LOGGED} samples for every trial; trials "
            f"{short[:5].tolist()} have {n_logged[short[:5]].tolist()}"
        )
    valid = np.arange(n)[None, :] < n_logged[:, None]
    q = ch["hand_pos"]
    ref = ch["ref_pos"]
    p = q - ref
    if "hand_vel" in trials.channels:
        v = np.asarray(trials.channels["hand_vel"], float)[rows]
    else:
        v = np.gradient(q, 1.0 / fs, axis=1)
    pos_noise_var = white_noise_var(q, valid)
    vel_cutoff = snr_cutoff_hz(p, valid, pos_noise_var, fs)
    v = smooth_velocity(v, fs, vel_cutoff, band_hz)
    guard = min(edge_guard_samples(fs, vel_cutoff, band_hz), int(n_logged.min()) // 4)
    j = np.arange(n)[None, :]
    scored = valid & (j >= guard) & (j < n_logged[:, None] - guard)
    a = np.gradient(v, 1.0 / fs, axis=1)
    force = ch["hand_force"]
    # the sequence of each trial: its stop, or the distinct reference positions in time order
    t0 = meta.get("t_start_s", np.arange(m) * n / fs).astype(float)
    if "stop" in meta:
        _, stop = np.unique(meta["stop"].astype(int), return_inverse=True)
    else:
        _, stop = np.unique(np.round(ref[:, 0], 6), axis=0, return_inverse=True)
        first = np.array([t0[stop.ravel() == s].min() for s in range(stop.max() + 1)])
        stop = np.argsort(np.argsort(first))[stop.ravel()]
    stop = stop.ravel()
    n_seq = int(stop.max()) + 1
    if n_seq < 4:
        raise DataError(
            "the diagnosis needs at least 4 sequences (stops) to fit the field and hold some out, "
            f"got {n_seq}"
        )
    held_trials = stop % _HELD_EVERY == 1
    train_valid = valid & ~held_trials[:, None]
    try:
        fits = [
            fit_sqrt_damping_field(
                q[train_valid], p[train_valid], v[train_valid], force[train_valid][:, j], j
            )
            for j in range(2)
        ]
    except EstimationError as err:
        raise DataError(f"the nominal field cannot be fitted on the training sequences: {err}") from None
    stops = np.array([ref[stop == s, 0].mean(axis=0) for s in range(n_seq)])
    centre = stops.mean(axis=0)
    radius = float(np.sqrt(np.mean(np.sum((stops - centre) ** 2, axis=1)))) or 0.1
    power = np.mean(force[valid] ** 2, axis=0)
    noise_var = np.maximum(white_noise_var(force, valid), MIN_FLOOR * power)
    phase = _phase_labels(p, valid)
    k_hat = np.stack([quadratic_basis(q) @ f.k for f in fits], axis=-1)  # (m, n, 2) N/m, K̂(q)
    u = _nominal_force(k_hat, p, v, fits)
    names = tuple(f"seq {s} {ph}" for s, ph in zip(stop, phase, strict=True))
    return CartSet(
        fs_hz=fs,
        band_hz=float(band_hz),
        q=q,
        p=p,
        v=v,
        a=a,
        force=force,
        u=u,
        t=(t0 - t0.min())[:, None] + np.arange(n)[None, :] / fs,
        valid=valid,
        scored=scored,
        edge_guard=guard,
        stop=stop,
        phase=phase,
        held_trials=held_trials,
        centre=centre,
        radius=radius,
        k0=np.array([f.k for f in fits]),
        delta0=np.array([f.delta for f in fits]),
        noise_var=noise_var,
        noise_gain=band_noise_gain(fs, band_hz),
        offset_var=trial_offset_var(
            force - u,
            valid,
            phase,
            (ref[:, 0] - centre) / radius,
            t0,
            _white_var(k_hat, valid, noise_var, pos_noise_var),
        ),
        pos_noise_var=pos_noise_var,
        vel_cutoff_hz=vel_cutoff,
        vel_gain=np.array([differentiated_gain(fs, band_hz, float(fc)) for fc in vel_cutoff]),
        names=names,
    )
