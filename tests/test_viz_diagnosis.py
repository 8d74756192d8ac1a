"""Figures and the Rerun recording of ``armlab diagnose``, from a synthetic joint with a reflex.

``torque = -(I·θ̈ + B·θ̇ + K·θ) - G·lowpass(max(θ̇(t - 45 ms), 0)) + noise`` under random position
steps: small, fast, and independent of the shared REKLAB data.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from conftest import (
    assert_png,
    noisy_joint_record,
    verify_rrd,
)

import armlab.viz
from armlab.config.diagnosis import DiagnosisConfig
from armlab.errors import DataError
from armlab.protocols.joint_1dof.diagnosis.diagnose import diagnose_joint
from armlab.viz import diagnosis_figures, diagnosis_recording

FIGURES = [
    "gap_by_band.png",
    "gap_by_window.png",
    "residual_correlation.png",
    "time_overlay.png",
    "vaf_per_trial.png",
]


@pytest.fixture(scope="module")
def pooled():
    return diagnose_joint(
        [noisy_joint_record("a", 1, reflex_gain=15.0), noisy_joint_record("b", 2, reflex_gain=15.0)],
        DiagnosisConfig(candidates=["reflex", "channel_delay"]),
    )


@pytest.fixture(scope="module")
def per_trial():
    return diagnose_joint(
        [noisy_joint_record("trial one", 3, reflex_gain=15.0), noisy_joint_record("b", 4, reflex_gain=15.0)],
        DiagnosisConfig(candidates=["reflex", "channel_delay"], per_trial=True),
    )


def _check_pngs(paths: list[Path], out: Path) -> None:
    assert paths == [out / name for name in FIGURES]
    for p in paths:
        assert_png(p)


def test_exported_from_viz():
    assert {"diagnosis_figures", "diagnosis_recording"} <= set(armlab.viz.__all__)


def test_importing_viz_does_not_import_rerun():
    code = "import sys, armlab.viz.diagnosis, armlab.viz; assert 'rerun' not in sys.modules"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr


def test_figures_pooled(pooled, tmp_path):
    results, series = pooled
    assert results["verdict"] == ["reflex"]
    _check_pngs(diagnosis_figures(series, results, tmp_path / "out"), tmp_path / "out")


def test_figures_per_trial(per_trial, tmp_path):
    results, series = per_trial
    assert set(series) == {"trial one", "b"}
    _check_pngs(diagnosis_figures(series, results, tmp_path), tmp_path)


def test_figures_never_overwrite_and_check_series(pooled, tmp_path):
    results, series = pooled
    (tmp_path / "gap_by_band.png").write_bytes(b"keep")
    with pytest.raises(DataError, match="gap_by_band.png"):
        diagnosis_figures(series, results, tmp_path)
    assert (tmp_path / "gap_by_band.png").read_bytes() == b"keep"
    with pytest.raises(DataError, match="series"):
        diagnosis_figures({"other": series["all"]}, results, tmp_path / "x")


@pytest.mark.parametrize("mode", ["pooled", "per_trial"])
def test_recording_written_and_verified(mode, pooled, per_trial, tmp_path):
    _, series = pooled if mode == "pooled" else per_trial
    path = diagnosis_recording(series, tmp_path / "diagnosis.rrd")
    assert path == tmp_path / "diagnosis.rrd"
    # 2 trials x 2500 samples x 6 series at least 8 B each
    assert path.stat().st_size > 2 * 2500 * 6 * 8
    verify_rrd(path, tmp_path)


def test_recording_refuses_overwrite_and_bad_input(pooled, tmp_path):
    _, series = pooled
    path = tmp_path / "diagnosis.rrd"
    path.write_bytes(b"keep")
    with pytest.raises(DataError, match="diagnosis.rrd"):
        diagnosis_recording(series, path)
    assert path.read_bytes() == b"keep"
    with pytest.raises(DataError, match=r"\.rrd"):
        diagnosis_recording(series, tmp_path / "diagnosis.txt")
    with pytest.raises(DataError, match="corrected"):
        diagnosis_recording(
            {"all": {k: v for k, v in series["all"].items() if k != "corrected"}}, tmp_path / "b.rrd"
        )
    with pytest.raises(DataError, match="at least one"):
        diagnosis_recording({}, tmp_path / "c.rrd")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["diagnosis.rrd"]
