"""Rerun recording of a fractional-elbow run: every trial's motor, link, elbow, force and angles.

Layout (entity paths): ``trials/t{i:03d}/<channel>`` scalar series (``FRACTIONAL_SCALAR_CHANNELS``
that exist) on the ``trial_time`` timeline (s from the start of the trial), decimated to
``max_scalar_hz``; ``trials/t{i:03d}/pose/{link,forearm}`` 3D line strips (motor axis to the
handle at angle theta, elbow to the grip at angle phi, 3 cm below) and ``pose/force`` the handle
force as an arrow along the link normal, decimated to ``max_3d_hz``; ``results`` the identified
models as a text document. ``rerun`` is imported inside :func:`write_fractional_recording` only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from armlab.data.trial import TrialSet
from armlab.errors import ConfigError, DataError
from armlab.viz._paths import fresh_path, recording
from armlab.viz.fractional_table import _num, format_fractional_table

__all__ = ["FRACTIONAL_SCALAR_CHANNELS", "write_fractional_recording"]

FRACTIONAL_SCALAR_CHANNELS = ("f_ref", "f_measured", "theta_measured", "phi_true", "current")
_CHANNEL_LABELS = {
    "f_ref": "F_ref",
    "f_measured": "F_measured",
    "f_true": "F_true",
    "theta_measured": "θ measured (motor)",
    "theta_true": "θ true (motor)",
    "phi_true": "φ true (elbow)",
    "current": "I motor",
    "tau_motor": "τ motor",
}
_TRIAL_TIMELINE = "trial_time"
_FOREARM_Z_M = -0.03
_FORCE_SCALE_M_PER_N = 0.02


def _f32(a: np.ndarray) -> np.ndarray:
    """Round to float32 precision and back to float64 (rerun's scalar type)."""
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def _first_channel(trials: TrialSet, names: Sequence[str]) -> str | None:
    return next((n for n in names if n in trials.channels), None)


def _blueprint(rrb, trial_paths: Sequence[str], groups: Mapping[str, list[str]], poses: bool, text: bool):
    """One tab per trial (time series grouped by unit, the 3D scene) and one with the results."""
    tabs = []
    for base in trial_paths:
        views = [
            rrb.TimeSeriesView(name=name, origin="/", contents=[f"/{base}/{c}" for c in chans])
            for name, chans in groups.items()
            if chans
        ]
        parts = [rrb.Vertical(*views)]
        if poses:
            parts.append(
                rrb.Spatial3DView(name="motor link and forearm", origin="/", contents=[f"/{base}/pose/**"])
            )
        tabs.append(rrb.Horizontal(*parts, name=base.split("/")[-1]))
    if text:
        tabs.append(rrb.TextDocumentView(name="results", origin="/results"))
    return rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(timeline=_TRIAL_TIMELINE), collapse_panels=False)


