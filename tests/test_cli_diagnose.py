"""``armlab effects`` and the argument errors of ``armlab diagnose`` / ``diagnose-benchmark``.

A full ``armlab diagnose`` run (figures, report) is not exercised here; every error below is
raised before anything is written.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from conftest import JOINT_FS_HZ, nominal_torque, prbs_position

from armlab.cli import main
from armlab.config.effects import EFFECTS
from armlab.data.joint_import import write_joint_csv
from armlab.protocols import registry
from armlab.protocols.joint_1dof.diagnosis.models import JOINT_SURROGATES


def _listed(out: str) -> list[str]:
    """Effect names of the catalogue lines (``name  [level]  params``)."""
    return re.findall(r"^(\w+)  \[(?:model|controller|sensor)\]", out, flags=re.M)


def test_effects_lists_the_whole_catalogue(capsys):
    assert main(["effects"]) == 0
    out = capsys.readouterr().out
    assert _listed(out) == list(EFFECTS)
    assert (
        "reflex  [model]  delay_s=0.045, gain_Nms_per_rad=10, cutoff_hz=3, damping_ratio=0.7, direction=1"
        in out
    )
    assert (
        "    confusable with transmission_compliance: separate with an accelerometer on the handle/pedal "
        "beside the motor encoder" in out
    )


def test_effects_of_one_protocol(capsys):
    assert main(["effects", "protocol=joint_1dof"]) == 0
    out = capsys.readouterr().out
    assert _listed(out) == list(registry.get("joint_1dof").catalogue)
    assert "cable_drag" not in _listed(out)
    # the diagnosable candidates are named first
    header = next(line for line in out.splitlines() if line.startswith("candidates of"))
    assert header.endswith(": " + ", ".join(JOINT_SURROGATES))
    assert main(["effects", "protocol=virtual_force_sensor"]) == 0
    out = capsys.readouterr().out
    assert _listed(out) == list(registry.get("virtual_force_sensor").catalogue) and "candidates of" not in out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["effects", "protocol=nope"],
            f"no effects for protocol 'nope'; valid protocols: {sorted(registry.names())}",
        ),
        (["effects", "foo"], "argument 'foo' must look like key=value"),
        (["effects", "bar=1"], "unknown argument 'bar=1'; valid: ['protocol=']"),
    ],
)
def test_effects_argument_errors(args, message, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"armlab: error: {message}"


@pytest.fixture
def trial_folder(tmp_path):
    """One 10 s CSV trial of the nominal joint (enough for the argument checks to get past loading)."""
    folder = tmp_path / "trials"
    folder.mkdir()
    x = prbs_position(np.random.default_rng(0), 10.0)
    t = np.arange(x.size) / JOINT_FS_HZ
    write_joint_csv(folder / "seq0_rep0.csv", t_s=t, position=x, torque=nominal_torque(x))
    return folder


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "diagnose needs ['data', 'protocol']: armlab diagnose data=<file|folder> protocol=<name>"),
        (["data={data}"], "diagnose needs ['protocol']"),
        (["data"], "argument 'data' must look like key=value"),
        (
            ["bogus=1"],
            "unknown argument 'bogus=1'; valid: ['data=', 'protocol=', 'out=', 'units=', "
            "'diagnosis.<field>=']",
        ),
        (["estimator.x=1"], "unknown argument 'estimator.x=1'"),
        (
            ["data={data}", "protocol=fractional_elbow"],
            "protocol 'fractional_elbow' cannot be diagnosed; valid: "
            "['conditioning_window', 'joint_1dof', 'cartesian_online', 'stiffness_5dof_emg']",
        ),
        (
            ["data={data}/missing", "protocol=joint_1dof"],
            "missing' does not exist; give a trial file or a folder",
        ),
        (
            ["data={data}", "protocol=joint_1dof", "diagnosis.nope=1"],
            "unknown diagnosis field 'nope'; valid: [",
        ),
        (
            ["data={data}", "protocol=joint_1dof", "diagnosis.holdout_fraction=0.9"],
            "diagnosis.holdout_fraction must lie in [0.05, 0.5], got 0.9",
        ),
        (
            ["data={data}", "protocol=joint_1dof", "diagnosis.candidates=[reflex,nope]"],
            "unknown candidate effect 'nope' for joint_1dof; valid: ['reflex', ",
        ),
        (
            [
                "data={data}",
                "protocol=joint_1dof",
                "diagnosis.candidates=[reflex]",
                "diagnosis.exclude=[reflex]",
            ],
            "no candidate effects left after exclude=['reflex']",
        ),
        (
            ["data={data}", "protocol=joint_1dof", "diagnosis.min_duration_s=20"],
            "trial 'seq0_rep0' lasts 10 s, shorter than min_duration_s = 20 s",
        ),
    ],
)
def test_diagnose_argument_errors(args, message, trial_folder, tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["diagnose", *(a.format(data=trial_folder) for a in args), f"out={out}"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("armlab: error: ") and message in err
    assert len(err.splitlines()) == 1
    assert not out.exists()  # nothing written


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["referee.protocol=x"],
            "unknown protocol 'x'; valid: "
            "['conditioning_window', 'joint_1dof', 'cartesian_online', 'stiffness_5dof_emg']",
        ),
        (
            ["referee.classes=[nope]"],
            "unknown referee classes ['nope'] for joint_1dof; valid: ['none', 'reflex', ",
        ),
        (["referee.replicates=0"], "referee.replicates >= 1 and n_trials >= 2"),
        (["diagnosis.max_effects=5"], "diagnosis.max_effects must be 1, 2 or 3, got 5"),
        (
            ["foo.bar=1"],
            "unknown argument 'foo.bar=1'; valid: ['out=', 'referee.<field>=', 'diagnosis.<field>=']",
        ),
    ],
)
def test_diagnose_benchmark_argument_errors(args, message, tmp_path, capsys):
    out = tmp_path / "bench"
    assert main(["diagnose-benchmark", *args, f"out={out}"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("armlab: error: ") and message in err
    assert not out.exists()
