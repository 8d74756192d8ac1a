"""Figures and Rerun recordings written from small synthetic results and trials."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import assert_png, verify_rrd

from armlab.data.trial import TrialSet
from armlab.errors import ConfigError, DataError
from armlab.viz import (
    plot_error_vs_window,
    plot_validation,
    plot_window_sweep,
    view_command,
    write_recording,
)

K_TRUE = [[12.0, 4.0], [4.0, 9.0]]
D_TRUE = [[1.2, 0.3], [0.3, 0.9]]
XI_TRUE = [0.391, 0.155, 0.149]


def _results(n_windows: int = 3) -> dict:
    """A results dict in the protocol's schema, estimates converging to the truth over k."""
    rng = np.random.default_rng(1)
    windows = []
    for k in range(1, n_windows + 1):
        scale = 1.0 / k
        K = (np.array(K_TRUE) + scale * rng.standard_normal((2, 2))).tolist()
        D = (np.array(D_TRUE) + 0.1 * scale * rng.standard_normal((2, 2))).tolist()
        xi = (np.array(XI_TRUE) * (1 + 0.1 * scale)).tolist()
        reduced = {
            "cond": 30.0 / k,
            "K": K,
            "D": D,
            "eig_Ks": np.linalg.eigvalsh(0.5 * (np.array(K) + np.array(K).T)).tolist(),
            "eig_Ds": np.linalg.eigvalsh(0.5 * (np.array(D) + np.array(D).T)).tolist(),
            "asym_K": 0.1 * scale,
            "asym_D": 0.1 * scale,
            "K_rel_err": 0.05 * scale,
            "D_rel_err": 0.08 * scale,
            "validation": {"vaf_pct": [90.0, 91.0], "rmse_Nm": [0.1, 0.1]},
        }
        windows.append(
            {
                "k": k,
                "T_k_s": 0.04 + 0.01 * k,
                "t_obs_s": 0.11 + 0.01 * k,
                "cond": 300.0 / k,
                "K": K,
                "D": D,
                "xi": xi,
                "eig_Ks": reduced["eig_Ks"],
                "eig_Ds": reduced["eig_Ds"],
                "asym_K": 0.2 * scale,
                "asym_D": 0.2 * scale,
                "K_rel_err": 0.1 * scale,
                "D_rel_err": 0.2 * scale,
                "xi_rel_err": 0.1 * scale if k > 1 else None,  # a missing value must not break the plots
                "K_true": K_TRUE,
                "D_true": D_TRUE,
                "xi_true": XI_TRUE,
                "validation": {"vaf_pct": [80.0, 85.0], "rmse_Nm": [0.2, 0.2]},
                "reduced": reduced,
            }
        )
    return {
        "protocol": "conditioning_window",
        "seed": 0,
        "ground_truth": {"K": K_TRUE, "D": D_TRUE, "xi": XI_TRUE, "q0": [0.08, 1.0]},
        "paper": {"K_pd_after_s": 0.32, "symmetric_after_s": 0.37, "constant_after_s": 0.40},
        "criteria": {
            "full": {"K_pd_from_s": 0.13, "symmetric_from_s": None, "constant_from_s": 0.14},
            "reduced": {"K_pd_from_s": 0.12, "symmetric_from_s": 0.13, "constant_from_s": None},
        },
        "windows": windows,
    }


