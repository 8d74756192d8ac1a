"""Issue 23's comparison figure in the style of Fig. 4 of the conditioning paper: condition number
and K, D, xi errors against the intrinsic truth over T_obs, one curve per excitation (median over
seeds, band: min-max), with each criterion's first window per seed marked
(armlab.protocols.conditioning_window.excitation_comparison)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from armlab.viz._paths import save_png
from armlab.viz._ticks import plain_log_ticks

__all__ = ["plot_excitation_comparison"]

_PANELS = (("cond", "cond(W), Eq. (19)"), ("K_rel_err", "K error (%)"), ("D_rel_err", "D error (%)"))
_PANELS += (("xi_rel_err", "ξ error (%)"),)
_MARKS = (
    ("K_pd_from_s", "v", "K p.d."),
    ("symmetric_from_s", "s", "symm."),
    ("constant_from_s", "o", "const."),
)


def plot_excitation_comparison(summary: dict, path: Path) -> Path:
    """Four panels over T_obs (ms): cond(W) and the K, D, xi errors (%, log) per excitation; the
    10 % target dashed; on the cond panel, each criterion's first-met window per seed (markers).

    Args:
        summary: label -> summary of ``compare_excitations``.
        path: the ``.png`` to write (must not exist).
    """
    fig = Figure(figsize=(9.0, 9.0), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    colors = ("tab:blue", "tab:red", "tab:green", "tab:purple")
    for (label, s), color in zip(summary.items(), colors, strict=False):
        t = np.array(s["t_obs_s"]) * 1e3
        for ax, (key, _) in zip(axes, _PANELS, strict=True):
            scale = 1.0 if key == "cond" else 100.0
            med = np.array(s[key]["median"]) * scale
            ax.plot(t, med, marker=".", color=color, label=label)
            ax.fill_between(
                t, np.array(s[key]["min"]) * scale, np.array(s[key]["max"]) * scale, color=color, alpha=0.2
            )
        top = float(np.max(s["cond"]["max"]))
        for row, (crit, marker, _) in enumerate(_MARKS):
            firsts = [v * 1e3 for v in s["criteria"][crit] if v is not None]
            axes[0].scatter(
                firsts, np.full(len(firsts), top * 1.3 ** (row + 1)), marker=marker, color=color, s=25
            )
    for ax, (key, name) in zip(axes, _PANELS, strict=True):
        ax.set_yscale("log")
        plain_log_ticks(ax.yaxis)
        ax.set_ylabel(name)
        if key != "cond":
            ax.axhline(10.0, ls="--", color="k", lw=1)
    axes[0].set_title(
        "median over seeds (band: min-max); markers: first window K p.d. (v), symm. (s), const. (o)"
    )
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("T_obs (ms)")
    return save_png(fig, path)
