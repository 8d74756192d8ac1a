"""Ground truth of the independent ODE joint generator (armlab.sim.joint_ode): CI-cheap, 2.5 s records."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from armlab.dsp import butterworth, five_point_derivatives, zero_phase
from armlab.errors import ConfigError
from armlab.perturbations.joint_families import (
    PERTURBATION_FAMILIES,
    JointPerturbation,
    perturbation_signal,
)
from armlab.sim.joint_ode import OdeJoint, OdeServo, simulate_joint_ode
from armlab.sim.joint_ode_effects import OdeEffects, SensorDynamics, TorqueDrift, drift_signal

FS = 2000.0  # Hz
JOINT = OdeJoint(inertia_kgm2=0.02, damping_Nms_per_rad=0.8, stiffness_Nm_per_rad=120.0)
I_TOT = JOINT.inertia_kgm2 + JOINT.pedal_inertia_kgm2


@pytest.fixture(scope="module")
def reference():
    p = JointPerturbation(family="multisine", amplitude_rad=0.03, fmax_hz=15.0)
    return perturbation_signal(p, int(2.5 * FS), FS, np.random.default_rng(0))[None, :]


@pytest.fixture(scope="module")
def clean(reference):
    return simulate_joint_ode(
        reference, FS, JOINT, OdeServo(), OdeEffects(), noise_std_Nm=0.0, rng=np.random.default_rng(1)
    )


def test_clean_torque_is_the_nominal_of_the_recorded_angle(reference, clean):
    # the recorded torque against (Ip + I)·θ̈ + B·θ̇ + K·θ of the *sampled* encoder angle (five-point
    # derivatives, independent of the ODE's right-hand side). Tolerance 1e-4 of the torque rms:
    # the five-point acceleration errs by ~(ωh)⁴/90 ≈ 1e-7 at 15 Hz and 2 kHz, the integration
    # by ~rtol = 1e-8; 1e-4 is the quietest noise the referee draws (1e-3) with a 10x margin
    v, a = five_point_derivatives(clean.position, FS, axis=1)
    nominal = I_TOT * a + JOINT.damping_Nms_per_rad * v + JOINT.stiffness_Nm_per_rad * clean.position
    inner = slice(10, -10)  # the five-point stencil's one-sided ends
    resid = (clean.torque - nominal)[:, inner]
    assert np.sqrt(np.mean(resid**2)) < 1e-4 * np.sqrt(np.mean(clean.torque[:, inner] ** 2))
    # the servo is not ideal: it tracks with an error (its own dynamics), under 20 % of the reference
    err = np.std(clean.motor_angle - reference) / np.std(reference)
    assert 1e-3 < err < 0.2


def test_delay_shifts_the_torque_by_the_set_time_and_the_encoder_reads_on_its_grid(reference, clean):
    # one simulation for two sensor-level effects: the torque channel's delay and the encoder's grid
    delay = 1.37 / FS  # s, a fractional number of samples
    q = 2 * np.pi / 2**14  # rad, a 14-bit encoder
    rec = simulate_joint_ode(
        reference,
        FS,
        JOINT,
        OdeServo(),
        OdeEffects(channel_delay_s=delay, quant_step_rad=q),
        noise_std_Nm=0.0,
        rng=np.random.default_rng(1),
    )
    # the undelayed torque interpolated at t − delay (cubic: its error (ωh)⁴ ~ 1e-6 of the rms)
    shifted = CubicSpline(clean.t_s, clean.torque, axis=1)(clean.t_s[10:] - delay)
    err = rec.torque[:, 10:] - shifted
    assert np.sqrt(np.mean(err**2)) < 1e-4 * np.std(clean.torque)
    assert np.sqrt(np.mean((rec.torque - clean.torque) ** 2)) > 1e-2 * np.std(clean.torque)  # it did shift
    # the encoder: every increment a whole count, the error a rounding (<= q/2), many counts moved
    np.testing.assert_allclose(rec.motor_angle, clean.motor_angle, rtol=0, atol=1e-12)
    steps = np.diff(rec.position) / q
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    assert np.max(np.abs(rec.position - rec.motor_angle)) <= q / 2 + 1e-12
    assert np.unique(np.round(steps)).size > 2


def test_sensor_dynamics_is_a_second_order_lag(reference, clean):
    # a 2nd-order sensor at fn with damping ζ lags a slow torque by 2ζ/ωn: the filtered torque
    # matches the clean one shifted by that lag to the next order ((ω/ωn)² of the band, < 2 %)
    fn, zeta = 150.0, 0.6
    rec = simulate_joint_ode(
        reference,
        FS,
        JOINT,
        OdeServo(),
        OdeEffects(sensor=SensorDynamics(natural_hz=fn, damping_ratio=zeta)),
        noise_std_Nm=0.0,
        rng=np.random.default_rng(1),
    )
    lag = 2 * zeta / (2 * np.pi * fn)
    shifted = CubicSpline(clean.t_s, clean.torque, axis=1)(clean.t_s[200:] - lag)
    err = np.sqrt(np.mean((rec.torque[:, 200:] - shifted) ** 2)) / np.std(clean.torque)
    raw = np.sqrt(np.mean((rec.torque[:, 200:] - clean.torque[:, 200:]) ** 2)) / np.std(clean.torque)
    assert err < 0.02 < raw
    # and it is that sensor's exact response: H(jω) = ωn²/(ωn² − ω² + 2jζωn·ω) applied to the clean
    # torque in the frequency domain (the record starts at rest, so the spectral wrap of its end
    # values is the only edge; the first-order hold's own error here is 5e-6 of the rms, measured
    # against 32x oversampling); 1e-3 of its rms, the referee's quietest torque noise
    wn = 2 * np.pi * fn
    pad = 2000
    u = np.pad(clean.torque, ((0, 0), (pad, pad)), mode="edge")
    w = 2 * np.pi * np.fft.rfftfreq(u.shape[1], 1.0 / FS)
    h = wn**2 / (wn**2 - w**2 + 2j * zeta * wn * w)
    exact = np.fft.irfft(h * np.fft.rfft(u, axis=1), u.shape[1], axis=1)[:, pad:-pad]
    assert np.sqrt(np.mean((rec.torque - exact) ** 2)) < 1e-3 * np.std(clean.torque)


def test_drift_lies_below_the_scoring_band():
    # the drift's power above the diagnosis' 0.3 Hz high-pass, away from the filter's edges, is
    # below 1e-4 of its variance (a smooth ramp, thermal settling and a wander below 0.02 Hz)
    fs = 500.0
    t = np.arange(int(60 * fs)) / fs
    d = drift_signal(
        t, TorqueDrift(rate_Nm_per_s=0.02, thermal_Nm=0.5, wander_Nm=0.2), 3, np.random.default_rng(4)
    )
    above = zero_phase(butterworth(0.3, fs, 4, btype="highpass"), d, axis=1)[:, int(5 * fs) : -int(5 * fs)]
    assert np.mean(above**2) < 1e-4 * np.var(d)
    assert np.ptp(d) > 0.5  # N·m: it drifts


@pytest.mark.parametrize("family", PERTURBATION_FAMILIES)
def test_perturbations_start_and_end_at_rest_within_their_amplitude(family):
    p = JointPerturbation(family=family, amplitude_rad=0.04)
    x = perturbation_signal(p, 6000, 1000.0, np.random.default_rng(3))
    assert x[0] == 0 and abs(x[-1]) < 1e-12 and np.max(np.abs(x)) <= 0.04 + 1e-12
    assert np.std(x) > 0.005


def test_bad_settings_are_refused():
    with pytest.raises(ConfigError, match="valid"):
        JointPerturbation(family="chirp", amplitude_rad=0.03)
    with pytest.raises(ConfigError, match="stiffness_Nm_per_rad"):
        OdeJoint(inertia_kgm2=0.02, damping_Nms_per_rad=1.0, stiffness_Nm_per_rad=-1.0)