def write_fractional_recording(
    path: str | Path,
    trials: TrialSet,
    results: Mapping[str, Any] | None = None,
    max_3d_hz: float = 50.0,
    *,
    max_scalar_hz: float | None = 500.0,
    scalar_channels: Sequence[str] = FRACTIONAL_SCALAR_CHANNELS,
    blueprint: bool = True,
) -> Path:
    """Write every trial of a ``fractional_elbow`` run (and its fit summary) into one ``.rrd`` file.

    Layout (entity paths), all time-varying data on the ``trial_time`` timeline (s from the start
    of the trial):

    - ``trials/t{i:03d}/<channel>``: one scalar series per channel of ``scalar_channels`` present
      (default ``f_ref``, ``f_measured`` N, ``theta_measured``, ``phi_true`` rad, ``current`` A),
      decimated to ``max_scalar_hz`` (every n-th sample).
    - ``trials/t{i:03d}/pose/link``: the motor link as a 3D line strip from the motor axis (origin)
      to the handle at angle θ (``theta_measured``, else ``theta_true``), length
      ``trials.attrs['link_length_m']``, in the horizontal plane z = 0; ``pose/forearm`` from the
      origin to the grip at the elbow angle φ (``phi_true``), at z = −0.03 m; ``pose/force`` the
      handle force (``f_measured``, else ``f_true``) as an arrow along the link normal,
      0.02 m/N; ``pose/zero``: the zero-point the subject holds (static). Decimated to
      ``max_3d_hz``; left out when ``link_length_m`` or the angle channel is missing.
    - ``results/summary`` (static text): :func:`format_fractional_table` of ``results``, which
      lists α/β and the indices of every fit.

    Scalars are rounded to float32 precision (7 significant digits, below any sensor
    resolution) so that the file compresses. Size: 2 trials of 80 000 samples at 2 kHz with the
    default five channels give 4.2 MB with the defaults (0.4 s to write; 500 Hz still samples the
    15 Hz input band 33-fold), 15 MB with ``max_scalar_hz=None``.

    Args:
        path: the ``.rrd`` file to write; must not exist.
        trials: the run's trials (see the module docstring of the protocol).
        results: the protocol's results dict to log as text, or ``None``.
        max_3d_hz: rate the 3D scene is decimated to, Hz (> 0).
        max_scalar_hz: rate the time series are decimated to, Hz (> 0); ``None`` logs every sample.
        scalar_channels: channel names logged as time series (those present).
        blueprint: store a default viewer layout (one tab per trial plus a results tab).

    Returns:
        The written path.

    Raises:
        ConfigError: ``max_3d_hz`` or ``max_scalar_hz`` is not a positive number.
        DataError: ``path`` exists or is not ``.rrd``, or no scalar channel is present.
    """
    import rerun as rr
    import rerun.blueprint as rrb

    if not (np.isfinite(max_3d_hz) and max_3d_hz > 0):
        raise ConfigError(f"max_3d_hz must be a positive number of Hz, got {max_3d_hz!r}")
    if max_scalar_hz is not None and not (np.isfinite(max_scalar_hz) and max_scalar_hz > 0):
        raise ConfigError(
            f"max_scalar_hz must be None (every sample) or a positive number of Hz, got {max_scalar_hz!r}"
        )
    channels = [c for c in scalar_channels if c in trials.channels]
    if not channels:
        raise DataError(
            f"none of the channels {list(scalar_channels)} is in the trials; "
            f"available: {sorted(trials.channels)}"
        )
    p = fresh_path(path, ".rrd")

    fs = float(trials.fs_hz)
    n = trials.n_samples
    step_scalar = 1 if max_scalar_hz is None else max(1, int(round(fs / max_scalar_hz)))
    step_3d = max(1, int(round(fs / max_3d_hz)))
    L = _num(trials.attrs.get("link_length_m"))
    theta_ch = _first_channel(trials, ("theta_measured", "theta_true"))
    phi_ch = _first_channel(trials, ("phi_true",))
    force_ch = _first_channel(trials, ("f_measured", "f_true"))
    poses = L is not None and L > 0 and theta_ch is not None
    trial_paths = [f"trials/t{i:03d}" for i in range(trials.n_trials)]
    groups = {
        "force [N]": [c for c in channels if c.startswith("f_")],
        "angle [rad]": [c for c in channels if c.startswith(("theta", "phi"))],
    }
    grouped = {c for chans in groups.values() for c in chans}
    for c in channels:
        if c not in grouped:
            groups[c] = [c]
    text = format_fractional_table(results) if results else None

    bp = _blueprint(rrb, trial_paths, groups, poses, text is not None) if blueprint else None
    with recording(p, "armlab", bp) as rec:
        rows = np.arange(0, n, step_scalar)
        time_col = [rr.TimeColumn(_TRIAL_TIMELINE, duration=rows / fs)]
        idx = np.arange(0, n, step_3d)
        pose_time = [rr.TimeColumn(_TRIAL_TIMELINE, duration=idx / fs)]
        for i, base in enumerate(trial_paths):
            for ch in channels:
                x = np.asarray(trials.channels[ch][i, rows, :])
                n_axes = x.shape[1]
                unit = trials.units.get(ch, "")
                label = _CHANNEL_LABELS.get(ch, ch)
                names = (
                    [f"{label} [{unit}]" if unit else label]
                    if n_axes == 1
                    else [f"{label}[{j}] [{unit}]" for j in range(n_axes)]
                )
                rec.log(f"{base}/{ch}", rr.SeriesLines(names=names), static=True)
                rec.send_columns(
                    f"{base}/{ch}",
                    indexes=time_col,
                    columns=rr.Scalars.columns(scalars=_f32(x).ravel()).partition(np.full(rows.size, n_axes)),
                )
            if not poses:
                continue
            assert L is not None and theta_ch is not None
            th = np.asarray(trials.channels[theta_ch][i, idx, 0], dtype=float)
            handle = np.stack([L * np.cos(th), L * np.sin(th), np.zeros_like(th)], axis=-1)
            zeros = np.zeros_like(handle)
            link = np.stack([zeros, handle], axis=1).astype(np.float32)  # (frames, 2 points, xyz)
            rec.log(
                f"{base}/pose/zero",
                rr.LineStrips3D(
                    [[[0.0, 0.0, 0.0], [L, 0.0, 0.0]]], colors=[(150, 150, 150, 255)], radii=0.002
                ),
                static=True,
            )
            rec.send_columns(
                f"{base}/pose/link",
                indexes=pose_time,
                columns=rr.LineStrips3D.columns(
                    strips=list(link),
                    colors=np.tile((90, 110, 200, 255), (idx.size, 1)),
                    radii=np.full(idx.size, 0.008, np.float32),
                ),
            )
            if phi_ch is not None:
                ph = np.asarray(trials.channels[phi_ch][i, idx, 0], dtype=float)
                grip = np.stack([L * np.cos(ph), L * np.sin(ph), np.full_like(ph, _FOREARM_Z_M)], axis=-1)
                start = np.tile([0.0, 0.0, _FOREARM_Z_M], (idx.size, 1))
                rec.send_columns(
                    f"{base}/pose/forearm",
                    indexes=pose_time,
                    columns=rr.LineStrips3D.columns(
                        strips=list(np.stack([start, grip], axis=1).astype(np.float32)),
                        colors=np.tile((230, 120, 40, 255), (idx.size, 1)),
                        radii=np.full(idx.size, 0.012, np.float32),
                    ),
                )
            if force_ch is not None:
                fz = np.asarray(trials.channels[force_ch][i, idx, 0], dtype=float)
                normal = np.stack([-np.sin(th), np.cos(th), np.zeros_like(th)], axis=-1)
                rec.send_columns(
                    f"{base}/pose/force",
                    indexes=pose_time,
                    columns=rr.Arrows3D.columns(
                        origins=handle.astype(np.float32),
                        vectors=(_FORCE_SCALE_M_PER_N * fz[:, None] * normal).astype(np.float32),
                        colors=np.tile((200, 40, 40, 255), (idx.size, 1)),
                        radii=np.full(idx.size, 0.004, np.float32),
                    ),
                )
        if text is not None:
            rec.log("results/summary", rr.TextDocument(text, media_type=rr.MediaType.TEXT), static=True)
    return p
