"""The EMG maps of seed paper 001 (Sec. 2.5, 4.1; spec 001 check 8) from the run's trial file.

Each disturbance contributes its 8 electrodes' stretch of 400 samples (200 ms at 2 kHz; where in the
record: ``estimation.emg_map_start_s``, by default the 200 ms before the onset, the working point
K_q describes), full-wave rectified and cut into windows of 70 samples (5 per disturbance); each
window's features are the per-channel maxima (:mod:`armlab.estimation.emg_features`; with
``estimation.emg_sparse_features`` followed by sparse-filtering layers,
:mod:`armlab.estimation.sparse_filtering`, trained on each training set) and its
target the perturbation-estimated K_q of its condition (the SPD estimate of Eqs. (16)-(19)). The
network of Eq. (20) and the ridge baseline (:mod:`armlab.estimation.emg_stiffness`) are compared by
NRMSE under two splits (spec 001):

- **random windows**: test and validation windows drawn at random from every condition (the
  paper's split, as far as it says; with only one target per condition it leaks the labels);
  hyper-parameters by the random search on the validation windows, NRMSE on the test windows;
- **leave one condition out**: each condition in turn predicted by maps trained on the others;
  the hyper-parameters chosen once, by the random search over k validation conditions
  (``estimation.emg_loco_validation``, 3: one condition kept out, each of k others validated by
  maps trained on the rest, the mean score picks; one validation condition alone made the pick,
  and with it the verdict, a draw of luck), then one map per fold; NRMSE over the pooled
  out-of-fold predictions of every window.

Entries of K_q that the conditions do not change (the truth equal in every condition: no muscle
spans both joints, e.g. elbow-shoulder rotation) have no spread to normalise by and carry no
information on the map; they are left out of the NRMSE and named in the results. One generator
(``[seed, 4]``) draws the splits and the searches.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.data.trial import TrialSet
from armlab.errors import DataError
from armlab.estimation.emg_features import MAP_SAMPLES, Standardiser, emg_windows, max_features
from armlab.estimation.emg_stiffness import (
    ValidationSplit,
    fit_linear,
    fit_network,
    lower_entries,
    nrmse,
    search_linear,
    search_network,
)
from armlab.estimation.sparse_filtering import fit_sparse_filter
from armlab.protocols.stiffness_5dof_emg.config import EstimationConfig

__all__ = [
    "MIN_EMG_CONDITIONS",
    "PAPER_LINEAR_NRMSE",
    "PAPER_NETWORK_NRMSE",
    "PAPER_RATIO",
    "EmgMap",
    "estimate_emg_map",
]

PAPER_NETWORK_NRMSE = 0.3378  # paper Sec. 4.1: "average normalized root mean squared error ... 0.3378"
PAPER_LINEAR_NRMSE = 0.39  # paper Sec. 4.1: "a linear model never achieved 0.39 or better"
# 0.866: the network's NRMSE over the linear's, at most (paper Sec. 4.1)
PAPER_RATIO = PAPER_NETWORK_NRMSE / PAPER_LINEAR_NRMSE
_JOINTS = ("sh_flex", "sh_abd", "sh_rot", "elbow", "pron")
ENTRY_NAMES = tuple(lower_entries(np.array([[f"K[{a},{b}]" for b in _JOINTS] for a in _JOINTS])))
# leave-one-out's search: a kept-out, a validation and two training conditions
MIN_EMG_CONDITIONS = 4


@dataclass(frozen=True, kw_only=True, eq=False)
class EmgMap:
    """The EMG stage's estimate: ``results`` (JSON-able), ``checks`` (spec 001 check 8 rows) and
    ``series`` (the NRMSE figure's numbers: ``splits``, ``network``, ``linear``)."""

    results: dict
    checks: list
    series: dict


def _split_result(net_pred, lin_pred, Z, K_true_w, entries, net_params, lin_params) -> dict:
    net, lin = nrmse(net_pred, Z, entries), nrmse(lin_pred, Z, entries)
    return {
        "network_nrmse": net,
        "linear_nrmse": lin,
        "ratio": net / lin,
        # the same predictions against the true K_q of each window's condition
        "network_nrmse_vs_truth": nrmse(net_pred, K_true_w, entries),
        "linear_nrmse_vs_truth": nrmse(lin_pred, K_true_w, entries),
        "network_params": net_params,
        "linear_ridge": lin_params["ridge"],
        "n_test_windows": int(len(Z)),
    }


def _phi(F: np.ndarray, train, est: EstimationConfig, rng) -> np.ndarray:
    """Every window's features from what the training windows teach: the maxima standardised and,
    with ``estimation.emg_sparse_features``, the sparse-filtering layers (trained on the training
    windows only) standardised again."""
    X = Standardiser.fit(F[train])(F)
    if not est.emg_sparse_features:
        return X
    Y = fit_sparse_filter(X[train], tuple(est.emg_sparse_features), rng)(X)
    return Standardiser.fit(Y[train])(Y)


def _random_split(F, Z, K_true_w, entries, est: EstimationConfig, rng) -> dict:
    n = len(F)
    order = rng.permutation(n)
    n_test, n_val = int(round(est.emg_test_fraction * n)), int(round(est.emg_val_fraction * n))
    test, val, train = order[:n_test], order[n_test : n_test + n_val], order[n_test + n_val :]
    X = _phi(F, train, est, rng)
    split = [ValidationSplit(X=X[train], Z=Z[train], X_val=X[val], Z_val=Z[val])]
    net = search_network(split, rng, est.emg_search_draws, n_hidden=est.emg_hidden, entries=entries)
    lin = search_linear(split, entries)
    return _split_result(
        net.model.predict(X[test]),
        lin.model.predict(X[test]),
        Z[test],
        K_true_w[test],
        entries,
        net.params,
        lin.params,
    )


def _condition_split(F, Z, train, val, est: EstimationConfig, rng) -> ValidationSplit:
    """Train on ``train``, validate on the condition ``val`` (normalised by the training targets'
    spread: one condition has none)."""
    X = _phi(F, train, est, rng)
    return ValidationSplit(
        X=X[train], Z=Z[train], X_val=X[val], Z_val=Z[val], scale=lower_entries(Z[train]).std(axis=0)
    )


def _loco_split(F, Z, K_true_w, cond, n_c, entries, est: EstimationConfig, rng) -> dict:
    # the hyper-parameters: one condition h0 kept out, each of k others validated in turn by maps
    # trained on the rest; the mean validation NRMSE picks (the same splits for both models)
    h0 = int(rng.integers(n_c))
    others = np.array([c for c in range(n_c) if c != h0])
    # each split trains on every condition but h0 and its validation one: any of the others can validate
    vals = rng.choice(others, size=min(est.emg_loco_validation, len(others)), replace=False)
    splits = [_condition_split(F, Z, (cond != h0) & (cond != v), cond == v, est, rng) for v in vals]
    net = search_network(splits, rng, est.emg_search_draws, n_hidden=est.emg_hidden, entries=entries)
    lin = search_linear(splits, entries)
    net_pred, lin_pred = np.empty_like(Z), np.empty_like(Z)
    for h in range(n_c):
        train, test = cond != h, cond == h
        X = _phi(F, train, est, rng)
        model = fit_network(X[train], Z[train], rng, n_hidden=est.emg_hidden, **net.params)
        net_pred[test] = model.predict(X[test])
        lin_pred[test] = fit_linear(X[train], Z[train], lin.params["ridge"]).predict(X[test])
    out = _split_result(net_pred, lin_pred, Z, K_true_w, entries, net.params, lin.params)
    out["search_conditions"] = {"kept_out": h0, "validation": [int(v) for v in vals]}
    return out


def estimate_emg_map(
    trials: TrialSet, K_hat: np.ndarray, K_true: np.ndarray, names: list[str], est: EstimationConfig
) -> EmgMap:
    """The EMG maps of the run (module docstring).

    Args:
        trials: the run's trials with channel ``emg`` (n_trials, n_samples, 8) mV.
        K_hat: (n_c, 5, 5) N·m/rad the perturbation-estimated K_q per condition (the targets).
        K_true: (n_c, 5, 5) N·m/rad the truth per condition (which entries vary; NRMSE vs truth).
        names: (n_c,) the conditions. est: the estimation settings (``emg_*``).

    Raises:
        DataError: no ``emg`` channel, fewer than 4 conditions, or the map's stretch outside the record.
    """
    if "emg" not in trials.channels:
        raise DataError("the trial file has no 'emg' channel: run with 'emg' in stages")
    n_c = len(names)
    if n_c < MIN_EMG_CONDITIONS:
        raise DataError(
            f"the EMG maps need at least {MIN_EMG_CONDITIONS} conditions (leave-one-condition-out: test, "
            f"validation and two to train on), the run has {n_c}: {names}"
        )
    fs = trials.fs_hz
    onset = int(np.asarray(trials.onset_index)[0])
    start = onset + int(round(est.emg_map_start_s * fs))
    windows = emg_windows(trials.channels["emg"], start, MAP_SAMPLES, est.emg_window_samples)
    n_win = windows.shape[1]
    F = max_features(windows).reshape(-1, windows.shape[-1])  # (n_trials * n_win, 8) mV
    cond = np.repeat(np.asarray(trials.trial_meta["condition"], int), n_win)
    Z, K_true_w = np.asarray(K_hat, float)[cond], np.asarray(K_true, float)[cond]
    spread = lower_entries(np.asarray(K_true, float)).std(axis=0)
    # entries equal in every condition (spread only rounding) have no std to normalise by: left out
    entries = spread > 1e-9 * spread.max()
    rng = np.random.default_rng([int(trials.attrs.get("seed", 0)), 4])
    random = _random_split(F, Z, K_true_w, entries, est, rng)
    loco = _loco_split(F, Z, K_true_w, cond, n_c, entries, est, rng)
    results = {
        "n_windows": int(len(F)),
        "windows_per_disturbance": int(n_win),
        "window_samples": int(est.emg_window_samples),
        "map_start_s": float(est.emg_map_start_s),
        "features": "per-channel maximum of the rectified window"
        + (
            f", then sparse-filtering layers of {list(est.emg_sparse_features)} features"
            if est.emg_sparse_features
            else " (no sparse filtering)"
        ),
        "entries_left_out": [ENTRY_NAMES[k] for k in np.flatnonzero(~entries)],
        "random_windows": random,
        "leave_one_condition_out": loco,
        "paper": {"network_nrmse": PAPER_NETWORK_NRMSE, "linear_nrmse_at_best": PAPER_LINEAR_NRMSE},
    }
    checks = [
        {
            "check": 8,
            "what": f"EMG network NRMSE / linear NRMSE, {label} (paper: <= {PAPER_RATIO:.3f})",
            "value": split["ratio"],
            "tolerance": 1.0,
            "passed": bool(split["ratio"] < 1.0),
        }
        for label, split in (("random windows", random), ("leave one condition out", loco))
    ]
    series = {
        "splits": ["random windows", "leave one condition out"],
        "network": [random["network_nrmse"], loco["network_nrmse"]],
        "linear": [random["linear_nrmse"], loco["linear_nrmse"]],
        "paper_network": PAPER_NETWORK_NRMSE,
        "paper_linear": PAPER_LINEAR_NRMSE,
        "hidden": est.emg_hidden,
    }
    return EmgMap(results=results, checks=checks, series=series)
