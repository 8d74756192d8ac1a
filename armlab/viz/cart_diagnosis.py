"""Figures and rerun recording of a ``cartesian_online`` diagnosis (the edge: files only here).

- ``diagnosis_overlay.png``: the held-out sequence with the largest nominal gap, its three
  perturbations (+x, −y, (+x, −y)): measured, nominal and corrected force on both axes, and the
  residuals;
- ``diagnosis_where.png``: held-out gap over the noise floor per window after onset and per
  held-out sequence, one bar per stage;
- ``diagnosis.rrd``: every trial's measured / nominal / corrected force and residuals per axis.
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

__all__ = ["cart_diagnosis_figures", "cart_diagnosis_recording"]

_AXES = ("x", "y")


def _per_trial(group: Mapping[str, Any], key: str) -> np.ndarray:
    """Scoring rows -> (m, n, 2) N, NaN where not scored (padding, edge guard)."""
    cs = group["set"]
    out = np.full((*cs.scored.shape, 2), np.nan)
    out[cs.scored] = np.asarray(group[key], float).reshape(-1, 2)
    return out


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
    ax.set_xticks(np.arange(len(labels)) + 0.4 - width / 2, labels)
    ax.set_ylabel("held-out gap / noise floor")
    ax.set_yscale("log")
    plain_log_ticks(ax.yaxis)


def cart_diagnosis_figures(
    series: Mapping[str, Any], results: Mapping[str, Any], out: str | Path
) -> list[Path]:
    """Write the two figures into ``out``; returns their paths (never overwrites)."""
    group = series["all"]
    cs = group["set"]
    meas, nom, cor = (_per_trial(group, k) for k in ("measured", "nominal", "corrected"))
    t_ms = 1e3 * np.arange(cs.valid.shape[1]) / cs.fs_hz
    seqs = results["where"]["sequences"]
    worst = max(seqs, key=lambda e: e["held_out_gap"] or 0.0)["sequence"]
    picks = np.flatnonzero(cs.stop == worst)
    fig = Figure(figsize=(11, 2.4 * len(picks) + 0.6))
    axes = fig.subplots(len(picks), 2, squeeze=False, sharex=True)
    for row, i in enumerate(picks):
        for j in range(2):
            ax = axes[row, j]
            ax.plot(t_ms, meas[i, :, j], color="0.1", lw=1.2, label="measured")
            ax.plot(t_ms, nom[i, :, j], color="0.55", lw=1.0, ls="--", label="nominal")
            ax.plot(t_ms, cor[i, :, j], color="tab:red", lw=1.0, label="corrected")
            twin = ax.twinx()
            twin.plot(t_ms, meas[i, :, j] - nom[i, :, j], color="tab:blue", lw=0.6, alpha=0.6)
            twin.plot(t_ms, meas[i, :, j] - cor[i, :, j], color="tab:orange", lw=0.6, alpha=0.6)
            twin.set_ylabel("residual (N): nominal blue, corrected orange", fontsize=7)
            ax.set_ylabel(f"F_{_AXES[j]} (N)")
            ax.set_title(
                f"held-out sequence {worst}, perturbation {cs.phase[i]}, axis {_AXES[j]}", fontsize=9
            )
    for ax in axes[-1]:
        ax.set_xlabel("time after onset (ms)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"verdict: {', '.join(results['verdict'])}")
    fig.tight_layout()
    paths = [save_png(fig, Path(out) / "diagnosis_overlay.png")]

    stages = results["how_far"]
    fig = Figure(figsize=(11, 3.8))
    ax1, ax2 = fig.subplots(1, 2)
    _bars(ax1, stages, "windows", lambda e: f"{e['window_ms'][0]:g}–{e['window_ms'][1]:g}")
    ax1.set_xlabel("window after onset (ms)")
    _bars(ax2, stages, "sequences", lambda e: str(e["sequence"]))
    ax2.set_xlabel("held-out sequence")
    ax1.legend(fontsize=8)
    fig.tight_layout()
    paths.append(save_png(fig, Path(out) / "diagnosis_where.png"))
    return paths


def cart_diagnosis_recording(
    series: Mapping[str, Any], path: str | Path, *, app_id: str = "armlab_diagnose"
) -> Path:
    """Every trial's force (measured, nominal, corrected) and residuals, per axis.

    Entity paths ``trials/<i>/<axis>/{measured,nominal,corrected,residual_nominal,
    residual_corrected}`` (N) on the ``time_after_onset`` timeline (s); held-out trials are marked
    by a text log at onset.
    """

    group = series.get("all")
    if group is None or "set" not in group:
        raise DataError("cart_diagnosis_recording needs series['all'] from diagnose_cart")
    cs = group["set"]
    meas, nom, cor = (_per_trial(group, k) for k in ("measured", "nominal", "corrected"))
    p = fresh_path(path, ".rrd")
    with recording(p, app_id) as rec:  # written under a temporary name, renamed when complete
        for i in range(cs.n_trials):
            k = np.flatnonzero(cs.scored[i])
            held = f"held-out {cs.names[i]}: scored, not fitted" if cs.held_trials[i] else None
            log_trial_stages(rec, i, _AXES, k / cs.fs_hz, meas[i, k], nom[i, k], cor[i, k], held)
    return p