def _trials(n_trials: int = 6, n_samples: int = 300, fs_hz: float = 1000.0) -> TrialSet:
    """Six trials over three windows with every channel the recording reads."""
    rng = np.random.default_rng(2)
    t = np.arange(n_samples) / fs_hz
    onset = np.array([80, 100, 90, 120, 60, 100])[:n_trials]
    s = np.clip((t[None, :] - onset[:, None] / fs_hz) / 0.1, 0.0, 1.0)
    ramp = s**3 * (10 - 15 * s + 6 * s**2)  # quintic point-to-point, Eq. (16) shape
    q = np.stack([0.08 + 0.05 * ramp, 1.0 - 0.05 * ramp], axis=-1)
    l1, l2 = 0.3, 0.35
    elbow = np.stack([l1 * np.cos(q[..., 0]), l1 * np.sin(q[..., 0]), np.zeros_like(ramp)], axis=-1)
    hand = elbow + np.stack([l2 * np.cos(q.sum(-1)), l2 * np.sin(q.sum(-1)), np.zeros_like(ramp)], axis=-1)
    arm_points = np.concatenate([np.zeros_like(elbow), elbow, hand], axis=-1)
    robot_points = np.concatenate([hand + 0.1 * j for j in range(8)], axis=-1)
    group = np.array([1, 1, 2, 2, 3, 3])[:n_trials]
    return TrialSet(
        fs_hz=fs_hz,
        onset_index=onset,
        channels={
            "hand_pos": hand[..., :2],
            "hand_force": 5.0 * np.stack([np.sin(6 * ramp), ramp], -1)
            + 0.01 * rng.standard_normal((n_trials, n_samples, 2)),
            "true_arm_q": q,
            "robot_q": np.zeros((n_trials, n_samples, 7)),
            "true_arm_points": arm_points,
            "true_robot_points": robot_points,
        },
        units={
            "hand_pos": "m",
            "hand_force": "N",
            "true_arm_q": "rad",
            "robot_q": "rad",
            "true_arm_points": "m",
            "true_robot_points": "m",
        },
        trial_meta={
            "group": group,
            "direction": np.arange(n_trials) % 6,
            "T_k_s": 0.04 + 0.01 * group,
            "validate": np.arange(n_trials) % 2 == 0,
        },
    )


def _validation_series(n: int = 200) -> dict:
    t = np.linspace(-0.05, 0.35, n)
    base = np.stack([np.sin(8 * t), 0.5 * np.cos(5 * t)], axis=-1)
    return {
        "t_s": t,
        "dtau_measured": base,
        "dtau_full": 1.05 * base,
        "dtau_reduced": 0.97 * base,
        "t_obs_s": 0.25,
    }


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_window_sweep_written(tmp_path, model):
    path = plot_window_sweep(_results(), tmp_path / f"fig_{model}.png", model=model)
    assert path == tmp_path / f"fig_{model}.png"
    assert_png(path)


def test_validation_and_error_figures_written(tmp_path):
    assert_png(plot_validation(_validation_series(), tmp_path / "fig6.png"))
    assert_png(plot_error_vs_window(_results(), tmp_path / "errors.png"))


def test_figures_never_overwrite(tmp_path):
    path = plot_window_sweep(_results(), tmp_path / "fig4.png")
    before = path.read_bytes()
    for call in (
        lambda: plot_window_sweep(_results(), path),
        lambda: plot_validation(_validation_series(), path),
        lambda: plot_error_vs_window(_results(), path),
    ):
        with pytest.raises(DataError, match="fig4.png"):
            call()
    assert path.read_bytes() == before


def test_figure_input_errors(tmp_path):
    with pytest.raises(ConfigError, match="full"):
        plot_window_sweep(_results(), tmp_path / "a.png", model="partial")
    with pytest.raises(DataError, match="windows"):
        plot_window_sweep({"windows": []}, tmp_path / "b.png")
    bad = _validation_series()
    bad["dtau_full"] = bad["dtau_full"][:10]
    with pytest.raises(DataError, match="dtau_full"):
        plot_validation(bad, tmp_path / "c.png")
    assert not any(tmp_path.iterdir())


def test_recording_written_and_verified(tmp_path):
    path = write_recording(tmp_path / "run.rrd", _trials(), _results())
    assert path == tmp_path / "run.rrd"
    assert path.stat().st_size > 10_000
    assert view_command(path) == ["rerun", str(path)]
    verify_rrd(path, tmp_path)


def test_recording_options_shrink_the_file(tmp_path):
    trials, results = _trials(), _results()
    full = write_recording(tmp_path / "full.rrd", trials, results, max_scalar_hz=None)
    small = write_recording(
        tmp_path / "small.rrd",
        trials,
        results,
        max_scalar_hz=250.0,
        poses_per_window=0,
        scalar_channels=("hand_force",),
        blueprint=False,
        ground_truth={"K": K_TRUE, "D": D_TRUE, "xi": XI_TRUE},
    )
    assert 0 < small.stat().st_size < full.stat().st_size


def test_recording_refuses_overwrite_and_bad_input(tmp_path):
    path = tmp_path / "run.rrd"
    path.write_bytes(b"keep")
    with pytest.raises(DataError, match="run.rrd"):
        write_recording(path, _trials(), _results())
    assert path.read_bytes() == b"keep"
    with pytest.raises(ConfigError, match="max_3d_hz"):
        write_recording(tmp_path / "a.rrd", _trials(), _results(), max_3d_hz=0.0)
    with pytest.raises(DataError, match="available"):
        write_recording(tmp_path / "b.rrd", _trials(), _results(), scalar_channels=("nope",))
    with pytest.raises(DataError, match=r"\.rrd"):
        write_recording(tmp_path / "c.txt", _trials(), _results())


