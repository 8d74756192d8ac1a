"""The second, ODE-generated referee of the joint_1dof diagnosis (referee.generator=ode)."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.data.joint_import import load_joint_data
from armlab.diagnosis.scoring import expected_verdict
from armlab.errors import ConfigError
from armlab.protocols.joint_1dof.diagnosis.referee import JOINT_CLASSES
from armlab.protocols.joint_1dof.diagnosis.referee_ode import ODE_CLASSES, make_ode_dataset
from armlab.runner.diagnose import run_benchmark, run_diagnoser


def test_a_dataset_is_written_read_back_and_diagnosed_end_to_end(tmp_path):
    # CI size: one perturbation recorded twice, 8.5 s (the diagnosis keeps 2 s edges and needs half
    # the record inside them), evaluation seed
    ref = RefereeConfig(n_trials=2, ode_trial_s=[8.5, 8.5], seed=1000)
    diag = DiagnosisConfig(min_duration_s=8.0)
    ds = make_ode_dataset("none", 0, ref, diag, tmp_path / "trials")
    assert sorted(p.name for p in ds.folder.iterdir()) == ["seq0_rep0.csv", "seq0_rep1.csv"]
    trials = load_joint_data(ds.folder, min_duration_s=diag.min_duration_s)
    assert trials[0].fs_hz == pytest.approx(ds.truth["fs_hz"], rel=1e-9)
    assert 500 <= ds.truth["fs_hz"] <= 2000 and ds.truth["generator"] == "ode" and ds.enr == 0.0
    np.testing.assert_array_equal(trials[0].position, trials[1].position)  # a repeat: same motion,
    assert not np.array_equal(trials[0].torque, trials[1].torque)  # other noise
    results, _ = run_diagnoser(ds.folder, "joint_1dof", diag)
    assert results["torque_sign"] == "in phase"  # this generator's sign (the first referee's: antiphase)
    # the nominal fitted on clean data finds the generator's joint: I, B, K of the truth within 5 %
    # (the noise drawn here is <= 1e-1 of the torque rms; the fit's spread on 8.5 s is ~1 %)
    truth = ds.truth["subject"]
    for fitted in results["how_far"][0]["parameters"]:
        for name in ("I", "B", "K"):
            assert fitted[name] == pytest.approx(truth[name], rel=0.05), name


def test_classes_extend_the_first_referees_with_the_catalogue_effects_it_lacks():
    assert set(JOINT_CLASSES) <= set(ODE_CLASSES)
    for name in ("encoder_quantisation", "force_sensor_drift", "voluntary_torque"):
        assert expected_verdict(name, ODE_CLASSES) == {name}
    assert expected_verdict("left_out:reflex", ODE_CLASSES) == {"unknown"}


def test_an_unknown_generator_is_refused_naming_the_valid_ones(tmp_path):
    with pytest.raises(ConfigError, match=r"valid: \['default', 'ode'\]"):
        run_benchmark(["referee.protocol=joint_1dof", "referee.generator=mujoco"], tmp_path / "b")
    with pytest.raises(ConfigError, match=r"valid: \['default'\]"):
        run_benchmark(["referee.protocol=conditioning_window", "referee.generator=ode"], tmp_path / "c")
    # the ODE referee reads its own trial lengths; the first referee refuses them, never ignores them
    with pytest.raises(ConfigError, match="not read by the joint_1dof referee"):
        run_benchmark(["referee.protocol=joint_1dof", "referee.ode_trial_s=[20,30]"], tmp_path / "d")
    assert not any(tmp_path.iterdir())


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="measured on the evaluation seed 1000, 130 datasets (docs/joint_1dof_referees.md, session 29, "
    "the presliding friction): top-1 where ENR >= 1 89 % (80 of 90, as in session 28; 87 % in 27), false "
    "alarms 0 %, median shrink 99 %, 96 % counting flagged ties; short: force_sensor_bandwidth 2/5 (a kHz "
    "sensor is a lag, named channel_delay), cuff_compliance 2/4 (the nested pair), cocontraction 6/8 (one "
    "drives the perturbation's speed through the servo), reflex+joint_friction replicate 1 unknown, "
    "left_out:reflex replicate 4 named cocontraction_variation",
)
def test_full_ode_benchmark_meets_the_issue_targets(tmp_path):
    # issue 18: 10 replicates per class on the evaluation seed: top-1 >= 90 % where ENR >= 1, false
    # alarms on none <= 5 %, median shrink >= 70 % (~40 min on 2 cores)
    _, summary = run_benchmark(
        ["referee.protocol=joint_1dof", "referee.generator=ode", "referee.replicates=10"], tmp_path / "b"
    )
    assert summary["n_classes"] == len(ODE_CLASSES)
    for key, target in summary["targets"].items():
        assert target["met"], f"ode referee: {key} = {target['value']} against the target {target['target']}"


def test_drift_scale_gives_the_expected_rms_below_0_05_hz():
    """The drift's noise-equivalent scale rests on :func:`_drift_unit_rms`: the expected rms below
    0.05 Hz (ends off, mean removed) of :func:`drift_signal` per N·m of ramp; against 200 drawn
    drifts (their signs and wanders) within 4 % (the wander's kept power scatters: it holds a
    few cycles of < 0.02 Hz per trial: over 4000 drawn trials, measured within 1.5 % on 4 seeds)."""
    from armlab.protocols.joint_1dof.diagnosis.referee_ode import _drift_unit_rms, _low_rms
    from armlab.sim.joint_ode_effects import TorqueDrift, drift_signal

    fs, trial_s = 10.0, 30.0  # Hz, s: the drift lies below 0.05 Hz, any rate above carries it
    t = np.arange(int(trial_s * fs)) / fs
    for thermal, tau, wander in ((0.2, 20.0, 0.5), (1.0, 120.0, 0.1)):
        drift = TorqueDrift(
            rate_Nm_per_s=1.0 / trial_s, thermal_Nm=thermal, thermal_tau_s=tau, wander_Nm=wander
        )
        d = drift_signal(t, drift, 4000, np.random.default_rng(2))
        assert _low_rms(d, fs) == pytest.approx(_drift_unit_rms(trial_s, thermal, tau, wander), rel=0.04)


def test_reflex_scale_follows_the_generators_reflex_pathway():
    """The reflex's noise-equivalent gain rests on :func:`_reflex_pathway` (activation with fast
    rise and slow decay, then the contraction lag) applied to the reference's stretch velocity:
    on the limb's stretch velocity it reproduces the torque the ODE generator's reflex adds (its
    clean torque less the nominal's on the recorded angle) within 3 % rms over a 3 s PRBS
    (measured 1.7 %: the pathway holds the excitation over each sample, the ODE does not). The
    scale applies it to the reference's velocity, which the servo's limb follows within ~10 % of
    this output's rms (measured 1.10 here): the aimed ENR's accuracy."""
    from armlab.perturbations.joint_families import JointPerturbation, perturbation_signal
    from armlab.protocols.joint_1dof.diagnosis.referee_ode import _reflex_pathway
    from armlab.sim.joint_ode import OdeJoint, OdeServo, simulate_joint_ode
    from armlab.sim.joint_ode_effects import OdeEffects, OdeReflex

    fs = 1000.0
    joint = OdeJoint(inertia_kgm2=0.02, damping_Nms_per_rad=0.8, stiffness_Nm_per_rad=120.0)
    pert = JointPerturbation(family="prbs", amplitude_rad=0.03, switch_s=0.08, ramp_s=0.02)
    ref = perturbation_signal(pert, int(3 * fs), fs, np.random.default_rng(0))[None, :]
    reflex = OdeReflex(gain_Nms_per_rad=2.0, delay_s=0.04, tau_act_s=0.012, tau_deact_s=0.05, direction=-1.0)
    rec = simulate_joint_ode(
        ref, fs, joint, OdeServo(), OdeEffects(reflex=reflex), noise_std_Nm=0.0, rng=np.random.default_rng(1)
    )
    i_tot = joint.inertia_kgm2 + joint.pedal_inertia_kgm2
    nominal = i_tot * rec.motor_acceleration + joint.damping_Nms_per_rad * rec.motor_velocity
    effect = rec.clean_torque - nominal - joint.stiffness_Nm_per_rad * rec.motor_angle
    v = np.gradient(rec.limb_angle[0], 1 / fs)
    lag = int(round(reflex.delay_s * fs))
    excitation = np.maximum(reflex.direction * np.concatenate([np.zeros(lag), v[:-lag]]), 0.0)[None, :]
    model = reflex.gain_Nms_per_rad * _reflex_pathway(
        excitation, fs, reflex.tau_act_s, reflex.tau_deact_s, reflex.tau_contraction_s
    )
    # the reflex pulls the limb by -direction × the contraction: the pedal pushes that much more
    err = np.sqrt(np.mean((effect - reflex.direction * model) ** 2)) / np.sqrt(np.mean(effect**2))
    assert err < 0.03
