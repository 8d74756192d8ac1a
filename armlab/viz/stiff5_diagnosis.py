"""Figures and rerun recording of a ``stiffness_5dof_emg`` diagnosis (the edge: files only here).

- ``diagnosis_where.png``: held-out gap over the noise floor per channel group, per hold bin after
  onset and per condition, one bar per stage;
- ``diagnosis_channels.png``: the same per channel (5 torques, 5 displacements, 6 base axes);
- ``diagnosis.rrd``: every trial's whitened rows (measured, nominal, corrected and residuals) per
  channel on the time-after-onset timeline.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from armlab.errors import DataError
from armlab.viz._paths import fresh_path, recording, save_png
from armlab.viz._ticks import plain_log_ticks
from armlab.viz._trial_stages import log_trial_stages

__all__ = ["stiff5_diagnosis_figures", "stiff5_diagnosis_recording"]


def _ratio(entry: Mapping[str, Any]) -> float:
    g, f = entry["held_out_gap"], entry["noise_floor"]
    return g / f if g is not None and f else np.nan


def _bars(ax, stages, key: str, label) -> None:
    labels = [label(e) for e in stages[0][key]]
    width = 0.8 / len(stages)
    for k, s in enumerate(stages):
        name = "nominal" if not s["effects"] else "+ " + " + ".join(s["effects"])
        ax.bar(np.arange(len(labels)) + k * width, [_ratio(e) for e in s[key]], width, label=name)
    ax.axhline(1.0, color="k", lw=0.8, ls=":", label="noise floor")
    ax.set_xticks(np.arange(len(labels)) + 0.4 - width / 2, labels, fontsize=7, rotation=30)
    ax.set_ylabel("held-out gap / noise floor")
    ax.set_yscale("log")
    plain_log_ticks(ax.yaxis)


def stiff5_diagnosis_figures(
    series: Mapping[str, Any], results: Mapping[str, Any], out: str | Path
) -> list[Path]:
    """Write the two figures into ``out``; returns their paths (never overwrites)."""
    stages = results["how_far"]
    fig = Figure(figsize=(13, 3.8))
    ax1, ax2, ax3 = fig.subplots(1, 3)
    _bars(ax1, stages, "groups", lambda e: e["group"])
    ax1.set_xlabel("channel group")
    _bars(ax2, stages, "windows", lambda e: f"{e['window_ms'][0]:g}–{e['window_ms'][1]:g}")
    ax2.set_xlabel("hold bin after onset (ms)")
    _bars(ax3, stages, "conditions", lambda e: e["condition"])
    ax3.set_xlabel("pre-load condition")
    ax1.legend(fontsize=7)
    fig.suptitle(f"verdict: {', '.join(results['verdict'])}")
    fig.tight_layout()
    paths = [save_png(fig, Path(out) / "diagnosis_where.png")]
    fig = Figure(figsize=(13, 3.8))
    ax = fig.subplots()
    _bars(ax, stages, "channels", lambda e: f"{e['channel']}.{e['axis']}")
    ax.legend(fontsize=7)
    fig.tight_layout()
    paths.append(save_png(fig, Path(out) / "diagnosis_channels.png"))
    return paths


def stiff5_diagnosis_recording(
    series: Mapping[str, Any], path: str | Path, *, app_id: str = "armlab_diagnose"
) -> Path:
    """Every trial's whitened rows per channel: ``trials/<i>/<channel>/{measured,nominal,corrected,
    residual_nominal,residual_corrected}`` (noise standard deviations) on ``time_after_onset``."""
    group = series.get("all")
    if group is None or "set" not in group:
        raise DataError("stiff5_diagnosis_recording needs series['all'] from diagnose_stiff5")
    cs = group["set"]
    shape = cs.y.shape
    meas, nom, cor = (
        np.asarray(group[k], float).reshape(shape) for k in ("measured", "nominal", "corrected")
    )
    names = [f"{g}_{a}" for g, a in (c.split(".") for c in group.get("channels", ()))] or [
        f"channel_{k}" for k in range(shape[2])
    ]
    t_s = cs.bin_ms.mean(axis=1) / 1000.0
    p = fresh_path(path, ".rrd")
    with recording(p, app_id) as rec:
        for i in range(cs.n_trials):
            held = f"held-out {cs.names[i]}: scored, not fitted" if cs.held_trials[i] else None
            log_trial_stages(rec, i, names, t_s, meas[i], nom[i], cor[i], held)
    return p