def test_view_command_is_plain():
    assert view_command("runs/x/recording.rrd") == ["rerun", "runs/x/recording.rrd"]


@pytest.mark.parametrize("lo, hi", [(1e-3, 1e2), (0.25, 8.0), (0.2, 1.2), (0.031, 0.039), (2e3, 4e5)])
def test_plain_log_ticks_label_the_ticks_matplotlib_labels_in_plain_text(lo, hi):
    """The plain-text log labels (no mathtext parse) name the same ticks with the same numbers as
    matplotlib's own mathtext labels, e.g. ``$\\mathdefault{2\\times10^{-1}}$`` -> ``2×10⁻¹``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from armlab.viz._ticks import plain_log_ticks

    def labels(ax):
        return [t.get_text() for t in ax.get_yticklabels() + ax.yaxis.get_minorticklabels() if t.get_text()]

    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    ax.semilogy([0, 1], [lo, hi])
    fig.canvas.draw()
    sup = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")

    def plain(label: str) -> str:  # matplotlib's mathtext label written as ours is
        body = label.removeprefix("$\\mathdefault{").removesuffix("}$").replace("\\times", "×")
        base, _, exponent = body.partition("10^{")
        return base + "10" + exponent.rstrip("}").translate(sup)

    expected = [plain(s) for s in labels(ax)]
    plain_log_ticks(ax.yaxis)
    fig.canvas.draw()
    assert labels(ax) == expected
    assert not any("$" in s for s in labels(ax))


def _chunks(path: Path, entity: str) -> dict[bool, object]:
    """{static?: the record batch} of ``entity`` in the recording, or skip without rerun's reader."""
    try:
        from rerun.chunk import RrdReader
    except ImportError:
        pytest.skip("this rerun has no rerun.chunk.RrdReader")
    return {
        c.is_static: c.to_record_batch()
        for c in RrdReader(str(path)).store().stream().to_chunks()
        if c.entity_path == entity
    }


def test_recording_logs_each_window_as_one_entity_of_all_its_trials(tmp_path):
    """Trials of a window sharing an onset are one entity: every row holds each trial's axes in
    trial order, named ``t<i> <axis>``, with the values of the trial file (to float32)."""
    import dataclasses

    trials = dataclasses.replace(_trials(), onset_index=np.full(6, 100))
    path = write_recording(tmp_path / "run.rrd", trials, _results(), max_scalar_hz=None)
    force = _chunks(path, "/trials/k02/hand_force")  # window 2: trials 2 and 3
    assert force[True].column("SeriesLines:names").to_pylist() == [
        ["t002 F_x [N]", "t002 F_y [N]", "t003 F_x [N]", "t003 F_y [N]"]
    ]
    t_s = np.array([t.total_seconds() for t in force[False].column("trial_time").to_pylist()])
    rows = np.asarray(force[False].column("Scalars:scalars").to_pylist())
    assert rows.shape == (trials.n_samples, 4)  # every sample, 2 trials x 2 axes
    assert t_s[100] == 0.0  # the onset sample at t = 0
    expected = trials.channels["hand_force"][[2, 3]].transpose(1, 0, 2).reshape(-1, 4)
    np.testing.assert_array_equal(rows, expected.astype(np.float32).astype(np.float64))
    text = _chunks(path, "/trials/k02/events")[False].column("TextLog:text").to_pylist()
    assert "t002 direction=2" in text[0][0] and "t003 direction=3" in text[0][0]
    strips = _chunks(path, "/trials/k02/pose/arm")[False].column("LineStrips3D:strips").to_pylist()
    assert all(len(row) == 2 for row in strips)  # one strip per trial in every row


def test_recording_splits_a_window_whose_trials_start_at_different_samples(tmp_path):
    path = write_recording(tmp_path / "run.rrd", _trials(), _results())  # onsets 80 and 100 in k01
    assert _chunks(path, "/trials/k01/onset80/hand_force") and _chunks(
        path, "/trials/k01/onset100/hand_force"
    )
    assert not _chunks(path, "/trials/k01/hand_force")
