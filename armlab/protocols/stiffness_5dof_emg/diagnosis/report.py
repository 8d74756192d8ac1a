"""``report.md`` of a ``stiffness_5dof_emg`` diagnosis: readable on its own, built from results.json."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from armlab.diagnosis.report_text import (
    gap_cells,
    how_far_table,
    md_table,
    verdict_paragraph,
    which_effect_section,
)
from armlab.protocols.stiffness_5dof_emg.diagnosis.rules import RULES

__all__ = ["format_stiff5_report"]

_WHERE = (
    ("groups", "channel group", lambda e: e["group"]),
    ("windows", "hold bin after onset", lambda e: f"{e['window_ms'][0]:g}–{e['window_ms'][1]:g} ms"),
    ("conditions", "pre-load condition", lambda e: e["condition"]),
    ("channels", "channel", lambda e: f"{e['channel']}.{e['axis']}"),
    ("directions", "disturbance direction", lambda e: str(e["direction"])),
)


def _where(r: Mapping[str, Any]) -> list[str]:
    out = ["## Where the gap lies (nominal model, held-out disturbances)", ""]
    for key, title, label in _WHERE:
        out += [f"### Per {title}", ""]
        out += md_table(
            [title, "gap", "noise floor", "gap / floor"],
            [[label(e), *gap_cells(e["held_out_gap"], e["noise_floor"])] for e in r["where"][key]],
        )
        out.append("")
    return out


def format_stiff5_report(results: Mapping[str, Any], *, data_path: str, figures: Sequence[str] = ()) -> str:
    """The Markdown report of a ``stiffness_5dof_emg`` diagnosis (docs/stiffness_5dof_emg.md)."""
    r = results
    sc = r.get("scoring", {})
    nm = r.get("nominal_model", {})
    lines = [
        "# Sim-to-real diagnosis — protocol `stiffness_5dof_emg`",
        "",
        f"Data: `{data_path}` — {sc.get('n_trials', '?')} disturbances, {sc.get('held_out_trials', '?')} "
        "held out (every third of each condition). Nominal model: the paper's static stiffness "
        "(Eq. (14), activation frozen), K_q per pre-load condition fitted on the other disturbances, "
        "gravity compensated with xi_red "
        f"{nm.get('xi_red', '?')}; the nominal lab's displacement (commanded less the LWR servos' give) "
        "and the seat's statics for the base JR3. Scored: the hold's 50 ms bins "
        f"{sc.get('window_ms', '?')} ms after onset, each row whitened by its channel's noise. "
        f"Gap = held-out residual power / measured power (1 − VAF); noise floor: {r['gap']['noise_source']}.",
        "",
        verdict_paragraph(r, {**RULES, **(r.get("settings") or {})}),
        "",
    ]
    lines += _where(r) + which_effect_section(r, "disturbances") + how_far_table(r["how_far"])
    spd = [e for e in nm.get("K_spd", []) if "K_spd_Nm_per_rad" in e]
    if spd:
        lines += [
            "",
            "SPD estimate of Eqs. (16)-(17) on the training disturbances (smallest eigenvalue):",
            "",
        ]
        lines += md_table(
            ["condition", "training disturbances", "λ_min (N·m/rad)"],
            [[e["condition"], e["n_train"], f"{e['min_eigenvalue_Nm_per_rad']:.3g}"] for e in spd],
        )
    lines += ["", "Not candidates: " + "; ".join(f"{k}: {v}" for k, v in r.get("not_candidates", {}).items())]
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    return "\n".join(lines) + "\n"
