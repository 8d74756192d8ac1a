"""Rerun recording of a paper 002 (Cartesian online LS) run: path, stops, forces, K̂ ellipses.

Layout (entity paths), on the ``sim_time`` timeline (s of the experiment's wall time; the thesis
logs only during perturbations, so time jumps between them):

- ``<case>/path`` (static): the reference path as a 2D line strip (m);
- ``<case>/stops`` (static): the stop points;
- ``<case>/hand``: the hand position during the perturbations (decimated to ``max_hz``);
- ``<case>/force``: the measured force as an arrow at the hand, ``force_scale_m_per_n`` m per N;
- ``<case>/k_true`` (static) and ``<case>/k_hat`` (after each sequence, where given): the
  diagonal stiffness at every stop as axis-aligned ellipses with half-sizes
  ``k_scale_m_per_n_per_m``·(K_xx, K_yy), truth grey, estimate orange;
- ``<case>/field_error_pct``: the field error after each sequence (scalar series), where given;
- ``results`` (static): the printed table.

``series['recording']`` is {case: {``path`` (p, 2) m, ``stops`` (s, 2) m, ``t`` (n,) s, ``hand``
(n, 2) m, ``force`` (n, 2) N, optional ``k_true`` (s, 2) N/m, ``k_hat`` (q, s, 2) N/m (NaN while
rank deficient), ``t_after`` (q,) s, ``field_error_pct`` (q,) %}}. ``rerun`` is imported inside
:func:`write_cartesian_recording` only.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from armlab.errors import ConfigError, DataError
from armlab.viz._paths import fresh_path, recording
from armlab.viz.cartesian import format_cartesian_table

__all__ = ["write_cartesian_recording"]

_TIMELINE = "sim_time"


def _blueprint(rrb, cases: list[str], text: bool):
    tabs = [
        rrb.Horizontal(
            rrb.Spatial2DView(name=f"{c}: path, forces, K ellipses", origin=f"/{c}"),
            rrb.TimeSeriesView(name="field error (%)", origin=f"/{c}/field_error_pct"),
            name=c,
        )
        for c in cases
    ]
    if text:
        tabs.append(rrb.TextDocumentView(name="results", origin="/results"))
    return rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(timeline=_TIMELINE), collapse_panels=False)


def write_cartesian_recording(
    path: str | Path,
    series: Mapping[str, Any],
    results: Mapping[str, Any] | None = None,
    *,
    max_hz: float = 50.0,
    force_scale_m_per_n: float = 2e-4,
    k_scale_m_per_n_per_m: float = 1e-6,
    application_id: str = "armlab",
) -> Path:
    """Write the recording described in the module docstring.

    Args:
        path: the ``.rrd`` file to write; must not exist.
        series: ``{"recording": {case: ...}}`` (module docstring).
        results: the protocol's results, logged as the printed table, or ``None``.
        max_hz: rate the hand and force are decimated to, Hz (> 0).
        force_scale_m_per_n: arrow length per newton, m/N (default: 240 N, the thesis's largest
            force, draws 48 mm, half the circle's radius).
        k_scale_m_per_n_per_m: ellipse half-size per N/m, m (default: 20 kN/m draws 20 mm).
        application_id: the recording's application id.

    Returns:
        The written path.

    Raises:
        ConfigError: a scale or rate that is not a positive number.
        DataError: ``path`` exists or is not ``.rrd``, or the series has no case to record.
    """
    import rerun as rr
    import rerun.blueprint as rrb

    for name, v in (
        ("max_hz", max_hz),
        ("force_scale_m_per_n", force_scale_m_per_n),
        ("k_scale_m_per_n_per_m", k_scale_m_per_n_per_m),
    ):
        if not (np.isfinite(v) and v > 0):
            raise ConfigError(f"{name} must be a positive number, got {v!r}")
    cases = dict(series.get("recording") or {})
    if not cases:
        raise DataError("series['recording'] holds no case to record")
    p = fresh_path(path, ".rrd")
    text = format_cartesian_table(results) if results else None
    with recording(p, application_id, _blueprint(rrb, list(cases), text is not None)) as rec:
        for case, c in cases.items():
            rec.log(
                f"{case}/path",
                rr.LineStrips2D([np.asarray(c["path"], np.float32)], colors=[(120, 120, 120)], radii=0.0008),
                static=True,
            )
            rec.log(
                f"{case}/stops",
                rr.Points2D(np.asarray(c["stops"], np.float32), radii=0.002, colors=[(40, 40, 40)]),
                static=True,
            )
            t = np.asarray(c["t"], dtype=float)
            fs = 1.0 / np.median(np.diff(t)) if len(t) > 1 else max_hz
            idx = np.arange(0, len(t), max(1, int(round(fs / max_hz))))
            hand = np.asarray(c["hand"], np.float32)[idx]
            force = np.asarray(c["force"], np.float32)[idx]
            ones = np.ones(len(idx), dtype=int)
            times = [rr.TimeColumn(_TIMELINE, duration=t[idx])]
            rec.send_columns(
                f"{case}/hand",
                indexes=times,
                columns=rr.Points2D.columns(
                    positions=hand, radii=np.full(len(idx), 0.003, np.float32)
                ).partition(ones),
            )
            rec.send_columns(
                f"{case}/force",
                indexes=times,
                columns=rr.Arrows2D.columns(origins=hand, vectors=force * force_scale_m_per_n).partition(
                    ones
                ),
            )
            if "k_true" in c:
                stops = np.asarray(c["stops"], np.float32)
                kt = np.asarray(c["k_true"], dtype=float) * k_scale_m_per_n_per_m
                rec.log(
                    f"{case}/k_true",
                    rr.Ellipses2D(
                        centers=stops,
                        half_sizes=kt.astype(np.float32),
                        colors=[(150, 150, 150)],
                        line_radii=0.0006,
                    ),
                    static=True,
                )
            if "k_hat" in c:
                kh = np.asarray(c["k_hat"], dtype=float)
                for j, tj in enumerate(np.asarray(c["t_after"], dtype=float)):
                    rec.set_time(_TIMELINE, duration=tj)
                    ok = np.all(np.isfinite(kh[j]), axis=1)
                    rec.log(
                        f"{case}/k_hat",
                        rr.Ellipses2D(
                            centers=np.asarray(c["stops"], np.float32)[ok],
                            half_sizes=np.abs(kh[j][ok] * k_scale_m_per_n_per_m).astype(np.float32),
                            colors=[(230, 120, 20)],
                            line_radii=0.0008,
                        ),
                    )
                    rec.log(f"{case}/field_error_pct", rr.Scalars(float(c["field_error_pct"][j])))
        if text is not None:
            rec.log("results", rr.TextDocument(text), static=True)
    return p
