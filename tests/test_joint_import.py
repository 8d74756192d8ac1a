"""Checks of the generic 1-DoF joint importer: CSV and .mat layouts, every error, REKLAB files."""

from __future__ import annotations

import time
import warnings

import numpy as np
import pytest
import scipy.io

import armlab.data
from armlab.data import (
    DEFAULT_REKLAB_ROOT,
    JOINT_COLUMNS,
    JointRecord,
    load_ankle_trial,
    load_joint_data,
    write_joint_csv,
)
from armlab.errors import DataError

STATIONARY = ("z_df", "z_df2", "z_df3", "z_pf", "z_pf2")
RAW = DEFAULT_REKLAB_ROOT / "raw"
PILOT = "IEEETBME2022_PilotData_AV_PT1_UT2"


def _matio():
    with warnings.catch_warnings():  # matio sets a deprecated pandas option on import
        warnings.simplefilter("ignore")
        import matio
        from matio.utils.matclass import MatlabOpaque
    return matio, MatlabOpaque


def _signals(n: int = 100, fs: float = 1000.0, t0: float = 0.0, seed: int = 0):
    rng = np.random.default_rng(seed)
    return t0 + np.arange(n) / fs, rng.normal(0.0, 0.05, n), rng.normal(0.0, 3.0, n)


def _csv(path, header: str, rows: list[str]):
    path.write_text("\n".join([header, *rows]) + "\n")
    return path


def _good_rows(n: int = 100) -> list[str]:
    t, p, q = _signals(n)
    return [f"{a:.3f},{b:.9g},{c:.9g}" for a, b, c in zip(t, p, q, strict=True)]


def _nldat(MatlabOpaque, data: np.ndarray, names: list[str], units: list[str], incr: float = 1e-3):
    cell = lambda xs: np.array([[np.array([x]) for x in xs]], dtype=object)  # noqa: E731
    return MatlabOpaque(
        properties={
            "chanNames": cell(names),
            "chanUnits": cell(units),
            "domainIncr": np.array([[incr]]),
            "domainStart": np.array([[0.0]]),
            "domainValues": np.array([[np.nan]]),
            "dataSet": data,
        },
        classname="nldat",
    )


@pytest.fixture(scope="module")
def reklab():
    if not DEFAULT_REKLAB_ROOT.is_dir():
        pytest.skip(f"REKLAB ankle data not present at {DEFAULT_REKLAB_ROOT}")
    return DEFAULT_REKLAB_ROOT


# --- writing and reading back ---------------------------------------------------------------------
def test_round_trip_is_exact_to_the_written_precision(tmp_path):
    t, p, q = _signals(500, fs=1000.0)
    path = write_joint_csv(tmp_path / "trial.csv", t_s=t, position=p, torque=q)
    assert path.read_text().splitlines()[0] == ",".join(JOINT_COLUMNS)
    (rec,) = load_joint_data(path)
    assert rec.name == "trial" and rec.path == path and rec.operating_point is None
    # the loaded values are exactly the decimal strings written: time %.15g, signals %.9g
    np.testing.assert_array_equal(rec.t_s, [float(f"{x:.15g}") for x in t])
    np.testing.assert_array_equal(rec.position, [float(f"{x:.9g}") for x in p])
    np.testing.assert_array_equal(rec.torque, [float(f"{x:.9g}") for x in q])
    # so they are within half a unit of the 9th significant digit of the originals
    np.testing.assert_allclose(rec.position, p, rtol=5.000001e-9, atol=0)
    assert rec.fs_hz == pytest.approx(1000.0, rel=1e-12)
    assert rec.n_samples == 500 and rec.duration_s == pytest.approx(0.5)


def test_round_trip_of_a_record_with_an_operating_point(tmp_path):
    t, p, q = _signals(200)
    rec = JointRecord(
        name="tv", t_s=t, position=p, torque=q, fs_hz=1000.0, path=tmp_path, operating_point=p / 2
    )
    (back,) = load_joint_data(write_joint_csv(tmp_path / "tv.csv", rec))
    assert back.operating_point is not None
    np.testing.assert_allclose(back.operating_point, p / 2, rtol=5.000001e-9, atol=0)
    np.testing.assert_allclose(back.torque, q, rtol=5.000001e-9, atol=0)


