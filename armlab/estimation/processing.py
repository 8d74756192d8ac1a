"""Measurement processing of Sec. IV-C of the conditioning paper: hand data -> joint signals.

The recorded hand position is mapped to joint angles by analytic inverse kinematics, low-pass
filtered without phase lag, and differentiated numerically; the hand force becomes joint torque
through ``tau_ext = J(q)^T F``. Increments ``dq`` and ``dtau`` are taken from the mean over the
steady state before the perturbation onset.

The filter and the differences are :func:`armlab.dsp.lowpass_zero_phase` and
:func:`armlab.dsp.five_point_derivatives`, re-exported here as ``lowpass_zero_phase`` and
``differentiate``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.dsp import five_point_derivatives as differentiate
from armlab.dsp import lowpass_zero_phase
from armlab.errors import ConfigError, DataError
from armlab.models.planar_arm import inverse, jacobian

__all__ = [
    "JointSignals",
    "ProcessingConfig",
    "differentiate",
    "joint_signals",
    "lowpass_zero_phase",
]


@dataclass(frozen=True, kw_only=True)
class ProcessingConfig:
    """Settings of the measurement processing (Sec. IV-C of the conditioning paper).

    Attributes:
        lowpass_hz: Hz, cut-off of the zero-phase Butterworth low-pass applied to joint angles and
            hand forces; ``None`` disables filtering.
        filter_order: order of the Butterworth prototype (the forward-backward pass doubles the
            attenuation), 1..10.
        baseline_s: s, length of the steady state before onset whose mean defines ``q0``, ``tau0``.
    """

    lowpass_hz: float | None = 40.0
    filter_order: int = 4
    baseline_s: float = 0.2

    def __post_init__(self) -> None:
        if self.lowpass_hz is not None and not (np.isfinite(self.lowpass_hz) and self.lowpass_hz > 0):
            raise ConfigError(
                f"lowpass_hz must be None (no filter) or a positive number, got {self.lowpass_hz!r}"
            )
        if (
            isinstance(self.filter_order, bool)
            or int(self.filter_order) != self.filter_order
            or not (1 <= self.filter_order <= 10)
        ):
            raise ConfigError(f"filter_order must be an integer in 1..10, got {self.filter_order!r}")
        if not (np.isfinite(self.baseline_s) and self.baseline_s > 0):
            raise ConfigError(f"baseline_s must be a positive number of seconds, got {self.baseline_s!r}")


@dataclass(frozen=True, kw_only=True, eq=False)
class JointSignals:
    """Joint-space signals of a set of trials, ready for the regressor of Eq. (13).

    Attributes:
        q: (n_trials, n_samples, 2) rad, filtered joint angles.
        qd: (n_trials, n_samples, 2) rad/s.
        qdd: (n_trials, n_samples, 2) rad/s².
        dq: (n_trials, n_samples, 2) rad, ``q - q0`` with ``q0`` the pre-onset mean.
        tau_ext: (n_trials, n_samples, 2) N·m, external joint torque ``J(q)^T F``.
        dtau: (n_trials, n_samples, 2) N·m, ``tau_ext - tau0`` with ``tau0`` the pre-onset mean.
        fs_hz: Hz, sample rate.
        onset_index: (n_trials,) int, sample index of the perturbation onset ``t_p``.
    """

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    dq: np.ndarray
    tau_ext: np.ndarray
    dtau: np.ndarray
    fs_hz: float
    onset_index: np.ndarray

    def __post_init__(self) -> None:
        shapes = {n: np.shape(getattr(self, n)) for n in ("q", "qd", "qdd", "dq", "tau_ext", "dtau")}
        if len(set(shapes.values())) != 1 or len(shapes["q"]) != 3 or shapes["q"][2] != 2:
            raise DataError(f"joint signals must all be (n_trials, n_samples, 2); got {shapes}")
        n_trials, n_samples, _ = shapes["q"]
        onset = np.asarray(self.onset_index)
        if onset.shape != (n_trials,) or not np.issubdtype(onset.dtype, np.integer):
            raise DataError(
                f"onset_index must be an int array of shape ({n_trials},), got {onset.dtype} {onset.shape}"
            )
        if np.any(onset < 1) or np.any(onset >= n_samples):
            raise DataError(f"onset_index must lie in [1, {n_samples - 1}]")
        if not (np.isfinite(self.fs_hz) and self.fs_hz > 0):
            raise DataError(f"fs_hz must be a positive number, got {self.fs_hz!r}")

    @property
    def n_trials(self) -> int:
        return int(self.q.shape[0])

    @property
    def n_samples(self) -> int:
        return int(self.q.shape[1])


def _baseline_mean(x: np.ndarray, onset: np.ndarray, n_base: int) -> np.ndarray:
    """(n_trials, 1, n_axes) mean of ``x`` over samples [onset - n_base, onset) of each trial."""
    idx = np.arange(x.shape[1])
    start = np.maximum(onset - n_base, 0)
    mask = (idx >= start[:, None]) & (idx < onset[:, None])
    return np.einsum("ts,tsa->ta", mask, x)[:, None, :] / mask.sum(axis=1)[:, None, None]


def joint_signals(
    hand_pos: np.ndarray,
    hand_force: np.ndarray,
    fs_hz: float,
    onset_index: np.ndarray,
    l1: float,
    l2: float,
    config: ProcessingConfig | None = None,
) -> JointSignals:
    """Joint angles, derivatives and external torques from hand data (Sec. IV-C of the conditioning paper).

    Steps: ``q = IK(hand_pos)`` (elbow flexed); zero-phase low-pass of ``q`` and ``F``;
    ``qd, qdd`` by central differences of the filtered ``q``; ``tau_ext = J(q)^T F``;
    ``dq = q - q0`` and ``dtau = tau_ext - tau0`` with ``q0``, ``tau0`` the means over the
    ``config.baseline_s`` before each trial's onset (fewer samples if the onset is earlier).

    Args:
        hand_pos: (n_trials, n_samples, 2) m, hand position in the shoulder frame.
        hand_force: (n_trials, n_samples, 2) N, force applied *on the hand*, shoulder frame.
        fs_hz: Hz, sample rate.
        onset_index: (n_trials,) int, onset sample of each trial, in [1, n_samples - 1].
        l1: upper-arm length, m.
        l2: forearm length, m.
        config: processing settings; default :class:`ProcessingConfig`.

    Returns:
        The :class:`JointSignals` of all trials.
    """
    config = ProcessingConfig() if config is None else config
    hand_pos = np.asarray(hand_pos, dtype=float)
    hand_force = np.asarray(hand_force, dtype=float)
    if hand_pos.ndim != 3 or hand_pos.shape[2] != 2 or hand_force.shape != hand_pos.shape:
        raise DataError(
            f"hand_pos and hand_force must both be (n_trials, n_samples, 2); "
            f"got {hand_pos.shape} and {hand_force.shape}"
        )
    for name, a in (("hand_pos", hand_pos), ("hand_force", hand_force)):
        if not np.all(np.isfinite(a)):
            raise DataError(f"{name} contains {int(np.sum(~np.isfinite(a)))} non-finite value(s)")
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise DataError(f"fs_hz must be a positive number, got {fs_hz!r}")
    n_trials, n_samples, _ = hand_pos.shape
    onset = np.asarray(onset_index)
    if onset.shape != (n_trials,) or not np.issubdtype(onset.dtype, np.integer):
        raise DataError(
            f"onset_index must be an int array of shape ({n_trials},), got {onset.dtype} {onset.shape}"
        )
    if np.any(onset < 1) or np.any(onset >= n_samples):
        raise DataError(f"onset_index must lie in [1, {n_samples - 1}], got {onset.min()}..{onset.max()}")

    def lowpass(x: np.ndarray) -> np.ndarray:
        return lowpass_zero_phase(x, fs_hz, config.lowpass_hz, config.filter_order, axis=1)

    # unwrap: q1 is returned in (-pi, pi]; a record crossing +-pi must stay continuous before filtering
    q = lowpass(np.unwrap(inverse(hand_pos, l1, l2, elbow="flexed"), axis=1))
    qd, qdd = differentiate(q, fs_hz, axis=1)
    tau = np.einsum("tsji,tsj->tsi", jacobian(q, l1, l2), lowpass(hand_force))
    n_base = max(1, round(config.baseline_s * fs_hz))
    dq = q - _baseline_mean(q, onset, n_base)
    dtau = tau - _baseline_mean(tau, onset, n_base)
    return JointSignals(
        q=q,
        qd=qd,
        qdd=qdd,
        dq=dq,
        tau_ext=tau,
        dtau=dtau,
        fs_hz=float(fs_hz),
        onset_index=onset.astype(np.intp),
    )
