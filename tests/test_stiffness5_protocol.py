"""The 5-DoF stiffness protocol (seed paper 001: calibration, inertial and stiffness stages) end to
end: run_protocol into a temporary folder with every output, K_q against the ground truth within
spec 001's check-5 tolerance, the trial file carrying everything the estimation of all three
stages needs, seeded bit-identical trials, and refused stages, presets and lab settings naming the
valid choices.

Reduced trial counts: 10 disturbances per condition (one per direction, the least the plan
accepts) instead of the paper's 50, to keep the suite fast (~2 s of stepping for 8 conditions);
10 s of calibration motion and 12 inertial configurations instead of 30 s and 40
(tests/test_stiffness5_stages.py runs those at full size).
The ideal-sensor error is a deterministic settling bias (0.1-0.3 %, the same at 10 and 50
trials, tests/test_arm5_stiffness_trials.py); with realistic sensors the noise part grows as
1/sqrt(N), so 10 trials test the 12 % tolerance more severely than the paper's 50."""

from __future__ import annotations

import json

import numpy as np
import pytest

from armlab.data.h5io import read_trials
from armlab.errors import ConfigError
from armlab.estimation import relative_error
from armlab.models import analytic_stiffness, load_arm_5dof
from armlab.protocols import registry
from armlab.protocols.compose import compose
from armlab.protocols.stiffness_5dof_emg.config import EstimationConfig
from armlab.protocols.stiffness_5dof_emg.experiment import build_lab, hold_markers, simulate_stiffness_stage
from armlab.protocols.stiffness_5dof_emg.results import estimate_stiffness
from armlab.runner.run import run_protocol

NAME = "stiffness_5dof_emg"
# module docstring: 10 disturbances instead of the paper's 50, shorter calibration, fewer holds
SMALL = ["trials.n_per_condition=10", "calibration.duration_s=10", "inertial.n_configurations=12"]
LAB = build_lab()


def _cfg(*overrides: str):
    return compose([f"protocol={NAME}", *SMALL, *overrides])[1]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("stiff5") / "run"
    results = run_protocol(_cfg(), out)
    return out, results


def test_run_writes_every_output(run):
    out, results = run
    for name in ("results.json", "trials.h5", "trials.rrd", "table.txt", "scene.xml"):
        assert (out / name).is_file(), name
    for name in ("kq_per_condition", "ellipsoids_xz"):
        assert (out / f"{name}.png").stat().st_size > 10_000, name
    assert (out / "trials.rrd").stat().st_size > 100_000  # 80 trials of skeleton, marker, wrenches
    saved = json.loads((out / "results.json").read_text())
    assert saved["n_trials"] == 80 and [r["condition"] for r in saved["conditions"]] == [
        "X-10", "X-5", "X+5", "X+10", "Z-10", "Z-5", "Z+5", "Z+10"
    ]  # fmt: skip
    assert "spec 001 acceptance checks" in (out / "table.txt").read_text()


def test_realistic_k_q_meets_check_5_against_the_truth(run):
    _, results = run
    arm = load_arm_5dof()
    trials = read_trials(run[0] / "trials.h5")
    acts = np.asarray(trials.attrs["ground_truth"]["activation"])
    for c, row in enumerate(results["conditions"]):
        truth = analytic_stiffness(arm, acts[c])  # linear muscles: the exact intrinsic K_q
        np.testing.assert_allclose(row["K_true_Nm_per_rad"], truth, rtol=1e-12)
        err = relative_error(np.array(row["K_hat_Nm_per_rad"]), truth)
        assert err < 0.12, (row["condition"], err)  # spec 001 check 5, realistic sensors
        assert row["min_eigenvalue_Nm_per_rad"] > 0  # SPD in every condition
    assert {c["check"]: c["passed"] for c in results["checks"]} == {
        1: True, 2: True, 4: True, 5: True, 6: True, 9: True
    }  # fmt: skip


