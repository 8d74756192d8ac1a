"""Level B of ``cartesian_online`` (paper 002): the LWR + hand scene, the exact per-step field, the
sensors, and the comparison with level A."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_array_equal

from armlab.config.schema import SimConfig
from armlab.errors import ConfigError
from armlab.estimation.cartesian_identification import identify_exp2, identify_exp4
from armlab.models.cartesian_field import THESIS_FIELD
from armlab.models.cartesian_hand_scene import build_hand_scene
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig, SimulationConfig
from armlab.protocols.cartesian_online.experiment import records_from_trials, simulate_cartesian
from armlab.protocols.cartesian_online.level_b import (
    clean_trials,
    executed_path_trials,
    inertia_compensated_trials,
    simulate_level_b_trials,
)
from armlab.sim import cartesian_level_b
from armlab.sim.cartesian_level_b import SETTLE_S, _jacobians, simulate_level_b, stop_postures
from armlab.sim.stability import warning_counts


def test_level_b_scene_compiles_and_steps_without_warnings():
    scene = build_hand_scene(SimConfig())
    data = mujoco.MjData(scene.model)
    mujoco.mj_resetData(scene.model, data)
    for _ in range(500):
        mujoco.mj_step(scene.model, data)
    assert warning_counts([data]) == {}
    assert np.all(np.isfinite(data.qpos))
    # the hand's slides are the thesis's coordinates: its site sits at (x, y, HAND_HEIGHT_M)
    data.qpos[scene.hand_qpos] = [0.95, 0.1, 0.0]
    mujoco.mj_kinematics(scene.model, data)
    np.testing.assert_allclose(data.site_xpos[scene.hand_site][:2], [0.95, 0.1], atol=1e-12)


def test_same_seed_gives_bit_identical_level_b_trials():
    cfg = CartesianOnlineConfig(seed=5, simulation=SimulationConfig(n_stops=3))
    a = simulate_cartesian(cfg)
    one, _, _ = simulate_level_b_trials(cfg, a.trials, a.field)
    two, _, _ = simulate_level_b_trials(cfg, a.trials, a.field)
    for name, arr in one.channels.items():
        assert_array_equal(arr, two.channels[name])
    other, _, _ = simulate_level_b_trials(
        CartesianOnlineConfig(seed=6, simulation=cfg.simulation), a.trials, a.field
    )
    assert not np.array_equal(other.channels["hand_force"], one.channels["hand_force"])
    assert_array_equal(other.channels["true_hand_force"], one.channels["true_hand_force"])


# --- level B against the truth (issue 20, fourth slice) ----------------------------------------


def _level_b(hand_mass_kg: float, cases: tuple[str, ...], seed: int = 0):
    """Level-B trials of ``cases`` at the thesis's 20 stops (level A's commanded paths)."""
    cfg = CartesianOnlineConfig(seed=seed, simulation=SimulationConfig(level="B", hand_mass_kg=hand_mass_kg))
    a = simulate_cartesian(cfg)
    trials_a = a.trials.select(np.isin(np.asarray(a.trials.trial_meta["case"]), cases))
    trials_b, _, summary = simulate_level_b_trials(cfg, trials_a, a.field)
    return trials_a, trials_b, summary


@pytest.fixture(scope="module")
def winter_hand():
    """Exps. 2 and 4 with the 0.966 kg hand (models/cartesian_hand)."""
    return _level_b(0.966, ("exp2", "exp4"))


@pytest.fixture(scope="module")
def light_hand():
    """Exp. 4 with a 0.1 kg hand."""
    return _level_b(0.1, ("exp4",))


def _exp4_field_pct(trials, method: str = "sqrt_damping") -> float:
    """Exp. 4's field error over the disc after the last sequence (Eq. 3.1.2, max), %."""
    return float(identify_exp4(records_from_trials(trials)["exp4"], method=method).field.max_pct[-1])


