"""Issue 23's excitation designer: waveforms against Eq. (16), the planning model against exact
cases, the designer's limits and determinism, and the designed scenario through the lab."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from armlab.errors import ConfigError
from armlab.perturbations.quintic import PAPER_DIRECTIONS, quintic_profile
from armlab.perturbations.scenario import load_scenario
from armlab.perturbations.segments import SegmentWaveform
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.design import (
    MIN_FRACTION,
    PAPER_PEAK_ACC_RAD_S2,
    PAPER_PEAK_VEL_RAD_S,
    DesignConfig,
    design_excitation,
    planning_model,
    register_design_config,
)
from armlab.protocols.conditioning_window.design_limits import LWR_TORQUE_LIMIT_NM, robot_limits
from armlab.protocols.conditioning_window.excitation_comparison import run_excitation
from armlab.protocols.conditioning_window.planning import planned_estimate

DIRS = np.asarray(PAPER_DIRECTIONS, float)


def test_one_segment_is_the_paper_quintic():
    t = np.linspace(-0.02, 0.2, 2001)
    for a, b in zip(SegmentWaveform(knots=(1.0,)).evaluate(t, 0.1), quintic_profile(t, 0.1), strict=True):
        np.testing.assert_array_equal(a, b)


def test_segments_bound_and_peaks():
    w = SegmentWaveform(knots=(0.5, -1.0, 0.2))
    x, xd, xdd = w.evaluate(np.linspace(0.0, 0.12, 120001), 0.12)
    assert x.min() >= -1.0 - 1e-12 and x.max() <= 0.5 + 1e-12  # monotone segments: the knots bound it
    vel, acc = w.peaks(0.12)
    # the analytic peaks against a 1 us grid: the grid misses the true peak by < 1e-6 relative
    np.testing.assert_allclose([np.abs(xd).max(), np.abs(xdd).max()], [vel, acc], rtol=1e-6)
    with pytest.raises(ConfigError, match=r"\[-1, 1\]"):
        SegmentWaveform(knots=(1.5,))
    with pytest.raises(ConfigError, match=r"\(0, 1\]"):
        SegmentWaveform(knots=(1.0,), fraction=0.0)


def test_fraction_holds_the_paper_quintic():
    """T_obs = T_k + 70 ms: the one-segment waveform over fraction T_k / T_obs is Eq. (16) over T_k
    (exact up to the round-off of fraction * duration)."""
    t = np.linspace(-0.01, 0.4, 4101)
    w = SegmentWaveform(knots=(1.0,), fraction=0.23 / 0.30).evaluate(t, 0.30)
    for a, b in zip(w, quintic_profile(t, 0.23), strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9)


def test_scenario_refuses_bad_profile_and_loads_designed():
    scen = load_scenario("designed_window")
    assert scen.waveform is not None and scen.t_k_s.tolist() == pytest.approx([0.12])
    assert np.abs(scen.directions_rad).max() <= 0.05  # the paper's amplitude bound


@pytest.fixture(scope="module")
def model():
    return planning_model(ConditioningWindowConfig())


def test_rigid_planning_recovers_the_nominal_parameters(model):
    """With the cuff rigid the planned data are Eq. (9) evaluated on the nominal parameters, so the
    least squares returns them exactly (round-off only)."""
    rigid = replace(model, cuff_stiffness_N_per_m=np.inf)
    zeta, *_ = planned_estimate(rigid, SegmentWaveform(knots=(1.0,)), DIRS, 0.12, 0.05)
    np.testing.assert_allclose(zeta, rigid.theta, rtol=1e-8, atol=1e-10)


def test_planned_cuff_torque_matches_an_ode_solution(model):
    """The discretised plant (first-order hold at 1 kHz) against the continuous arm + cuff
    integrated by solve_ivp (rtol 1e-10): within 1e-3 of the peak torque (measured 2.3e-4; the
    hold is exact for inputs linear between samples, the quintics' curvature leaves O(dt^2))."""
    from scipy.integrate import solve_ivp

    from armlab.models import planar_arm
    from armlab.protocols.conditioning_window.planning import planned_signals

    w = SegmentWaveform(knots=(0.3, 1.0, -0.5), fraction=0.8)
    d = np.array([[0.05, -0.05]])
    _, tau, _ = planned_signals(model, w, d, 0.12)
    J = planar_arm.jacobian(model.q0, model.l1, model.l2)
    Kc, Dc = model.cuff_stiffness_N_per_m * J.T @ J, model.cuff_damping_Ns_per_m * J.T @ J
    M = planar_arm.mass_matrix(model.q0, model.xi)

    def f(t, x):
        s, sd, _ = w.evaluate(np.array(t), 0.12)
        q, qd = x[:2], x[2:]
        return np.concatenate(
            [qd, np.linalg.solve(M, Kc @ (s * d[0] - q) + Dc @ (sd * d[0] - qd) - model.K @ q - model.D @ qd)]
        )

    t = np.arange(120) / 1000.0
    sol = solve_ivp(f, (0.0, t[-1]), np.zeros(4), t_eval=t, rtol=1e-10, atol=1e-13, max_step=1e-4)
    s, sd, _ = w.evaluate(t, 0.12)
    exact = (s[:, None] * d[0] - sol.y[:2].T) @ Kc.T + (sd[:, None] * d[0] - sol.y[2:].T) @ Dc.T
    assert np.abs(tau[0] - exact).max() < 1e-3 * np.abs(exact).max()


def test_cuff_planning_reproduces_the_labs_negative_stiffness(model):
    """The lab measured (seed 0, T_k = 50 ms quintic, window 120 ms) K11 = -268 N m/rad through the
    3 kN/m cuff; the linear planning model must show the same sign flip and order (within a factor
    of 2: it has no reflex, filter or noise)."""
    zeta, *_ = planned_estimate(model, SegmentWaveform(knots=(1.0,)), DIRS, 0.12, 0.05)
    assert -2 * 268 < zeta[7] < -268 / 2


def test_planning_model_predicts_the_labs_quintic_at_370ms(model):
    """The lab's paper quintic at T_obs = 370 ms (T_k = 300 ms), seeds 0-4 (docs/excitation_design.md):
    K 15-41 %, D 51-67 %, xi 18-47 % from the intrinsic truth. The planning model (linear arm + cuff,
    no reflex) with the noise measured over 120 ms cannot plan a 370 ms window: it refuses; over
    370 ms its bias must fall inside those seed ranges widened by 10 points (its noise term is
    the seeds' spread, the reflex it lacks)."""
    with pytest.raises(ConfigError, match="longer than the measured noise"):
        planned_estimate(model, SegmentWaveform(knots=(1.0,)), DIRS, 0.37, 0.30)
    noiseless = replace(model, noise=None)
    zeta, *_ = planned_estimate(noiseless, SegmentWaveform(knots=(1.0,)), DIRS, 0.37, 0.30)
    th = model.theta
    err = {
        n: np.linalg.norm(zeta[b] - th[b]) / np.linalg.norm(th[b])
        for n, b in (("xi", slice(0, 3)), ("D", slice(3, 7)), ("K", slice(7, 11)))
    }
    assert 0.05 <= err["K"] <= 0.51 and 0.41 <= err["D"] <= 0.77 and 0.08 <= err["xi"] <= 0.57, err


def test_design_respects_limits_and_is_deterministic(model):
    cfg = DesignConfig(t_obs_s=0.12, n_segments=3, criterion="d_optimal", n_starts=2, max_iter=50)
    a, b = design_excitation(model, cfg), design_excitation(model, cfg)
    assert a.waveform == b.waveform
    assert a.waveform.knots[-1] == 1.0 and MIN_FRACTION <= a.waveform.fraction <= 1.0  # ending "hold"
    assert a.peak_vel_rad_s <= 0.95 * PAPER_PEAK_VEL_RAD_S * (1 + 1e-9)  # limit_margin 0.95
    assert a.peak_acc_rad_s2 <= 0.95 * PAPER_PEAK_ACC_RAD_S2 * (1 + 1e-9)
    assert np.abs(a.directions_rad).max() <= 0.05 and max(abs(k) for k in a.waveform.knots) <= 1.0


def test_robot_limits_refuse_a_too_fast_waveform():
    """Full-amplitude reversals every 10 ms would ask the LWR for ~9x its A1/A2 velocity limit."""
    cfg = ConditioningWindowConfig()
    scen = load_scenario("designed_window")
    robot_limits(cfg, scen).check("designed_window")  # the committed design is within every limit
    fast = replace(scen, waveform=SegmentWaveform(knots=(1.0, -1.0, 1.0, -1.0)), t_k_s=np.array([0.04]))
    with pytest.raises(ConfigError, match=r"A2 velocity .* > 1\.92 rad/s"):
        robot_limits(cfg, fast).check("fast")


def test_hydra_composes_the_design_config():
    from hydra import compose, initialize
    from omegaconf import OmegaConf

    register_design_config()
    register_design_config()  # idempotent
    with initialize(version_base="1.3", config_path=None):
        cfg = OmegaConf.to_object(compose(config_name="design_config", overrides=["criterion=d_optimal"]))
        assert isinstance(cfg, DesignConfig) and cfg.criterion == "d_optimal" and cfg.t_obs_s == 0.12
        with pytest.raises(ConfigError, match="design.n_segments must lie in 1..12, got 20"):
            OmegaConf.to_object(compose(config_name="design_config", overrides=["n_segments=20"]))


def test_design_config_refuses_bad_values():
    with pytest.raises(ConfigError, match="d_optimal"):
        DesignConfig(criterion="a_optimal")
    with pytest.raises(ConfigError, match="0.05"):
        DesignConfig(amplitude_rad=0.1)
    with pytest.raises(ConfigError, match="hold"):
        DesignConfig(ending="return")


def test_designed_window_in_the_lab_seed0():
    """The committed design in the default realistic lab, seed 0 (docs/excitation_design.md):
    K positive definite from 300 ms and quasi-constant from 340 ms, pinned within one window
    step of the designed scenario's grid (20 ms there; 340 -> 370 ms is its next step); the
    intrinsic-truth K error at 120 ms stays above 10x (measured 13.5x: the soft cuff's bias, which
    is deterministic; the seeds' spread is 13.0-14.0x), and the robot's torques stay within limits."""
    r = run_excitation(ConditioningWindowConfig(seed=0), "designed_window")
    assert 0.28 - 1e-9 <= r["criteria"]["K_pd_from_s"] <= 0.32 + 1e-9
    assert 0.32 - 1e-9 <= r["criteria"]["constant_from_s"] <= 0.37 + 1e-9
    i = r["t_obs_s"].index(0.12)
    assert r["K_rel_err"][i] > 10.0
    assert np.all(np.array(r["robot_tau_peak_Nm"]) < LWR_TORQUE_LIMIT_NM)


def test_planning_follows_the_labs_model_effects():
    # joint friction settles the arm elsewhere (0.5 N·m Coulomb: ~3 mrad at the elbow); the design
    # must plan at the operating point the lab will simulate, not the frictionless one
    from armlab.config.effects import EffectsConfig, JointFriction
    from armlab.sim.lab import settled_scene

    cfg = ConditioningWindowConfig()
    rough = replace(cfg, effects=EffectsConfig(joint_friction=JointFriction(coulomb_Nm=0.5)))
    _, _, truth = settled_scene(rough)
    sensor = DesignConfig(noise="sensor")  # the operating point only: no noise measured in the lab
    planned = planning_model(rough, sensor).q0
    np.testing.assert_array_equal(planned, truth.q_op)
    assert np.max(np.abs(planned - planning_model(cfg, sensor).q0)) > 1e-3
