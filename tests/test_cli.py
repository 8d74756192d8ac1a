"""The armlab CLI and Hydra configs: composition, one-line errors, help."""

from __future__ import annotations

import importlib
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from armlab.cli import compose, main
from armlab.config.schema import ExperimentConfig


def test_default_config_composes_to_the_paper_protocol():
    _, exp = compose([])
    assert isinstance(exp, ExperimentConfig)
    assert exp.protocol_name == "conditioning_window"
    assert tuple(exp.arm.q0) == (0.08, 1.0) and exp.arm.preload_N == 5.0
    assert exp.arm.muscle == "hill" and exp.reflex.enabled


def test_group_override_selects_linear_arm():
    _, exp = compose(["arm=planar_linear", "seed=3"])
    assert exp.arm.muscle == "linear" and exp.seed == 3


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "protocol=nope"], "unknown protocol 'nope'; valid: ['conditioning_window', 'fractional_"),
        (["run", "reflex.stretch_latency_s=-0.01"], "reflex.stretch_latency_s must be positive"),
        (["run", "arm.muscle=foo"], "choose one of ['hill', 'linear']"),
        (["run", "arm.q0=[0.08]"], "arm.q0 must be [shoulder, elbow] in rad (two angles), got [0.08]"),
        (["run", "scenario.k_values=[]"], "scenario.k_values is empty"),
        (["run", "arm.nope=1"], "'arm' has no key 'nope'; its keys: ['model', 'muscle'"),
        (["frobnicate"], "unknown verb 'frobnicate'"),
        (["estimate", "/nonexistent/run"], "has no trials.h5"),
        (["view", "/nonexistent/run"], "trials.rrd not found"),
    ],
)
def test_bad_input_gives_one_line_error(args, message, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("armlab: error:") and message in err
    assert len(err.splitlines()) == 1


def test_missing_model_file_is_a_one_line_error(capsys, monkeypatch, tmp_path):
    import armlab.models.scene as scene

    monkeypatch.setattr(scene, "MODELS_DIR", tmp_path)
    from armlab.config.schema import ArmConfig, CuffConfig, RobotConfig, SimConfig
    from armlab.errors import ModelError

    with pytest.raises(ModelError, match="not found"):
        scene.build_scene(ArmConfig(), CuffConfig(), RobotConfig(), SimConfig())


def test_help_lists_verbs_and_protocols(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for word in ("run", "estimate", "view", "conditioning_window"):
        assert word in out


def _public_modules() -> list[str]:
    """Every armlab module and package that declares a public API (``__all__``)."""
    import pkgutil

    import armlab

    names = ["armlab"] + [m.name for m in pkgutil.walk_packages(armlab.__path__, "armlab.")]
    return [n for n in names if hasattr(importlib.import_module(n), "__all__")]


@pytest.mark.parametrize("module", _public_modules())
def test_public_api_names_resolve(module):
    mod = importlib.import_module(module)
    missing = [name for name in mod.__all__ if not hasattr(mod, name)]
    assert not missing, f"{module}.__all__ names what it lacks: {missing}"
    assert len(set(mod.__all__)) == len(mod.__all__), f"{module}.__all__ repeats a name"


# A small run: two windows (k = 1, 26), 7 trials each (6 identify, one per direction), no figures
# or recording. Through the installed console script, as a user runs it.
_SMALL = ["scenario.k_values=[1,26]", "scenario.n_trials=7", "output.recording=false", "output.figures=false"]


def _armlab(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).with_name("armlab")
    return subprocess.run([str(exe), *args], cwd=cwd, capture_output=True, text=True, timeout=300)


def _estimate(capsys, *args: str) -> Path:
    """``armlab estimate <args>`` in this process (the entry point's own start-up and exit status
    are checked with `armlab run` above and in tests/test_bad_input.py): the folder it names last."""
    assert main(["estimate", *args]) == 0, capsys.readouterr().err
    out = capsys.readouterr().out
    return Path(out.strip().splitlines()[-1].removeprefix("outputs: "))


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """A small run without out=: a new timestamped folder under outputs/ of the working folder."""
    tmp = tmp_path_factory.mktemp("cli")
    proc = _armlab("run", *_SMALL, "seed=5", cwd=tmp)
    assert proc.returncode == 0, proc.stderr
    (run_dir,) = (tmp / "outputs" / "conditioning_window").iterdir()
    return run_dir, proc


def test_run_writes_results_trials_and_prints_the_table(small_run):
    run_dir, proc = small_run
    results = json.loads((run_dir / "results.json").read_text())
    assert [w["t_obs_s"] for w in results["windows"]] == pytest.approx([0.12, 0.37, 0.40, 0.45, 0.50])
    assert results["seed"] == 5 and (run_dir / "trials.h5").is_file()
    assert "criteria first met" in proc.stdout and f"outputs: {run_dir}" in proc.stdout


def test_estimate_reproduces_the_run_from_its_trial_file(small_run, capsys, monkeypatch):
    run_dir, _ = small_run
    monkeypatch.chdir(run_dir)
    out = _estimate(capsys, str(run_dir))
    assert out.parent == run_dir and out.name.startswith("reestimate_")
    again = json.loads((out / "results.json").read_text())["windows"]
    first = json.loads((run_dir / "results.json").read_text())["windows"]
    # same trials, same estimator: the same numbers (float32-free trial file, same code path)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_allclose(a["K"], b["K"], rtol=1e-9)
        np.testing.assert_allclose(a["D"], b["D"], rtol=1e-9)
    # an estimator override changes the estimate, and the original run is untouched
    out40 = _estimate(capsys, str(run_dir), "estimator.lowpass_hz=40")
    assert out40 != out
    k40 = json.loads((out40 / "results.json").read_text())["windows"][-1]["K"]
    assert not np.allclose(k40, first[-1]["K"], rtol=1e-6)
    assert json.loads((run_dir / "results.json").read_text())["windows"] == first


def test_estimate_writes_into_the_folder_out_names_and_never_over_it(
    small_run, tmp_path, capsys, monkeypatch
):
    run_dir, _ = small_run
    monkeypatch.chdir(tmp_path)
    target = tmp_path / "re, estimated"  # a comma and a space: a literal folder name
    assert _estimate(capsys, str(run_dir), f"out={target}") == target and (target / "results.json").is_file()
    again = json.loads((target / "results.json").read_text())["windows"][-1]["K"]
    np.testing.assert_allclose(again, json.loads((run_dir / "results.json").read_text())["windows"][-1]["K"])
    before = (target / "results.json").read_bytes()
    assert main(["estimate", str(run_dir), f"out={target}"]) == 2
    assert "is not empty" in capsys.readouterr().err
    assert (target / "results.json").read_bytes() == before


def test_run_without_out_writes_a_new_folder_under_outputs(small_run):
    folder, proc = small_run  # the fixture's run names no out=; its folder is the only one there
    assert folder.parent.parent.name == "outputs"
    assert re.fullmatch(r"\d{4}-\d\d-\d\d_\d\d-\d\d-\d\d-\d{6}", folder.name), folder.name  # a timestamp
    assert proc.stdout.strip().endswith(f"outputs: {folder}")
    assert (folder / "results.json").is_file()


def test_estimate_rejects_unknown_estimator_field(small_run, capsys):
    run_dir, _ = small_run
    assert main(["estimate", str(run_dir), "estimator.nope=1"]) == 2
    assert "unknown estimator field 'nope'" in capsys.readouterr().err


# joblib: slow (make test-all). In `make test`, tests/test_resume.py's joblib sweep checks that each
# joblib job's trials and results are bit-identical to the serial job of the same number, and
# "basic" here that the serial jobs are separate folders with their own seeds
@pytest.mark.parametrize(
    "launcher",
    [[], pytest.param(["hydra/launcher=joblib"], marks=pytest.mark.slow)],
    ids=["basic", "joblib"],
)
def test_multirun_sweeps_seeds_into_separate_directories(tmp_path, launcher):
    sweep = tmp_path / "sweep"
    args = ["run", "--multirun", "seed=0,1", *_SMALL, *launcher, f"out={sweep}"]
    proc = _armlab(*args, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    runs = sorted(p for p in sweep.iterdir() if (p / "results.json").is_file())
    assert [p.name for p in runs] == ["0", "1"]
    seeds = [json.loads((p / "results.json").read_text())["seed"] for p in runs]
    assert seeds == [0, 1]
    k = [json.loads((p / "results.json").read_text())["windows"][-1]["K"] for p in runs]
    assert not np.allclose(k[0], k[1])  # different seeds: different noise, different estimates


@pytest.fixture(scope="module")
def fractional_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cli_fe")
    run_dir = tmp / "run"
    # the five-element recovery needs the lab without the Fig. 4 effects that lie outside the
    # five-element model (the handle mass beyond the sensor; the stiff 15 kN/m grip leaves d1
    # undetermined below 15 Hz): the earlier grasp and the sensor at the skin, set explicitly
    args = ["protocol=fractional_elbow", "elbow.impedance=five_element", "output.recording=false"]
    args += [
        "motor.sensed_mass_kg=0",
        "elbow.grasp_stiffness_N_per_m=2000",
        "elbow.grasp_damping_Ns_per_m=10",
    ]
    proc = _armlab("run", *args, f"out={run_dir}", cwd=tmp)
    assert proc.returncode == 0, proc.stderr
    return run_dir, proc


def test_fractional_elbow_run_writes_its_outputs(fractional_run):
    run_dir, proc = fractional_run
    results = json.loads((run_dir / "results.json").read_text())
    assert results["protocol"] == "fractional_elbow" and results["n_trials"] == 2
    assert set(results["models"]) == {"27", "28", "29", "A", "B"}
    # five-element truth at the protocol's default 0.1 ms steps: within the 5 %
    assert max(results["five_element_rel_err"].values()) < 0.05
    for name in ("fig4_bode_fits.png", "fig5_time_overlay.png", "fig6_bode_literature.png", "table_I.txt"):
        assert (run_dir / name).stat().st_size > 0, name
    assert "(27)" in proc.stdout and "paper" in proc.stdout


def test_fractional_elbow_reestimate_uses_frf_overrides(fractional_run, capsys, monkeypatch):
    run_dir, _ = fractional_run
    monkeypatch.chdir(run_dir)
    first = json.loads((run_dir / "results.json").read_text())
    out = _estimate(capsys, str(run_dir))
    again = json.loads((out / "results.json").read_text())
    assert again["five_element_fit"]["k1"] == pytest.approx(first["five_element_fit"]["k1"], rel=1e-9)
    assert again["five_element_rel_err"] == pytest.approx(first["five_element_rel_err"], rel=1e-9)
    out = _estimate(capsys, str(run_dir), "frf.welch_window=10000")
    frf = json.loads((out / "results.json").read_text())["frf"]
    assert frf["settings"]["welch_window"] == 10000 and first["frf"]["settings"]["welch_window"] == 5000
    assert frf["mean_coherence"] != pytest.approx(first["frf"]["mean_coherence"], rel=1e-6)
    # values the schema rejects or cannot parse: one-line errors, no traceback
    assert main(["estimate", str(run_dir), "frf.welch_window=abc"]) == 2
    assert main(["estimate", str(run_dir), "frf.band_hz=[20,10]"]) == 2
    assert main(["estimate", str(run_dir), "estimator.lowpass_hz=3"]) == 2