def test_compiled_stepping_equals_a_per_step_python_reference(monkeypatch):
    """The kernel's field and stepping against a plain loop: numpy's field (Eq. 2.2.1), one mj_step
    per call, each trial on a fresh MjData -> bit-identical. A pool of 2 MjData makes the third
    trial reuse a reset one, which must not change it."""
    monkeypatch.setattr(cartesian_level_b, "DATA_POOL", 2)
    scene = build_hand_scene(SimConfig())
    model = scene.model
    stops = np.array([[0.95, 0.0], [1.05, 0.1]])
    stop_of = np.array([0, 1, 1])
    t = np.arange(40)[None, :, None] / 1000.0
    displacement = np.concatenate([0.04 * t * [1, 0], 0.04 * t * [0, -1], 0.04 * t * [1, -1]])
    got = simulate_level_b(scene, THESIS_FIELD, stops, stop_of, displacement, nthread=2)
    one_thread = simulate_level_b(scene, THESIS_FIELD, stops, stop_of, displacement, nthread=1)
    for name in ("hand_pos", "hand_vel", "robot_q", "ft_force", "hand_acc", "human_force"):
        assert_array_equal(getattr(one_thread, name), getattr(got, name))  # a trial owns its MjData

    q_stop = stop_postures(scene, stops)
    jac = _jacobians(scene, q_stop)[stop_of]
    targets = q_stop[stop_of][:, None, :] + np.einsum("nij,nsj->nsi", jac, displacement)
    substeps, n_settle = 2, int(round(SETTLE_S / model.opt.timestep))
    ft, acc = scene.sensors["ft_force"], scene.sensors["hand_acc"]
    for i in range(3):
        data = mujoco.MjData(model)
        q0, ref = q_stop[stop_of[i]], stops[stop_of[i]]
        data.qpos[scene.robot_qpos], data.qpos[scene.hand_qpos[:2]], data.ctrl[scene.robot_act] = q0, ref, q0
        mujoco.mj_forward(model, data)
        for step in range(n_settle + displacement.shape[1] * substeps):
            q_h, qd_h = data.qpos[scene.hand_qpos[:2]].copy(), data.qvel[scene.hand_dof[:2]].copy()
            q_robot = data.qpos[scene.robot_qpos].copy()
            f_h = -THESIS_FIELD.force(q_h, qd_h, q_h - ref)
            data.ctrl[scene.field_act] = f_h
            k = step - n_settle
            data.ctrl[scene.robot_act] = q0 if k < 0 else targets[i, min(k // substeps + 1, 39)]
            mujoco.mj_step(model, data)
            if k >= 0 and k % substeps == 0:
                j = k // substeps
                assert_array_equal(got.hand_pos[i, j], q_h)
                assert_array_equal(got.hand_vel[i, j], qd_h)
                assert_array_equal(got.robot_q[i, j], q_robot)
                assert_array_equal(got.human_force[i, j], f_h)
                assert_array_equal(got.ft_force[i, j], data.sensordata[ft])
                assert_array_equal(got.hand_acc[i, j], data.sensordata[acc][:2])


def test_ideal_sensors_with_the_inertia_taken_out_recover_the_field(winter_hand):
    """Ideal sensors, the 12 + 2 fit (the model's own form, exact at level A): the inertial force
    m·a of the 1.006 kg beyond the F/T sensor moves Exp. 4's field by ~8 %; taken out with the
    handle's accelerometer the field is recovered."""
    _, trials_b, _ = winter_hand
    ideal, comp = clean_trials(trials_b), inertia_compensated_trials(trials_b)
    human = -np.asarray(trials_b.channels["human_force"])
    inertial = np.asarray(ideal.channels["hand_force"]) - human
    left = np.asarray(comp.channels["hand_force"]) - human
    rms = lambda x: float(np.sqrt(np.mean(x**2)))  # noqa: E731
    # measured 0.26 N of inertial force, 1.5e-3 N left: only the cuff bodies' rotation about the
    # flange is not m·a of the hand; 2 % leaves room for other seeds and paths
    assert rms(left) <= 0.02 * rms(inertial)
    # measured 7.97 % with the inertia, 0.042 % without. Bound: the field error is linear in the
    # unmodelled force for errors this small, so the ~0.6 % of the inertia left gives ~0.05 %;
    # 0.2 % (4x) for the grid maximum's variation; an uncompensated estimate would fail by 40x
    assert _exp4_field_pct(ideal) > 2.0
    assert _exp4_field_pct(comp) <= 0.2


def test_inertia_effect_shrinks_with_the_hand_mass(winter_hand, light_hand):
    """Against level A's generator on the path level B executed (no inertia, the same excursions),
    level B's field error with ideal sensors shrinks in proportion to the mass beyond the F/T
    sensor (0.966 -> 0.1 kg hand: 1.006 -> 0.140 kg): the estimate's error is linear in the
    unmodelled force m·a while the path hardly changes."""
    diffs, masses = [], []
    for _, trials_b, _ in (winter_hand, light_hand):
        exec_path = _exp4_field_pct(executed_path_trials(trials_b))
        assert exec_path < 1e-6  # the 12 + 2 fit is exact on the model's own forces (level A: 6e-14 %)
        diffs.append(_exp4_field_pct(clean_trials(trials_b)) - exec_path)
        masses.append(float(trials_b.attrs["ft_load_mass_kg"]))
    assert masses == pytest.approx([1.006, 0.140])
    # measured 7.97 / 1.17 = 6.8 against 7.19: ±25 % for the nonlinear (√K damping) fit and the
    # grid maximum, which is not exactly linear in the force error
    assert diffs[0] / diffs[1] == pytest.approx(masses[0] / masses[1], rel=0.25)


def test_level_b_without_inertia_is_level_a_on_the_executed_path(winter_hand):
    """What keeps level B's field error above level A's once the inertia is out: the executed path.
    The LWR's servos give way to the 10-30 kN/m field (thesis: an ideal position source), so the
    hand moves ~2 mm of the commanded 8 mm, and the thesis's Eq. 3.4.1 (constant damping columns,
    mis-specified for D = δ√K) gives 1.15 % there instead of 0.033 % on 8 mm."""
    trials_a, trials_b, _ = winter_hand
    rows = np.asarray(trials_b.trial_meta["case"]) == "exp4"
    commanded = np.abs(np.asarray(trials_a.channels["pert_pos"])[rows]).max(axis=1)
    executed = np.abs(np.asarray(trials_b.channels["true_hand_pos"]) - trials_b.channels["ref_pos"])[rows]
    ratio = np.median(executed.max(axis=1)[commanded > 0] / commanded[commanded > 0])
    assert 0.15 < ratio < 0.5  # measured 0.26: the servos' compliance, not a bug in the targets
    linear_a = _exp4_field_pct(trials_a, "linear")
    linear_exec = _exp4_field_pct(executed_path_trials(trials_b), "linear")
    linear_comp = _exp4_field_pct(inertia_compensated_trials(trials_b), "linear")
    assert linear_a < 0.1 < linear_exec  # measured 0.033 and 1.15 %
    # the compensated level B equals level A on the executed path: measured 1.149 vs 1.171 %
    assert abs(linear_comp - linear_exec) <= 0.1


def test_level_b_with_realistic_sensors_against_the_truth(winter_hand):
    """Level B as measured (JR3 noise, offset, 125 Hz filter, 1 ms delay; 0.01° encoders).

    Exp. 2's per-sequence fits are local (one K per sequence): the inertia (peak m·a 1.7 N) and the
    sensors move them little, and the spec's limit for level A (check 3: diagonal ≤ 2.5 %) still
    holds (measured 1.48 %). Exp. 4's field is ill-conditioned on one circle (spec 002's trap), so
    both effects are amplified: measured 10.1 % after 20 sequences (inertia 8.0, sensors 2.1
    points; see the tests above). Bound 15 %: the inertia's 8 % (linear in the known mass) plus
    twice the sensors' share; a 10x wrong sensor or a lost force sign fails it.
    """
    _, trials_b, _ = winter_hand
    exp2 = identify_exp2(records_from_trials(trials_b)["exp2"])
    assert np.nanmax(exp2.diagonal_error_pct) <= 2.5
    assert _exp4_field_pct(trials_b) <= 15.0
    ideal = _exp4_field_pct(clean_trials(trials_b))
    assert abs(_exp4_field_pct(trials_b) - ideal) <= 5.0  # the sensors' share: measured 2.1 points


def test_hand_mass_below_the_explicit_field_limit_is_refused():
    with pytest.raises(ConfigError, match=r"simulation.hand_mass_kg must be >= 0.01 kg"):
        SimulationConfig(level="B", hand_mass_kg=0.001)
