"""Table II signals from the capstan robot's channels: analytic motion and force in, both methods out."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.errors import DataError
from armlab.estimation.capstan_signals import CapstanSignals, capstan_signals, rotate_by
from armlab.estimation.smoothing import SmoothingSpec
from armlab.models.capstan_robot import CapstanDynamics, CapstanParameters

FS_HZ = 1000.0  # Hz, the paper's rate
DURATION_S = 20.0
EDGE = slice(2000, -2000)  # drop 2 s at each end: the filters' edge transients (smoothing.py)
THETA0 = np.array([1.0, 0.6])  # rad, elbow 0.4 rad from straight: J well conditioned
DYN = CapstanDynamics()  # Table VI, the robot's lengths
SPEC = SmoothingSpec()  # the paper's SG N = 6, W = 151 and 4.5 Hz 5th-order zero-phase low-pass


def _sines(t: np.ndarray, freqs: np.ndarray, amp: float, phases: np.ndarray):
    """A sum of sines (n,) and its first two derivatives."""
    w = 2 * np.pi * freqs
    arg = w * t[:, None] + phases
    return (
        amp * np.sin(arg).sum(-1),
        amp * (w * np.cos(arg)).sum(-1),
        -amp * (w**2 * np.sin(arg)).sum(-1),
    )


def _truth(seed: int = 7):
    """Analytic joint motion (0.2..2 Hz, ~8 deg peak to peak) and end-effector force (0.3..1.9 Hz)."""
    rng = np.random.default_rng(seed)
    t = np.arange(round(DURATION_S * FS_HZ)) / FS_HZ
    freqs = np.linspace(0.2, 2.0, 10)
    joints = [_sines(t, freqs, 0.013, rng.uniform(0, 2 * np.pi, 10)) for _ in range(2)]
    r, theta_dot, theta_ddot = (np.stack([j[i] for j in joints], axis=-1) for i in range(3))
    theta = THETA0 + r
    force = np.stack(
        [
            3.0 * np.sin(2 * np.pi * 0.5 * t + 0.3) + 1.5 * np.sin(2 * np.pi * 1.9 * t) + 1.0,
            2.0 * np.cos(2 * np.pi * 1.3 * t) - 1.0 * np.sin(2 * np.pi * 0.3 * t) - 0.5,
        ],
        axis=-1,
    )  # N, the paper's F_ext: the hand (or fixture) on the robot
    jac = DYN.jacobian(theta)
    x_dot = np.einsum("nij,nj->ni", jac, theta_dot)
    x_ddot = np.einsum("nij,nj->ni", jac, theta_ddot) + np.einsum(
        "nij,nj->ni", DYN.jacobian_dot(theta, theta_dot), theta_dot
    )
    # Eq. (1) with the external force: tau = I theta_dd + C theta_d + F_r - J^T F_ext
    tau = DYN.inverse_dynamics(theta, theta_dot, theta_ddot) - np.einsum("nji,nj->ni", jac, force)
    channels = {
        "theta": theta[None],
        "tau": tau[None],
        "acc_site": rotate_by(-theta[:, 1], x_ddot)[None],  # link 2's frame is turned by theta2
        "ft_site": rotate_by(-theta[:, 1], -force)[None],  # link 2 on the handle: -F_ext
    }
    truth = dict(
        theta=theta,
        theta_dot=theta_dot,
        theta_ddot=theta_ddot,
        x=DYN.fk(theta),
        x_dot=x_dot,
        x_ddot=x_ddot,
        tau=tau,
        force=force,
    )
    return channels, truth


@pytest.fixture(scope="module")
def processed() -> tuple[CapstanSignals, dict, dict]:
    channels, truth = _truth()
    return capstan_signals(channels, FS_HZ, SPEC, DYN), truth, channels


def _peak(a: np.ndarray) -> float:
    return float(np.abs(a).max())


def test_shapes_and_stages(processed):
    sig, truth, _ = processed
    n = round(DURATION_S * FS_HZ)
    for name in ("x", "x_dot", "x_ddot", "theta", "theta_dot", "theta_ddot", "tau", "f_virtual", "f_sensor"):
        assert getattr(sig, name).shape == (1, n, 2), name
        assert sig.sg[name].shape == (1, n, 2), name
    assert np.ptp(truth["theta"], axis=0).min() > np.deg2rad(5)  # a motion of the paper's size


def test_both_methods_recover_the_external_force(processed):
    sig, truth, _ = processed
    force = truth["force"][EDGE]
    # The force (0.3..1.9 Hz) lies in the filters' pass band. The zero-phase 5th-order Butterworth
    # has gain 1 / (1 + (f / 4.5 Hz)^10): 1 - 1.8e-4 at 1.9 Hz, so the 1.5 N component there comes
    # out 2.7e-4 N short (the SG stage's error is smaller). Seen 3.0e-4 N by either method; allow
    # 1e-3 N. A rotation by the wrong sign of theta2 errs by 6.5 N.
    assert _peak(force) > 5.0
    np.testing.assert_allclose(sig.f_sensor[0, EDGE], force, rtol=0, atol=1e-3)
    np.testing.assert_allclose(sig.f_virtual[0, EDGE], force, rtol=0, atol=1e-3)


def test_kinematic_signals_match_the_analytic_motion(processed):
    sig, truth, _ = processed
    # position: fk of the smoothed encoders, low-passed; fk's curvature puts a little of the
    # 0-2 Hz motion at 2-4 Hz where the 4.5 Hz low-pass attenuates it: seen 1.5e-5 m on 0.42 m
    np.testing.assert_allclose(sig.x[0, EDGE], truth["x"][EDGE], rtol=0, atol=1e-4)
    # velocity: the differentiation filter on fk(theta), same effect on a derivative that
    # weights the harmonics by their frequency: seen 3.2e-4 m/s on a 0.19 m/s peak (0.16 %)
    np.testing.assert_allclose(sig.x_dot[0, EDGE], truth["x_dot"][EDGE], rtol=0, atol=1e-3)
    # acceleration: the accelerometer turned back into the base frame; J_dot theta_dot carries
    # 2-4 Hz products as well: seen 7.5e-3 m/s² on a 2 m/s² peak (0.4 %)
    np.testing.assert_allclose(sig.x_ddot[0, EDGE], truth["x_ddot"][EDGE], rtol=0, atol=2e-2)
    # joints: linear filtering of 0.2-2 Hz sines, seen 1.2e-5 rad, 7e-5 rad/s, 8e-4 rad/s²
    # (theta_dd from Eq. (7) on the filtered x_dd) on peaks of 1.06 rad, 0.64 rad/s, 6 rad/s²
    np.testing.assert_allclose(sig.theta[0, EDGE], truth["theta"][EDGE], rtol=0, atol=1e-4)
    np.testing.assert_allclose(sig.theta_dot[0, EDGE], truth["theta_dot"][EDGE], rtol=0, atol=1e-3)
    np.testing.assert_allclose(sig.theta_ddot[0, EDGE], truth["theta_ddot"][EDGE], rtol=0, atol=1e-2)
    # commanded torque, smoothed (J^T F adds 2-4 Hz products): seen 1.1e-3 N·m on a 2.2 N·m peak
    np.testing.assert_allclose(sig.tau[0, EDGE], truth["tau"][EDGE], rtol=0, atol=3e-3)


def test_x_is_the_forward_kinematics_of_the_smoothed_encoders(processed):
    sig, _, _ = processed
    # before the low-pass stage the position is fk of the SG-smoothed theta exactly
    np.testing.assert_allclose(sig.sg["x"], DYN.fk(sig.sg["theta"]), rtol=0, atol=1e-15)


def test_each_method_reads_only_its_own_sensor(processed):
    sig, truth, channels = processed
    # Method 2 (f_sensor) is the F/T sensor alone, Method 1 (f_virtual) the encoders, the
    # accelerometer and the torques: corrupting the other one's channel leaves each unchanged
    bad_ft = dict(channels, ft_site=channels["ft_site"] + 5.0)
    bad_tau = dict(channels, tau=channels["tau"] + 0.5)
    a = capstan_signals(bad_ft, FS_HZ, SPEC, DYN)
    b = capstan_signals(bad_tau, FS_HZ, SPEC, DYN)
    np.testing.assert_array_equal(a.f_virtual, sig.f_virtual)
    np.testing.assert_array_equal(b.f_sensor, sig.f_sensor)
    assert _peak(a.f_sensor - sig.f_sensor) > 4.0 and _peak(b.f_virtual - sig.f_virtual) > 1.0


def test_wrong_robot_model_biases_only_method_1(processed):
    sig, truth, channels = processed
    # a robot model without viscous friction: Eq. (2) is off by J^-T F_r(theta_dot), which the
    # physical sensor does not see (alpha4,5 ~ 0.07 N·m·s/rad * 0.6 rad/s / 0.35 m ~ 0.1 N;
    # seen 0.13 N against the 3e-4 N of the true model)
    alpha = DYN.params.as_array()
    no_friction = CapstanDynamics(params=CapstanParameters.from_array(np.r_[alpha[:3], 0.0, 0.0]))
    other = capstan_signals(channels, FS_HZ, SPEC, no_friction)
    np.testing.assert_array_equal(other.f_sensor, sig.f_sensor)
    assert _peak(other.f_virtual[0, EDGE] - truth["force"][EDGE]) > 0.05


def test_too_short_a_record_is_rejected():
    channels, _ = _truth()
    short = {k: v[:, :100] for k, v in channels.items()}  # shorter than the 151-sample window
    with pytest.raises(DataError, match="151"):
        capstan_signals(short, FS_HZ, SPEC, DYN)


def test_rotate_by_is_a_planar_rotation():
    rng = np.random.default_rng(0)
    angle = rng.uniform(-np.pi, np.pi, (3, 50))
    v = rng.normal(size=(3, 50, 2))
    turned = rotate_by(angle, v)
    assert turned.shape == v.shape
    np.testing.assert_allclose(np.linalg.norm(turned, axis=-1), np.linalg.norm(v, axis=-1), rtol=1e-13)
    np.testing.assert_allclose(rotate_by(-angle, turned), v, rtol=0, atol=1e-14)
    # the angle between v and its image is the rotation angle (counter-clockwise positive)
    cross = v[..., 0] * turned[..., 1] - v[..., 1] * turned[..., 0]
    dot = np.sum(v * turned, axis=-1)
    np.testing.assert_allclose(np.arctan2(cross, dot), angle, atol=1e-12)
    np.testing.assert_allclose(rotate_by(np.pi / 2, np.array([1.0, 0.0])), [0.0, 1.0], atol=1e-16)
    # one angle per vector along the leading dimensions
    pair = rotate_by(np.array([0.3, -1.2]), np.array([[1.0, 2.0], [1.0, 2.0]]))
    np.testing.assert_array_equal(pair[0], rotate_by(0.3, np.array([1.0, 2.0])))
    np.testing.assert_array_equal(pair[1], rotate_by(-1.2, np.array([1.0, 2.0])))
