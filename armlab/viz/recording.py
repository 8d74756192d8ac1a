"""One Rerun recording (``.rrd``) of a conditioning-window run: every trial and every estimate.

Layout of the recording (entity paths):

- ``trials/k{k:02d}/<channel>``: scalars of every trial of observation window ``k``
  (``trial_meta['group']``), one series per trial and axis, named ``t{i:03d} <axis> [unit]`` (``i``
  the trial's row in the TrialSet), on the ``trial_time`` timeline (s, relative to the
  perturbation onset, so the onset is t = 0 in every trial). Only ``pre_onset_s`` before the onset
  to the end of the record is logged. The trials of a window are one entity, logged in one call:
  780 trials took ~4700 calls as one entity each, and 2 s. A window whose trials have several
  onset samples gets one entity per onset, ``trials/k{k:02d}/onset{n}/<channel>``.
- ``trials/k../events``: text markers at the onset (each trial's direction, T_k and role) and at
  the end of the window's observation interval (t = T_obs).
- ``trials/k../pose/arm`` and ``pose/robot``: 3D line strips through the world positions of
  shoulder, elbow, hand and of the robot's base and joint origins, one strip per trial,
  decimated to ``max_3d_hz``.
- ``estimates/{full,reduced}/{cond,K11..K22,D11..D22,xi1..xi3,eig_Ks1,..}`` and
  ``truth/{K11..,D11..,xi1..}``: one value per window on the ``t_obs`` timeline (duration, s) and
  the ``window`` sequence timeline (k).

Rerun stores scalars as float64; values are rounded to float32 precision (7 significant digits,
far below any sensor resolution) so that the file compresses, and 3D positions are sent as
float32. Logging goes through a dedicated :class:`rerun.RecordingStream` (never the global one).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from armlab.data.trial import TrialSet
from armlab.errors import ConfigError, DataError
from armlab.viz._paths import fresh_path, recording

__all__ = [
    "write_recording",
    "view_command",
    "DEFAULT_SCALAR_CHANNELS",
]

DEFAULT_SCALAR_CHANNELS = ("hand_force", "true_arm_q", "hand_pos")
_AXIS_NAMES = {
    "hand_force": ("F_x", "F_y"),
    "hand_pos": ("x", "y"),
    "true_arm_q": ("q1 shoulder", "q2 elbow"),
    "robot_q": tuple(f"q{j + 1}" for j in range(7)),
}
_POSE_CHANNELS = (
    ("true_arm_points", "arm", (230, 120, 40, 255), 0.012),
    ("true_robot_points", "robot", (90, 110, 200, 255), 0.02),
)
_MATRIX_NAMES = ("11", "12", "21", "22")
_TRIAL_TIMELINE = "trial_time"
_WINDOW_TIMELINE = "t_obs"


def _f32(a: np.ndarray) -> np.ndarray:
    """Round to float32 precision and back to float64 (rerun's scalar type)."""
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def _onset_aligned(onset: int, start: int, stop: int, step: int) -> np.ndarray:
    """Sample indices in ``[start, stop)`` spaced by ``step`` that include ``onset``."""
    return np.arange(onset - ((onset - start) // step) * step, stop, step)


def _series_names(trials: TrialSet, ch: str) -> list[str]:
    """Legend names of a channel's axes, with the channel's unit."""
    n_axes = trials.channels[ch].shape[2]
    unit = trials.units.get(ch, "")
    axis = _AXIS_NAMES.get(ch, tuple(f"{ch}[{j}]" for j in range(n_axes)))
    return [f"{a} [{unit}]" if unit else a for a in axis[:n_axes]]


def _groups(trials: TrialSet) -> np.ndarray:
    """(n_trials,) window index k of every trial (``trial_meta['group']``, 0 if absent)."""
    n = trials.n_trials
    return np.asarray(trials.trial_meta.get("group", np.zeros(n, dtype=int))).astype(int)


def _batch_paths(batches: Mapping[tuple[int, int], Sequence[int]]) -> dict[tuple[int, int], str]:
    """Entity path of each (window k, onset sample) batch: ``trials/k{k:02d}``, or
    ``trials/k{k:02d}/onset{onset}`` where the window's trials have several onsets."""
    onsets_of: dict[int, int] = {}
    for k, _ in batches:
        onsets_of[k] = onsets_of.get(k, 0) + 1
    return {(k, o): f"trials/k{k:02d}" + (f"/onset{o}" if onsets_of[k] > 1 else "") for k, o in batches}


def _onset_text(k: int, members: np.ndarray, meta: Mapping[str, np.ndarray]) -> str:
    """The onset marker of one batch: the window and each trial's direction, T_k and role."""

    def trial(i: int) -> str:
        desc = [f"{name}={meta[name][i]}" for name in ("direction", "T_k_s") if name in meta]
        val = " (validation)" if "validate" in meta and bool(meta["validate"][i]) else ""
        return f"t{i:03d}" + (f" {', '.join(desc)}" if desc else "") + val

    return f"onset, k={k}, {members.size} trials: " + "; ".join(trial(int(i)) for i in members)


def _window_params(parts: Sequence[Mapping[str, Any]], with_xi: bool) -> dict[str, np.ndarray]:
    """Name -> (n_windows,) values of one model's estimates, NaN where missing."""

    def get(p, key, shape):
        v = p.get(key)
        return np.full(shape, np.nan) if v is None else np.asarray(v, dtype=float).reshape(shape)

    out: dict[str, np.ndarray] = {"cond": np.array([get(p, "cond", ()) for p in parts])}
    for key in ("K", "D"):
        m = np.stack([get(p, key, (4,)) for p in parts])
        out.update({f"{key}{s}": m[:, j] for j, s in enumerate(_MATRIX_NAMES)})
    if with_xi:
        xi = np.stack([get(p, "xi", (3,)) for p in parts])
        out.update({f"xi{j + 1}": xi[:, j] for j in range(3)})
    for key in ("eig_Ks", "eig_Ds"):
        e = np.stack([get(p, key, (2,)) for p in parts])
        out.update({f"{key}{j + 1}": e[:, j] for j in range(2)})
    return out


def _truth_params(
    results: Mapping[str, Any], windows: Sequence[Mapping[str, Any]], ground_truth: Mapping[str, Any] | None
) -> dict[str, np.ndarray]:
    """Truth per window: ``ground_truth`` if given, else ``window['K_true']``..., else results'."""
    fallback = ground_truth if ground_truth is not None else (results.get("ground_truth") or {})
    out: dict[str, np.ndarray] = {}
    for key, size, names in (("K", 4, _MATRIX_NAMES), ("D", 4, _MATRIX_NAMES), ("xi", 3, ("1", "2", "3"))):
        rows = []
        for w in windows:
            v = fallback.get(key) if ground_truth is not None else w.get(f"{key}_true", fallback.get(key))
            rows.append(np.full(size, np.nan) if v is None else np.asarray(v, dtype=float).reshape(size))
        m = np.stack(rows)
        if np.any(np.isfinite(m)):
            out.update({f"{key}{s}": m[:, j] for j, s in enumerate(names)})
    return out


def _blueprint(
    rrb,
    paths: Mapping[tuple[int, int], tuple[str, bool]],
    scalar_channels: Sequence[str],
    pose_names: Sequence[str],
    t_obs_by_k: Mapping[int, float],
    models: Sequence[str],
    truth_names: Sequence[str],
):
    """Tabs: one per window (time series per channel, 3D poses, markers) and one of estimates.

    ``paths``: (k, onset) -> (entity path of that batch of trials, whether it has 3D poses).
    """
    tabs = []
    for k in sorted({key[0] for key in paths}):
        bases = [paths[key] for key in paths if key[0] == k]
        series = [
            rrb.TimeSeriesView(
                name=ch,
                origin="/",
                contents=[f"/{b}/{ch}" for b, _ in bases],
                plot_legend=rrb.PlotLegend(visible=False),
            )
            for ch in scalar_channels
        ]
        poses = [f"/{b}/pose/{name}" for b, posed in bases if posed for name in pose_names]
        right = [rrb.Spatial3DView(name="poses", origin="/", contents=poses)] if poses else []
        right.append(rrb.TextLogView(name="markers", origin="/", contents=[f"/{b}/events" for b, _ in bases]))
        t_obs = t_obs_by_k.get(k)
        label = f"k{k:02d}" + (f" · T_obs {1e3 * t_obs:.0f} ms" if t_obs is not None else "")
        tabs.append(
            rrb.Horizontal(
                rrb.Vertical(*series), rrb.Vertical(*right, row_shares=[3, 1][: len(right)]), name=label
            )
        )
    est_views = []
    for prefix in ("K", "D", "xi"):
        for model in models:
            if prefix == "xi" and model != "full":
                continue
            names = [f"{prefix}{s}" for s in (_MATRIX_NAMES if prefix != "xi" else ("1", "2", "3"))]
            contents = [f"/estimates/{model}/{n}" for n in names] + [
                f"/truth/{n}" for n in names if n in truth_names
            ]
            est_views.append(
                rrb.TimeSeriesView(name=f"{prefix} ({model}) vs truth", origin="/", contents=contents)
            )
    est_views.append(
        rrb.TimeSeriesView(name="cond(W)", origin="/", contents=[f"/estimates/{m}/cond" for m in models])
    )
    tabs.append(rrb.Grid(*est_views, name="estimates (timeline t_obs)"))
    return rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(timeline=_TRIAL_TIMELINE), collapse_panels=False)


def write_recording(
    path: str | Path,
    trials: TrialSet,
    results: Mapping[str, Any],
    ground_truth: Mapping[str, Any] | None = None,
    max_3d_hz: float = 50.0,
    *,
    max_scalar_hz: float | None = 500.0,
    pre_onset_s: float = 0.2,
    poses_per_window: int | None = None,
    scalar_channels: Sequence[str] = DEFAULT_SCALAR_CHANNELS,
    blueprint: bool = True,
) -> Path:
    """Write every trial and every window's estimates of one run into one ``.rrd`` file.

    See the module docstring for the entity layout. Size, measured for 780 trials of 1000 samples
    at 1 kHz (onset near sample 300) with the default channels: 45 MB with the defaults (2.2 s to
    write), 37 MB with ``poses_per_window=1``, 70 MB with ``max_scalar_hz=None``. Each scalar
    channel costs ~28 B per logged sample (row id, time and values), so the rate and the channel
    list set the size.

    Args:
        path: the ``.rrd`` file to write; must not exist.
        trials: the run's trials; channels in ``scalar_channels`` that are present are logged (at
            least one must be), and ``true_arm_points`` (n_trials, n_samples, 9) m /
            ``true_robot_points`` (n_trials, n_samples, 3·P) m, world xyz, if present.
            ``trial_meta['group']`` gives the window index k (0 if absent), ``direction``,
            ``T_k_s`` and ``validate`` label the onset marker.
        results: the protocol's results dict (``windows`` with ``k``, ``t_obs_s``, estimates;
            ``ground_truth``). Windows may be empty to log trials only.
        ground_truth: ``K`` (2, 2) N·m/rad, ``D`` (2, 2) N·m·s/rad, ``xi`` (3,) kg·m² to log as
            truth for every window instead of the per-window ``K_true``/``D_true``/``xi_true``.
        max_3d_hz: rate the 3D poses are decimated to, Hz (> 0).
        max_scalar_hz: rate the time series are decimated to (every n-th sample, keeping the
            onset sample), Hz (> 0); ``None`` logs every sample. 500 Hz halves the file at 1 kHz
            and still resolves the 50–300 ms perturbations; the estimation always uses all data.
        pre_onset_s: how much of the record before the onset is logged, s (≥ 0).
        poses_per_window: log 3D poses of only the first this-many trials of each window (``None``:
            all trials).
        scalar_channels: channel names logged as time series.
        blueprint: store a default viewer layout (one tab per window plus an estimates tab).

    Returns:
        The written path.

    Raises:
        ConfigError: ``max_3d_hz``, ``pre_onset_s`` or ``poses_per_window`` out of range.
        DataError: ``path`` exists, no scalar channel is present, or a pose channel's width is not
            a multiple of 3.
    """
    import rerun as rr
    import rerun.blueprint as rrb

    if not (np.isfinite(max_3d_hz) and max_3d_hz > 0):
        raise ConfigError(f"max_3d_hz must be a positive number of Hz, got {max_3d_hz!r}")
    if max_scalar_hz is not None and not (np.isfinite(max_scalar_hz) and max_scalar_hz > 0):
        raise ConfigError(
            f"max_scalar_hz must be None (every sample) or a positive number of Hz, got {max_scalar_hz!r}"
        )
    if not (np.isfinite(pre_onset_s) and pre_onset_s >= 0):
        raise ConfigError(f"pre_onset_s must be >= 0 s, got {pre_onset_s!r}")
    if poses_per_window is not None and poses_per_window < 0:
        raise ConfigError(f"poses_per_window must be None (all) or >= 0, got {poses_per_window!r}")
    channels = [c for c in scalar_channels if c in trials.channels]
    if not channels:
        raise DataError(
            f"none of the channels {list(scalar_channels)} is in the trials; "
            f"available: {sorted(trials.channels)}"
        )
    poses = [(c, name, colour, radius) for c, name, colour, radius in _POSE_CHANNELS if c in trials.channels]
    for c, *_ in poses:
        if trials.channels[c].shape[2] % 3:
            raise DataError(
                f"channel {c!r} must hold xyz triples; its width {trials.channels[c].shape[2]} "
                "is not a multiple of 3"
            )
    p = fresh_path(path, ".rrd")

    windows = list(results.get("windows") or [])
    t_obs_by_k = {int(w["k"]): float(w["t_obs_s"]) for w in windows if "k" in w and "t_obs_s" in w}
    group = _groups(trials)
    meta = {k: np.asarray(v) for k, v in trials.trial_meta.items()}
    fs = float(trials.fs_hz)
    n_samples = trials.n_samples
    onsets = np.asarray(trials.onset_index).astype(int)
    pre = int(round(pre_onset_s * fs))
    step_3d = max(1, int(round(fs / max_3d_hz)))
    step_scalar = 1 if max_scalar_hz is None else max(1, int(round(fs / max_scalar_hz)))
    # the trials of one window that share an onset share a clock: they are logged together
    batches: dict[tuple[int, int], list[int]] = {}
    for i, (k, onset) in enumerate(zip(group.tolist(), onsets.tolist(), strict=True)):
        batches.setdefault((k, onset), []).append(i)

    # Which trials get 3D poses: the first `poses_per_window` of each window, in trial order.
    with_pose = np.ones(trials.n_trials, dtype=bool)
    if poses_per_window is not None:
        rank = np.zeros(trials.n_trials, dtype=int)
        for g in np.unique(group):
            idx = np.flatnonzero(group == g)
            rank[idx] = np.arange(idx.size)
        with_pose = rank < poses_per_window

    models = ["full"] + (
        ["reduced"] if windows and all(w.get("reduced") is not None for w in windows) else []
    )
    truth = _truth_params(results, windows, ground_truth) if windows else {}

    entity = _batch_paths(batches)
    bp = None
    if blueprint:
        posed = {key: bool(poses) and bool(with_pose[rows].any()) for key, rows in batches.items()}
        paths = {key: (entity[key], posed[key]) for key in batches}
        bp = _blueprint(
            rrb, paths, channels, [name for _, name, _, _ in poses], t_obs_by_k, models, list(truth)
        )
    axis_names = {ch: _series_names(trials, ch) for ch in channels}
    with recording(p, "armlab", bp) as rec:
        for (k, onset), rows_of in batches.items():
            base = entity[k, onset]
            members = np.asarray(rows_of)
            start = max(0, onset - pre)
            rows = _onset_aligned(onset, start, n_samples, step_scalar)
            time_col = [rr.TimeColumn(_TRIAL_TIMELINE, duration=(rows - onset) / fs)]
            for ch in channels:
                # (rows, trials, axes): each row holds every trial's axes, instance j = trial * n_axes + axis
                x = np.ascontiguousarray(np.moveaxis(trials.channels[ch][members[:, None], rows], 1, 0))
                names = [f"t{i:03d} {axis}" for i in members for axis in axis_names[ch]]
                rec.log(f"{base}/{ch}", rr.SeriesLines(names=names), static=True)
                rec.send_columns(
                    f"{base}/{ch}",
                    indexes=time_col,
                    columns=rr.Scalars.columns(scalars=_f32(x).ravel()).partition(
                        np.full(rows.size, x.shape[1] * x.shape[2])
                    ),
                )
            texts, times = [_onset_text(k, members, meta)], [0.0]
            if k in t_obs_by_k:
                texts.append(f"end of the observation window T_obs = {1e3 * t_obs_by_k[k]:.0f} ms")
                times.append(t_obs_by_k[k])
            rec.send_columns(
                f"{base}/events",
                indexes=[rr.TimeColumn(_TRIAL_TIMELINE, duration=times)],
                columns=rr.TextLog.columns(text=texts, level=["INFO"] * len(texts)),
            )
            posed = members[with_pose[members]]
            if posed.size and poses:
                idx = _onset_aligned(onset, start, n_samples, step_3d)
                idx_time = [rr.TimeColumn(_TRIAL_TIMELINE, duration=(idx - onset) / fs)]
                per_row = np.full(idx.size, posed.size)
                for c, name, colour, radius in poses:
                    # one (n_points, 3) strip per trial and row, rows after rows: (rows * trials, P, 3)
                    pts = np.moveaxis(np.asarray(trials.channels[c][posed[:, None], idx], np.float32), 1, 0)
                    strips = np.ascontiguousarray(pts).reshape(idx.size * posed.size, -1, 3)
                    rec.send_columns(
                        f"{base}/pose/{name}",
                        indexes=idx_time,
                        columns=rr.LineStrips3D.columns(
                            strips=strips,
                            colors=np.tile(colour, (strips.shape[0], 1)),
                            radii=np.full(strips.shape[0], radius, np.float32),
                        ).partition(per_row),
                    )
        if windows:
            w_idx = [
                rr.TimeColumn(_WINDOW_TIMELINE, duration=[float(w["t_obs_s"]) for w in windows]),
                rr.TimeColumn("window", sequence=[int(w.get("k", j + 1)) for j, w in enumerate(windows)]),
            ]
            for model in models:
                parts = windows if model == "full" else [w["reduced"] for w in windows]
                for name, values in _window_params(parts, with_xi=model == "full").items():
                    rec.send_columns(
                        f"estimates/{model}/{name}", indexes=w_idx, columns=rr.Scalars.columns(scalars=values)
                    )
            for name, values in truth.items():
                rec.log(f"truth/{name}", rr.SeriesLines(names=f"{name} (truth)", widths=1.0), static=True)
                rec.send_columns(f"truth/{name}", indexes=w_idx, columns=rr.Scalars.columns(scalars=values))
    return p


def view_command(path: str | Path) -> list[str]:
    """Return the command line that opens a recording in the Rerun viewer: ``["rerun", path]``."""
    return ["rerun", str(path)]
