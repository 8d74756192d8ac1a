"""Unit checks of paper 002's pieces: waveforms, paths, timelines, regressors, polar form, LS/RLS
options, order selection, level A noise, and their bad-input errors (thesis Ch. 3, §2.2.2)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import ConfigError, DataError
from armlab.estimation import (
    cumulative_ls,
    disc_grid,
    field_error,
    fit_separable_polynomial,
    identify_exp1,
    identify_exp3,
    identify_exp4,
    linear_coupled_regressor,
    ls_fit,
    polar_force,
    polar_signals,
    quadratic_field_regressor,
    recursive_ls,
    select_order,
    to_polar,
)
from armlab.models import THESIS_FIELD, QuadraticImpedanceField, quadratic_basis
from armlab.perturbations import (
    TABLE_3_3,
    TRAPEZOIDAL,
    TRIANGULAR,
    circle_path,
    experiment_timeline,
    golden_omega,
    ramp_waveform,
    sinusoid_path,
    spiral_path,
    table_3_3_path,
)
from armlab.sim import simulate_level_a


# waveforms (§3.1.1) ---------------------------------------------------------------------------
def test_triangular_and_trapezoidal_shapes():
    t, p, v = TRIANGULAR.sample(1000.0)
    assert len(t) == 400 and TRIANGULAR.duration == pytest.approx(0.4)
    assert p.max() == pytest.approx(0.008, abs=1e-15) and t[np.argmax(p)] == pytest.approx(0.2)
    assert set(np.round(v, 12)) == {0.04, -0.04}
    assert TRIANGULAR.net_displacement == pytest.approx(0.0, abs=1e-18)
    t, p, v = TRAPEZOIDAL.sample(1000.0)
    assert len(t) == 350 and TRAPEZOIDAL.peak == pytest.approx(0.007)
    # +0.14 m/s for 50 ms, hold 200 ms, −0.07 m/s for 100 ms
    assert_allclose(v[:50], 0.14) and assert_allclose(v[50:250], 0.0) and assert_allclose(v[250:], -0.07)
    assert_allclose(p[50:250], 0.007, atol=1e-15)
    assert TRAPEZOIDAL.net_displacement == pytest.approx(0.0, abs=1e-18)


def test_smooth_corners_are_consistent_and_keep_the_plateaus():
    w = ramp_waveform("triangular", corner_s=0.04)
    assert w.duration == pytest.approx(0.44)
    t = np.linspace(-0.01, w.duration + 0.01, 4401)
    p, v, a = w.evaluate(t)
    h = 1e-6
    p_p, v_p, _ = w.evaluate(t + h)
    p_m, v_m, _ = w.evaluate(t - h)
    # central differences: truncation h²·|p'''|/6 ~ 1e-10 m/s, round-off eps·|p|/h ~ 1e-12
    assert_allclose((p_p - p_m) / (2 * h), v, atol=1e-8)
    assert_allclose((v_p - v_m) / (2 * h), a, atol=1e-5 * np.abs(a).max())
    assert np.max(np.abs(np.diff(v))) < 0.08 * 0.05  # no velocity step left (a sharp one is 0.08 m/s)
    assert p[0] == 0.0 and abs(p[-1]) < 1e-15 and v[0] == 0.0 and v[-1] == 0.0
    assert_allclose(w.evaluate(np.array([0.1, 0.32]))[1], [0.04, -0.04])  # plateau speeds kept
    # the tip is rounded: 8 mm -> 7.75 mm for a 40 ms blend (measured; the thesis's corner is sharp)
    assert 0.0077 < p.max() < 0.008


def test_waveform_bad_input():
    with pytest.raises(ConfigError, match="triangular, trapezoidal"):
        ramp_waveform("sine")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="shortest segment"):
        TRAPEZOIDAL.smoothed(0.06)
    with pytest.raises(ConfigError, match="fewer than 10 samples"):
        TRAPEZOIDAL.sample(100.0)


# paths (Table 3.3, §3.2.1, §3.3.1, §3.5.1) -----------------------------------------------------
def test_paths_geometry_and_velocity():
    w = np.asarray(TABLE_3_3)
    assert_allclose(table_3_3_path().position(w[:, 2]), w[:, :2], atol=1e-15)
    s = np.linspace(0.0, 100.0, 1001)
    circ = circle_path().position(s)
    assert_allclose(np.hypot(circ[:, 0] - 0.95, circ[:, 1] - 0.1), 0.1, rtol=1e-12)
    spiral = spiral_path().position(s)
    r = np.hypot(spiral[:, 0] - 0.95, spiral[:, 1] - 0.1)
    assert r[0] == pytest.approx(0.1) and r[-1] == pytest.approx(0.01)
    assert_allclose(np.diff(r), np.diff(r)[0], rtol=1e-9)  # linear shrink
    assert_allclose(sinusoid_path().position(s)[:, 1], 0.0)
    for path in (table_3_3_path(), circle_path(), spiral_path(), sinusoid_path()):
        s_mid = np.array([3.1, 20.3, 55.5, 91.7])  # away from waypoint corners
        h = 1e-5
        fd = (path.position(s_mid + h) - path.position(s_mid - h)) / (2 * h)
        assert_allclose(path.velocity(s_mid), fd, atol=1e-8)


def test_golden_omega_spreads_the_stops():
    omega = golden_omega(5.0)
    phases = np.mod(omega * (np.arange(20) + 0.5) * 5.0, 2 * np.pi)
    gaps = np.diff(np.sort(phases))
    # three-distance theorem: the 20 phases leave gaps of at most three sizes, none tiny
    assert gaps.min() > 0.15 and len(np.unique(np.round(gaps, 9))) <= 3
    with pytest.raises(ConfigError):
        golden_omega(0.0)


# timelines -------------------------------------------------------------------------------------
def test_reference_stops_during_each_sequence():
    tl = experiment_timeline(2)
    in_stop = tl.stop >= 0
    assert np.all(tl.qd_r[in_stop] == 0)
    for j in range(tl.n_stops):
        assert np.ptp(tl.q_r[tl.stop == j], axis=0).max() == 0.0
        assert_allclose(tl.q_r[tl.stop == j][0], tl.stop_position[j])
    # each stop: +x 400, pause 500, −y 400, pause 500, (+x, −y) 400 samples = 2.2 s
    idx = np.flatnonzero(tl.stop == 0)
    labels = tl.perturbation[idx]
    assert len(idx) == 2200 and np.sum(labels >= 0) == 1200
    assert_allclose(tl.directions[:3], [[1, 0], [0, -1], [1, -1]])
    assert np.all(tl.q_p[idx[:400], 0] >= 0) and np.all(tl.q_p[idx[900:1300], 1] <= 0)
    # the path resumes where it stopped: the reference is continuous
    assert np.abs(np.diff(tl.q_r, axis=0)).max() < 1e-5
    assert tl.s[-1] == pytest.approx(100.0) and tl.t[-1] == pytest.approx(100.0 + 20 * 2.2)


def test_experiment_bad_input():
    with pytest.raises(ConfigError, match="1, 2, 3, 4, 5"):
        experiment_timeline(6)
    with pytest.raises(ConfigError, match="noise"):
        simulate_level_a(experiment_timeline(2), THESIS_FIELD, noise_std_n=-1.0)
    with pytest.raises(ConfigError, match="Generator"):
        simulate_level_a(experiment_timeline(2), THESIS_FIELD, noise_std_n=0.05)
    with pytest.raises(ConfigError, match="stiffness_scale"):
        THESIS_FIELD.scaled(0.0)
    with pytest.raises(ConfigError, match="sigma"):
        THESIS_FIELD.stiffness([0.95, 0.1], sigma=2.0)
    rec2 = simulate_level_a(experiment_timeline(2), THESIS_FIELD)
    with pytest.raises(ConfigError, match="linear, sqrt_damping"):
        identify_exp4(rec2, method="quadratic")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="window_blocks"):
        identify_exp4(rec2, method="sqrt_damping", window_blocks=3)
    # a record of the wrong shape is a data problem, not a config one
    with pytest.raises(DataError, match="y = 0"):
        identify_exp3(rec2)
    with pytest.raises(DataError, match="single-axis"):
        identify_exp1(rec2)


def test_level_a_noise_is_seeded_and_has_its_level():
    tl = experiment_timeline(4)
    a = simulate_level_a(tl, THESIS_FIELD, noise_std_n=0.05, rng=np.random.default_rng(3))
    b = simulate_level_a(tl, THESIS_FIELD, noise_std_n=0.05, rng=np.random.default_rng(3))
    assert np.array_equal(a.force, b.force)
    noise = a.force - a.force_clean
    # 2 × 144 001 draws: the sample std is within 1 % of 0.05 N (its relative sd is ~0.2 %)
    assert noise.std() == pytest.approx(0.05, rel=0.01)


# regressors ------------------------------------------------------------------------------------
def test_quadratic_regressor_is_the_model_derivative():
    rng = np.random.default_rng(0)
    q_h = rng.uniform([0.85, 0.0], [1.05, 0.2], (50, 2))
    q_p = rng.uniform(-0.008, 0.008, (50, 2))
    qd_h = rng.uniform(-0.04, 0.04, (50, 2))
    # with constant damping the model force is exactly φᵀθ (Eq. 3.4.1 with Table 3.1)
    flat = QuadraticImpedanceField(coefficients=THESIS_FIELD.coefficients, delta=(0.0, 0.0))
    d = np.array([[120.0, 0.0], [0.0, 150.0]])
    force = flat.force(q_h, qd_h, q_p) + qd_h @ d.T
    for a in (0, 1):
        phi, names = quadratic_field_regressor(q_h, q_p, qd_h, a)
        theta = np.concatenate([flat.scaled_coefficients[a], d[a]])
        assert_allclose(phi @ theta, force[:, a], rtol=1e-12)
        assert names[0] == f"k_{'xy'[a]}0"
        # the stiffness columns are ∂F_a/∂k_a (finite differences of the field in its coefficients)
        for j in range(6):
            bumped = np.array(flat.coefficients, dtype=float)
            bumped[a, j] += 1.0
            df = QuadraticImpedanceField(coefficients=tuple(map(tuple, bumped)), delta=(0.0, 0.0))
            assert_allclose(
                df.force(q_h, qd_h, q_p)[:, a] - flat.force(q_h, qd_h, q_p)[:, a], phi[:, j], atol=1e-9
            )
    phi2, _ = linear_coupled_regressor(q_p, qd_h, 1)
    assert_allclose(phi2, np.c_[q_p, qd_h[:, 1]])
    with pytest.raises(ConfigError, match="axis"):
        quadratic_field_regressor(q_h, q_p, qd_h, 2)
    with pytest.raises(DataError, match=r"\(n, 2\)"):
        quadratic_field_regressor(q_h[:, :1], q_p, qd_h, 0)


# polar form (§2.2.2) ---------------------------------------------------------------------------
def test_polar_transform():
    rng = np.random.default_rng(2)
    q = rng.uniform([0.8, 0.0], [1.1, 0.2], (40, 2))
    f = rng.normal(0.0, 50.0, (40, 2))
    pol = to_polar(q)
    assert_allclose(pol[:, :1] * np.c_[np.cos(pol[:, 1]), np.sin(pol[:, 1])], q)
    fp = polar_force(f, q)
    e_rho = q / pol[:, :1]
    assert_allclose(fp[:, 0], np.sum(f * e_rho, axis=1))  # radial component
    assert_allclose(fp[:, 1], q[:, 0] * f[:, 1] - q[:, 1] * f[:, 0])  # moment r × F about the origin
    # velocities: chain rule against finite differences along a path
    tl = experiment_timeline(5)
    k = slice(30000, 30400)
    sig = polar_signals(tl.q_h[k], tl.q_r[k], tl.qd_h[k], np.ones((400, 2)))
    fd = np.gradient(to_polar(tl.q_h[k]), 1e-3, axis=0)
    assert_allclose(sig.qd[5:-5], fd[5:-5], atol=1e-3 * np.abs(sig.qd).max())  # O(h²·jerk) at corners
    # displacement: the reference's polar coordinates plus q_p map back (ρ cos θ, ρ sin θ) onto the
    # hand, an independent evaluation (atol: 1e-15 m rounding of m-sized positions)
    # over a window holding the first perturbation (the window above has none)
    first = np.flatnonzero(np.abs(tl.q_p).max(axis=1) > 0)[0]
    w = slice(first - 50, first + 950)
    sig = polar_signals(tl.q_h[w], tl.q_r[w], tl.qd_h[w], np.ones((1000, 2)))
    back = to_polar(tl.q_r[w]) + sig.q_p
    assert_allclose(back[:, :1] * np.c_[np.cos(back[:, 1]), np.sin(back[:, 1])], tl.q_h[w], atol=1e-15)
    assert np.abs(sig.q_p).max() > 1e-3  # the window holds a perturbation (~8 mm), not only zeros


# LS, RLS options -------------------------------------------------------------------------------
def _toy(rng: np.random.Generator, n_blocks: int = 12, m: int = 30):
    phi = rng.normal(size=(n_blocks * m, 3))
    theta = np.array([2.0, -1.0, 0.5])
    y = phi @ theta + 0.01 * rng.normal(size=n_blocks * m)
    return phi, y, np.repeat(np.arange(n_blocks), m)


def test_ls_fit_covariance_and_rank():
    rng = np.random.default_rng(4)
    phi, y, _ = _toy(rng)
    fit = ls_fit(phi, y)
    ref = np.linalg.lstsq(phi, y, rcond=None)[0]
    assert_allclose(fit.theta, ref, rtol=1e-12)
    s2 = np.sum((y - phi @ ref) ** 2) / (len(y) - 3)
    assert_allclose(fit.covariance, s2 * np.linalg.inv(phi.T @ phi), rtol=1e-9)
    dep = np.c_[phi, phi[:, 0] + phi[:, 1]]
    assert ls_fit(dep, y).rank == 3 and np.all(np.isnan(ls_fit(dep, y).covariance))
    with pytest.raises(DataError, match="finite"):
        ls_fit(np.full((5, 2), np.nan), np.ones(5))


def test_rls_forgetting_prior_and_window():
    rng = np.random.default_rng(6)
    phi, y, block = _toy(rng)
    lam = 0.98
    r = recursive_ls(phi, y, block, forgetting=lam)
    # exponentially weighted LS, weights λ^(age in samples), solved directly after block 6
    end = 7 * 30
    w = np.sqrt(lam ** np.arange(end - 1, -1, -1))
    direct = np.linalg.lstsq(phi[:end] * w[:, None], y[:end] * w, rcond=None)[0]
    assert_allclose(r.theta[6], direct, rtol=1e-10)
    # a vague prior (P0 = 1e12·I) changes the λ = 1 solution by ~1e-12 relative
    r0 = recursive_ls(phi, y, block, theta0=np.zeros(3), p0=1e12 * np.eye(3))
    c = cumulative_ls(phi, y, block)
    assert_allclose(r0.theta[-1], c.theta[-1], rtol=1e-9)
    # an informative prior pulls the first estimate towards it
    r1 = recursive_ls(phi, y, block, theta0=np.array([0.0, 0.0, 0.0]), p0=1e-4 * np.eye(3))
    assert np.linalg.norm(r1.theta[0]) < np.linalg.norm(c.theta[0])
    # a sliding window of 3 blocks is LS on those blocks only
    win = cumulative_ls(phi, y, block, window_blocks=3)
    assert_allclose(win.theta[8], np.linalg.lstsq(phi[6 * 30 : 9 * 30], y[6 * 30 : 9 * 30], rcond=None)[0])
    with pytest.raises(DataError, match=r"\(0, 1\]"):
        recursive_ls(phi, y, block, forgetting=1.5)
    with pytest.raises(DataError, match="contiguous"):
        cumulative_ls(phi, y, np.r_[block[:-5], np.zeros(5, int)])


# order selection (§3.5.2) ----------------------------------------------------------------------
def test_adjusted_r2_and_order_selection():
    rng = np.random.default_rng(8)
    pos = rng.uniform([0.85, 0.0], [1.05, 0.2], (20, 2))
    z = 3.0 + 2.0 * pos[:, 0] - 5.0 * pos[:, 1] ** 2
    sel = select_order(pos, z)
    assert sel.order == (1, 2) and sel.r2_adj == pytest.approx(1.0)
    assert_allclose(sel.evaluate(pos), z, rtol=1e-10)
    noisy = z + 0.05 * rng.normal(size=20)
    fit = fit_separable_polynomial(pos, noisy, (1, 1))
    ss_res = np.sum((noisy - fit.evaluate(pos)) ** 2)
    r2 = 1 - ss_res / np.sum((noisy - noisy.mean()) ** 2)
    assert fit.r2 == pytest.approx(r2) and fit.r2_adj == pytest.approx(1 - (1 - r2) * 19 / 17)
    assert fit.n_parameters == 3
    with pytest.raises(ConfigError, match="threshold"):
        select_order(pos, z, threshold=1.5)


def test_field_error_is_zero_for_the_truth():
    grid = disc_grid()
    assert field_error(THESIS_FIELD.scaled_coefficients, THESIS_FIELD, grid).max_pct == pytest.approx(
        0.0, abs=1e-12
    )
    k = THESIS_FIELD.stiffness(grid)
    assert_allclose(quadratic_basis(grid) @ THESIS_FIELD.scaled_coefficients.T, k)
    # 1 % on k_0 alone shows as ≤ 1 %·k_0/K over the disc
    bumped = THESIS_FIELD.scaled_coefficients.copy()
    bumped[:, 0] *= 1.01
    err = field_error(bumped, THESIS_FIELD, grid)
    assert_allclose(err.error_pct, 100 * 0.01 * bumped[:, 0] / 1.01 / k, rtol=1e-9)
