"""``armlab fit-joint``: CSV recordings in, results.json, table and Bode figure out."""

from __future__ import annotations

import json

import numpy as np
import pytest

from armlab import viz
from armlab.cli import main
from armlab.errors import ConfigError, DataError
from armlab.protocols.joint_1dof.fit_command import fit_joint_recordings, joint_frf_config

FS = 1000.0
I, B, K = 0.02, 1.0, 100.0  # kg m², N m s/rad, N m/rad


def _write_trial(path, seed: int, seconds: float = 30.0) -> None:
    rng = np.random.default_rng(seed)
    n = int(seconds * FS)
    f = np.fft.rfftfreq(n, 1 / FS)
    spec = np.fft.rfft(rng.standard_normal(n)) * (f < 60.0)
    s = 2j * np.pi * f
    position = np.fft.irfft(spec, n) * 0.01
    torque = -np.fft.irfft(spec * (I * s**2 + B * s + K), n) * 0.01
    t = np.arange(n) / FS
    np.savetxt(
        path,
        np.column_stack([t, position, torque]),
        delimiter=",",
        fmt="%.9g",
        header="t_s,position_rad,torque_Nm",
        comments="",
    )


@pytest.fixture()
def folder(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    _write_trial(data / "a.csv", 0)
    _write_trial(data / "b.csv", 1)
    return data


def test_folder_is_fitted_and_written(folder, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["fit-joint", str(folder), f"out={out}", "frf.welch_window=4000"]) == 0
    results = json.loads((out / "results.json").read_text())
    assert sorted(results["trials"]) == ["a", "b"] and results["frf"]["welch_window"] == 4000
    for r in results["trials"].values():
        integer = r["impedance"]["integer"]
        assert integer["I"] == pytest.approx(I, rel=0.01) and integer["K"] == pytest.approx(K, rel=0.01)
        assert integer["B"] == pytest.approx(B, rel=0.02)
        assert r["impedance"]["fractional"]["alpha"] == pytest.approx(1.0, abs=0.1 + 1e-9)
    assert (out / "bode_impedance.png").stat().st_size > 0 and (out / "table.txt").is_file()
    assert "z_" not in capsys.readouterr().out  # only our two trials


def test_single_file_and_bad_input(folder, tmp_path, capsys):
    out = tmp_path / "one"
    results = fit_joint_recordings(folder / "a.csv", joint_frf_config(), out, viz=viz)
    assert list(results["trials"]) == ["a"]
    with pytest.raises(DataError, match="not empty"):
        fit_joint_recordings(folder / "a.csv", joint_frf_config(), out, viz=viz)
    (tmp_path / "afile").write_text("keep me")
    with pytest.raises(DataError, match="not a directory"):
        fit_joint_recordings(folder / "a.csv", joint_frf_config(), tmp_path / "afile", viz=viz)
    assert (tmp_path / "afile").read_text() == "keep me"
    assert joint_frf_config(["frf.band_hz=[1,20]"]).band_hz[1] == 20.0
    with pytest.raises(
        DataError, match="missing.csv does not exist; expected a .csv or .mat file or a folder"
    ):
        fit_joint_recordings(folder / "missing.csv", joint_frf_config(), tmp_path / "x", viz=viz)
    with pytest.raises(ConfigError, match="unknown frf field 'nope'"):
        joint_frf_config(["frf.nope=1"])
    with pytest.raises(ConfigError, match="frf.<field>=<value>"):
        joint_frf_config(["estimator.lowpass_hz=3"])
    assert main(["fit-joint"]) == 2
    assert "needs a CSV file or folder" in capsys.readouterr().err