def test_time_keeps_enough_digits_for_a_non_decimal_rate_late_in_a_record(tmp_path):
    # at t ~ 1000 s, %.9g would resolve only 1e-5 s, far beyond the 1.5e-9 s uniformity tolerance
    t, p, q = _signals(300, fs=2048.0, t0=1000.0)
    (rec,) = load_joint_data(write_joint_csv(tmp_path / "late.csv", t_s=t, position=p, torque=q))
    assert rec.fs_hz == pytest.approx(2048.0, rel=1e-9) and rec.t_s[0] == 1000.0


def test_write_refuses_an_existing_file_unless_told(tmp_path):
    t, p, q = _signals()
    path = write_joint_csv(tmp_path / "a.csv", t_s=t, position=p, torque=q)
    with pytest.raises(DataError, match=r"a\.csv: file already exists; pass overwrite=True"):
        write_joint_csv(path, t_s=t, position=2 * p, torque=q)
    write_joint_csv(path, t_s=t, position=2 * p, torque=q, overwrite=True)
    np.testing.assert_allclose(load_joint_data(path)[0].position, 2 * p, rtol=1e-8)


def test_write_errors(tmp_path):
    t, p, q = _signals()
    rec = JointRecord(name="r", t_s=t, position=p, torque=q, fs_hz=1000.0, path=tmp_path)
    with pytest.raises(DataError, match=r"must end in \.csv"):
        write_joint_csv(tmp_path / "a.txt", rec)
    with pytest.raises(DataError, match="not both"):
        write_joint_csv(tmp_path / "a.csv", rec, torque=q)
    with pytest.raises(DataError, match="all three arrays"):
        write_joint_csv(tmp_path / "a.csv", t_s=t, position=p)
    with pytest.raises(DataError, match=r"1 NaN or inf value\(s\); the first in column 'torque_Nm' at row 4"):
        write_joint_csv(tmp_path / "a.csv", t_s=t, position=p, torque=np.where(t == t[3], np.nan, q))
    with pytest.raises(DataError, match="does not exist; create it first"):
        write_joint_csv(tmp_path / "no" / "a.csv", rec)
    assert not (tmp_path / "a.csv").exists()
    with pytest.raises(DataError, match="1-D of one length"):
        JointRecord(name="r", t_s=t, position=p[:-1], torque=q, fs_hz=1000.0, path=tmp_path)


# --- CSV layouts and errors -----------------------------------------------------------------------
def test_csv_column_order_is_free_and_extra_columns_are_ignored(tmp_path):
    rows = [f"subj1,{r.split(',')[2]},{r.split(',')[0]},{r.split(',')[1]}" for r in _good_rows()]
    (rec,) = load_joint_data(_csv(tmp_path / "x.csv", "label,torque_Nm,t_s,position_rad", rows))
    (ref,) = load_joint_data(_csv(tmp_path / "ref.csv", "t_s,position_rad,torque_Nm", _good_rows()))
    np.testing.assert_array_equal(rec.torque, ref.torque)
    np.testing.assert_array_equal(rec.position, ref.position)


def test_time_varying_layout(tmp_path):
    rows = [f"{r},{0.01 * i:.3f}" for i, r in enumerate(_good_rows())]  # a slow ramp, < pi rad
    (rec,) = load_joint_data(_csv(tmp_path / "tv.csv", ",".join(armlab.data.TIME_VARYING_COLUMNS), rows))
    assert rec.operating_point is not None and rec.operating_point[1] == pytest.approx(0.01)
    _csv(tmp_path / "tv2.csv", "t_s,position_perturbation_rad,torque_Nm", _good_rows())
    with pytest.raises(
        DataError, match=r"missing column\(s\) \['torque_perturbation_Nm', 'ankle_position_rad'\]"
    ):
        load_joint_data(tmp_path / "tv2.csv")


def test_missing_columns_lists_missing_expected_and_found(tmp_path):
    _csv(tmp_path / "cols.csv", "t_s,position_rad,force_N", _good_rows())
    with pytest.raises(DataError) as err:
        load_joint_data(tmp_path / "cols.csv")
    msg = str(err.value)
    assert "cols.csv: missing column(s) ['torque_Nm']" in msg
    assert "expected ['t_s', 'position_rad', 'torque_Nm']" in msg
    assert "found ['t_s', 'position_rad', 'force_N']" in msg
    _csv(tmp_path / "dup.csv", "t_s,position_rad,torque_Nm,t_s", _good_rows())
    with pytest.raises(DataError, match=r"duplicate column\(s\) \['t_s'\]"):
        load_joint_data(tmp_path / "dup.csv")


