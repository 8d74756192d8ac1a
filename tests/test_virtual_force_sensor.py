"""The virtual-force-sensor protocol (seeds/003) against Table I / Table VI ground truth.

Trials are 20 s here (identification on the first 15 s, VAF on the last 5 s) instead of the
paper's 50 s (40 s / 10 s) to keep the suite fast; the paper-length run is `armlab run
protocol=virtual_force_sensor` (figures in the issue note).
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from omegaconf import OmegaConf

from armlab.config.capstan import CapstanConfig, VfsConfig
from armlab.config.schema import ArmConfig, OutputConfig, SensorsConfig, SimConfig
from armlab.errors import ConfigError, DataError
from armlab.models.capstan_robot import TABLE_VI_ALPHA
from armlab.protocols.virtual_force_sensor.config import VirtualForceSensorConfig
from armlab.protocols.virtual_force_sensor.experiment import simulate_vfs
from armlab.protocols.virtual_force_sensor.results import estimate_vfs
from armlab.runner.run import reestimate, run_protocol

SHORT = {"trial_s": 20.0, "id_s": 15.0, "val_s": 5.0, "settle_s": 1.0}


def _cfg(capstan: CapstanConfig, preset: str, **vfs) -> VirtualForceSensorConfig:
    return VirtualForceSensorConfig(
        protocol_name="virtual_force_sensor",
        sim=SimConfig(timestep_s=0.00025, integrator="Euler"),
        arm=ArmConfig(muscle="linear", cocontraction=0.04),
        sensors=SensorsConfig(preset=preset),
        capstan=capstan,
        vfs=VfsConfig(**{**SHORT, **vfs}),
    )


def _run(cfg: VirtualForceSensorConfig) -> dict:
    rec = simulate_vfs(cfg)
    results, _ = estimate_vfs(rec.trials, cfg.vfs, rec.truth)
    return results


def _rel(results: dict, method: str) -> dict[str, dict[str, float]]:
    t3 = results["fixture"]["table_III"]
    return {lab: {n: c[method][n]["rel_err"] for n in c[method] if n != "vaf_pct"} for lab, c in t3.items()}


@pytest.fixture(scope="module")
def rigid_ideal():
    cfg = _cfg(
        CapstanConfig(cable="rigid", drag=False, coulomb_Nm=0.0, id_ee_mass_kg=0.0),  # every effect off
        "ideal",
        trials_per_config=1,
        arm_trials=0,
        robot_id_trials=2,
        # 12 s trials (9 s least squares, 3 s VAF) instead of SHORT's 20 s: without noise or
        # effects the fit needs no longer record (measured at most 0.5 % against 0.4 % at 20 s)
        trial_s=12.0,
        id_s=9.0,
        val_s=3.0,
    )
    return _run(cfg)


def test_rigid_noise_free_lab_recovers_every_table_i_configuration_by_both_methods(rigid_ideal):
    # the bound is 2 %; measured at most 0.5 % (k_xx, k_yy, m) on these 12 s trials
    t3 = rigid_ideal["fixture"]["table_III"]
    assert sorted(t3) == [f"K{i}" for i in range(1, 6)] + [f"M{i}" for i in range(1, 6)]
    for method in ("method1", "method2"):
        for label, cell in t3.items():
            c = cell[method]
            for n in ("k_xx", "k_yy", "m"):
                if n in c:
                    assert abs(c[n]["rel_err"]) < 0.02, (method, label, n, c[n])
            if "k_s" in c:  # k_s of K4 is -2 N/m: judged against the matrix's scale
                scale = max(abs(c["k_xx"]["truth"]), abs(c["k_yy"]["truth"]))
                assert abs(c["k_s"]["mean"] - c["k_s"]["truth"]) < 0.02 * scale, (method, label)
            assert min(c["vaf_pct"]) > 99.0


def test_rigid_robot_identification_returns_table_vi(rigid_ideal):
    # bound 1 % (issue); measured <= 0.05 %: the MJCF realises Table VI exactly with rigid cables
    alpha = [row["mean"] for row in rigid_ideal["robot_id"]["table_VI"]]
    np.testing.assert_allclose(alpha, TABLE_VI_ALPHA.alpha, rtol=0.01)
    assert np.min(rigid_ideal["robot_id"]["vaf_pct"]) > 99.0


@pytest.fixture(scope="module")
def realistic_lab():
    # the default robot: compliant capstan, cabling drag, Coulomb friction; realistic sensors
    cfg = _cfg(
        CapstanConfig(),
        "realistic",
        stiffness=["K1", "K3", "K4", "K5"],  # K4: the paper's largest relative k_xx gap (26 %)
        payloads=["M1", "M5"],
        trials_per_config=1,
        arm_trials=0,
        robot_id_trials=2,
    )
    return _run(cfg)


def test_method2_stays_within_ten_percent_of_table_i_with_realistic_sensors(realistic_lab):
    # measured: |k_xx|, |k_yy| <= 4 %, |m| <= 5 % (the series compliance of the cables)
    for label, errs in _rel(realistic_lab, "method2").items():
        for n in ("k_xx", "k_yy", "m"):
            if n in errs:
                assert abs(errs[n]) < 0.10, (label, n, errs[n])


def test_method1_shows_the_papers_bias_pattern_with_compliance_and_drag(realistic_lab):
    rel = _rel(realistic_lab, "method1")
    for label in ("K1", "K3", "K5"):  # stiffness over-estimated (the drag adds ~40 N/m along x)
        assert rel[label]["k_xx"] > 0 and rel[label]["k_yy"] > 0, (label, rel[label])
    for label in ("M1", "M5"):  # inertia under-estimated
        assert rel[label]["m"] < 0, (label, rel[label])
    # Sec. IV-A: "the relative discrepancy between Methods 1 and 2 is the largest for k_xx" (the
    # cables pull hardest along x); Method 1 - Method 2 relative to the truth
    rel2 = _rel(realistic_lab, "method2")
    largest = max(
        ((abs(e[n] - rel2[lab][n]), n) for lab, e in rel.items() for n in ("k_xx", "k_yy", "m") if n in e),
        key=lambda p: p[0],
    )
    assert largest[1] == "k_xx"
    # Method 1 relative to Method 2, as the paper reads Table III: stiffer, lighter
    assert all(rel[lab]["k_xx"] > rel2[lab]["k_xx"] for lab in ("K1", "K3", "K5"))
    assert all(rel[lab]["m"] < rel2[lab]["m"] for lab in ("M1", "M5"))
    # Table IV: Method 1's VAF is larger in the direction of greater stiffness. K3, K4 (stiff in
    # y): every cell, seen by 5-9 points; K1 (stiff in x, where the cables' hysteresis also acts):
    # on average over its cells only (single cells seen -0.6..+1.4 points, the full default run
    # misses the rule in some K1/K2 cells: docs/reproduction/virtual_force_sensor.md)
    t4 = realistic_lab["fixture"]["table_IV"]
    for label in ("K3", "K4"):
        assert all(v[1] > v[0] for v in t4[label].values()), (label, t4[label])
    vaf = t4["K1"]
    assert np.mean([v[0] for v in vaf.values()]) > np.mean([v[1] for v in vaf.values()]), vaf
    vaf2 = realistic_lab["fixture"]["table_III"]["K1"]["method2"]["vaf_pct"]
    assert np.mean([v[1] for v in vaf.values()]) < vaf2[1]  # and lower than Method 2's


def test_exciting_above_2hz_with_compliant_cables_degrades_method1():
    capstan = CapstanConfig(cable="compliant", drag=False, coulomb_Nm=0.0, id_ee_mass_kg=0.0)
    common = dict(
        stiffness=["K1"],
        payloads=["M3"],
        trials_per_config=1,
        arm_trials=0,
        robot_id_trials=0,
        robot_model="table_vi",
    )
    low = _run(_cfg(capstan, "realistic", band_hz=(0.2, 2.0), **common))
    high = _run(_cfg(capstan, "realistic", band_hz=(0.6, 6.0), **common))

    def worst(res):
        return max(abs(v) for e in _rel(res, "method1").values() for n, v in e.items() if n != "k_s")

    # measured (50 s trials): worst error 3.5 % -> 8.3 %, VAF ~99.98 % -> 95-96.5 %
    assert worst(high) > 1.5 * worst(low)
    vaf_low = low["fixture"]["table_IV"]["K1"]["M3"]
    vaf_high = high["fixture"]["table_IV"]["K1"]["M3"]
    assert min(vaf_low) > 99.5
    assert min(vaf_high) < min(vaf_low) - 2.0


def test_bad_protocol_settings_are_clear_errors():
    with pytest.raises(ConfigError, match="window"):
        VfsConfig(sg_window=5, sg_order=6)
    with pytest.raises(ConfigError, match="odd"):
        VfsConfig(sg_window=150)
    with pytest.raises(ConfigError, match="K1"):
        VfsConfig(stiffness=["K9"])
    with pytest.raises(ConfigError, match="robot_model"):
        VfsConfig(robot_model="perfect")
    with pytest.raises(ConfigError, match="cable"):
        CapstanConfig(cable="elastic")


def test_run_writes_outputs_reestimates_and_never_overwrites(tmp_path):
    cfg = _cfg(
        CapstanConfig(),
        "realistic",
        stiffness=["K2"],
        payloads=["M2"],
        trials_per_config=1,
        arm_trials=1,
        robot_id_trials=1,
        trial_s=12.0,
        id_s=9.0,
        val_s=3.0,
    )
    cfg.output = OutputConfig(recording=True, figures=True)
    out = tmp_path / "run"
    results = run_protocol(cfg, out, config_yaml=OmegaConf.to_yaml(OmegaConf.structured(cfg)))
    for name in (
        "results.json",
        "trials.h5",
        "scene.xml",
        "tables.txt",
        "fig4_forces.png",
        "fig5_identified_vs_theory.png",
        "trials.rrd",
    ):
        assert (out / name).is_file(), name
    saved = json.loads((out / "results.json").read_text())
    assert saved["fixture"]["table_III"]["K2"]["method2"]["k_xx"]["truth"] == pytest.approx(476.38)
    assert results["arm"]["table_V"]["method2"]["K"]["truth"][0][0] > 0
    again, res2 = reestimate(out, ["vfs.robot_model=table_vi"])
    assert res2["robot_model"] == "table_vi" and again.parent == out
    assert res2["fixture"]["table_III"]["K2"]["method2"]["k_xx"]["mean"] == pytest.approx(
        saved["fixture"]["table_III"]["K2"]["method2"]["k_xx"]["mean"]
    )  # Method 2 does not use the robot model
    with pytest.raises(DataError, match="never overwrites"):
        run_protocol(cfg, out)


def test_subject_fluctuation_reaches_only_the_arm_and_leaves_the_other_streams_unchanged():
    # the subject (paper 000's values) draws from a spawned child generator: switching it off
    # gives the same robot/fixture data and the same sensor noise; on, only the arm's forces move
    kw = dict(
        stiffness=["K1"],
        payloads=["M1"],
        trials_per_config=1,
        arm_trials=2,
        robot_id_trials=0,
        robot_model="table_vi",
        trial_s=3.0,
        id_s=2.0,
        val_s=1.0,
        settle_s=0.5,
    )
    on = _cfg(CapstanConfig(), "realistic", **kw)
    assert on.subject.active and on.subject.fluctuation_cv == 0.035  # the default lab has it
    off = replace(on, subject=replace(on.subject, enabled=False))
    a, b = simulate_vfs(on).trials, simulate_vfs(off).trials
    arm = a.trial_meta["kind"] == "arm"
    assert arm.sum() == 2 and np.array_equal(a.channels["ft_site"][~arm], b.channels["ft_site"][~arm])
    diff = a.channels["ft_site"][arm] - b.channels["ft_site"][arm]
    assert 0.005 < np.std(diff) < 5.0  # N: the fluctuation moves the arm's force, but not wildly
    # same config and seed: bit-identical
    assert np.array_equal(simulate_vfs(on).trials.channels["ft_site"], a.channels["ft_site"])
