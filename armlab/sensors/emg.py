"""Surface EMG synthesised from the muscles' neural drive (seed paper 001's eight electrodes).

The paper records 8 Delsys Trigno wireless electrodes at 2 kHz (Sec. 3, Fig. 1b: BRAD, BILH, DELC,
PMJC, DELS, TRIO, TRIA, TRIM) and gives nothing of their signal model. Spec 001's assumption,
implemented here for every electrode i::

    s_i(t)   = g_i u_i(t) n_i(t)                        the muscle's own signal at its electrode
    emg_j(t) = s_j(t) + c sum_{i in N(j)} s_i(t) + nu_j  what electrode j records

with u_i the neural drive (the muscle command, 0..1), n_i unit-rms Gaussian noise band-limited to
20-450 Hz (the wireless sensor's band; :func:`armlab.noise.bandpass_noise`), independent per
channel and trial, g_i the rms amplitude at full drive, c the cross-talk fraction between
neighbouring electrodes N(j) (:data:`EMG_NEIGHBOURS`) and nu the electrode's own noise and
converter (a :class:`~armlab.sensors.channel.ChannelSpec` through
:func:`~armlab.sensors.channel.apply_channel`). The rms of s_i over a stretch of constant drive is
g_i u_i: the EMG amplitude follows the drive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from armlab.errors import ConfigError, DataError
from armlab.models.arm_5dof import ELECTRODE_MUSCLES
from armlab.noise import bandpass_noise
from armlab.sensors.channel import ChannelSpec, apply_channel

__all__ = [
    "ELECTRODES",
    "EMG_BAND_HZ",
    "EMG_CROSSTALK",
    "EMG_FS_HZ",
    "EMG_GAIN_MV",
    "EMG_NEIGHBOURS",
    "TRIGNO_EMG",
    "EmgSpec",
    "crosstalk_matrix",
    "neural_drive",
    "synthesize_emg",
]

#: The paper's electrodes in its order (Fig. 1b), keys of ``armlab.models.ELECTRODE_MUSCLES``.
ELECTRODES: tuple[str, ...] = tuple(ELECTRODE_MUSCLES)
EMG_FS_HZ = 2000.0  # Hz, the Trigno electrodes' rate (paper Sec. 3: "sampled at 2 kHz")
EMG_BAND_HZ = (20.0, 450.0)  # Hz, -3 dB edges of the carrier (spec 001: the wireless sensor's band)
# mV rms of a muscle's signal at full drive (u = 1) at its own electrode (assumption: surface EMG at
# maximal contraction is of the order 0.1-1 mV; the paper gives none). Equal for every electrode.
EMG_GAIN_MV = 0.5
# fraction of a neighbouring muscle's signal an electrode picks up (spec 001: 10-20 % cross-talk
# between neighbours; the middle taken)
EMG_CROSSTALK = 0.15
# Electrodes whose muscles lie side by side (assumption from the placement of the paper's Fig. 1b:
# the anterior chain brachioradialis - biceps - anterior deltoid - clavicular pectoralis, the two
# deltoid heads over the shoulder, the posterior chain posterior deltoid - long - lateral - medial
# triceps). Cross-talk is symmetric: each pair leaks both ways.
EMG_NEIGHBOURS: tuple[tuple[str, str], ...] = (
    ("BRAD", "BILH"),
    ("BILH", "DELC"),
    ("DELC", "PMJC"),
    ("DELC", "DELS"),
    ("DELS", "TRIO"),
    ("TRIO", "TRIA"),
    ("TRIA", "TRIM"),
)
# The electrode's own noise and converter, mV (spec 001: "a few uV of sensor noise" -> 3 uV rms;
# assumption: a 16-bit converter over an 11 mV range, 11 / 2**16 mV per count, the Trigno's class).
TRIGNO_EMG = ChannelSpec(noise_std=3e-3, quant_step=11.0 / 2**16)


def neural_drive(activation: np.ndarray, shape_factor: float = 0.0) -> np.ndarray:
    """The neural drive u behind an activation a, the inverse of the EMG-to-activation relation
    a = (exp(A u) - 1) / (exp(A) - 1) of Lloyd and Besier (2003, J. Biomech. 36: 765-776; their
    shape factor -3 < A < 0): u = ln(1 + a (exp(A) - 1)) / A, and u = a for A = 0 (the limit).

    The simulated muscles take their activation as the command (MuJoCo ``ctrl``); the electrodes
    see the drive. Spec 001's default is A = 0 (EMG amplitude proportional to activation); A < 0
    makes activation rise faster than the EMG at low drive, as measured muscles do.

    Args:
        activation: (...) in [0, 1].
        shape_factor: A in (-3, 0].

    Returns:
        (...) the drive in [0, 1].

    Raises:
        ConfigError: ``shape_factor`` outside (-3, 0].
    """
    if not (isinstance(shape_factor, (int, float, np.floating)) and -3.0 < shape_factor <= 0.0):
        raise ConfigError(
            f"the EMG shape factor A must lie in (-3, 0] (Lloyd and Besier 2003), got {shape_factor!r}"
        )
    a = np.asarray(activation, dtype=float)
    if shape_factor == 0.0:
        return a.copy()
    return np.log1p(a * np.expm1(shape_factor)) / shape_factor


def crosstalk_matrix(
    fraction: float, neighbours: tuple[tuple[str, str], ...] = EMG_NEIGHBOURS, electrodes=ELECTRODES
) -> np.ndarray:
    """The mixing matrix C (n, n): recorded = C @ sources, C = I + fraction * adjacency.

    Raises:
        ConfigError: ``fraction`` outside [0, 0.5) or a neighbour not among ``electrodes``.
    """
    if not (isinstance(fraction, (int, float, np.floating)) and 0.0 <= fraction < 0.5):
        raise ConfigError(f"the EMG cross-talk fraction must lie in [0, 0.5), got {fraction!r}")
    index = {name: i for i, name in enumerate(electrodes)}
    C = np.eye(len(electrodes))
    for a, b in neighbours:
        if a not in index or b not in index:
            raise ConfigError(f"EMG neighbours ({a!r}, {b!r}): both must be among {list(electrodes)}")
        C[index[a], index[b]] = C[index[b], index[a]] = fraction
    return C


@dataclass(frozen=True, kw_only=True)
class EmgSpec:
    """How the electrodes turn neural drive into recorded EMG (module docstring).

    Attributes:
        band_hz: (low, high) Hz, -3 dB band of the carrier n_i (20-450 Hz, spec 001).
        order: Butterworth order of the band-pass (2: four poles; assumption).
        gain_mV: mV rms at full drive, one for every electrode or one per electrode (n_channels,).
        crosstalk: fraction c of a neighbour's signal picked up (0.15, spec 001: 10-20 %).
        neighbours: electrode pairs that leak into each other (:data:`EMG_NEIGHBOURS`).
        sensor: the electrode's noise and converter, mV (:data:`TRIGNO_EMG`; ideal: none).
    """

    band_hz: tuple[float, float] = EMG_BAND_HZ
    order: int = 2
    gain_mV: float | tuple[float, ...] = EMG_GAIN_MV
    crosstalk: float = EMG_CROSSTALK
    neighbours: tuple[tuple[str, str], ...] = EMG_NEIGHBOURS
    sensor: ChannelSpec = field(default_factory=lambda: TRIGNO_EMG)

    def __post_init__(self) -> None:
        lo, hi = self.band_hz
        if not 0 < lo < hi:
            raise ConfigError(
                f"EmgSpec.band_hz must be (low, high) Hz with 0 < low < high, got {self.band_hz}"
            )
        g = np.atleast_1d(np.asarray(self.gain_mV, dtype=float))
        if not (np.all(np.isfinite(g)) and np.all(g >= 0) and g.size in (1, len(ELECTRODES))):
            raise ConfigError(
                f"EmgSpec.gain_mV must be one number >= 0 mV or {len(ELECTRODES)} (one per electrode "
                f"{list(ELECTRODES)}), got {self.gain_mV!r}"
            )
        crosstalk_matrix(self.crosstalk, self.neighbours)  # checks both

    @property
    def mixing(self) -> np.ndarray:
        """C (8, 8): recorded = C @ sources (:func:`crosstalk_matrix`)."""
        return crosstalk_matrix(self.crosstalk, self.neighbours)


def synthesize_emg(drive: np.ndarray, fs_hz: float, spec: EmgSpec, rng: np.random.Generator) -> np.ndarray:
    """Recorded EMG of the electrodes from their muscles' neural drive (module docstring).

    Random draws, in this order: the carriers (n_trials, n_samples, n_channels) in one
    :func:`armlab.noise.bandpass_noise` call, then the sensor's (:func:`apply_channel`), so one
    generator state gives bit-identical output.

    Args:
        drive: (n_trials, n_samples, 8) the neural drive u_i of each electrode's muscle, 0..1, in
            :data:`ELECTRODES` order, at ``fs_hz``.
        fs_hz: Hz, the sample rate (the paper's 2 kHz, :data:`EMG_FS_HZ`).
        spec: the electrodes.
        rng: the only source of randomness.

    Returns:
        (n_trials, n_samples, 8) mV, the recorded (raw, unrectified) EMG.

    Raises:
        DataError: ``drive`` not (n_trials, n_samples, 8), not finite, or outside [0, 1].
        ConfigError: the band not below Nyquist.
    """
    u = np.asarray(drive, dtype=float)
    if u.ndim != 3 or u.shape[2] != len(ELECTRODES):
        raise DataError(
            f"drive must be (n_trials, n_samples, {len(ELECTRODES)}) (one per electrode), got {u.shape}"
        )
    if not np.all(np.isfinite(u)) or u.min(initial=0.0) < 0.0 or u.max(initial=0.0) > 1.0:
        raise DataError("drive must be finite and within [0, 1] (muscle commands)")
    if not (isinstance(fs_hz, (int, float, np.floating)) and math.isfinite(fs_hz) and fs_hz > 0):
        raise ConfigError(f"fs_hz must be a finite number > 0 Hz, got {fs_hz!r}")
    carrier = bandpass_noise(
        rng, u.shape, float(fs_hz), spec.band_hz, order=spec.order, name="EmgSpec.band_hz"
    )
    gain = np.broadcast_to(np.asarray(spec.gain_mV, dtype=float), (len(ELECTRODES),))
    source = carrier * u * gain  # (n_trials, n_samples, 8) mV, s_i = g_i u_i n_i
    recorded = source @ spec.mixing.T  # emg_j = sum_i C_ji s_i
    return apply_channel(recorded, float(fs_hz), spec.sensor, rng)