def test_the_trial_file_carries_the_estimation(run):
    out, results = run
    trials = read_trials(out / "trials.h5")
    again, _ = estimate_stiffness(trials, EstimationConfig())
    for a, b in zip(again["conditions"], results["conditions"], strict=True):
        np.testing.assert_array_equal(a["K_hat_Nm_per_rad"], b["K_hat_Nm_per_rad"])
    # the calibration and inertial stages are estimated again from the file, to the bit
    assert again["calibration"] == results["calibration"] and again["inertial"] == results["inertial"]
    assert trials.attrs["stages"] == ["calibration", "inertial", "stiffness"]
    # the Vicon channels hold each 500 Hz frame for 4 samples of the 2 kHz record
    pos = trials.channels["forearm_marker_pos"]
    m = (pos.shape[1] - 3) // 4
    blocks = pos[:, 3 : 3 + 4 * m].reshape(len(pos), m, 4, 3)
    assert np.all(blocks == blocks[:, :, :1]) and not np.all(blocks[:, 1:, 0] == blocks[:, :-1, 0])
    assert trials.attrs["marker_fs_hz"] == 500.0 and trials.fs_hz == 2000.0


def test_ideal_sensors_meet_check_5():
    cfg = _cfg("sensors=ideal", "trials.conditions=[Z-10,X+10]")
    results, _ = estimate_stiffness(simulate_stiffness_stage(cfg, LAB), cfg.estimation)
    for row in results["conditions"]:
        # spec 001 check 5 allows 5 % with ideal sensors; measured 0.1-0.3 % (the residual settling
        # in the post-interval), so the guard is far inside it
        assert row["rel_error"] < 0.01


def test_same_seed_gives_bit_identical_trials():
    cfg = _cfg("trials.conditions=[Z+5]", "seed=4")
    a, b = simulate_stiffness_stage(cfg, LAB), simulate_stiffness_stage(cfg, LAB)
    for k in a.channels:
        assert np.array_equal(a.channels[k], b.channels[k]), k
    for k in a.trial_meta:
        assert np.array_equal(a.trial_meta[k], b.trial_meta[k]), k
    c = simulate_stiffness_stage(_cfg("trials.conditions=[Z+5]", "seed=5"), LAB)
    assert not np.array_equal(a.channels["wrist_force"], c.channels["wrist_force"])


def test_marker_hold_is_causal():
    frames = np.arange(3.0)[None, :, None]  # frames taken at samples 3, 7, 11 (step 4)
    held = hold_markers(frames, 4, 12)[0, :, 0]
    np.testing.assert_array_equal(held, [0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2])


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("stages=[emg]", r"lacks 'stiffness': the stiffness trials are the run's trial file"),
        ("emg.crosstalk=0.6", r"emg.crosstalk must lie in \[0, 0.5\)"),
        ("emg.shape_factor=-3", r"emg.shape_factor must lie in \(-3, 0\]"),
        ("estimation.emg_sparse_features=[8,0]", r"estimation.emg_sparse_features must list integers >= 1"),
        ("emg.band_hz=[20,1500]", r"emg.band_hz must be \(low, high\) Hz with 0 < low < high < 1000"),
        (
            "estimation.emg_window_samples=500",
            r"estimation.emg_window_samples must be an integer in \[1, 400\]",
        ),
        ("stages=[calibration,inertial]", r"lacks 'stiffness': .* containing 'stiffness'"),
        ("stages=[stiffness,stiffness]", r"stages repeats a stage"),
        ("calibration.duration_s=1", r"calibration.duration_s must lie in \[2, 600\] s"),
        ("inertial.n_configurations=5", r"inertial.n_configurations must be an integer >= 9"),
        (
            "stages=[fly]",
            r"stages='fly' is not valid; choose one of \['calibration', 'inertial', 'stiffness', 'emg'\]",
        ),
        (
            "sensors.preset=noisy",
            r"sensors.preset='noisy' is not valid; choose one of \['realistic', 'ideal'\]",
        ),
        ("trials.conditions=[Y+5]", r"trials.conditions='Y\+5' is not valid; choose one of \['X-10'"),
        ("trials.n_per_condition=5", r"trials.n_per_condition must be an integer >= 10"),
        ("sensors.fs_hz=1000", r"sensors.fs_hz=1000 Hz: .* valid: 2000"),
        ("sim.timestep_s=0.001", r"sim.timestep_s=0.001 s: .* valid: 0.0005"),
        ("estimation.post_interval_s=[0.2,0.6]", r"post_interval .* must lie in the hold"),
        # a floor of 0.95 leaves no room to push 10 N: the force task fails before any run folder
        ("trials.a_min=0.95", r"trials.conditions '.*' with trials.a_min=0.95: "),
    ],
)
def test_bad_settings_are_refused_naming_the_valid_choices(override, message):
    with pytest.raises(ConfigError, match=message):
        compose([f"protocol={NAME}", override])


