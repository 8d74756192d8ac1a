"""Tests of armlab.data.h5io: round trips, layout, overwrite safety and corrupt-file diagnostics."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from armlab.data import FORMAT_NAME, FORMAT_VERSION, TrialSet, read_trials, write_trials
from armlab.errors import DataError

N_TRIALS, N_SAMPLES = 4, 60


def _trials(seed: int = 0, **attrs_extra) -> TrialSet:
    rng = np.random.default_rng(seed)
    attrs = {
        "protocol": "conditioning",
        "seed": 1234,
        "config_yaml": "arm:\n  l1: 0.3\n" + "# padding\n" * 1000,  # > 8 KiB: stored as a dataset
        "arm_l1_m": 0.31,
        "arm_l2_m": 0.34,
        "simulated": True,
        "note": None,
        "ground_truth": {
            "K": np.array([[300.0, 50.0], [50.0, 200.0]]),
            "D": np.array([[10.0, 1.0], [1.0, 8.0]]),
            "xi": 0.12,
            "per_window": {"k": [1, 2, 3], "labels": ["a", "b", "c"]},
        },
        "ints": [1, 2, 3],
        "matrix_list": [[1.0, 2.0], [3.0, 4.0]],
        "flags": [True, False],
        "mixed": [1, "two", 3.0, {"four": 4}, [5, 6]],
        "ragged": [[1, 2], [3]],
        "mixed_numbers": [1, 2.5],
        "empty_list": [],
        "empty_dict": {},
        "int_array": np.arange(5, dtype=np.int32),
        "str_array": np.array(["x", "yy"]),
        "scalar_array": np.array(2.5),
    }
    attrs.update(attrs_extra)
    return TrialSet(
        fs_hz=1000.0,
        onset_index=np.array([10, 12, 11, 15]),
        channels={
            "hand_pos": rng.normal(size=(N_TRIALS, N_SAMPLES, 2)),
            "hand_force": rng.normal(size=(N_TRIALS, N_SAMPLES, 2)),
            "robot_q": rng.normal(size=(N_TRIALS, N_SAMPLES, 7)),
        },
        units={"hand_pos": "m", "hand_force": "N", "robot_q": "rad"},
        trial_meta={
            "group": np.array([1, 1, 2, 2]),
            "direction": np.array([0, 3, 5, 1]),
            "T_k_s": np.array([0.1, 0.1, 0.2, 0.2]),
            "wait_s": np.array([1.5, 2.0, 1.2, 1.9]),
            "validate": np.array([False, True, False, False]),
            "subject": np.array(["s01", "s01", "s02", "s02"]),
        },
        attrs=attrs,
    )


def _assert_same(a, b, where="attrs"):
    assert type(a) is type(b), f"{where}: {type(a).__name__} != {type(b).__name__}"
    if isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            _assert_same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b), where
    else:
        assert a == b, where


def test_round_trip_is_exact(tmp_path):
    ts = _trials()
    path = write_trials(tmp_path / "trials.h5", ts)
    back = read_trials(path)
    assert back.fs_hz == ts.fs_hz
    assert np.array_equal(back.onset_index, ts.onset_index)
    assert back.channels.keys() == ts.channels.keys()
    for k, v in ts.channels.items():
        assert back.channels[k].dtype == np.float64
        assert np.array_equal(back.channels[k], v)
    assert dict(back.units) == dict(ts.units)
    assert back.trial_meta.keys() == ts.trial_meta.keys()
    for k, v in ts.trial_meta.items():
        assert back.trial_meta[k].dtype.kind == v.dtype.kind, k
        assert np.array_equal(back.trial_meta[k], v), k
    _assert_same(dict(ts.attrs), dict(back.attrs))
    assert list(tmp_path.iterdir()) == [path]  # no temporary files left behind


def test_layout_matches_the_contract(tmp_path):
    path = write_trials(tmp_path / "trials.h5", _trials())
    with h5py.File(path, "r") as f:
        assert f.attrs["format"] == FORMAT_NAME == "armlab-trials"
        assert f.attrs["format_version"] == FORMAT_VERSION == 1
        ds = f["channels/robot_q"]
        assert ds.dtype == np.float64 and ds.shape == (N_TRIALS, N_SAMPLES, 7)
        assert ds.chunks == (1, N_SAMPLES, 7)
        assert ds.compression == "gzip" and ds.compression_opts == 1 and ds.shuffle
        assert ds.attrs["unit"] == "rad"
        assert f["onset_index"].shape == (N_TRIALS,)
        assert f["trial_meta/group"].shape == (N_TRIALS,)
        assert f["attrs"].attrs["protocol"] == "conditioning"
        assert isinstance(f["attrs/ground_truth"], h5py.Group)
        assert f["attrs/ground_truth/K"].shape == (2, 2)


def test_refuses_to_overwrite_and_keeps_original_bytes(tmp_path):
    path = tmp_path / "trials.h5"
    write_trials(path, _trials(seed=0))
    original = path.read_bytes()
    with pytest.raises(DataError, match=r"trials\.h5 already exists; pass overwrite=True"):
        write_trials(path, _trials(seed=1))
    assert path.read_bytes() == original
    write_trials(path, _trials(seed=1), overwrite=True)
    assert path.read_bytes() != original
    assert np.array_equal(read_trials(path).channels["hand_pos"], _trials(seed=1).channels["hand_pos"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["trials.h5"]


def test_write_errors_leave_nothing_behind(tmp_path):
    with pytest.raises(DataError, match="cannot store a set"):
        write_trials(tmp_path / "a.h5", _trials(bad={1, 2}))
    ts = _trials()
    ts.channels["hand_force"][2, 7, 1] = np.nan
    with pytest.raises(DataError, match=r"'hand_force' has NaN/inf in trial\(s\) \[2\]"):
        write_trials(tmp_path / "b.h5", ts)
    with pytest.raises(DataError, match="does not exist"):
        write_trials(tmp_path / "missing_dir" / "c.h5", _trials())
    assert list(tmp_path.iterdir()) == []


def _corrupt(tmp_path: Path, edit) -> Path:
    path = write_trials(tmp_path / "trials.h5", _trials())
    with h5py.File(path, "a") as f:
        edit(f)
    return path


def _replace(f: h5py.File, name: str, data, unit: str | None = None) -> None:
    del f[name]
    f[name] = data
    if unit is not None:
        f[name].attrs["unit"] = unit


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda f: f.attrs.__setitem__("format", "other"), r"format is 'other', expected 'armlab-trials'"),
        (
            lambda f: f.attrs.__setitem__("format_version", 2),
            r"format_version is 2; this armlab reads version 1",
        ),
        (lambda f: f.attrs.__delitem__("fs_hz"), r"'fs_hz' \(sample rate, Hz\) is missing"),
        (lambda f: f.__delitem__("onset_index"), r"required dataset 'onset_index' is missing"),
        (lambda f: f.__delitem__("channels"), r"required group 'channels' is missing"),
        (
            lambda f: _replace(f, "channels/hand_pos", np.zeros((3, 10, 2)), "m"),
            r"channel 'hand_pos' has shape \(3, 10, 2\) but onset_index says 4 trials",
        ),
        (
            lambda f: _replace(f, "channels/hand_pos", np.zeros((4, 10, 2)), "m"),
            r"channel '(hand_pos|hand_force|robot_q)' has \d+ samples, other channels \d+",
        ),
        (lambda f: _replace(f, "channels/hand_pos", np.zeros((4, 60))), r"'hand_pos' must be a 3-D dataset"),
        (lambda f: f["channels/robot_q"].attrs.__delitem__("unit"), r"channel 'robot_q' has no 'unit' attr"),
        (
            lambda f: f["channels/hand_force"].__setitem__((1, 30, 0), np.nan),
            r"channel 'hand_force' has NaN/inf in trial\(s\) \[1\] \(first at trial 1, sample 30\)",
        ),
        (
            lambda f: _replace(f, "trial_meta/group", np.array([1, 2])),
            r"trial_meta 'group' has shape \(2,\) but onset_index says 4 trials",
        ),
        (lambda f: _replace(f, "onset_index", np.array([0, 1, 2, 3])), r"onset_index must lie in \[1, 59\]"),
        (lambda f: _replace(f, "onset_index", np.array([1.0, 2, 3, 4])), r"1-D integer array"),
    ],
)
def test_corrupt_files_raise_data_error_naming_the_problem(tmp_path, edit, match):
    path = _corrupt(tmp_path, edit)
    with pytest.raises(DataError, match=match) as info:
        read_trials(path)
    assert str(path) in str(info.value)


def test_missing_and_non_hdf5_files(tmp_path):
    with pytest.raises(DataError, match="no such file"):
        read_trials(tmp_path / "nope.h5")
    text = tmp_path / "notes.h5"
    text.write_text("not hdf5")
    with pytest.raises(DataError, match="not a readable HDF5 file"):
        read_trials(text)


def test_zero_trial_set_round_trips(tmp_path):
    empty = _trials().select(np.zeros(N_TRIALS, dtype=bool))
    back = read_trials(write_trials(tmp_path / "empty.h5", empty))
    assert back.n_trials == 0 and back.channels["robot_q"].shape == (0, N_SAMPLES, 7)
