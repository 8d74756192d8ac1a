"""Joint impedance/admittance fits recover known parameters; the real ankle data get sane fits."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.config.schema import FrfConfig
from armlab.data.reklab import DEFAULT_REKLAB_ROOT, list_ankle_trials, load_ankle_trial
from armlab.errors import ConfigError, DataError
from armlab.protocols.joint_1dof.frf import JOINT_BAND_HZ, fit_joint_frf

FS = 1000.0  # Hz, the REKLAB rate
I, B, K = 0.018, 1.2, 130.0  # kg m², N m s/rad^alpha, N m/rad: the ankle's order of magnitude


def _recording(alpha: float, noise: float = 0.0, seed: int = 0, seconds: float = 60.0):
    """Broadband position (white, low-passed at 60 Hz) and the torque of ``I s² + B s^alpha + K``."""
    rng = np.random.default_rng(seed)
    n = int(seconds * FS)
    f = np.fft.rfftfreq(n, 1 / FS)
    spec = np.fft.rfft(rng.standard_normal(n)) * (f < 60.0)
    s = 2j * np.pi * f
    with np.errstate(divide="ignore", invalid="ignore"):
        z = I * s**2 + B * np.where(f > 0, s**alpha, 0) + K
    position = np.fft.irfft(spec, n) * 0.01
    torque = -np.fft.irfft(spec * z, n) * 0.01  # the joint resists: impedance = -torque/position
    torque = torque + noise * torque.std() * rng.standard_normal(n)
    return position, torque


@pytest.mark.parametrize("alpha", [0.6, 1.0])
def test_impedance_parameters_and_order_are_recovered(alpha):
    position, torque = _recording(alpha, noise=0.05)
    res, series = fit_joint_frf(position, torque, FS, FrfConfig(band_hz=JOINT_BAND_HZ), "synthetic")
    frac = res["impedance"]["fractional"]
    assert frac["alpha"] == pytest.approx(alpha, abs=0.1 + 1e-9)
    # 5 % torque noise; measured errors I 0.06 %, K <= 0.06 %, B 1.1 % (alpha 0.6), R² 0.9998
    assert frac["I"] == pytest.approx(I, rel=0.01)
    assert frac["K"] == pytest.approx(K, rel=0.01)
    assert frac["B"] == pytest.approx(B, rel=0.03)
    assert frac["r2"] > 0.999
    if alpha == 1.0:
        integer = res["impedance"]["integer"]
        for name, true in (("I", I), ("B", B), ("K", K)):
            assert integer[name] == pytest.approx(true, rel=0.01), name
    else:  # a springpot is not a damper: the integer model fits the complex response worse
        assert res["impedance"]["integer"]["mse_complex"] > 1.2 * frac["mse_complex"]  # measured 1.37
    adm = res["admittance"]
    assert set(adm["models"]) == {"27", "28", "29", "A", "B"}
    # the admittance fits describe 1/(I s² + B s^alpha + K): measured R² of (27) 0.94 (alpha 0.6,
    # Levy's equation error weights the stiff band) and 0.997 (alpha 1)
    assert adm["models"]["27"]["r2"] > 0.9
    if alpha == 1.0:  # (27) contains the true admittance: measured 0.7 % from it
        s = 2j * np.pi * series["f_hz"]
        true_y = 1 / (I * s**2 + B * s + K)
        assert np.linalg.norm(series["Y_fits"]["27"] - true_y) / np.linalg.norm(true_y) < 0.02


def test_bad_input_is_rejected():
    position, torque = _recording(1.0, seconds=10.0)
    with pytest.raises(DataError, match="equal 1-D arrays"):
        fit_joint_frf(position, torque[:-1], FS, FrfConfig())
    with pytest.raises(ConfigError, match="beyond Nyquist"):
        fit_joint_frf(position, torque, FS, FrfConfig(band_hz=(0.5, 600.0)))
    with pytest.raises(ConfigError, match="longer than the recording"):
        fit_joint_frf(position, torque, FS, FrfConfig(welch_window=20_000))
    with pytest.raises(ConfigError, match="frequency points"):
        fit_joint_frf(position, torque, FS, FrfConfig(band_hz=(10.0, 11.0)))


@pytest.mark.skipif(not list_ankle_trials(), reason=f"no REKLAB data at {DEFAULT_REKLAB_ROOT}")
def test_real_ankle_trials_get_physical_fits():
    """Measured (0.5-40 Hz): integer I 0.016-0.019 kg m², K 56-198 N m/rad, R² 0.973-0.993;
    fractional order 1.0 on four trials, 0.9 on z_df3."""
    for name in ("z_df", "z_df2", "z_df3", "z_pf", "z_pf2"):
        t = load_ankle_trial(name)
        res, _ = fit_joint_frf(t.position, t.torque, t.fs_hz, FrfConfig(band_hz=JOINT_BAND_HZ), name)
        integer, frac = res["impedance"]["integer"], res["impedance"]["fractional"]
        # physiological ranges (foot inertia 0.01-0.05 kg m², ankle stiffness tens to hundreds N m/rad)
        assert 0.01 < integer["I"] < 0.05 and 20 < integer["K"] < 500 and integer["r2"] > 0.97, name
        assert frac["alpha"] >= 0.9, (name, frac["alpha"])  # the ankle's damper is nearly viscous
        # the fractional family contains the integer model (alpha = 1): never worse on its criterion
        assert frac["mse_complex"] <= integer["mse_complex"] * (1 + 1e-9)