def test_registered_with_its_groups():
    p = registry.get(NAME, need="run")
    assert p.reestimate_group == "estimation" and p.groups == {"sensors": "realistic"}


def test_reflex_tangent_stiffness_is_the_analytic_half_rectified_sum():
    """Ground truth of the effective-truth code: at a vanishing step the static reflex's central
    difference is 1/2 (g_s + g_sp) / L_s sum_i F_i R_i R_i^T (each muscle answers one side of the
    displacement only), F_i = -(gainprm0 + gainprm1 L_i) the affine muscle's tension per unit
    activation (models/arm_5dof), R the length Jacobian. The difference at a 1e-6 rad step is the
    tension's change with the stretched length (16 % at 0.08 rad, arm5_reflex), ~2.5e-6 of the
    largest entry (measured 2.0e-5 N·m/rad on 7.9): compared to 1e-5 of the largest entry."""
    import mujoco

    from armlab.config.schema import ReflexConfig
    from armlab.sim.arm5_reflex import muscle_length_jacobian, reflex_stiffness_fd
    from armlab.sim.rollout import REFLEX_LENGTH_SCALE_M

    arm = LAB.arm
    act = np.full(12, 0.2)
    reflex = ReflexConfig(enabled=True)
    K = reflex_stiffness_fd(
        arm.model, arm.muscle_act, arm.muscle_actadr, arm.qpos, arm.dof, arm.q0, act, reflex, 1e-6
    )
    R = muscle_length_jacobian(arm.model, arm.muscle_act, arm.qpos, arm.q0)
    data = arm.data_at(arm.q0, act)
    mujoco.mj_forward(arm.model, data)
    L = data.actuator_length[arm.muscle_act]
    F = -(arm.model.actuator_gainprm[arm.muscle_act, 0] + arm.model.actuator_gainprm[arm.muscle_act, 1] * L)
    G = (reflex.stretch_gain + reflex.spinal_gain) / REFLEX_LENGTH_SCALE_M
    expected = 0.5 * G * np.einsum("i,ij,ik->jk", F, R, R)
    np.testing.assert_allclose(K, expected, rtol=0, atol=1e-5 * np.abs(expected).max())
    off = ReflexConfig(enabled=False)
    assert not reflex_stiffness_fd(
        arm.model, arm.muscle_act, arm.muscle_actadr, arm.qpos, arm.dof, arm.q0, act, off, 0.08
    ).any()


def test_check_7_reflex_raises_the_diagonal_and_is_measured_against_the_effective_truth():
    cfg = _cfg("sensors=ideal", "reflex.enabled=true", "trials.conditions=[Z-10,X+10]")
    trials = simulate_stiffness_stage(cfg, LAB)
    results, _ = estimate_stiffness(trials, cfg.estimation)
    gt = trials.attrs["ground_truth"]
    assert results["truth"].startswith("effective")
    for c, row in enumerate(results["conditions"]):
        k_hat = np.array(row["K_hat_Nm_per_rad"])
        # spec 001 check 7: the reflex adds stiffness on every joint (measured excess 0.5-10 N m/rad)
        assert np.all(np.diag(k_hat) > np.diag(gt["K_intrinsic_Nm_per_rad"][c]))
        # the reflex is no small effect here: the intrinsic truth misses it by > 10 % (measured ~25 %)
        assert row["rel_error_vs_intrinsic"] > 0.10
        # against the effective truth (intrinsic + the static reflex's secant) within check 5's
        # ideal-sensor 5 % (measured 0.7-1.7 %: the servo's off-axis deflection, rectified by the
        # reflex, is not in the per-joint secant)
        np.testing.assert_allclose(row["K_true_Nm_per_rad"], gt["K_effective_Nm_per_rad"][c])
        assert row["rel_error"] < 0.05
    assert [c["passed"] for c in results["checks"] if c["check"] == 7] == [True, True]
