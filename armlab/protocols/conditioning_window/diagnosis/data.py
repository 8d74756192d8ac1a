"""Measured trials of the conditioning-window protocol, prepared for the diagnosis.

Input is an armlab trial file (``trials.h5``, docs/trial_format.md) or the run folder holding
one: channels ``hand_pos`` (m) and ``hand_force`` (N, on the hand, shoulder frame), attrs
``arm_l1_m`` / ``arm_l2_m`` and every trial's ``onset_index``; the trial_meta ``group`` and
``direction`` are used where present (repeats of one perturbation). The joint-space signals are
those of the paper's processing (Sec. IV-C: inverse kinematics, zero-phase low-pass, central
differences, ``tau_ext = J^T F``, baselines over the pre-onset span), low-passed at the
diagnosis band instead of the estimator's 20 Hz.

Scoring rows are the samples 0-400 ms after each onset (the longest window of the issue's
breakdown), both joints. Whole trials are held out: the last of every three repeats of a
(group, direction) cell, or every third trial without metadata.

Noise floor (:func:`noise_variance`): the band-limited torque over the pre-onset hold (no
perturbation, no reflex: only sensor noise and tremor) is mapped back to hand-force noise
``J⁻ᵀ·Δτ`` and its 2×2 covariance pooled over trials; each scoring row's variance is that
covariance through the row's own ``J(q)ᵀ`` (a perturbation that extends the arm raises the
joint-torque noise of the same force noise by tens of percent) plus the variance of the trial's
baseline mean, which ``Δτ`` carries as a constant offset (the mean of a 200 ms baseline of 40 Hz
noise has about 1/16 of its variance). Both the sample covariance's loss to its own mean and
the baseline mean's variance come from the pre-onset autocorrelation. Without this, clean
recordings scored 1.2-1.5 times the floor and were called ``unknown``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from armlab.errors import DataError
from armlab.estimation.joint_ls import regressor
from armlab.estimation.processing import ProcessingConfig, differentiate, joint_signals, lowpass_zero_phase
from armlab.models.planar_arm import jacobian

__all__ = [
    "CHANNELS",
    "COMPLIANCE_BASIS_HZ",
    "WINDOW_S",
    "CondSet",
    "load_cond_trials",
    "prepare_cond",
]

CHANNELS = ("shoulder", "elbow")
#: Hz, low-pass of the measured torque from which the series-compliance basis is built: well
#: below the band, so the regressor carries little of the output's own noise (CondSet.u).
COMPLIANCE_BASIS_HZ = 15.0
WINDOW_S = 0.4  # s, end of the last window of the breakdown (250-400 ms)
_BASELINE_S = 0.2  # s, pre-onset span of the baselines (conditioning paper Sec. IV-C)
_EDGE_S = 0.05  # s, start of record left out of the noise estimate (filter start-up)
_REQUIRED = ("hand_pos", "hand_force")


@dataclass(frozen=True, eq=False)
class CondSet:
    """All trials of one dataset as one scoring set (the joint model is shared by the trials).

    Attributes:
        fs_hz: Hz.
        band_hz: Hz, the zero-phase low-pass (4th order) every signal went through; a model
            column with content above it (a friction step) goes through it too.
        onset: sample of the perturbation onset (common to all trials).
        n_window: samples scored after the onset.
        q, qd, qdd, dq, dtau: (m, n, 2) full-record joint signals (rad, rad/s, rad/s², rad, N·m).
        u, ud, udd: (m, n, 2) ``J⁻¹·ΔF`` and its derivatives (the joint displacement a 1 m/N
            series compliance adds under the force change ΔF). ``ΔF = J⁻ᵀΔτ`` with Δτ the
            measured torque low-passed at :data:`COMPLIANCE_BASIS_HZ`, well below the band: a
            regressor built from the band-limited measured force would carry the output's own
            noise and "explain" it (a test guards this). On the paper's fastest ramps (k = 1,
            T_k = 50 ms, content to 40 Hz) this basis misses the cuff's fast part, and neither
            the nominal model's noise-free prediction (first order in the compliance) nor that
            prediction plus the low-passed measured discrepancy recovers it: the reflex
            surrogate then takes the cuff's place (measured on the referee's tuning seed 7 with
            ``referee.cond_windows=[1, 26]``).
        l1, l2: m, segment lengths.
        direction, group: (m,) int perturbation labels (-1 where unknown).
        held_trials: (m,) bool, the held-out trials.
        noise_var: (m, n, 2) N·m², band-limited noise variance of ``dtau`` at every sample
            (:func:`noise_variance`).
        names: (m,) trial labels.
    """

    fs_hz: float
    band_hz: float
    onset: int
    n_window: int
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    dq: np.ndarray
    dtau: np.ndarray
    u: np.ndarray
    ud: np.ndarray
    udd: np.ndarray
    direction: np.ndarray
    group: np.ndarray
    held_trials: np.ndarray
    noise_var: np.ndarray
    names: tuple[str, ...]
    l1: float
    l2: float

    @property
    def n_trials(self) -> int:
        return self.q.shape[0]

    def rows(self, z: np.ndarray) -> np.ndarray:
        """(m, n, 2, ...) full-record array -> (m·n_window·2, ...) scoring rows."""
        w = z[:, self.onset : self.onset + self.n_window]
        return w.reshape(-1, *z.shape[3:])

    @property
    def y(self) -> np.ndarray:
        """Measured torque change on the scoring rows, N·m."""
        return self.rows(self.dtau)

    @property
    def row_noise_var(self) -> np.ndarray:
        """Noise variance of every scoring row, N·m²."""
        return self.rows(self.noise_var)

    @property
    def row_channel(self) -> np.ndarray:
        return np.tile(np.arange(2), self.n_trials * self.n_window)

    @property
    def row_time_s(self) -> np.ndarray:
        return np.tile(np.repeat(np.arange(self.n_window) / self.fs_hz, 2), self.n_trials)

    @property
    def row_trial(self) -> np.ndarray:
        return np.repeat(np.arange(self.n_trials), 2 * self.n_window)

    @property
    def held(self) -> np.ndarray:
        """Bool mask of the held-out scoring rows (trial, sample, joint flattened)."""
        return self.held_trials[self.row_trial]

    @property
    def train(self) -> np.ndarray:
        return ~self.held

    @cached_property
    def nominal_columns(self) -> np.ndarray:
        """(m, n, 2, 11) regressor of Eq. (9) over the full records (computed once)."""
        return regressor(self.q, self.qd, self.qdd, self.dq)


def load_cond_trials(path: Path):
    """Read a conditioning-window trial file (or the run folder that holds ``trials.h5``)."""
    from armlab.data.h5io import read_trial_file

    path, trials = read_trial_file(path, _REQUIRED, "the conditioning_window diagnosis")
    for key in ("arm_l1_m", "arm_l2_m"):
        if key not in trials.attrs:
            raise DataError(
                f"{path.name} lacks attr {key!r} (segment length, m); have {sorted(trials.attrs)}"
            )
    _check_units(path, trials)
    return trials


# m: the hand from the shoulder; the longest human arms (shoulder to fingertip) measure ~0.8 m
_MAX_HAND_POS_M = 1.0
# N: the largest forces a human arm pushes or pulls with are some 300-600 N (maximal effort)
_MAX_HAND_FORCE_N = 1000.0


def _check_units(path: Path, trials) -> None:
    """The stored units are those the diagnosis computes in (m, N), and the values are within
    human ranges (a file written in mm or with forces in mN is refused, naming the channel)."""
    for name, unit, bound, other in (
        ("hand_pos", "m", _MAX_HAND_POS_M, "mm"),
        ("hand_force", "N", _MAX_HAND_FORCE_N, "mN"),
    ):
        stored = trials.units.get(name)
        if stored != unit:
            raise DataError(
                f"{path.name}: channel {name!r} is in {stored!r}; the diagnosis reads it in {unit!r}"
            )
        peak = float(np.max(np.abs(trials.channel(name))))
        if peak > bound:
            raise DataError(
                f"{path.name}: channel {name!r} reaches {peak:.4g} {unit}, beyond a human arm's range "
                f"(<= {bound:g} {unit}): it looks like {other} stored as {unit!r}; store it in {unit}"
            )


def _holdout(direction: np.ndarray, group: np.ndarray, holdout_fraction: float) -> np.ndarray:
    every = max(2, int(round(1.0 / holdout_fraction)))
    held = np.zeros(direction.size, bool)
    for key in set(zip(group.tolist(), direction.tolist(), strict=True)):
        idx = np.flatnonzero((group == key[0]) & (direction == key[1]))
        held[idx[every - 1 :: every]] = True
    if not held.any():  # fewer than `every` repeats per cell: every `every`-th trial overall
        held[every - 1 :: every] = True
    if held.all() or not held.any():
        raise DataError(
            f"{direction.size} trial(s) cannot be split into training and held-out trials; need >= 2"
        )
    return held


def _mean_variance_factor(rho: np.ndarray, n: int) -> float:
    """var(mean of n samples) / variance, for a stationary noise of autocorrelation ``rho``."""
    k = np.arange(min(n, rho.size))
    return float((rho[0] * n + 2.0 * np.sum((n - k[1:]) * rho[k[1:]])) / n**2)


def noise_variance(dtau: np.ndarray, jac: np.ndarray, on: int, edge: int, n_base: int) -> np.ndarray:
    """(m, n, 2) noise variance of ``dtau`` at every sample, from its pre-onset hold (module doc).

    Args:
        dtau: (m, n, 2) band-limited baseline-subtracted torque, N·m; jac: (m, n, 2, 2) the arm
            Jacobian at every sample, m/rad.
        on: onset sample; edge: first pre-onset sample used; n_base: baseline samples before onset.
    """
    pre = dtau[:, edge:on]
    pre = pre - pre.mean(axis=1, keepdims=True)
    n_pre = pre.shape[1]
    # autocorrelation of the hold's noise (both joints, all trials), to the last lag that matters
    full = np.fft.irfft(np.abs(np.fft.rfft(pre, 2 * n_pre, axis=1)) ** 2, axis=1)[:, :n_pre]
    acf = full.sum(axis=(0, 2))
    rho = acf / acf[0] * n_pre / (n_pre - np.arange(n_pre))  # unbiased lag products
    cut = int(np.argmax(rho < 0)) or n_pre  # up to the first zero crossing
    rho = rho[:cut]
    loss = _mean_variance_factor(rho, n_pre)  # the sample covariance's loss to its own mean
    f = np.linalg.solve(np.swapaxes(jac[:, edge:on], -1, -2), pre[..., None])[..., 0]  # hand-force noise
    cov_f = np.einsum("tsi,tsj->ij", f, f) / (f.shape[0] * n_pre) / (1.0 - loss)
    var = np.einsum("tsji,jk,tski->tsi", jac, cov_f, jac)
    base = var[:, on - n_base : on].mean(axis=1, keepdims=True)
    return var + _mean_variance_factor(rho, n_base) * base


def prepare_cond(trials, *, band_hz: float, holdout_fraction: float) -> CondSet:
    """Joint-space signals, scoring rows, hold-out split and noise floor of a trial set."""
    fs = float(trials.fs_hz)
    onset = np.asarray(trials.onset_index)
    if np.any(onset != onset[0]):
        raise DataError(f"trials have different onset samples ({np.unique(onset)}); the diagnosis needs one")
    on = int(onset[0])
    n_window = int(round(WINDOW_S * fs))
    if trials.n_samples - on < n_window:
        raise DataError(
            f"trials end {(trials.n_samples - on) / fs:.3f} s after onset; the diagnosis windows need "
            f"{WINDOW_S} s (0-20 ... 250-400 ms)"
        )
    n_base = int(round(_BASELINE_S * fs))
    if on - int(round(_EDGE_S * fs)) < n_base // 2:
        raise DataError(
            f"trials start {on / fs:.3f} s before onset; the baseline and noise floor need >= 0.15 s"
        )
    if not 0 < band_hz < fs / 2:
        raise DataError(f"diagnosis.band_hz={band_hz} must lie in (0, {fs / 2}) Hz (Nyquist)")
    l1, l2 = float(trials.attrs["arm_l1_m"]), float(trials.attrs["arm_l2_m"])
    proc = ProcessingConfig(lowpass_hz=band_hz, filter_order=4, baseline_s=_BASELINE_S)
    sig = joint_signals(trials.channel("hand_pos"), trials.channel("hand_force"), fs, onset, l1, l2, proc)
    # the series-compliance basis u = J⁻¹ J⁻ᵀ Δτ (see CondSet.u)
    jac = jacobian(sig.q, l1, l2)
    dtau_slow = lowpass_zero_phase(sig.dtau, fs, COMPLIANCE_BASIS_HZ, 4, axis=1)
    u = np.linalg.solve(jac, np.linalg.solve(np.swapaxes(jac, -1, -2), dtau_slow[..., None]))[..., 0]
    ud, udd = differentiate(u, fs, axis=1)
    meta = trials.trial_meta
    m = trials.n_trials
    direction = np.asarray(meta.get("direction", np.full(m, -1)), int)
    group = np.asarray(meta.get("group", np.full(m, -1)), int)
    held_trials = _holdout(direction, group, holdout_fraction)
    edge = int(round(_EDGE_S * fs))
    noise_var = noise_variance(sig.dtau, jac, on, edge, min(n_base, on))
    return CondSet(
        fs_hz=fs,
        band_hz=float(band_hz),
        onset=on,
        n_window=n_window,
        q=sig.q,
        qd=sig.qd,
        qdd=sig.qdd,
        dq=sig.dq,
        dtau=sig.dtau,
        u=u,
        ud=ud,
        udd=udd,
        direction=direction,
        group=group,
        held_trials=held_trials,
        noise_var=noise_var,
        names=tuple(f"trial {i}" for i in range(m)),
        l1=l1,
        l2=l2,
    )
