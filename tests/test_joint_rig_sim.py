"""Tests for armlab.sim.joint_rig: the rigid chain, each hidden effect against an independent
computation, the sensor effects, and determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from armlab.config.effects import (
    CableDrag,
    ChannelDelay,
    CocontractionVariation,
    CuffCompliance,
    EffectsConfig,
    EncoderQuantisation,
    ForceSensorBandwidth,
    ForceSensorDrift,
    ForceSensorNoise,
    JointFriction,
    PayloadMass,
    PlaneTilt,
    Reflex,
    TransmissionCompliance,
)
from armlab.errors import ConfigError, DataError
from armlab.perturbations import prbs_position
from armlab.sim import JointSubject, simulate_joint_rig
from armlab.sim.joint_rig import activation_fluctuation, reflex_torque

FS = 1000.0
I, B, K, IP, TONIC = 0.02, 0.8, 150.0, 0.005, 3.0
SUBJECT = JointSubject(I, B, K, TONIC, IP)


def smooth_reference(n_trials: int, seconds: float, band_hz: float = 15.0, rms: float = 0.02, seed: int = 0):
    """Band-limited random position (4th-order Butterworth, zero phase), tapered to 0 at both ends
    over 5 % of the record by a quintic smoothstep (C2: the reference's acceleration stays smooth)."""
    n = int(seconds * FS)
    x = np.random.default_rng(seed).standard_normal((n_trials, n))
    x = signal.sosfiltfilt(signal.butter(4, band_hz, fs=FS, output="sos"), x, axis=1)
    u = np.clip(np.minimum(np.arange(n), np.arange(n)[::-1]) / (0.05 * n), 0.0, 1.0)
    return x * rms / x.std() * (10 * u**3 - 15 * u**4 + 6 * u**5)


def simulate(ref, effects=None, *, subject=SUBJECT, noise=0.0, seed=1):
    return simulate_joint_rig(
        ref, FS, subject, effects or EffectsConfig(), noise_std_Nm=noise, rng=np.random.default_rng(seed)
    )


def derivatives(theta):
    """Central first and second differences at 1 kHz (ends dropped by the callers)."""
    v, a = np.zeros_like(theta), np.zeros_like(theta)
    v[:, 1:-1] = (theta[:, 2:] - theta[:, :-2]) * FS / 2
    a[:, 1:-1] = (theta[:, 2:] - 2 * theta[:, 1:-1] + theta[:, :-2]) * FS**2
    return v, a


def intrinsic_torque(theta, inertia=I + IP):
    """The recorded torque of the nominal joint: −((I + Ip)·θ̈ + B·θ̇ + K·θ) − tonic."""
    v, a = derivatives(theta)
    return -(inertia * a + B * v + K * theta) - TONIC


IN = slice(5, -5)  # drop the finite-difference ends


def rel_rms(err, ref):
    return float(np.sqrt(np.mean(err**2)) / np.sqrt(np.mean(ref**2)))


# ---------------------------------------------------------------- rigid chain, sign convention


def test_rigid_chain_torque_is_the_joint_inverse_dynamics_and_the_limb_follows_the_reference():
    ref = smooth_reference(2, 3.0)
    rec = simulate(ref)
    pred = intrinsic_torque(rec.limb_angle)
    # 1 kHz central differences of a 15 Hz-band signal err by (w·dt)²/12 ~ 1e-3 of the inertial
    # term; the semi-implicit Euler step adds O(dt) on the damping: 0.5 % of the torque rms
    assert rel_rms((rec.clean_torque - pred)[:, IN], rec.clean_torque[:, IN] + TONIC) < 5e-3
    # rigid chain: the limb is the motor is the encoder
    np.testing.assert_allclose(rec.limb_angle, rec.motor_angle, atol=1e-15)
    np.testing.assert_array_equal(rec.position, rec.motor_angle)
    # servo: tracking error (subject load / kp, ~0.2 %) under 1 % of the reference rms
    assert rel_rms(rec.motor_angle - ref, ref) < 0.01
    assert rec.timestep_s == pytest.approx(1.0 / (FS * round(1.0 / (FS * rec.timestep_s))))


def test_tracking_under_one_percent_for_the_stiffest_subject_on_the_prbs():
    stiff = JointSubject(0.03, 1.5, 200.0, 5.0)  # top of the ankle ranges (Kearney & Hunter 1990)
    rng = np.random.default_rng(0)
    ref = np.stack([prbs_position(3000, FS, rng=rng) for _ in range(2)])
    rec = simulate(ref, subject=stiff)
    assert rel_rms(rec.motor_angle - ref, ref) < 0.01


def test_sign_convention_matches_the_reklab_antiphase():
    # a slow stretch to +0.02 rad: torque ~ −K·θ − tonic, in antiphase with position
    t = np.arange(2000) / FS
    ref = (0.02 * 0.5 * (1 - np.cos(np.pi * np.clip(t / 1.5, 0, 1))))[None]
    rec = simulate(ref)
    # static equilibrium at rest: the servo yields tonic/kp = 3e-5 rad to the tonic torque
    assert rec.clean_torque[0, 0] == pytest.approx(-K * rec.limb_angle[0, 0] - TONIC, abs=1e-9)
    assert rec.limb_angle[0, 0] == pytest.approx(-TONIC / 1e5, rel=0.01)
    assert rec.clean_torque[0, -1] == pytest.approx(-K * rec.limb_angle[0, -1] - TONIC, abs=1e-6)
    assert rec.limb_angle[0, -1] == pytest.approx(0.02, rel=1e-2)
    assert np.corrcoef(rec.position[0], rec.clean_torque[0])[0, 1] < -0.99


# ---------------------------------------------------------------- model-level effects


def test_reflex_is_the_formula_on_the_simulated_velocity_with_the_exact_delay():
    rng = np.random.default_rng(4)
    ref = np.stack([prbs_position(2500, FS, rng=rng) for _ in range(2)])
    reflex = Reflex(delay_s=0.045, gain_Nms_per_rad=5.0, cutoff_hz=3.0, damping_ratio=0.7, direction=-1.0)
    rec = simulate(ref, EffectsConfig(reflex=reflex))
    v = rec.limb_velocity

    def formula(delay):  # independent of the module: scipy's bilinear LP2 on the delayed stretch
        w = 2 * math.pi * 3.0
        b, a = signal.bilinear([w * w], [1, 2 * 0.7 * w, w * w], fs=FS)
        u = np.zeros_like(v)
        u[:, delay:] = np.maximum(-v[:, :-delay], 0.0)
        return 5.0 * signal.lfilter(b, a, u, axis=1)  # −direction·gain = +5

    scale = np.abs(rec.reflex_torque).max()
    assert scale > 0.1  # N·m: the reflex did fire
    np.testing.assert_allclose(rec.reflex_torque, formula(45), atol=1e-12 * scale)
    for wrong in (44, 46):  # one sample off is far outside that tolerance
        assert np.abs(rec.reflex_torque - formula(wrong)).max() > 1e-3 * scale
    np.testing.assert_allclose(reflex_torque(v, FS, reflex), rec.reflex_torque, atol=1e-12 * scale)
    # closed loop and rigid: the recorded torque carries the reflex torque with its own sign (the
    # servo keeps the trajectory: what differs from the run without reflex is the reflex, to 1 %)
    base = simulate(ref)
    assert rel_rms(rec.clean_torque - base.clean_torque - rec.reflex_torque, rec.reflex_torque) < 0.01


def _frf(rec):
    f, pxy = signal.csd(rec.position[0], rec.torque[0], fs=FS, nperseg=1000)
    _, pxx = signal.welch(rec.position[0], fs=FS, nperseg=1000)
    return f, pxy / pxx


def test_cuff_compliance_resonates_at_the_predicted_frequency():
    kc, dc = 800.0, 0.5
    ref = smooth_reference(1, 8.0, band_hz=80.0, rms=0.01)
    rec = simulate(
        ref, EffectsConfig(cuff_compliance=CuffCompliance(stiffness_Nm_per_rad=kc, damping_Nms_per_rad=dc))
    )
    f, h = _frf(rec)
    s = 2j * math.pi * f
    limb = I * s**2 + B * s + K
    z = IP * s**2 + (kc + dc * s) * limb / (limb + kc + dc * s)  # pedal rigid, limb behind the cuff
    band = (f >= 20) & (f <= 80)  # above the 10 Hz notch where |Z| ~ B·w only
    f_res = math.sqrt((K + kc) / I) / (2 * math.pi)  # 33.8 Hz
    # peak within the 1 Hz resolution; Welch H1 of a noise-free run: leakage of a lightly damped
    # mode (zeta 0.15) gives a few %: 10 % on the magnitude
    assert abs(f[band][np.argmax(np.abs(h[band]))] - f_res) <= 1.0
    np.testing.assert_allclose(np.abs(h[band] / -z[band]), 1.0, atol=0.1)
    # and the limb moves differently from the pedal
    assert np.abs(rec.limb_angle - rec.pedal_angle).max() > 1e-3


def test_transmission_compliance_makes_the_pedal_lag_the_encoder_by_torque_over_kt():
    kt = 2000.0
    ref = smooth_reference(1, 8.0, band_hz=80.0, rms=0.005)
    rec = simulate(
        ref, EffectsConfig(transmission_compliance=TransmissionCompliance(stiffness_Nm_per_rad=kt))
    )
    np.testing.assert_allclose(rec.motor_angle - rec.pedal_angle, -rec.clean_torque / kt, atol=1e-15)
    assert np.abs(rec.motor_angle - rec.pedal_angle).max() > 1e-3
    # the spring's torque is the pedal+limb inverse dynamics of the pedal angle (not the encoder's)
    pred = intrinsic_torque(rec.pedal_angle)
    assert rel_rms((rec.clean_torque - pred)[:, IN], rec.clean_torque[:, IN] + TONIC) < 0.01
    f, h = _frf(rec)
    band = (f >= 20) & (f <= 80)
    f_res = math.sqrt((K + kt) / (I + IP)) / (2 * math.pi)  # 46.1 Hz
    assert abs(f[band][np.argmax(np.abs(h[band]))] - f_res) <= 1.0


@pytest.mark.parametrize("stribeck", [0.0, 0.2])
def test_friction_is_coulomb_at_the_limb_with_a_2fc_jump_at_reversals(stribeck):
    fc, vs = 0.3, 0.05
    ref = smooth_reference(1, 2.0, band_hz=5.0)
    fric = JointFriction(coulomb_Nm=fc, stribeck_Nm=stribeck, stribeck_velocity_rad_s=vs)
    rec = simulate(ref, EffectsConfig(joint_friction=fric))
    res = (rec.clean_torque - intrinsic_torque(rec.limb_angle))[0, IN]
    v = rec.limb_velocity[0, IN]
    rev = np.flatnonzero(np.diff(np.sign(v)) != 0)
    assert rev.size >= 4
    # outside MuJoCo's regularised zone (|v| < ~1e-3 rad/s) and 5 ms away from a reversal, where the
    # friction's step makes the servo jerk and the 1 kHz second difference err
    near = np.zeros(v.size, bool)
    for r in rev:
        near[max(r - 5, 0) : r + 6] = True
    moving = (np.abs(v) > 0.02) & ~near
    expected = -(fc + stribeck * np.exp(-((v / vs) ** 2))) * np.sign(v)
    # finite-difference inertia residual ~2e-3 N·m (see the rigid-chain test)
    np.testing.assert_allclose(res[moving], expected[moving], atol=0.01)
    # the jump across each reversal, from the last to the first moving sample 5-60 ms around it:
    # 2·Fc (+ the Stribeck excess at those velocities), to the same 0.01 N·m
    jumps = 0
    for r in rev:
        b = np.flatnonzero(moving[max(r - 60, 0) : r + 1])
        a = np.flatnonzero(moving[r + 1 : r + 61])
        if b.size == 0 or a.size == 0:
            continue  # a slow wiggle near rest: no moving sample on one side
        ib, ia = max(r - 60, 0) + b[-1], r + 1 + a[0]
        assert res[ia] - res[ib] == pytest.approx(expected[ia] - expected[ib], abs=0.01)
        assert abs(expected[ia] - expected[ib]) >= 2 * fc
        jumps += 1
    assert jumps >= 4


def test_payload_adds_m_r2_to_the_apparent_inertia():
    ref = smooth_reference(2, 3.0)
    pm = PayloadMass(mass_kg=0.3, lever_m=0.12)
    inertias = []
    for eff in (EffectsConfig(), EffectsConfig(payload_mass=pm)):
        rec = simulate(ref, eff)
        v, a = derivatives(rec.limb_angle)
        x = np.stack(
            [a[:, IN].ravel(), v[:, IN].ravel(), rec.limb_angle[:, IN].ravel(), np.ones(v[:, IN].size)], 1
        )
        inertias.append(-np.linalg.lstsq(x, rec.clean_torque[:, IN].ravel(), rcond=None)[0][0])
    # identified inertias are within 0.2 % (rigid-chain test); m·r² = 4.32e-3 kg·m² to 2 %
    assert inertias[0] == pytest.approx(I + IP, rel=5e-3)
    assert inertias[1] - inertias[0] == pytest.approx(0.3 * 0.12**2, rel=0.02)


def test_cocontraction_scales_stiffness_damping_and_tonic_with_the_activation():
    ref = smooth_reference(1, 12.0)
    cv = CocontractionVariation(depth=0.3, bandwidth_hz=0.3, tonic_torque_Nm=2.0)
    rec = simulate(ref, EffectsConfig(cocontraction_variation=cv))
    act = rec.activation
    assert act.std() > 0.1  # the activation did vary
    v, a = derivatives(rec.limb_angle)
    pred = -((I + IP) * a + act * (B * v + K * rec.limb_angle)) - TONIC - 2.0 * (act - 1)
    assert rel_rms((rec.clean_torque - pred)[:, IN], rec.clean_torque[:, IN] + TONIC) < 5e-3
    # the stiffness identified in 0.5 s windows follows a(t) (offset and its trend fitted too)
    ratio, mean_a = [], []
    for s0 in range(500, act.shape[1] - 1000, 500):
        sl = slice(s0, s0 + 500)
        t = np.arange(500) / FS
        x = np.stack([a[0, sl], v[0, sl], rec.limb_angle[0, sl], np.ones(500), t], 1)
        coef = np.linalg.lstsq(x, -rec.clean_torque[0, sl], rcond=None)[0]
        ratio.append(coef[2] / K)
        mean_a.append(act[0, sl].mean())
    # a(t) drifts within a window (0.3 Hz): a few % of its rms of 0.3
    assert np.sqrt(np.mean((np.array(ratio) - np.array(mean_a)) ** 2)) < 0.05
    assert np.corrcoef(ratio, mean_a)[0, 1] > 0.98


def test_activation_fluctuation_is_unit_rms_at_its_bandwidth():
    a = activation_fluctuation(20, 200_000, FS, 0.2, 0.3, np.random.default_rng(0))
    n = (a - 1) / 0.2
    # 20 x 200 s of a 0.3 Hz process: ~2400 correlation times, rms known to ~2 %; 5 %
    assert n.std() == pytest.approx(1.0, rel=0.05) and abs(n.mean()) < 0.05
    f, p = signal.welch(n, fs=FS, nperseg=2**16, axis=1)
    p = p.mean(axis=0)
    low = p[(f > 0.02) & (f < 0.1)].mean()
    # 2nd-order Butterworth: -3 dB at the bandwidth (Welch resolution 0.015 Hz, 1 dB)
    assert 10 * np.log10(np.interp(0.3, f, p) / low) == pytest.approx(-3.0, abs=1.0)


# ---------------------------------------------------------------- sensor-level effects


def test_channel_delay_shifts_the_torque_by_whole_samples():
    ref = smooth_reference(2, 1.0)
    base = simulate(ref)
    rec = simulate(ref, EffectsConfig(channel_delay=ChannelDelay(delay_s=0.0072)))  # 7.2 -> 7 samples
    np.testing.assert_array_equal(rec.torque[:, 7:], base.torque[:, :-7])
    np.testing.assert_array_equal(rec.position, base.position)
    neg = simulate(ref, EffectsConfig(channel_delay=ChannelDelay(delay_s=-0.003)))  # position later
    np.testing.assert_array_equal(neg.position[:, 3:], base.position[:, :-3])
    np.testing.assert_array_equal(neg.torque, base.torque)


def test_bandwidth_is_minus_3_db_at_the_cutoff():
    ref = smooth_reference(1, 8.0, band_hz=80.0, rms=0.01)
    rec = simulate(ref, EffectsConfig(force_sensor_bandwidth=ForceSensorBandwidth(cutoff_hz=20.0)))
    f, pxy = signal.csd(rec.clean_torque[0], rec.torque[0], fs=FS, nperseg=2000)
    _, pxx = signal.welch(rec.clean_torque[0], fs=FS, nperseg=2000)
    h = np.abs(pxy / pxx)
    # -3.01 dB within 0.1 dB (noise-free H1 of a 2nd-order filter: leakage ~1e-3)
    assert 20 * np.log10(h[f == 20.0][0]) == pytest.approx(-3.01, abs=0.1)
    assert 20 * np.log10(h[f == 2.0][0]) == pytest.approx(0.0, abs=0.1)


def test_quantisation_puts_every_position_on_the_grid():
    ref = smooth_reference(2, 1.0)
    step = 2 * math.pi / 65536
    rec = simulate(ref, EffectsConfig(encoder_quantisation=EncoderQuantisation(step=step)))
    k = rec.position / step
    np.testing.assert_allclose(k, np.round(k), atol=1e-9)
    assert np.abs(rec.position - rec.motor_angle).max() <= step / 2 + 1e-15


def test_drift_is_bias_plus_slope_exactly_and_noise_adds_in_quadrature():
    ref = smooth_reference(2, 2.0)
    drift = ForceSensorDrift(bias=0.4, drift_per_s=-0.05)
    rec = simulate(ref, EffectsConfig(force_sensor_drift=drift))
    np.testing.assert_allclose(
        rec.torque - rec.clean_torque, np.broadcast_to(0.4 - 0.05 * rec.t_s, rec.torque.shape), atol=1e-12
    )
    noisy = simulate(ref, EffectsConfig(force_sensor_noise=ForceSensorNoise(std=0.2)), noise=0.15)
    # std of 4000 Gaussian samples: 1.1 % sd; 5 %
    assert np.std(noisy.torque - noisy.clean_torque) == pytest.approx(0.25, rel=0.05)


# ---------------------------------------------------------------- randomness and errors


def test_same_seed_is_bit_identical_and_different_seeds_differ():
    ref = smooth_reference(2, 1.0)
    eff = EffectsConfig(
        cocontraction_variation=CocontractionVariation(depth=0.2, bandwidth_hz=1.0),
        reflex=Reflex(gain_Nms_per_rad=3.0),
    )
    a, b = simulate(ref, eff, noise=0.1, seed=5), simulate(ref, eff, noise=0.1, seed=5)
    c = simulate(ref, eff, noise=0.1, seed=6)
    for name in ("position", "torque", "clean_torque", "limb_angle", "reflex_torque", "activation"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert not np.array_equal(a.torque, c.torque)
    assert not np.array_equal(a.activation, c.activation)


def test_effects_of_other_protocols_are_rejected_with_the_valid_ones_named():
    ref = smooth_reference(1, 0.5)
    with pytest.raises(ConfigError) as err:
        simulate(ref, EffectsConfig(cable_drag=CableDrag(), plane_tilt=PlaneTilt(), reflex=Reflex()))
    msg = str(err.value)
    assert "cable_drag" in msg and "plane_tilt" in msg and "joint rig" in msg
    assert "reflex" in msg.split("simulates:")[1]  # the list of valid ones


def test_bad_inputs_raise():
    with pytest.raises(DataError, match="shape"):
        simulate(np.zeros(100))
    with pytest.raises(ConfigError, match="one sample"):
        simulate(smooth_reference(1, 0.5), EffectsConfig(reflex=Reflex(delay_s=1e-4)))
    with pytest.raises(ConfigError, match="noise_std_Nm"):
        simulate(smooth_reference(1, 0.5), noise=-1.0)
