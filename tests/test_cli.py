"""The armlab CLI and Hydra configs: composition, one-line errors, help."""

from __future__ import annotations

import importlib

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
        (["run", "protocol=nope"], "unknown protocol 'nope'; valid: ['conditioning_window']"),
        (["run", "reflex.stretch_latency_s=-0.01"], "reflex.stretch_latency_s must be positive"),
        (["run", "arm.muscle=foo"], "choose one of ['hill', 'linear']"),
        (["run", "arm.nope=1"], "nope"),
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


@pytest.mark.parametrize(
    "package",
    [
        "armlab",
        "armlab.config",
        "armlab.data",
        "armlab.estimation",
        "armlab.models",
        "armlab.perturbations",
        "armlab.protocols",
        "armlab.sensors",
        "armlab.sim",
        "armlab.viz",
    ],
)
def test_public_api_names_resolve(package):
    mod = importlib.import_module(package)
    for name in mod.__all__:
        assert hasattr(mod, name), f"{package}.{name}"
