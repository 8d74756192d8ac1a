"""Ground truth of the EMG synthesis (armlab.sensors.emg; spec 001's assumption emg = g u n + nu):
the carrier's band, the amplitude following the drive, the cross-talk, the sensor, reproducibility."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import signal

from armlab.dsp import butterworth
from armlab.errors import ConfigError, DataError
from armlab.noise import bandpass_noise
from armlab.sensors import (
    ELECTRODES,
    EMG_BAND_HZ,
    EMG_CROSSTALK,
    EMG_FS_HZ,
    EMG_GAIN_MV,
    TRIGNO_EMG,
    ChannelSpec,
    EmgSpec,
    crosstalk_matrix,
    neural_drive,
    synthesize_emg,
)

FS = EMG_FS_HZ  # Hz
N = 20_000  # samples: 10 s per trial at 2 kHz
# Independent samples of a 430 Hz wide band over 10 s: about 2 x 430 x 10 = 8600, so an rms over
# one trial scatters by ~1 / sqrt(2 x 8600) = 0.8 %; the tolerances below are ~4 sigma.
RMS_RTOL = 0.03
IDEAL = EmgSpec(crosstalk=0.0, sensor=ChannelSpec.ideal())


def _drive(levels) -> np.ndarray:
    """(n_trials, N, 8) constant drive, one level per trial on every electrode."""
    return np.broadcast_to(np.asarray(levels, float)[:, None, None], (len(levels), N, len(ELECTRODES))).copy()


def test_carrier_band_is_20_to_450_hz():
    """The measured spectrum's share of power inside 20-450 Hz equals the band-pass design's
    (|H|^2 integrated), and most of the power lies in the band."""
    emg = synthesize_emg(_drive([1.0, 1.0]), FS, IDEAL, np.random.default_rng(0))
    f, p = signal.welch(emg, FS, nperseg=1024, axis=1)
    p = p.mean(axis=(0, 2))
    inside = (f >= EMG_BAND_HZ[0]) & (f <= EMG_BAND_HZ[1])
    measured = p[inside].sum() / p.sum()
    _, h = signal.sosfreqz(butterworth(EMG_BAND_HZ, FS, 2, btype="bandpass"), worN=f, fs=FS)
    expected = (np.abs(h[inside]) ** 2).sum() / (np.abs(h) ** 2).sum()
    # 16 trials-channels x 39 Welch segments average the periodogram: its share scatters by < 0.5 %
    assert measured == pytest.approx(expected, abs=0.01)
    # most of it in the band: the 2nd-order (4-pole) band-pass's skirts carry the rest (~12 %)
    assert measured > 0.85
    # the spectrum itself is the design's: PSD = g^2 |H(f)|^2 (2 / fs) / sum(h_k^2) for unit-rms
    # noise of gain g; 624 averaged periodograms scatter ~4 % per bin, so 15 % at the two band
    # edges (where |H|^2 = 1/2) and 3 % on the median ratio over 10-800 Hz
    _, h_imp = signal.sosfreqz(butterworth(EMG_BAND_HZ, FS, 2, btype="bandpass"), worN=8192, fs=FS)
    white_gain = np.sum(np.abs(h_imp) ** 2) / 8192  # mean |H|^2 over 0..fs/2 = sum(h_k^2)
    sel = (f > 10) & (f < 800)
    ratio = p[sel] / (EMG_GAIN_MV**2 * np.abs(h[sel]) ** 2 * (2.0 / FS) / white_gain)
    for edge in EMG_BAND_HZ:
        assert ratio[np.argmin(np.abs(f[sel] - edge))] == pytest.approx(1.0, abs=0.15)
    assert np.median(ratio) == pytest.approx(1.0, abs=0.03)


def test_rms_amplitude_follows_the_drive():
    """rms of each electrode over a constant drive u is g u (ground truth: the model's gain)."""
    levels = np.array([0.1, 0.3, 0.6, 1.0])
    emg = synthesize_emg(_drive(levels), FS, IDEAL, np.random.default_rng(1))
    rms = np.sqrt(np.mean(emg**2, axis=1))  # (4, 8) mV
    assert_allclose(rms, EMG_GAIN_MV * levels[:, None] * np.ones((1, 8)), rtol=RMS_RTOL)
    silent = synthesize_emg(np.zeros((1, N, 8)), FS, IDEAL, np.random.default_rng(1))
    assert np.all(silent == 0.0)


def test_crosstalk_fraction_is_recovered():
    """Drive on DELC alone: its neighbours (BILH, PMJC, DELS) record exactly the cross-talk fraction
    of its signal sample by sample; the others nothing (ideal sensor)."""
    spec = EmgSpec(sensor=ChannelSpec.ideal())
    drive = np.zeros((1, N, 8))
    src = ELECTRODES.index("DELC")
    drive[..., src] = 0.8
    emg = synthesize_emg(drive, FS, spec, np.random.default_rng(2))[0]
    neighbours = {ELECTRODES.index(n) for n in ("BILH", "PMJC", "DELS")}
    for j in range(8):
        if j == src:
            continue
        # the fraction recovered by least squares of channel j on the source electrode
        c = float(emg[:, j] @ emg[:, src] / (emg[:, src] @ emg[:, src]))
        assert c == pytest.approx(EMG_CROSSTALK if j in neighbours else 0.0, abs=1e-12)
    C = crosstalk_matrix(0.2)
    assert_allclose(C, C.T)
    assert_allclose(np.diag(C), 1.0)


def test_sensor_noise_and_converter():
    """Zero drive through the realistic electrode: 3 uV rms of noise (spec: a few uV), every value
    on the converter's grid."""
    emg = synthesize_emg(np.zeros((2, N, 8)), FS, EmgSpec(), np.random.default_rng(3))
    assert np.sqrt(np.mean(emg**2)) == pytest.approx(TRIGNO_EMG.noise_std, rel=0.02)  # 320k samples
    q = TRIGNO_EMG.quant_step
    assert_allclose(emg / q, np.round(emg / q), atol=1e-6)


def test_same_seed_same_emg_bit_for_bit():
    drive = np.random.default_rng(9).uniform(0.1, 0.9, (3, 500, 8))
    a = synthesize_emg(drive, FS, EmgSpec(), np.random.default_rng(4))
    b = synthesize_emg(drive, FS, EmgSpec(), np.random.default_rng(4))
    c = synthesize_emg(drive, FS, EmgSpec(), np.random.default_rng(5))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_bandpass_noise_unit_rms():
    x = bandpass_noise(np.random.default_rng(6), (4, N), FS, (20.0, 450.0))
    assert np.sqrt(np.mean(x**2)) == pytest.approx(1.0, rel=0.015)  # 4 x 8600 independent samples


def test_bad_input_is_refused():
    with pytest.raises(DataError, match="one per electrode"):
        synthesize_emg(np.zeros((1, 10, 5)), FS, IDEAL, np.random.default_rng(0))
    with pytest.raises(DataError, match="within"):
        synthesize_emg(np.full((1, 10, 8), 1.5), FS, IDEAL, np.random.default_rng(0))
    with pytest.raises(ConfigError, match="Nyquist"):
        synthesize_emg(np.zeros((1, 10, 8)), 500.0, IDEAL, np.random.default_rng(0))
    with pytest.raises(ConfigError, match="cross-talk"):
        EmgSpec(crosstalk=0.7)
    with pytest.raises(ConfigError, match="gain_mV"):
        EmgSpec(gain_mV=(1.0, 2.0))
    with pytest.raises(ConfigError, match="must be among"):
        crosstalk_matrix(0.1, (("BRAD", "XXX"),))


def test_neural_drive_inverts_the_emg_to_activation_relation():
    """u(a) inverts a = (e^(A u) - 1) / (e^A - 1) (Lloyd and Besier 2003); A = 0 is the identity."""
    u = np.linspace(0.0, 1.0, 11)
    for A in (-2.9, -1.5, -0.2):
        a = np.expm1(A * u) / np.expm1(A)
        assert_allclose(neural_drive(a, A), u, atol=1e-12)
        assert np.all(neural_drive(a, A)[1:-1] < a[1:-1])  # activation rises faster than the drive
    assert_allclose(neural_drive(u, 0.0), u)
    with pytest.raises(ConfigError, match=r"\(-3, 0\]"):
        neural_drive(u, -3.0)
