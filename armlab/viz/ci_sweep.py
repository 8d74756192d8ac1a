"""The figure of CI's observation-window sweep: each criterion per window, and the errors vs T_obs,
against the committed baseline (armlab.protocols.conditioning_window.window_sweep)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from armlab.viz._paths import save_png
from armlab.viz._ticks import plain_log_ticks

__all__ = ["plot_ci_window_sweep"]

_CRITERIA = (
    ("K_pd", "K_pd_from_s", "K p.d."),
    ("symmetric", "symmetric_from_s", "symm."),
    ("constant", "constant_from_s", "const."),
)
_ERRORS = (("K_err", "K"), ("D_err", "D"), ("xi_err", "ξ"))  # against the intrinsic truth


def plot_ci_window_sweep(summary: dict, baseline: dict | None, path: Path) -> Path:
    """Two panels: where each criterion holds (filled: holds; the line: first met, dashed: baseline),
    and the relative errors against the intrinsic truth (circles: baseline at the longest window)."""
    t_ms = np.array([w["t_obs_s"] for w in summary["windows"]]) * 1e3
    models = list(summary["first_met"])
    fig = Figure(figsize=(10.0, 6.4), layout="constrained")
    ax_c, ax_e = fig.subplots(2, 1, sharex=True, height_ratios=(1.0, 1.3))
    labels = []
    for row, (model, (flag, key, name)) in enumerate((m, c) for m in models for c in _CRITERIA):
        held = np.array([w[model][flag] for w in summary["windows"]])
        ax_c.scatter(t_ms[held], np.full(held.sum(), row), marker="s", s=28, color="tab:green")
        ax_c.scatter(t_ms[~held], np.full((~held).sum(), row), marker="s", s=28, color="0.85")
        for src, style in ((summary, "-"), (baseline, "--")):
            t = None if src is None else src["first_met"][model][key]
            if t is not None:
                ax_c.plot([t * 1e3] * 2, [row - 0.4, row + 0.4], style, color="k", lw=1.4)
        labels.append(f"{model} {name}")
    ax_c.set_yticks(range(len(labels)), labels)
    ax_c.invert_yaxis()
    ax_c.set_title("criteria per window (green: holds; solid: first met; dashed: baseline)")
    for (key, name), color in zip(_ERRORS, ("tab:blue", "tab:orange", "tab:purple"), strict=True):
        for model, style in zip(models, ("-", ":"), strict=False):
            if key not in summary["windows"][0][model]:
                continue
            err = np.array([w[model][key] for w in summary["windows"]]) * 100
            ax_e.plot(t_ms, err, style, marker=".", color=color, label=f"{model} {name}")
            if baseline is not None and key in baseline["longest"][model]:
                ax_e.plot(t_ms[-1], baseline["longest"][model][key] * 100, "o", mfc="none", color=color)
    ax_e.set_yscale("log")
    plain_log_ticks(ax_e.yaxis)
    ax_e.set_xlabel("T_obs (ms)")
    ax_e.set_ylabel("error vs intrinsic truth (%)")
    ax_e.legend(fontsize=8, ncol=2)
    return save_png(fig, path)
