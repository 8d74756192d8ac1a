"""Checks of the minimum-jerk perturbation and the conditioning ratio, Eqs. (16)-(17)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import polynomial as P
from numpy.testing import assert_allclose

from armlab.errors import ConfigError
from armlab.perturbations import (
    PAPER_DIRECTIONS,
    QuinticPerturbation,
    conditioning_ratio,
    observation_durations,
    polynomial_coefficients,
    quintic_profile,
    window_durations,
)


def test_profile_boundary_conditions_and_hold():
    T = 0.2
    s, sd, sdd = quintic_profile(np.array([-0.1, 0.0, T, T + 0.1]), T)
    assert_allclose(s, [0, 0, 1, 1], atol=1e-15)
    assert_allclose(sd, 0, atol=1e-12)
    assert_allclose(sdd, 0, atol=1e-9)
    s_mid, sd_mid, sdd_mid = quintic_profile(np.array(T / 2), T)
    # closed form at tau = 1/2: s = 1/2, s' = 15/8 / T, s'' = 0
    assert_allclose([s_mid, sd_mid, sdd_mid], [0.5, 15 / 8 / T, 0.0], atol=1e-12)


def test_profile_derivatives_match_finite_differences():
    T, h = 0.15, 1e-6
    t = np.linspace(0.001, T - 0.001, 101)
    s_p, sd_p, _ = quintic_profile(t + h, T)
    s_m, sd_m, _ = quintic_profile(t - h, T)
    _, sd, sdd = quintic_profile(t, T)
    # central differences: truncation h²/6·|s'''| ~ 1e-8, round-off eps/h ~ 1e-10 (relative to peaks)
    assert_allclose((s_p - s_m) / (2 * h), sd, rtol=0, atol=1e-6 * np.max(sd))
    assert_allclose((sd_p - sd_m) / (2 * h), sdd, rtol=0, atol=1e-6 * np.max(np.abs(sdd)))


def test_polynomial_coefficients_satisfy_boundary_conditions():
    assert_allclose(polynomial_coefficients("quintic"), [0, 0, 0, 10, -15, 6], atol=1e-12)
    c6 = polynomial_coefficients("sextic")
    for order, at0, at1 in [(0, 0, 1), (1, 0, 0), (2, 0, 0)]:
        assert_allclose(P.polyval([0.0, 1.0], P.polyder(c6, order)), [at0, at1], atol=1e-12)
    assert_allclose(P.polyval(1.0, P.polyder(c6, 3)), 0.0, atol=1e-10)  # jerk(t_f) = 0
    assert abs(P.polyval(1.0, P.polyder(polynomial_coefficients("quintic"), 3))) > 1  # quintic: 60
    with pytest.raises(ConfigError, match=r"one of \('quintic', 'sextic'\)"):
        polynomial_coefficients("cubic")


def test_conditioning_ratio_closed_form():
    # quintic: mean(s'²) = 10/7 / T², mean(s''²) = 120/7 / T⁴, mean(s'''²) = 720 / T⁶
    T = 0.3
    assert_allclose(conditioning_ratio(1, 2, "quintic", T), T**2 / 12, rtol=1e-12)
    assert_allclose(conditioning_ratio(2, 3, "quintic", T), T**2 * (120 / 7) / 720, rtol=1e-12)
    assert_allclose(conditioning_ratio(1, 3, "quintic", T, n_nodes=40), T**4 * (10 / 7) / 720, rtol=1e-12)


@pytest.mark.parametrize("duration", [*window_durations()[::5], 0.5])
def test_quintic_better_conditioned_than_sextic(duration):
    # Table I of the paper: for each C_ij (i < j, i in 1..2, j in 2..3) the quintic is closer to 1
    for i, j in [(1, 2), (1, 3), (2, 3)]:
        c5 = conditioning_ratio(i, j, "quintic", duration)
        c6 = conditioning_ratio(i, j, "sextic", duration)
        assert abs(np.log(c5)) < abs(np.log(c6)), (i, j, c5, c6)


def test_conditioning_ratio_validation():
    with pytest.raises(ConfigError, match="derivative order in 0..4"):
        conditioning_ratio(1, 7)
    with pytest.raises(ConfigError, match="duration_s must be a positive"):
        conditioning_ratio(1, 2, duration_s=0.0)


def test_perturbation_sample():
    p = QuinticPerturbation(amplitude=(0.05, -0.05), duration_s=0.1, onset_s=0.5)
    t = np.arange(0, 1.0, 0.001)
    pos, vel, acc = p.sample(t)
    assert pos.shape == vel.shape == acc.shape == (t.size, 2)
    assert_allclose(pos[t < 0.5], 0.0)
    assert_allclose(pos[t >= 0.6 + 1e-9], [[0.05, -0.05]] * int(np.sum(t >= 0.6 + 1e-9)), atol=1e-15)
    s, sd, sdd = quintic_profile(t - 0.5, 0.1)
    assert_allclose(vel[:, 1], -0.05 * sd)
    assert p.amplitude == (0.05, -0.05) and p.dof == 2 and p.end_s == pytest.approx(0.6)
    assert p == QuinticPerturbation(amplitude=[0.05, -0.05], duration_s=0.1, onset_s=0.5)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(amplitude=(), duration_s=0.1), "non-empty"),
        (dict(amplitude=(0.1, np.nan), duration_s=0.1), "finite"),
        (dict(amplitude=("a",), duration_s=0.1), "sequence of numbers"),
        (dict(amplitude=(0.1,), duration_s=0.0), "duration_s must be a positive"),
        (dict(amplitude=(0.1,), duration_s=0.1, onset_s=-1.0), "onset_s must be"),
    ],
)
def test_perturbation_validation(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        QuinticPerturbation(**kwargs)


def test_profile_rejects_bad_duration():
    with pytest.raises(ConfigError, match="duration must be a positive"):
        quintic_profile(np.zeros(3), -0.1)


def test_paper_protocol_constants():
    assert len(PAPER_DIRECTIONS) == 6 and all(max(map(abs, d)) == 0.05 for d in PAPER_DIRECTIONS)
    T = window_durations()
    assert T.shape == (26,) and T[0] == pytest.approx(0.05) and T[-1] == pytest.approx(0.30)
    t_obs = observation_durations()
    assert t_obs[0] == pytest.approx(0.12) and t_obs[-1] == pytest.approx(0.37)
    with pytest.raises(ConfigError, match="k_max must be a positive integer"):
        window_durations(0)


def test_public_api_resolves():
    import armlab.perturbations as pert
    import armlab.perturbations.quintic as quintic

    assert all(hasattr(pert, name) for name in pert.__all__)
    assert set(quintic.__all__) <= set(pert.__all__)
