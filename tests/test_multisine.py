"""Random-phase multisine force references (seeds/004, Sec. III-A)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from armlab.errors import ConfigError
from armlab.perturbations.multisine import load_force_scenario, multisine


def test_reference_respects_the_paper_band_and_peak():
    sc = load_force_scenario("fractional_elbow")
    f = multisine(sc, np.random.default_rng(0))
    assert f.shape == (80000,) and np.max(np.abs(f)) == pytest.approx(5.0)
    freqs = sc.frequencies_hz
    assert freqs.min() >= 0.12 - 1e-12 and freqs.max() <= 15.0 + 1e-12
    spec = np.abs(np.fft.rfft(f))
    fgrid = np.fft.rfftfreq(f.size, 1 / sc.fs_hz)
    out_of_band = spec[(fgrid > 16.0)].max() / spec.max()
    assert out_of_band < 0.02  # only the 0.5 s tapers leak (measured 1.2 % of the peak line)
    assert f[0] == 0.0 and abs(f[-1]) < 1e-3


def test_same_generator_same_signal_other_seed_other_phases():
    sc = replace(load_force_scenario("fractional_elbow"), duration_s=10.0, spacing_hz=0.1)
    a = multisine(sc, np.random.default_rng(3))
    assert np.array_equal(a, multisine(sc, np.random.default_rng(3)))
    assert not np.allclose(a, multisine(sc, np.random.default_rng(4)))


def test_components_off_the_record_grid_are_rejected():
    sc = replace(load_force_scenario("fractional_elbow"), duration_s=5.0)  # 0.025 Hz * 5 s = 1/8
    with pytest.raises(ConfigError, match="not a multiple of 1 / duration_s"):
        multisine(sc, np.random.default_rng(0))


def test_unknown_or_conditioning_scenario_is_rejected():
    with pytest.raises(ConfigError, match="unknown scenario 'nope'"):
        load_force_scenario("nope")
    with pytest.raises(ConfigError, match="not a force scenario"):
        load_force_scenario("conditioning_window")
