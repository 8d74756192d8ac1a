"""cartesian_online diagnosis: data preparation, surrogate models, diagnosis, referee, files.

Datasets come from the protocol's own generators (level A: the thesis's exact algebra; level B:
the referee's MuJoCo lab), so the truth of every hidden effect is known.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.data.h5io import read_trials, write_trials
from armlab.data.trial import TrialSet
from armlab.diagnosis.scoring import expected_verdict
from armlab.errors import ConfigError, DataError
from armlab.estimation.sqrt_damping_fit import fit_sqrt_damping_field
from armlab.models.cartesian_field import THESIS_FIELD, quadratic_basis
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig, SimulationConfig
from armlab.protocols.cartesian_online.diagnosis.data import MIN_FLOOR, load_cart_trials, prepare_cart
from armlab.protocols.cartesian_online.diagnosis.diagnose import cart_candidates, diagnose_cart
from armlab.protocols.cartesian_online.diagnosis.models import cubic_basis
from armlab.protocols.cartesian_online.diagnosis.noise_floor import white_noise_var
from armlab.protocols.cartesian_online.diagnosis.position_noise import edge_guard_samples
from armlab.protocols.cartesian_online.diagnosis.referee import (
    _CENTRE,
    _RADIUS,
    CART_CLASSES,
    _taylor_fields,
    make_cart_dataset,
)
from armlab.protocols.cartesian_online.experiment import (
    CHANNEL_UNITS,
    _timeline,
    case_trials,
    simulate_cartesian,
)
from armlab.protocols.cartesian_online.level_b import simulate_level_b_trials
from armlab.sensors.channel import apply_channel
from armlab.sensors.presets import JR3_FORCE
from armlab.sim.cartesian_level_a import simulate_level_a

NOISE_N = 0.3  # N, the referee's white F/T noise (RefereeConfig.force_noise_N)


def _level_a(noise: float, seed: int = 0, n_stops: int = 12, velocity: bool = False) -> TrialSet:
    """Exp. 4 of the thesis by its own generator (level A), as a trial set of the measured channels
    (with ``velocity``, also the generator's exact ``hand_vel``)."""
    cfg = CartesianOnlineConfig(simulation=SimulationConfig(n_stops=n_stops))
    rec = simulate_level_a(
        _timeline(cfg, 4, "triangular"), THESIS_FIELD, noise_std_n=noise, rng=np.random.default_rng(seed)
    )
    ch, meta = case_trials("exp4", rec, 400)
    names = ("hand_pos", "ref_pos", "hand_force", *(("hand_vel",) if velocity else ()))
    return TrialSet(
        fs_hz=1000.0,
        onset_index=np.ones(len(meta["case"]), dtype=int),
        channels={k: ch[k] for k in names},
        units={k: CHANNEL_UNITS[k] for k in names},
        trial_meta={k: meta[k] for k in ("case", "stop", "n_logged", "t_start_s")},
        attrs={"protocol": "cartesian_online"},
    )


def test_noise_floor_and_nominal_field_on_the_thesis_generator():
    cs = prepare_cart(_level_a(NOISE_N), band_hz=40.0)
    # the second-difference estimate of 0.3 N white noise, by the trimmed mean of the squares (the
    # lowest 90 %, over its χ²₁ mean): ~14 000 samples per axis give a standard error of the
    # variance under 2 % (the full mean's would be √(2/14000) = 1.2 %); 6 % is over 3 of them
    np.testing.assert_allclose(cs.noise_var, NOISE_N**2, rtol=0.06)
    clean = prepare_cart(_level_a(0.0), band_hz=40.0)
    assert np.all(clean.noise_var < 1e-4 * NOISE_N**2)  # the field's own curvature is not noise
    # the nominal 12 + 2 fit on the training sequences gives the Table 3.1 field over the circle
    # (velocities by central differences, not the generator's exact ones: the triangle's corners
    # leave ~1e-4 relative)
    th = np.linspace(0, 2 * np.pi, 50)
    ring = _CENTRE + 0.1 * np.c_[np.cos(th), np.sin(th)]
    k_hat = quadratic_basis(ring) @ clean.k0.T
    np.testing.assert_allclose(k_hat, THESIS_FIELD.stiffness(ring), rtol=1e-3)
    np.testing.assert_allclose(clean.delta0, THESIS_FIELD.delta, rtol=1e-2)
    assert sorted(set(clean.phase)) == ["+x", "+x-y", "-y"]
    assert set(np.unique(clean.stop[clean.held_trials])) == {1, 4, 7, 10}


@pytest.mark.parametrize("noise_n", [0.006, 0.0122, 0.05])  # N: half a count, one count, the JR3 preset's
def test_noise_floor_of_the_jr3_model_low_passed_and_quantised(noise_n):
    # the JR3 model (125 Hz filter, 1 ms delay, white noise, 0.0122 N steps; its per-trial offset
    # and drift left out: they are not white) on the thesis's force; the truth is the white noise
    # plus the quantisation's step²/12 (Sheppard). Measured 0.98-1.09 x over these levels and
    # seeds 0-3: the filter spreads each triangle corner over ~5 samples, some of which stay in
    # the kept 90 %; 12 % allows for that bias and the 1.7 % sampling error
    spec = dataclasses.replace(JR3_FORCE, bias_std=0.0, drift_per_s=0.0, noise_std=noise_n)
    clean = np.asarray(_level_a(0.0).channels["hand_force"])
    f = apply_channel(clean, 1000.0, spec, np.random.default_rng(0))
    truth = noise_n**2 + spec.quant_step**2 / 12
    np.testing.assert_allclose(white_noise_var(f, np.ones(f.shape[:2], bool)), truth, rtol=0.12)


def test_the_thesis_generator_without_noise_is_none():
    # the nominal model is the generator's own (with its exact velocity): the gap is round-off,
    # below the floor's minimum (MIN_FLOOR of the force power), and nothing is selected
    res, _ = diagnose_cart(_level_a(0.0, velocity=True), DiagnosisConfig())
    assert res["verdict"] == ["none"]
    assert res["gap"]["nominal"] < MIN_FLOOR


def _with_force(ts: TrialSet, force: np.ndarray) -> TrialSet:
    return dataclasses.replace(ts, channels={**ts.channels, "hand_force": force})


def test_per_trial_force_offsets_are_read_into_the_floor_and_a_common_bias_is_not():
    # the thesis's generator at its 20 stops with 0.3 N white noise, plus an offset per trial and
    # axis of 0.3 N (an F/T tared before each trial): the floor's estimate has 3 x (20 - 8) = 36
    # degrees of freedom per axis (a standard error of ~12 % on the sd); 36 % is three of them.
    # Measured: this draw 0.82 / 0.88 x (its own offsets' sd is 0.27 / 0.26 N), 12 other draws
    # 0.84-1.33 x
    sigma_o = 0.3
    ts = _level_a(NOISE_N, seed=0, n_stops=20)
    force = np.asarray(ts.channels["hand_force"])
    tared = force + sigma_o * np.random.default_rng(5).standard_normal((force.shape[0], 1, 2))
    with_offsets = prepare_cart(_with_force(ts, tared), band_hz=40.0).offset_var
    np.testing.assert_allclose(np.sqrt(with_offsets), sigma_o, rtol=0.36)
    # a bias common to all trials and a drift over the run (the referee's force_sensor_drift at its
    # largest) are smooth along the stops: added to the same trials they leave the estimate where
    # it was (the nominal field's fit moves with them, by a smooth function the basis holds:
    # measured 3e-7 relative, round-off of the fits)
    t = np.asarray(ts.trial_meta["t_start_s"], float)[:, None] + np.arange(force.shape[1]) / 1000.0
    common = np.array([1.0, -0.6]) + 0.02 * t[..., None] * np.array([0.6, 0.8])  # N, N/s · s
    moved = prepare_cart(_with_force(ts, tared + common), band_hz=40.0).offset_var
    np.testing.assert_allclose(moved, with_offsets, rtol=1e-5)
    # without offsets nothing beyond the white noise's share of the means shows (measured 0)
    assert np.all(np.sqrt(prepare_cart(ts, band_hz=40.0).offset_var) < 0.1 * sigma_o)
    # a bias common to all trials is still the candidate's: named as before
    res, _ = diagnose_cart(_with_force(ts, force + common), DiagnosisConfig())
    assert res["verdict"] == ["force_sensor_drift"]


def test_edge_guard_is_the_smoothed_differentiators_response_and_none_on_ideal_sensors():
    # the half-width holding 99 % of the smoothing ∘ central difference's energy: 39 samples at a
    # 25 Hz cut-off (0.9918 of it inside ±39, 0.9897 inside ±38), shorter at higher cut-offs
    assert edge_guard_samples(1000.0, np.array([25.0, np.inf]), 40.0) == 39
    assert edge_guard_samples(1000.0, np.array([32.5, 25.0]), 40.0) == 39  # the lowest smoothed axis
    assert edge_guard_samples(1000.0, np.array([32.5, np.inf]), 40.0) < 39
    assert edge_guard_samples(1000.0, np.array([40.0, np.inf]), 40.0) == 0  # nothing smoothed
    # ideal sensors (the thesis's generator with white force noise): every logged sample scored
    cs = prepare_cart(_level_a(NOISE_N), band_hz=40.0)
    assert cs.edge_guard == 0 and np.array_equal(cs.scored, cs.valid)
    # smoothed (the quantised hand): the first and last guard samples of each trial are not scored
    q = prepare_cart(_quantised_hand(0)[0], band_hz=40.0)
    g = q.edge_guard
    assert g > 0 and not q.scored[:, :g].any() and not q.scored[:, -g:].any() and q.scored[:, g:-g].all()


def test_too_short_trials_are_refused_by_name():
    ts = _level_a(NOISE_N)
    meta = {**ts.trial_meta, "n_logged": np.where(np.arange(len(ts.trial_meta["n_logged"])) == 3, 0, 400)}
    with pytest.raises(DataError, match=r"n_logged.*trials \[3\] have \[0\]"):
        prepare_cart(dataclasses.replace(ts, trial_meta=meta), band_hz=40.0)


def _default_lab_exp4(seed: int) -> TrialSet:
    """Exp. 4 in the protocol's default lab (level B: the 0.966 kg hand, realistic JR3 and LWR
    encoders), the thesis's 20 stops."""
    cfg = CartesianOnlineConfig(seed=seed)
    a = simulate_cartesian(cfg)
    trials_a = a.trials.select(np.asarray(a.trials.trial_meta["case"]) == "exp4")
    return simulate_level_b_trials(cfg, trials_a, a.field)[0]


@pytest.mark.parametrize(
    "seed", [0, pytest.param(1, marks=pytest.mark.slow), pytest.param(2, marks=pytest.mark.slow)]
)
def test_the_default_lab_is_diagnosed_as_the_hand_inertia_the_thesis_neglects(seed):
    # the default lab differs from the thesis's model by the hand's inertia and by its sensors; the
    # sensors' white noise, the encoders' noise and the JR3's per-trial tare offset (0.1 N) are the
    # floor, and the trials' ends, where the smoothed velocity is the filter's, are not scored, so
    # the verdict is the hand (before: unknown, 0.64-0.79 of the excess explained). Measured on
    # seeds 0-2: payload_mass, 0.82-0.83 kg (the JR3's lag against m·a's lead reads the 0.966 kg
    # hand low), offsets 0.088-0.128 N per axis
    res, _ = diagnose_cart(_default_lab_exp4(seed), DiagnosisConfig())
    # first, and a whole explanation (a second name may follow: the JR3's lag is a real delay,
    # named on 1 of seeds 0-9)
    assert res["verdict"][0] == "payload_mass" and not res["partial"]
    # the hand's 0.966 kg: the JR3's lag against m·a's lead reads it ~15 % low (0.81-0.84 kg
    # measured) and a channel_delay named after it ~10 % high (1.07-1.08 kg): 0.6-1.1 holds both
    # with a margin of about two of their spreads
    assert 0.6 < res["how_far"][-1]["parameters"]["payload_mass.mass_kg"] < 1.1
    # 60 trials, 36 degrees of freedom per axis (~12 % standard error on the sd): within a factor
    # 1.5 of the JR3 model's 0.1 N, over three standard errors
    assert all(0.067 < s < 0.15 for s in res["gap"]["trial_offset_N"])


def test_taylor_field_per_stop_is_the_cubic_field_up_to_its_third_order_remainder():
    extra = np.array([[300.0, -120.0, 50.0, 200.0], [-80.0, 40.0, 150.0, -60.0]])  # N/m
    stops = _CENTRE + 0.1 * np.array([[1.0, 0.0], [0.0, -1.0], [-0.6, 0.8]])
    fields = _taylor_fields(THESIS_FIELD, extra, stops)
    rng = np.random.default_rng(0)
    for f, s in zip(fields, stops, strict=True):
        q = s + rng.uniform(-0.008, 0.008, (20, 2))  # within the 8 mm triangles
        w, ws = (q - _CENTRE) / _RADIUS, (s - _CENTRE) / _RADIUS
        exact = THESIS_FIELD.stiffness(q) + cubic_basis(w) @ extra.T
        remainder = cubic_basis(w - ws) @ extra.T  # f(w) = T2(w) + f(w - w_s) for a cubic form f
        # identity to round-off of N/m values ~2e4 (1e-7 relative)
        np.testing.assert_allclose(f.stiffness(q), exact - remainder, atol=2e-3)
        assert np.abs(remainder).max() < 1e-3 * np.abs(extra).sum()  # (8 mm / 0.1 m)³ of the term


def test_bad_input_is_refused_with_the_valid_choices(tmp_path):
    with pytest.raises(DataError, match="holds 0 .h5 files"):
        load_cart_trials(tmp_path)
    trials = _level_a(NOISE_N)
    no_ref = TrialSet(
        fs_hz=trials.fs_hz,
        onset_index=trials.onset_index,
        channels={k: v for k, v in trials.channels.items() if k != "ref_pos"},
        units={k: v for k, v in trials.units.items() if k != "ref_pos"},
        trial_meta=trials.trial_meta,
    )
    write_trials(tmp_path / "a.h5", no_ref)
    with pytest.raises(DataError, match=r"lacks channel\(s\) \['ref_pos'\]"):
        load_cart_trials(tmp_path / "a.h5")
    mm = TrialSet(
        fs_hz=trials.fs_hz,
        onset_index=trials.onset_index,
        channels={**trials.channels, "hand_pos": 1e3 * np.asarray(trials.channels["hand_pos"])},
        units=trials.units,
        trial_meta=trials.trial_meta,
    )
    write_trials(tmp_path / "b.h5", mm)
    with pytest.raises(DataError, match="'hand_pos' reaches .* computes in m and N"):
        load_cart_trials(tmp_path / "b.h5")
    with pytest.raises(DataError, match="at least 4 sequences"):
        prepare_cart(_level_a(NOISE_N, n_stops=3), band_hz=40.0)
    with pytest.raises(DataError, match="band_hz must lie in"):
        prepare_cart(trials, band_hz=600.0)
    with pytest.raises(ConfigError, match="valid: \\['payload_mass'"):
        cart_candidates(DiagnosisConfig(candidates=["reflex"]))


@pytest.fixture(scope="module")
def none_run(tmp_path_factory):
    """A clean referee dataset (level B, evaluation seed 1000) diagnosed end to end as
    `armlab diagnose` does: (dataset, output folder, results)."""
    from armlab.runner.diagnose import run_diagnosis

    tmp = tmp_path_factory.mktemp("cart_diag")
    ds = make_cart_dataset("none", 0, RefereeConfig(seed=1000), DiagnosisConfig(), tmp / "none")
    out, res = run_diagnosis(ds.folder, "cartesian_online", [], tmp / "out")
    return ds, out, res


def test_referee_dataset_hides_the_truth(none_run):
    ds, _, _ = none_run
    trials = read_trials(ds.folder / "trials.h5")
    assert set(trials.channels) == {"hand_pos", "ref_pos", "hand_force"}
    assert "truth_json" not in trials.attrs and set(trials.trial_meta) == {
        "case",
        "stop",
        "n_logged",
        "t_start_s",
    }
    # nothing hidden: the ENR is computed (not set) and the effect's path is the nominal's, exactly
    assert ds.enr == 0.0 and ds.truth["hidden"] == []
    assert expected_verdict("none", CART_CLASSES) == {"none"}
    assert expected_verdict("left_out:payload_mass", CART_CLASSES) == {"unknown"}
    assert expected_verdict("payload_mass+force_sensor_drift", CART_CLASSES) == {
        "payload_mass",
        "force_sensor_drift",
    }
    with pytest.raises(FileExistsError, match="new folder"):  # refused before simulating
        make_cart_dataset("none", 0, RefereeConfig(seed=1000), DiagnosisConfig(), ds.folder)


def test_clean_lab_is_none_and_files_are_written(none_run):
    from armlab.runner.diagnose import run_diagnosis

    ds, out, res = none_run
    # the nominal lab is the thesis's model up to the 0.01 kg hand (0.014 N rms inertial force,
    # 5 % of the noise): the nominal gap stays within the rule's 25 % of the floor
    assert res["verdict"] == ["none"]
    assert res["gap"]["nominal"] < 1.25 * res["gap"]["noise_floor"]
    report = (out / "report.md").read_text()
    assert "Where the gap lies" in report and "Held-out sequence" in report
    assert json.loads((out / "results.json").read_text())["verdict"] == ["none"]
    assert {"diagnosis_overlay.png", "diagnosis_where.png", "diagnosis.rrd"} <= {
        p.name for p in out.iterdir()
    }
    with pytest.raises(DataError, match="never overwrites"):
        run_diagnosis(ds.folder, "cartesian_online", [], out)


def test_a_strong_force_offset_is_named_with_its_size(none_run):
    ds, _, _ = none_run
    trials = read_trials(ds.folder / "trials.h5")
    force = np.asarray(trials.channels["hand_force"]) + np.array([0.5, 0.0])  # N, an F/T offset on x
    biased = TrialSet(
        fs_hz=trials.fs_hz,
        onset_index=trials.onset_index,
        channels={**trials.channels, "hand_force": force},
        units=trials.units,
        trial_meta=trials.trial_meta,
    )
    res, _ = diagnose_cart(biased, DiagnosisConfig())
    assert res["verdict"] == ["force_sensor_drift"]
    p = res["how_far"][-1]["parameters"]
    # 0.3 N noise over ~10 000 training samples in a 40 Hz band (~800 independent ones): standard
    # error ~0.011 N of the offset; 0.05 N is 4.5 of them
    assert abs(p["force_sensor_drift.x_bias_N"] - 0.5) < 0.05
    assert abs(p["force_sensor_drift.y_bias_N"]) < 0.05
    where = {e["axis"]: e for e in res["where"]["channels"]}
    assert where["x"]["held_out_gap"] > 10 * where["y"]["held_out_gap"]  # the gap lies on the x axis


def test_a_compliant_cuff_is_found_with_its_stiffness(tmp_path):
    # the referee's hidden cuff (a softened connect constraint); its stiffness is measured in the
    # simulation (force over the cuff-hand stretch). On the 10 evaluation datasets the surrogate's
    # 1/c was 0.94-1.03 of it: the first-order model (stretch from the nominal field's force) reads
    # the cuff low by up to 6 %; 10 % allows that and the noise of one dataset
    ds = make_cart_dataset("cuff_compliance", 0, RefereeConfig(seed=1000), DiagnosisConfig(), tmp_path / "c")
    res, _ = diagnose_cart(load_cart_trials(ds.folder), DiagnosisConfig(candidates=["cuff_compliance"]))
    assert res["verdict"] == ["cuff_compliance"]
    k_fit = 1.0 / res["ranking"][0]["params"]["cuff_compliance.compliance_m_per_N"]
    k_true = ds.truth["effect_params"]["cuff_compliance"]["measured_stiffness_N_per_m"]
    assert abs(k_fit / k_true - 1.0) < 0.1


def test_realistic_sensors_class_records_the_lab_sensors_and_names_the_hand(tmp_path):
    # the evaluation seed's replicate 0 (a 1.89 kg hand, ENR 1.63): the referee's simulation
    # recorded by the default lab's encoders and JR3, plus its white noise
    cls = "realistic_sensors:payload_mass"
    assert expected_verdict(cls, CART_CLASSES) == {"payload_mass"}
    ds = make_cart_dataset(cls, 0, RefereeConfig(seed=1000), DiagnosisConfig(), tmp_path / "r")
    cs = prepare_cart(load_cart_trials(ds.folder), band_hz=40.0)
    # the LWR encoders' 0.01° steps at the cuff: measured 39 / 24 µm rms on the default run
    # (docs/cartesian_online.md); the ideal classes' position noise is round-off
    assert np.all((np.sqrt(cs.pos_noise_var) > 10e-6) & (np.sqrt(cs.pos_noise_var) < 100e-6))
    # the JR3's 0.1 N per-trial offsets, read beside 0.3 N of white noise from 12 stops (12 degrees
    # of freedom per axis: a factor 2 is over two standard errors of the sd either way)
    assert np.all((np.sqrt(cs.offset_var) > 0.05) & (np.sqrt(cs.offset_var) < 0.2))
    res, _ = diagnose_cart(load_cart_trials(ds.folder), DiagnosisConfig())
    assert res["verdict"][0] == "payload_mass"


@pytest.mark.slow
def test_small_blind_benchmark_names_every_class(tmp_path):
    # one replicate of each class on the evaluation seed (~1 min on 2 cores: 9 of 10 right, the
    # left-out class named channel_delay; 8 of the 9 ENR >= 1 + none cases, 89 %); the
    # 10-replicate run and its confusion matrix are in docs/cartesian_online.md
    from armlab.runner.diagnose import run_benchmark

    _, summary = run_benchmark(
        ["referee.protocol=cartesian_online", "referee.replicates=1", "referee.jobs=1"], tmp_path / "b"
    )
    assert summary["n_classes"] == len(CART_CLASSES) and summary["false_alarm_none"] == 0.0
    assert summary["top1_enr_ge_1"] >= 0.8  # issue 20's target


_DITHER_M = 30e-6  # m, white position noise before the converter (~the LWR's 40 µm at the cuff)
_STEP_M = 50e-6  # m, the converter's resolution (dither > step/2: the error is white, Sheppard)
_HAND_KG = 1.0  # kg, the synthetic hand's inertia (the default run's is 0.966 kg)


def _quantised_hand(seed: int) -> tuple[TrialSet, np.ndarray]:
    """Exp. 4 by the thesis's generator with rounded corners (40 ms: a finite acceleration), a
    1 kg hand's ``m·a`` added to the force (0.05 N white F/T noise) and the position measured
    through white noise and a 50 µm quantiser; no velocity channel. Returns it and the
    perturbation's ``valid`` mask."""
    cfg = CartesianOnlineConfig(simulation=SimulationConfig(n_stops=12, corner_s=0.04))
    rng = np.random.default_rng(seed)
    rec = simulate_level_a(_timeline(cfg, 4, "triangular"), THESIS_FIELD, noise_std_n=0.05, rng=rng)
    ch, meta = case_trials("exp4", rec, 400)
    acc = np.gradient(ch["hand_vel"], 1e-3, axis=1)
    q = np.round((ch["hand_pos"] + _DITHER_M * rng.standard_normal(ch["hand_pos"].shape)) / _STEP_M) * _STEP_M
    names = ("hand_pos", "ref_pos", "hand_force")
    ts = TrialSet(
        fs_hz=1000.0,
        onset_index=np.ones(len(q), dtype=int),
        channels={"hand_pos": q, "ref_pos": ch["ref_pos"], "hand_force": ch["hand_force"] + _HAND_KG * acc},
        units={k: CHANNEL_UNITS[k] for k in names},
        trial_meta={k: meta[k] for k in ("case", "stop", "n_logged", "t_start_s")},
        attrs={"protocol": "cartesian_online"},
    )
    return ts, np.arange(400)[None, :] < np.asarray(meta["n_logged"])[:, None]


@pytest.mark.parametrize("seed", [0, 1])
def test_quantised_position_the_damping_is_recovered_by_the_smoothing_differentiator(seed):
    ts, valid = _quantised_hand(seed)
    cs = prepare_cart(ts, band_hz=40.0)
    # the position noise read from the data: dither² + step²/12 (Sheppard); ~14 000 second
    # differences per axis give ~1.5 % of standard error on the variance, 5 % on the sd is generous
    np.testing.assert_allclose(
        np.sqrt(cs.pos_noise_var), np.hypot(_DITHER_M, _STEP_M / np.sqrt(12)), rtol=0.05
    )
    # the SNR crossing lies below the band (so the velocity is smoothed) and above the rounded
    # triangles' content (their spectrum falls by > 40 dB by 20 Hz)
    assert np.all((cs.vel_cutoff_hz > 20.0) & (cs.vel_cutoff_hz < 40.0))
    # δ of the 12 + 2 fit within 3 %: measured 1.0-1.2 % high on seeds 0-1 (the noise left below
    # the cut-off and the 1 kg hand's m·a, which the nominal model lacks, on the damping column)
    np.testing.assert_allclose(cs.delta0, THESIS_FIELD.delta, rtol=0.03)
    # without the smoothing (the central differences alone), the same fit attenuates δ to ~0.64:
    # the errors in variables this processing removes
    q, p = np.asarray(ts.channels["hand_pos"]), cs.p
    v_raw = np.gradient(q, 1e-3, axis=1)
    raw = fit_sqrt_damping_field(
        q[valid], p[valid], v_raw[valid], np.asarray(ts.channels["hand_force"])[valid][:, 0], 0
    )
    assert raw.delta < 0.8 * THESIS_FIELD.delta[0]


@pytest.mark.slow
def test_quantised_position_hand_inertia_is_named_with_its_mass():
    ts, _ = _quantised_hand(0)
    res, _ = diagnose_cart(ts, DiagnosisConfig())
    assert res["verdict"] == ["payload_mass"]
    mass = res["how_far"][-1]["parameters"]["payload_mass.mass_kg"]
    # measured 1.0275 kg (seeds 0-4: 1.007-1.046; 1.0017 before the 30 ms edge guard, which leaves
    # out the start corner's acceleration and most of the record's cut end): 5 % allows the
    # noise's share of the acceleration column over those seeds' spread
    assert abs(mass - _HAND_KG) < 0.05 * _HAND_KG
