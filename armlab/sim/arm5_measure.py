"""The stiffness lab's sensors applied to the clean trial record (seed paper 001, Sec. 3).

The two JR3s (wrist, base) are read at the physics rate, 2 kHz; the Vicon marker clusters at
500 Hz, every fourth physics sample. Each sensor model is a preset of
:class:`armlab.sensors.presets.Arm5SensorSuite` (``ideal()`` or ``realistic()``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError
from armlab.sensors.presets import Arm5SensorSuite, measure
from armlab.sim.arm5_trials import StiffnessRecord

__all__ = [
    "MARKER_RATE_HZ",
    "MeasuredTrials",
    "measure_stiffness_record",
]

MARKER_RATE_HZ = 500.0  # Hz, Vicon T10 (paper Sec. 3)
_FT = ("wrist_force", "wrist_torque", "base_force", "base_torque")
_MARKERS = ("forearm_marker_pos", "forearm_marker_quat")


@dataclass(frozen=True, kw_only=True, eq=False)
class MeasuredTrials:
    """What the lab records of the stiffness trials.

    Attributes:
        ft: ``wrist_force`` N, ``wrist_torque`` N·m (JR3 frame), ``base_force`` N,
            ``base_torque`` N·m -> (n_trials, n_ft, 3) at ``ft_fs_hz``; ``ft_t`` (n_ft,) s from
            the onset.
        marker_pos: (n_trials, n_m, 3) m; marker_quat: (n_trials, n_m, 4) unit quaternions
            (w, x, y, z), renormalised; at ``marker_fs_hz``, ``marker_t`` (n_m,) s from the onset.
    """

    ft: dict[str, np.ndarray]
    ft_t: np.ndarray
    ft_fs_hz: float
    marker_pos: np.ndarray
    marker_quat: np.ndarray
    marker_t: np.ndarray
    marker_fs_hz: float


def measure_stiffness_record(
    record: StiffnessRecord, suite: Arm5SensorSuite, rng: np.random.Generator, t0_s: np.ndarray | None = None
) -> MeasuredTrials:
    """Apply the suite to the clean record.

    Args:
        record: the clean trials (:func:`armlab.sim.arm5_trials.simulate_stiffness_trials`).
        suite: the sensor models.
        rng: the only source of randomness (the JR3s first, then the markers).
        t0_s: (n_trials,) s since taring at each record's start (the random holds: drift).

    Raises:
        ConfigError: the physics rate is not a whole multiple of the marker rate.
    """
    fs = record.fs_hz
    step = int(round(fs / MARKER_RATE_HZ))
    if step < 1 or abs(step * MARKER_RATE_HZ - fs) > 1e-9 * fs:
        raise ConfigError(
            f"the record's rate {fs} Hz must be a whole multiple of the markers' {MARKER_RATE_HZ} Hz"
        )
    ch = record.channels
    n = next(iter(ch.values())).shape[1]
    ft = measure({k: ch[k] for k in _FT}, suite, fs, rng, t0_s=t0_s)
    # a marker frame every `step` physics samples, the last of each group (sample k ends at (k+1)/fs)
    idx = np.arange(step - 1, n, step)
    mk = measure({k: ch[k][:, idx] for k in _MARKERS}, suite, MARKER_RATE_HZ, rng, t0_s=t0_s)
    quat = mk["forearm_marker_quat"]
    return MeasuredTrials(
        ft=ft,
        ft_t=(np.arange(n) - record.onset_index) / fs,
        ft_fs_hz=fs,
        marker_pos=mk["forearm_marker_pos"],
        marker_quat=quat / np.linalg.norm(quat, axis=-1, keepdims=True),
        marker_t=(idx - record.onset_index) / fs,
        marker_fs_hz=MARKER_RATE_HZ,
    )
