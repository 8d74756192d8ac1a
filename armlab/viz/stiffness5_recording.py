"""Rerun recording of the 5-DoF stiffness trials (seeds/001): skeleton, markers, both wrenches,
the stiffness ellipsoids.

Layout (entity paths); the trials lie back to back on the ``sim_time`` timeline (trial k from
k times the record's length, its onset at ``t = 0`` of that slot):

- ``arm/skeleton``: shoulder-elbow-wrist line strip (m, world) from the true joint angles;
- ``arm/marker``: the measured forearm marker cluster (m);
- ``arm/wrist_force``: the force on the limb at the wrist, ``force_scale_m_per_n`` m per N;
- ``arm/base_force``: the base JR3's force at the seat (world origin), scaled by
  ``base_scale_m_per_n`` (it carries the body's weight);
- ``ellipsoids/<condition>/truth`` and ``/estimate`` (static): the Fig. 3 ellipsoids' surface
  points (N, in force space);
- ``results`` (static): the printed table.

``rec`` is :func:`armlab.protocols`' recording series (``t`` (n_trials, n) s, ``skeleton``
(n_trials, n, 3, 3) m, ``marker`` (n_trials, n, 3) m, ``wrist_force``, ``base_force``
(n_trials, n, 3) N, ``condition`` (n_trials,), ``names``); ``series`` may hold ``surface_hat`` /
``surface_true`` (n_c, a, b, 3) N. ``rerun`` is imported inside the writer only.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from armlab.errors import ConfigError, DataError
from armlab.viz._paths import fresh_path, recording
from armlab.viz.stiffness5 import format_stiffness5_table

__all__ = ["write_stiffness5_recording"]

_TIMELINE = "sim_time"


def _blueprint(rrb, text: bool):
    tabs = [
        rrb.Spatial3DView(name="arm, marker, wrenches", origin="/arm"),
        rrb.Spatial3DView(name="stiffness ellipsoids (N)", origin="/ellipsoids"),
    ]
    if text:
        tabs.append(rrb.TextDocumentView(name="results", origin="/results"))
    return rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(timeline=_TIMELINE), collapse_panels=False)


def write_stiffness5_recording(
    path: str | Path,
    rec: Mapping[str, Any],
    series: Mapping[str, Any] | None = None,
    results: Mapping[str, Any] | None = None,
    *,
    force_scale_m_per_n: float = 0.01,
    base_scale_m_per_n: float = 0.001,
    application_id: str = "armlab",
) -> Path:
    """Write the recording described in the module docstring.

    Args:
        path: the ``.rrd`` file to write; must not exist.
        rec: the trials' recording series (module docstring).
        series: the estimation's series (ellipsoid surfaces), or ``None``.
        results: the protocol's results, logged as the printed table, or ``None``.
        force_scale_m_per_n: wrist-force arrow length per N (10 N draws 0.1 m).
        base_scale_m_per_n: base-force arrow length per N (the body's ~700 N draws 0.7 m).
        application_id: the recording's application id.

    Raises:
        ConfigError: a scale that is not a positive number.
        DataError: ``path`` exists or is not ``.rrd``, or ``rec`` holds no trial.
    """
    import rerun as rr
    import rerun.blueprint as rrb

    for name, v in (("force_scale_m_per_n", force_scale_m_per_n), ("base_scale_m_per_n", base_scale_m_per_n)):
        if not (np.isfinite(v) and v > 0):
            raise ConfigError(f"{name} must be a positive number, got {v!r}")
    skeleton = np.asarray(rec["skeleton"], np.float32)
    if skeleton.ndim != 4 or skeleton.shape[0] == 0:
        raise DataError(f"rec['skeleton'] must be (n_trials, n, 3, 3) with a trial, got {skeleton.shape}")
    n_trials, n = skeleton.shape[:2]
    t = np.asarray(rec["t"], float)
    slot = (t[-1] - t[0]) + (t[1] - t[0] if n > 1 else 0.01)
    times = (np.arange(n_trials)[:, None] * slot + (t - t[0])[None]).reshape(-1)
    ones = np.ones(times.size, dtype=int)
    marker = np.asarray(rec["marker"], np.float32).reshape(-1, 3)
    wrist = skeleton[:, :, 2].reshape(-1, 3)
    f_w = np.asarray(rec["wrist_force"], np.float32).reshape(-1, 3) * force_scale_m_per_n
    f_b = np.asarray(rec["base_force"], np.float32).reshape(-1, 3) * base_scale_m_per_n
    p = fresh_path(path, ".rrd")
    text = format_stiffness5_table(results) if results else None
    index = [rr.TimeColumn(_TIMELINE, duration=times)]
    with recording(p, application_id, _blueprint(rrb, text is not None)) as stream:
        stream.send_columns(
            "arm/skeleton",
            indexes=index,
            columns=rr.LineStrips3D.columns(strips=list(skeleton.reshape(-1, 3, 3))),
        )
        stream.send_columns(
            "arm/marker",
            indexes=index,
            columns=rr.Points3D.columns(
                positions=marker, radii=np.full(times.size, 0.01, np.float32)
            ).partition(ones),
        )
        stream.send_columns(
            "arm/wrist_force",
            indexes=index,
            columns=rr.Arrows3D.columns(origins=wrist, vectors=f_w).partition(ones),
        )
        stream.send_columns(
            "arm/base_force",
            indexes=index,
            columns=rr.Arrows3D.columns(origins=np.zeros_like(f_b), vectors=f_b).partition(ones),
        )
        names = list(rec.get("names") or [])
        if series is not None and "surface_hat" in series:
            for c, name in enumerate(names):
                for kind, key, colour in (
                    ("truth", "surface_true", (150, 150, 150)),
                    ("estimate", "surface_hat", (230, 120, 20)),
                ):
                    pts = np.asarray(series[key][c], np.float32).reshape(-1, 3)
                    stream.log(
                        f"ellipsoids/{name}/{kind}",
                        rr.Points3D(pts, radii=0.02, colors=[colour]),
                        static=True,
                    )
        if text is not None:
            stream.log("results", rr.TextDocument(text), static=True)
    return p
