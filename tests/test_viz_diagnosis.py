"""Figures and the Rerun recording of ``armlab diagnose``, from a synthetic joint with a reflex.

``torque = -(I·θ̈ + B·θ̇ + K·θ) - G·lowpass(max(θ̇(t - 45 ms), 0)) + noise`` under random position
steps: small, fast, and independent of the shared REKLAB data.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

import armlab.viz
from armlab.config.diagnosis import DiagnosisConfig
from armlab.diagnosis.diagnose import diagnose_joint
from armlab.errors import DataError
from armlab.viz import diagnosis_figures, diagnosis_recording

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
FS_HZ = 1000.0
FIGURES = [
    "gap_by_band.png",
    "gap_by_window.png",
    "residual_correlation.png",
    "time_overlay.png",
    "vaf_per_trial.png",
]


@dataclass(frozen=True)
class _Record:
    name: str
    position: np.ndarray  # rad
    torque: np.ndarray  # N·m
    fs_hz: float


def _record(name: str, seed: int, duration_s: float = 10.0) -> _Record:
    rng = np.random.default_rng(seed)
    n = int(duration_s * FS_HZ)
    level = np.zeros(n)
    i, sign = 0, 1.0
    while i < n:
        hold = int(rng.uniform(0.15, 0.6) * FS_HZ)
        level[i : i + hold] = 0.03 * sign
        sign, i = -sign, i + hold
    x = signal.sosfiltfilt(signal.butter(2, 8.0, fs=FS_HZ, output="sos"), level)
    v = np.gradient(x, 1 / FS_HZ)
    a = np.gradient(v, 1 / FS_HZ)
    lag = int(0.045 * FS_HZ)
    w = 2 * np.pi * 3.0
    b_lp, a_lp = signal.bilinear([w * w], [1.0, 2 * 0.7 * w, w * w], FS_HZ)
    reflex = signal.lfilter(b_lp, a_lp, np.maximum(np.r_[np.zeros(lag), v[:-lag]], 0.0))
    torque = -(0.015 * a + 1.0 * v + 80.0 * x) - 15.0 * reflex + 0.05 * rng.standard_normal(n)
    return _Record(name, x, torque, FS_HZ)


@pytest.fixture(scope="module")
def pooled():
    return diagnose_joint(
        [_record("a", 1), _record("b", 2)], DiagnosisConfig(candidates=["reflex", "channel_delay"])
    )


@pytest.fixture(scope="module")
def per_trial():
    return diagnose_joint(
        [_record("trial one", 3), _record("b", 4)],
        DiagnosisConfig(candidates=["reflex", "channel_delay"], per_trial=True),
    )


def _check_pngs(paths: list[Path], out: Path) -> None:
    assert paths == [out / name for name in FIGURES]
    for p in paths:
        data = p.read_bytes()
        assert data.startswith(PNG_MAGIC) and len(data) > 10_000, p


def test_exported_from_viz():
    assert {"diagnosis_figures", "diagnosis_recording"} <= set(armlab.viz.__all__)
    for name in armlab.viz.__all__:
        assert getattr(armlab.viz, name) is not None


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


def _rerun_cli() -> Path | None:
    exe = Path(sys.executable).parent / "rerun"
    return exe if exe.is_file() else None


@pytest.mark.parametrize("mode", ["pooled", "per_trial"])
def test_recording_written_and_verified(mode, pooled, per_trial, tmp_path):
    _, series = pooled if mode == "pooled" else per_trial
    path = diagnosis_recording(series, tmp_path / "diagnosis.rrd")
    assert path == tmp_path / "diagnosis.rrd"
    # 2 trials x 2500 samples x 6 series at least 8 B each
    assert path.stat().st_size > 2 * 2500 * 6 * 8
    exe = _rerun_cli()
    if exe is None:
        pytest.skip("no rerun CLI next to the interpreter; cannot verify the .rrd")
    env = {**os.environ, "HOME": str(tmp_path), "XDG_CONFIG_HOME": str(tmp_path / ".config")}
    subprocess.run([str(exe), "analytics", "disable"], env=env, capture_output=True, timeout=30, check=False)
    done = subprocess.run(
        [str(exe), "rrd", "verify", str(path)], env=env, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stdout + done.stderr


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
