"""Tests of armlab.sensors.presets: presets, the sensor suite and measure()."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.errors import ConfigError
from armlab.sensors import (
    JR3_FORCE,
    JR3_TORQUE,
    LWR_ENCODER,
    LWR_JOINT_TORQUE,
    SENSOR_PRESETS,
    ChannelSpec,
    SensorSuite,
    get_preset,
    measure,
)

FS = 1000.0  # Hz, the paper's logging rate (section IV-A)


def _clean(n_trials: int = 3, n_samples: int = 200) -> dict[str, np.ndarray]:
    t = np.arange(n_samples) / FS
    s = np.sin(2 * np.pi * 3 * t)[None, :, None]
    return {
        "ft_force": np.broadcast_to(10 * s, (n_trials, n_samples, 3)).copy(),
        "ft_torque": np.broadcast_to(0.5 * s, (n_trials, n_samples, 3)).copy(),
        "robot_q": np.broadcast_to(0.3 * s + 0.2, (n_trials, n_samples, 7)).copy(),
        "robot_tau": np.broadcast_to(5 * s, (n_trials, n_samples, 7)).copy(),
    }


def test_presets_registry_and_lookup():
    assert all(isinstance(s, ChannelSpec) for s in SENSOR_PRESETS.values())
    assert get_preset("jr3_force") is JR3_FORCE
    assert get_preset("lwr_encoder") is LWR_ENCODER
    assert get_preset("ideal").is_ideal
    with pytest.raises(ConfigError, match=r"unknown sensor preset 'jr4'.*'jr3_force'"):
        get_preset("jr4")


def test_presets_are_usable_at_1khz():
    nyquist = FS / 2
    for spec in (JR3_FORCE, JR3_TORQUE, LWR_ENCODER, LWR_JOINT_TORQUE):
        assert spec.bandwidth_hz is None or spec.bandwidth_hz < nyquist
        assert spec.delay_samples(FS) < 10
    assert LWR_ENCODER.quant_step == pytest.approx(math.radians(0.01))
    assert LWR_ENCODER.noise_std < LWR_ENCODER.quant_step


def test_ideal_suite_measures_exactly():
    clean = _clean()
    out = measure(clean, SensorSuite.ideal(), FS, np.random.default_rng(0))
    assert set(out) == set(clean)
    for k in clean:
        assert np.array_equal(out[k], clean[k])


def test_realistic_suite_shapes_grid_and_determinism():
    clean = _clean()
    suite = SensorSuite.realistic()
    a = measure(clean, suite, FS, np.random.default_rng(3))
    b = measure(clean, suite, FS, np.random.default_rng(3))
    c = measure(clean, suite, FS, np.random.default_rng(4))
    for k in clean:
        assert a[k].shape == clean[k].shape and a[k].dtype == np.float64
        assert np.array_equal(a[k], b[k])
        assert not np.array_equal(a[k], c[k])
    step = LWR_ENCODER.quant_step
    np.testing.assert_allclose(a["robot_q"] / step, np.round(a["robot_q"] / step), atol=1e-9)
    # encoder: no bias or drift, noise far below a step -> within one step of the truth
    assert np.max(np.abs(a["robot_q"] - clean["robot_q"])) < 2 * step


def test_adding_a_channel_does_not_change_the_others():
    clean = _clean()
    suite = SensorSuite.realistic()
    full = measure(clean, suite, FS, np.random.default_rng(11))
    for name in clean:  # each channel alone gives the same result as among all the others
        only = measure({name: clean[name]}, suite, FS, np.random.default_rng(11))
        assert np.array_equal(only[name], full[name]), name


def test_channels_get_independent_streams():
    spec = ChannelSpec(noise_std=1.0)
    suite = SensorSuite(ft_force=spec, ft_torque=spec, encoder=spec, joint_torque=spec)
    zeros = np.zeros((2, 100, 3))
    out = measure({"ft_force": zeros, "ft_torque": zeros}, suite, FS, np.random.default_rng(0))
    assert not np.array_equal(out["ft_force"], out["ft_torque"])


def test_t0_is_passed_to_every_channel():
    spec = ChannelSpec(drift_per_s=1.0)
    suite = SensorSuite(ft_force=spec, ft_torque=spec, encoder=spec, joint_torque=spec)
    zeros = np.zeros((2, 10, 1))
    out = measure({"robot_tau": zeros}, suite, FS, np.random.default_rng(0), t0_s=np.array([1.0, 2.0]))
    assert np.all(out["robot_tau"][:, 0] != 0)


def test_measure_and_suite_validation():
    with pytest.raises(ConfigError, match=r"no sensor model for channels \['hand_pos'\].*'robot_q'"):
        measure({"hand_pos": np.zeros((1, 5, 2))}, SensorSuite.ideal(), FS, np.random.default_rng(0))
    with pytest.raises(ConfigError, match="SensorSuite.encoder must be a ChannelSpec"):
        SensorSuite(ft_force=JR3_FORCE, ft_torque=JR3_TORQUE, encoder="lwr", joint_torque=LWR_JOINT_TORQUE)
    with pytest.raises(ConfigError, match="valid channels"):
        SensorSuite.ideal().spec_for("emg")


def test_channels_measured_concurrently_equal_one_after_the_other():
    # measure() applies the channels on threads; each must be what its own child generator gives
    # serially (the seeds drawn from rng in the suite's channel order), in the same key order
    from armlab.sensors.channel import apply_channel

    clean, suite, wait = _clean(n_trials=4), SensorSuite.realistic(), np.array([0.5, 1.0, 1.5, 2.0])
    out = measure(clean, suite, FS, np.random.default_rng(7), t0_s=wait)
    order = suite.channel_fields()
    seeds = np.random.default_rng(7).integers(0, 2**63, size=len(order), dtype=np.int64)
    serial = {
        name: apply_channel(clean[name], FS, suite.spec_for(name), np.random.default_rng(int(s)), t0_s=wait)
        for s, name in zip(seeds, order, strict=True)
        if name in clean
    }
    assert list(out) == list(serial)
    for name in serial:
        assert np.array_equal(out[name], serial[name])
