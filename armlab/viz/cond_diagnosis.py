"""Figures and rerun recording of a conditioning-window diagnosis (the edge: files only here).

- ``diagnosis_overlay.png``: for one held-out trial per perturbation direction, the measured,
  nominal and corrected torque change of both joints, 0-400 ms after onset;
- ``diagnosis_windows.png``: held-out gap over the noise floor per window after onset, per stage;
- ``diagnosis.rrd``: every trial's measured / nominal / corrected torque and residuals.
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

__all__ = ["cond_diagnosis_figures", "cond_diagnosis_recording"]

_JOINTS = ("shoulder", "elbow")


def _per_trial(group: Mapping[str, Any], key: str) -> np.ndarray:
    cs = group["set"]
    return np.asarray(group[key], float).reshape(cs.n_trials, cs.n_window, 2)


def cond_diagnosis_figures(
    series: Mapping[str, Any], results: Mapping[str, Any], out: str | Path
) -> list[Path]:
    """Write the two figures into ``out``; returns their paths (never overwrites)."""
    group = series["all"]
    cs = group["set"]
    meas, nom, cor = (_per_trial(group, k) for k in ("measured", "nominal", "corrected"))
    t_ms = 1e3 * np.arange(cs.n_window) / cs.fs_hz
    held = np.flatnonzero(cs.held_trials)
    picks = []
    for d in np.unique(cs.direction[held]):
        picks.append(int(held[cs.direction[held] == d][0]))
    picks = picks[:6]
    fig = Figure(figsize=(11, 2.2 * len(picks) + 0.6))
    axes = fig.subplots(len(picks), 2, squeeze=False, sharex=True)
    for row, i in enumerate(picks):
        for j in range(2):
            ax = axes[row, j]
            ax.plot(t_ms, meas[i, :, j], color="0.1", lw=1.2, label="measured")
            ax.plot(t_ms, nom[i, :, j], color="0.55", lw=1.0, ls="--", label="nominal")
            ax.plot(t_ms, cor[i, :, j], color="tab:red", lw=1.0, label="corrected")
            ax.set_ylabel(f"Δτ {_JOINTS[j]} (N·m)")
            if row == 0:
                ax.set_title(f"{_JOINTS[j]} — held-out trial {i} (direction {cs.direction[i]})")
            else:
                ax.set_title(f"trial {i} (direction {cs.direction[i]})", fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("time after onset (ms)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"verdict: {', '.join(results['verdict'])}")
    fig.tight_layout()
    paths = [save_png(fig, Path(out) / "diagnosis_overlay.png")]

    stages = results["how_far"]
    fig = Figure(figsize=(8, 3.8))
    ax = fig.subplots()
    labels = [f"{w['window_ms'][0]:g}–{w['window_ms'][1]:g}" for w in stages[0]["windows"]]
    width = 0.8 / len(stages)
    for k, s in enumerate(stages):
        ratio = [
            (w["held_out_gap"] / w["noise_floor"])
            if w["held_out_gap"] is not None and w["noise_floor"]
            else np.nan
            for w in s["windows"]
        ]
        name = "nominal" if not s["effects"] else "+ " + " + ".join(s["effects"])
        ax.bar(np.arange(len(labels)) + k * width, ratio, width, label=name)
    ax.axhline(1.0, color="k", lw=0.8, ls=":", label="noise floor")
    ax.set_xticks(np.arange(len(labels)) + 0.4 - width / 2, labels)
    ax.set_xlabel("window after onset (ms)")
    ax.set_ylabel("held-out gap / noise floor")
    ax.set_yscale("log")
    plain_log_ticks(ax.yaxis)
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths.append(save_png(fig, Path(out) / "diagnosis_windows.png"))
    return paths


def cond_diagnosis_recording(
    series: Mapping[str, Any], path: str | Path, *, app_id: str = "armlab_diagnose"
) -> Path:
    """Every trial's torque change (measured, nominal, corrected) and residuals, per joint.

    Entity paths ``trials/<i>/<joint>/{measured,nominal,corrected,residual_nominal,
    residual_corrected}`` on the ``time_after_onset`` timeline (s); held-out trials are marked
    by a text log at onset.
    """

    group = series.get("all")
    if group is None or "set" not in group:
        raise DataError("cond_diagnosis_recording needs series['all'] from diagnose_cond")
    cs = group["set"]
    meas, nom, cor = (_per_trial(group, k) for k in ("measured", "nominal", "corrected"))
    p = fresh_path(path, ".rrd")
    t = np.arange(cs.n_window) / cs.fs_hz
    with recording(p, app_id) as rec:  # written under a temporary name, renamed when complete
        for i in range(cs.n_trials):
            held = "held-out trial: scored, not fitted" if cs.held_trials[i] else None
            log_trial_stages(rec, i, _JOINTS, t, meas[i], nom[i], cor[i], held)
    return p