def test_files_without_data_rows(tmp_path):
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(DataError, match=r"empty\.csv: is empty; expected a header row"):
        load_joint_data(tmp_path / "empty.csv")
    _csv(tmp_path / "head.csv", "t_s,position_rad,torque_Nm", ["", ""])
    with pytest.raises(DataError, match=r"head\.csv: has no data rows below the header"):
        load_joint_data(tmp_path / "head.csv")
    _csv(tmp_path / "one.csv", "t_s,position_rad,torque_Nm", ["0,0,0"])
    with pytest.raises(DataError, match=r"one\.csv: has 1 data row; a trial needs at least 2"):
        load_joint_data(tmp_path / "one.csv")


def test_non_numeric_cells_are_located(tmp_path):
    rows = _good_rows()
    rows[2] = "0.002,0.1,abc"
    _csv(tmp_path / "txt.csv", "t_s,position_rad,torque_Nm", rows)
    with pytest.raises(
        DataError, match=r"txt\.csv: non-numeric cell 'abc' at data row 3, column 'torque_Nm'"
    ):
        load_joint_data(tmp_path / "txt.csv")
    rows[2] = "0.002,,1"
    _csv(tmp_path / "blank.csv", "t_s,position_rad,torque_Nm", rows)
    with pytest.raises(DataError, match=r"non-numeric cell '' at data row 3, column 'position_rad'"):
        load_joint_data(tmp_path / "blank.csv")
    rows[2] = "0.002,0.1"
    _csv(tmp_path / "short.csv", "t_s,position_rad,torque_Nm", rows)
    with pytest.raises(DataError, match=r"short\.csv: data row 3 has 2 cell\(s\), the header has 3 columns"):
        load_joint_data(tmp_path / "short.csv")


def test_nan_and_inf_are_counted_with_the_first_row(tmp_path):
    rows = _good_rows()
    rows[3], rows[7] = "0.003,nan,1", "0.007,1,-inf"
    _csv(tmp_path / "nan.csv", "t_s,position_rad,torque_Nm", rows)
    with pytest.raises(
        DataError, match=r"nan\.csv: 2 NaN or inf value\(s\); the first in column 'position_rad' at row 4"
    ):
        load_joint_data(tmp_path / "nan.csv")


def test_time_must_increase_strictly_and_uniformly(tmp_path):
    rows = _good_rows()
    rows[5] = "0.004" + rows[5][5:]  # repeats row 5's time
    _csv(tmp_path / "back.csv", "t_s,position_rad,torque_Nm", rows)
    with pytest.raises(
        DataError, match=r"back\.csv: time is not strictly increasing at row 6: t_s = 0\.004 s"
    ):
        load_joint_data(tmp_path / "back.csv")
    t, p, q = _signals()
    t[50:] += 0.005
    _csv(
        tmp_path / "gap.csv",
        "t_s,position_rad,torque_Nm",
        [f"{a:.6f},{b},{c}" for a, b, c in zip(t, p, q, strict=True)],
    )
    with pytest.raises(DataError) as err:
        load_joint_data(tmp_path / "gap.csv")
    msg = str(err.value)
    assert "gap.csv: non-uniform sampling: the interval 0.006 s between rows 50 and 51" in msg
    assert "median interval 0.001 s" in msg
    # within tolerance (1e-6 of the step + 1e-9 s): a 1e-10 s jitter passes
    t, p, q = _signals()
    _csv(
        tmp_path / "jit.csv",
        "t_s,position_rad,torque_Nm",
        [f"{a + 1e-10 * (i % 2):.12f},{b},{c}" for i, (a, b, c) in enumerate(zip(t, p, q, strict=True))],
    )
    assert load_joint_data(tmp_path / "jit.csv")[0].fs_hz == pytest.approx(1000.0, rel=1e-6)


