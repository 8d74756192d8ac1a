"""Issue 23's comparison sweep (not timed): the paper's quintic vs the designed excitation in the
default realistic lab, seeds 0-4, and the planning model's lower bound on what any designed
waveform of the family can reach per window.

Usage: ``python benchmarks/excitation_comparison.py OUT_DIR`` writes ``comparison.json`` and
``comparison.png`` (armlab.viz.plot_excitation_comparison) and prints the README table
(docs/excitation_design.md). About 2 min on 2 cores.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.excitation_comparison import compare_excitations
from armlab.viz import plot_excitation_comparison

SEEDS = [0, 1, 2, 3, 4]


def _ms(v) -> str:
    return "never" if v is None else f"{1e3 * v:.0f}"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    summary = compare_excitations(
        ConditioningWindowConfig(),
        {"paper quintic": ("conditioning_window", None), "designed (120 ms)": ("designed_window", None)},
        SEEDS,
    )
    (out / "comparison.json").write_text(json.dumps(summary, indent=1))
    plot_excitation_comparison(summary, out / "comparison.png")
    print("| excitation | window (ms) | cond | K err | D err | ξ err |")
    print("|---|---|---|---|---|---|")
    for label, s in summary.items():
        for want in (0.12, 0.2, 0.3, 0.37, 0.4):
            i = min(range(len(s["t_obs_s"])), key=lambda j: abs(s["t_obs_s"][j] - want))
            row = [f"{s['cond']['median'][i]:.3g}"] + [
                f"{100 * s[k]['median'][i]:.0f} % ({100 * s[k]['min'][i]:.0f}-{100 * s[k]['max'][i]:.0f})"
                for k in ("K_rel_err", "D_rel_err", "xi_rel_err")
            ]
            print(f"| {label} | {1e3 * s['t_obs_s'][i]:.0f} | " + " | ".join(row) + " |")
    print(
        "\n| excitation | K p.d. from (ms, per seed) | quasi-symmetric from | quasi-constant from | K, D, ξ all ≤ 10 % from | peak robot torque A1..A7 (N m) |"
    )
    print("|---|---|---|---|---|---|")
    for label, s in summary.items():
        c = s["criteria"]
        crit = [
            ", ".join(_ms(v) for v in c[k]) for k in ("K_pd_from_s", "symmetric_from_s", "constant_from_s")
        ]
        tau = ", ".join(f"{v:.0f}" for v in s["robot_tau_peak_Nm"])
        print(f"| {label} | " + " | ".join(crit) + f" | {_ms(s['all_within_10pct_from_s'])} | {tau} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
