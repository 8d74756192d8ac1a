"""Checks of the REKLAB ankle importer, and the FRF + Levy machinery on one real recording."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from armlab.data import DEFAULT_REKLAB_ROOT, list_ankle_trials, load_ankle_trial
from armlab.errors import DataError
from armlab.estimation.frf import estimate_frf
from armlab.estimation.levy import LevyStructure, levy_fit

STATIONARY = ("z_df", "z_df2", "z_df3", "z_pf", "z_pf2")


@pytest.fixture(scope="module")
def z_df():
    if not (DEFAULT_REKLAB_ROOT / "z_df.csv").is_file():
        pytest.skip(f"REKLAB ankle data not present at {DEFAULT_REKLAB_ROOT}")
    return load_ankle_trial("z_df")


def test_default_root_is_anchored_next_to_the_repository():
    repo = Path(__file__).resolve().parents[1]
    assert DEFAULT_REKLAB_ROOT == repo.parent / "shared" / "data" / "reklab_ankle"


def test_z_df_loads_60_s_at_1_khz(z_df):
    assert set(STATIONARY) <= set(list_ankle_trials())
    assert z_df.fs_hz == pytest.approx(1000.0, rel=1e-9)
    assert z_df.position.shape == z_df.torque.shape == z_df.t_s.shape == (60000,)
    assert z_df.duration_s == pytest.approx(60.0, rel=1e-9)
    assert z_df.operating_point is None and z_df.name == "z_df"
    # a few degrees of perturbation and a few N·m of torque
    assert 0.005 < np.std(z_df.position) < 0.1 and 0.5 < np.std(z_df.torque) < 20


def test_tv_pilot_has_an_operating_point():
    if "tv_pilot" not in list_ankle_trials():
        pytest.skip(f"tv_pilot.csv not present at {DEFAULT_REKLAB_ROOT}")
    tv = load_ankle_trial("tv_pilot")
    assert tv.operating_point is not None and tv.operating_point.shape == tv.position.shape
    assert tv.duration_s == pytest.approx(106.0, rel=1e-3)


def test_ankle_impedance_by_frf_and_levy(z_df):
    """Intrinsic impedance ``K + B s + I s²`` of -torque/position, 0.5-40 Hz, paper's Welch settings.

    Measured: I = 0.0186 kg·m², B = 1.50 N·m·s/rad, K = 129 N·m/rad, R² (magnitude) = 0.981.
    """
    frf = estimate_frf(z_df.position, -z_df.torque, z_df.fs_hz, window_len=5000, overlap=0.25)
    band = frf.band(0.5, 40.0)
    fit = levy_fit(band.f_hz, band.G, LevyStructure.full(2, 0), alpha=1.0)
    K, B, I = fit.model.b
    # ankle plausibility: foot inertia 0.01-0.05 kg·m²; stiffness tens to hundreds N·m/rad
    assert 0.01 < I < 0.05
    assert 0.1 < B < 10.0
    assert 20.0 < K < 500.0
    assert fit.indices.r2 > 0.9
    assert fit.bandwidth_hz is None  # an impedance rises with frequency


def test_list_is_empty_for_a_missing_folder(tmp_path):
    assert list_ankle_trials(tmp_path / "nowhere") == ()


def _write(path: Path, header: str, rows: np.ndarray) -> None:
    np.savetxt(path, rows, delimiter=",", header=header, comments="", fmt="%.6f")


def test_importer_errors(tmp_path):
    t = np.arange(100) * 1e-3
    # torque 100 N·m per rad of angle: within human joints' scale (armlab.data.joint_units)
    _write(tmp_path / "ok.csv", "t_s,position_rad,torque_Nm", np.column_stack([t, t, 100 * t]))
    assert load_ankle_trial("ok", tmp_path).fs_hz == pytest.approx(1000.0)
    with pytest.raises(DataError, match=r"no ankle trial 'z_xx'.*available: \['ok'\]"):
        load_ankle_trial("z_xx", tmp_path)
    _write(tmp_path / "cols.csv", "t_s,position_rad,force_N", np.column_stack([t, t, t]))
    with pytest.raises(DataError, match=r"missing column\(s\) \['torque_Nm'\]"):
        load_ankle_trial("cols", tmp_path)
    t_gap = np.concatenate([t[:50], t[50:] + 0.005])
    _write(tmp_path / "gap.csv", "t_s,position_rad,torque_Nm", np.column_stack([t_gap, t, t]))
    with pytest.raises(DataError, match="non-uniform sampling"):
        load_ankle_trial("gap", tmp_path)