def test_min_duration(tmp_path):
    _csv(tmp_path / "short.csv", "t_s,position_rad,torque_Nm", _good_rows(100))
    assert load_joint_data(tmp_path / "short.csv", min_duration_s=0.1)[0].duration_s == pytest.approx(0.1)
    with pytest.raises(
        DataError, match=r"short\.csv: trial 'short' lasts 0\.1 s, shorter than min_duration_s = 1 s"
    ):
        load_joint_data(tmp_path / "short.csv", min_duration_s=1.0)
    with pytest.raises(DataError, match="min_duration_s must be a finite number of seconds >= 0"):
        load_joint_data(tmp_path / "short.csv", min_duration_s=-1.0)


def test_path_errors(tmp_path):
    with pytest.raises(
        DataError, match=r"nowhere\.csv does not exist; expected a \.csv or \.mat file or a folder"
    ):
        load_joint_data(tmp_path / "nowhere.csv")
    (tmp_path / "notes.txt").write_text("hi")
    with pytest.raises(
        DataError, match=r"notes\.txt: unsupported file type '\.txt'; supported: \['\.csv', '\.mat'\]"
    ):
        load_joint_data(tmp_path / "notes.txt")
    (tmp_path / "sub").mkdir()
    _csv(tmp_path / "sub" / "deep.csv", "t_s,position_rad,torque_Nm", _good_rows())
    with pytest.raises(
        DataError, match=r"no trial files; looked for \*\.csv, \*\.mat directly in the folder"
    ):
        load_joint_data(tmp_path)


# --- folders --------------------------------------------------------------------------------------
def test_folder_reads_csv_and_mat_in_name_order_not_recursively(tmp_path):
    t, p, q = _signals()
    for name in ("b", "a"):
        write_joint_csv(tmp_path / f"{name}.csv", t_s=t, position=p, torque=q)
    trial = {"t_s": t, "position_rad": p, "torque_Nm": q}
    scipy.io.savemat(tmp_path / "c.mat", {"y": trial, "x": trial})
    (tmp_path / "sub").mkdir()
    write_joint_csv(tmp_path / "sub" / "0.csv", t_s=t, position=p, torque=q)
    (tmp_path / "readme.txt").write_text("ignored")
    recs = load_joint_data(tmp_path)
    assert [r.name for r in recs] == ["a", "b", "c/x", "c/y"]
    assert [r.path.name for r in recs] == ["a.csv", "b.csv", "c.mat", "c.mat"]


def test_folder_sample_rates_must_agree(tmp_path):
    for name, fs in (("fast", 1000.0), ("slow", 500.0)):
        t, p, q = _signals(fs=fs)
        write_joint_csv(tmp_path / f"{name}.csv", t_s=t, position=p, torque=q)
    with pytest.raises(DataError, match=r"different sample rates \(fast: 1000 Hz, slow: 500 Hz\)"):
        load_joint_data(tmp_path)


def test_folder_trial_names_must_be_unique(tmp_path):
    t, p, q = _signals()
    write_joint_csv(tmp_path / "a.csv", t_s=t, position=p, torque=q)
    scipy.io.savemat(tmp_path / "a.mat", {"t_s": t, "position_rad": p, "torque_Nm": q})
    with pytest.raises(DataError, match=r"several trials named \['a'\]"):
        load_joint_data(tmp_path)


# --- MATLAB files ---------------------------------------------------------------------------------
def test_plain_mat_variables_v5_and_v73(tmp_path):
    matio, _ = _matio()
    t, p, q = _signals(fs=250.0)
    scipy.io.savemat(tmp_path / "v5.mat", {"t_s": t, "position_rad": p, "torque_Nm": q, "note": "x"})
    matio.save_to_mat(tmp_path / "v73.mat", {"position": p, "torque": q, "fs_hz": 250.0})
    scipy.io.savemat(tmp_path / "st.mat", {"trial": {"position": p, "torque": q, "fs_hz": 250.0}})
    for name in ("v5", "v73", "st"):
        (rec,) = load_joint_data(tmp_path / f"{name}.mat")
        assert rec.name == name and rec.fs_hz == pytest.approx(250.0, rel=1e-12)
        np.testing.assert_array_equal(rec.position, p)  # binary: exact
        np.testing.assert_array_equal(rec.torque, q)
        np.testing.assert_allclose(rec.t_s, t, rtol=0, atol=1e-12)


def test_mat_table(tmp_path):
    pd = pytest.importorskip("pandas")
    matio, _ = _matio()
    t, p, q = _signals()
    matio.save_to_mat(
        tmp_path / "tab.mat", {"tab": pd.DataFrame({"t_s": t, "position_rad": p, "torque_Nm": q})}
    )
    (rec,) = load_joint_data(tmp_path / "tab.mat")
    np.testing.assert_array_equal(rec.torque, q)


