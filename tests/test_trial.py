"""Tests of armlab.data.trial: TrialSet validation and selection."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.data import TrialSet
from armlab.errors import DataError


def _kwargs(n_trials: int = 5, n_samples: int = 20) -> dict:
    return {
        "fs_hz": 1000.0,
        "onset_index": np.arange(1, n_trials + 1),
        "channels": {
            "hand_pos": np.arange(n_trials * n_samples * 2, dtype=float).reshape(n_trials, n_samples, 2),
            "hand_force": np.ones((n_trials, n_samples, 2)),
        },
        "units": {"hand_pos": "m", "hand_force": "N"},
        "trial_meta": {"group": np.arange(n_trials) % 2 + 1, "validate": np.arange(n_trials) == 0},
        "attrs": {"protocol": "conditioning"},
    }


def test_properties():
    ts = TrialSet(**_kwargs())
    assert ts.n_trials == 5 and ts.n_samples == 20
    np.testing.assert_allclose(ts.t, np.arange(20) / 1000.0)
    assert ts.channel("hand_force") is ts.channels["hand_force"]


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"fs_hz": 0.0}, "fs_hz must be a positive number"),
        ({"fs_hz": float("nan")}, "fs_hz must be a positive number"),
        ({"channels": {}, "units": {}}, "at least one channel"),
        (
            {"channels": {"hand_pos": np.zeros((5, 20))}, "units": {"hand_pos": "m"}},
            r"\(n_trials, n_samples, n_axes\)",
        ),
        (
            {
                "channels": {"a": np.zeros((5, 20, 1)), "b": np.zeros((5, 19, 1))},
                "units": {"a": "m", "b": "m"},
            },
            r"share \(n_trials, n_samples\)",
        ),
        ({"units": {"hand_pos": "m"}}, r"channels without a unit: \['hand_force'\]"),
        ({"onset_index": np.arange(1, 5)}, r"onset_index must have shape \(5,\)"),
        ({"onset_index": np.array([0, 1, 2, 3, 4])}, r"onset_index must lie in \[1, 19\]"),
        ({"onset_index": np.array([1, 2, 3, 4, 20])}, r"onset_index must lie in \[1, 19\]"),
        ({"trial_meta": {"group": np.arange(4)}}, r"trial_meta\['group'\] must have shape \(5,\)"),
    ],
)
def test_validation_errors(change, match):
    kwargs = _kwargs() | change
    with pytest.raises(DataError, match=match):
        TrialSet(**kwargs)


def test_unknown_channel_lists_available():
    with pytest.raises(DataError, match=r"no channel 'emg'; available: \['hand_force', 'hand_pos'\]"):
        TrialSet(**_kwargs()).channel("emg")


def test_select_by_mask_and_by_index():
    ts = TrialSet(**_kwargs())
    mask = np.array([True, False, True, False, False])
    sub = ts.select(mask)
    assert sub.n_trials == 2 and sub.fs_hz == ts.fs_hz
    assert np.array_equal(sub.onset_index, [1, 3])
    assert np.array_equal(sub.channels["hand_pos"], ts.channels["hand_pos"][[0, 2]])
    assert np.array_equal(sub.trial_meta["group"], [1, 1])
    assert np.array_equal(sub.trial_meta["validate"], [True, False])
    assert dict(sub.units) == dict(ts.units) and dict(sub.attrs) == dict(ts.attrs)
    by_index = ts.select(np.array([4, 1]))
    assert np.array_equal(by_index.onset_index, [5, 2])
    assert np.array_equal(by_index.channels["hand_pos"], ts.channels["hand_pos"][[4, 1]])
    # selecting by a metadata condition, as the protocol does for the validation trial
    held_out = ts.select(~np.asarray(ts.trial_meta["validate"]))
    assert held_out.n_trials == 4
    assert ts.n_trials == 5  # the original is unchanged