def test_plain_mat_errors(tmp_path):
    t, p, q = _signals()
    scipy.io.savemat(tmp_path / "notime.mat", {"position": p, "torque": q})
    with pytest.raises(DataError, match=r"notime\.mat: has 'position' and 'torque' but no time; add 't_s'"):
        load_joint_data(tmp_path / "notime.mat")
    scipy.io.savemat(tmp_path / "fs.mat", {"t_s": t, "position": p, "torque": q, "fs_hz": 500.0})
    with pytest.raises(DataError, match=r"'fs_hz' = 500 Hz but 't_s' gives 1000 Hz"):
        load_joint_data(tmp_path / "fs.mat")
    scipy.io.savemat(tmp_path / "len.mat", {"t_s": t, "position": p[:-1], "torque": q})
    with pytest.raises(DataError, match="differ in length"):
        load_joint_data(tmp_path / "len.mat")
    scipy.io.savemat(tmp_path / "nan.mat", {"t_s": t, "position": np.where(t > 0.05, np.nan, p), "torque": q})
    with pytest.raises(
        DataError, match=r"nan\.mat: 49 NaN or inf value\(s\); the first in column 'position' at sample 52"
    ):
        load_joint_data(tmp_path / "nan.mat")
    scipy.io.savemat(tmp_path / "other.mat", {"emg": {"v": p}, "x": p})
    with pytest.raises(DataError) as err:
        load_joint_data(tmp_path / "other.mat")
    assert "cannot map variable(s) ['emg', 'x']" in str(err.value)
    assert "emg (struct/table with fields ['v'])" in str(err.value)
    (tmp_path / "junk.mat").write_bytes(b"not a mat file at all" * 10)
    with pytest.raises(DataError, match=r"junk\.mat: not a readable MATLAB file"):
        load_joint_data(tmp_path / "junk.mat")


def test_nldat_channels_identified_by_name_and_units(tmp_path):
    matio, Opaque = _matio()
    t, p, q = _signals(50)
    emg = np.where(t > 0.01, np.abs(q), np.nan)  # an ignored channel is not checked
    objs = {
        "io": _nldat(Opaque, np.column_stack([p, q]), ["posPert1", "tqPert1"], ["Default Units"]),
        "sv": _nldat(
            Opaque, (p / 3)[:, None], ["Scheduling Variable (SV) - Ankle Position (rad)"], ["(rad)"]
        ),
    }
    matio.save_to_mat(tmp_path / "pilot.mat", objs, version="v7")
    (rec,) = load_joint_data(tmp_path / "pilot.mat")  # one trial: named by the file, sv its operating point
    assert rec.name == "pilot" and rec.fs_hz == 1000.0
    np.testing.assert_array_equal(rec.position, p)
    np.testing.assert_array_equal(rec.operating_point, p / 3)
    # channels known only by units, plus an extra channel that is ignored; order of channels free
    objs = {
        "a": _nldat(Opaque, np.column_stack([emg, q, p]), ["emg", "ch2", "ch1"], ["V", "N m", "rad"]),
        "b": _nldat(Opaque, np.column_stack([q, p]), ["Torque", "Angle"], ["Nm", "rad"], incr=1e-3),
    }
    matio.save_to_mat(tmp_path / "two.mat", objs)
    recs = load_joint_data(tmp_path / "two.mat")
    assert [r.name for r in recs] == ["two/a", "two/b"]
    for r in recs:
        np.testing.assert_array_equal(r.position, p)
        np.testing.assert_array_equal(r.torque, q)


def test_nldat_errors(tmp_path):
    matio, Opaque = _matio()
    t, p, q = _signals(50)
    cases = {
        "deg": (
            ["pos", "tq"],
            ["deg", "Nm"],
            r"position channel 'pos' has units 'deg'; accepted: rad or unset",
        ),
        "both": (
            ["postq", "tq position"],
            ["Default Units"],
            r"channel 'tq position' names both a position and a torque",
        ),
        "units": (["pos", "tq"], ["rad", "Nm", "V"], r"2 channel name\(s\) \['pos', 'tq'\] but 3 unit\(s\)"),
    }
    cases["nan"] = (
        ["pos", "tq"],
        ["Default Units"],
        r"nan\.mat: variable 'x': 1 NaN or inf value\(s\); the first in column 'tq' at sample 3",
    )
    for name, (names, units, match) in cases.items():
        data = np.column_stack([p, np.where(t == t[2], np.nan, q) if name == "nan" else q])
        matio.save_to_mat(tmp_path / f"{name}.mat", {"x": _nldat(Opaque, data, names, units)})
        with pytest.raises(DataError, match=match):
            load_joint_data(tmp_path / f"{name}.mat")
    objs = {
        "z": _nldat(Opaque, np.column_stack([p, q]), ["pos", "tq"], ["Default Units"]),
        "emg": _nldat(Opaque, q[:, None], ["EMG TA"], ["V"]),
        "k": Opaque(properties={"a": np.array([[1.0]])}, classname="foo"),
        "two": _nldat(Opaque, np.column_stack([p, q, q]), ["pos", "tq", "tq"], ["Default Units"]),
    }
    matio.save_to_mat(tmp_path / "mixed.mat", objs)
    with pytest.raises(DataError) as err:
        load_joint_data(tmp_path / "mixed.mat")
    msg = str(err.value)
    assert "mixed.mat: cannot map variable(s) ['emg', 'k', 'two'] to a position and a torque channel" in msg
    assert "emg (nldat, channels ['EMG TA'])" in msg and "k (foo object)" in msg and "z (nldat" in msg


# --- the REKLAB recordings ------------------------------------------------------------------------
def test_reklab_stationary_csvs_are_60_s_at_1_khz(reklab):
    t0 = time.perf_counter()
    (one,) = load_joint_data(reklab / "z_df.csv")
    assert time.perf_counter() - t0 < 1.0  # 60 000 rows; ~0.03 s measured
    recs = {r.name: r for r in load_joint_data(reklab)}
    assert set(STATIONARY) <= set(recs)
    for name in STATIONARY:
        r = recs[name]
        assert r.fs_hz == pytest.approx(1000.0, rel=1e-9) and r.duration_s == pytest.approx(60.0, rel=1e-9)
        assert r.position.shape == r.torque.shape == (60000,) and r.operating_point is None
    np.testing.assert_array_equal(one.torque, recs["z_df"].torque)
    # the REKLAB loader reads through this module
    np.testing.assert_array_equal(load_ankle_trial("z_df", reklab).torque, one.torque)


# Tolerance of the .mat/CSV comparison: the CSVs were written from these doubles with 9 significant
# digits, so each value differs by at most half a unit of the 9th digit, <= 5e-9 relative (plus
# ~1e-16 of decimal parsing); time was printed with 1 ms resolution from k * 0.001, ~1e-14 s off.
_CSV_RTOL = 5.000001e-9


def test_reklab_mat_trials_are_the_csv_trials(reklab):
    if not (RAW / "experimental_data.mat").is_file():
        pytest.skip(f"REKLAB raw .mat files not present at {RAW}")
    mats = {r.name: r for r in load_joint_data(RAW / "experimental_data.mat")}
    assert sorted(mats) == [f"experimental_data/{n}" for n in STATIONARY]
    for name in STATIONARY:
        m, (c,) = mats[f"experimental_data/{name}"], load_joint_data(reklab / f"{name}.csv")
        assert m.fs_hz == 1000.0 and m.n_samples == c.n_samples == 60000
        np.testing.assert_allclose(m.t_s, c.t_s, rtol=0, atol=1e-12)
        np.testing.assert_allclose(c.position, m.position, rtol=_CSV_RTOL, atol=0)
        np.testing.assert_allclose(c.torque, m.torque, rtol=_CSV_RTOL, atol=0)
    (pilot,) = load_joint_data(RAW / f"{PILOT}.mat")
    (tv,) = load_joint_data(reklab / "tv_pilot.csv")
    assert pilot.name == PILOT and pilot.n_samples == 106000 and pilot.fs_hz == 1000.0
    np.testing.assert_allclose(tv.position, pilot.position, rtol=_CSV_RTOL, atol=0)
    np.testing.assert_allclose(tv.torque, pilot.torque, rtol=_CSV_RTOL, atol=0)
    np.testing.assert_allclose(tv.operating_point, pilot.operating_point, rtol=_CSV_RTOL, atol=0)
