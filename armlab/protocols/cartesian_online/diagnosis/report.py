"""``report.md`` of a ``cartesian_online`` diagnosis: readable on its own, built from results.json."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from armlab.diagnosis.report_text import (
    fmt_num,
    fmt_pct,
    fmt_share,
    gap_cells,
    how_far_table,
    md_table,
    verdict_paragraph,
    which_effect_section,
    window_meaning,
)
from armlab.protocols.cartesian_online.diagnosis.rules import RULES

__all__ = ["format_cart_report"]

_PHASES = {"+x": "+x triangle", "-y": "−y triangle", "+x-y": "combined (+x, −y)"}


def _gap_rows(entries: Sequence[Mapping[str, Any]], label) -> list[list[str]]:
    return [[label(e), *gap_cells(e["held_out_gap"], e["noise_floor"])] for e in entries]


def _where(r: Mapping[str, Any]) -> list[str]:
    w = r["where"]
    head = ["", "gap", "noise floor", "gap / floor"]
    out = [
        "## Where the gap lies (nominal model, held-out sequences)",
        "",
        "### Time after perturbation onset",
        "",
    ]
    out += md_table(
        ["window", *head[1:], "what acts there"],
        [
            [
                f"{e['window_ms'][0]:g}–{e['window_ms'][1]:g} ms",
                *gap_cells(e["held_out_gap"], e["noise_floor"]),
                window_meaning(*e["window_ms"]),
            ]
            for e in w["windows"]
        ],
    )
    out += ["", "### Perturbation of the sequence", ""]
    out += md_table(
        ["perturbation", *head[1:]],
        _gap_rows(w["perturbations"], lambda e: _PHASES.get(e["perturbation"], e["perturbation"])),
    )
    out += ["", "### Held-out sequence (stop on the path)", ""]
    out += md_table(["sequence", *head[1:]], _gap_rows(w["sequences"], lambda e: str(e["sequence"])))
    out += ["", "### Force axis", ""]
    out += md_table(["axis", *head[1:]], _gap_rows(w["channels"], lambda e: e["axis"]))
    out += ["", "### Frequency band (spectra of the held-out perturbations)", ""]
    out += md_table(
        ["band", "share of the residual power", "gap in the band"],
        [
            [
                f"{b['band_hz'][0]:g}–{b['band_hz'][1]:g} Hz",
                fmt_share(b["residual_share"]),
                fmt_pct(b["held_out_gap"]),
            ]
            for b in w["bands"]
        ],
    )
    t = w["residual_tests"]
    out += [
        "",
        "### Residual test",
        "",
        f"- Residual–hand-velocity cross-correlation: peak {fmt_num(t['max_cross_correlation'])} at "
        f"{1e3 * t['max_cross_correlation_lag_s']:.0f} ms (a white residual stays within "
        f"±{fmt_num(t['bound_95'])}). At zero lag: a missing instantaneous term (mass, field shape); "
        "a few ms: a delay of the force channel or of the hand's reaction.",
    ]
    return out


def _how_far(r: Mapping[str, Any]) -> list[str]:
    stages = r["how_far"]
    out = how_far_table(stages)
    out += [
        "",
        "Calibrated parameters of the last stage (k N/m per power of the scaled position, δ as a "
        "factor on the nominal √K̂ profile; effects' own units in their names):",
        "",
    ]
    last = stages[-1]["parameters"]
    out += md_table(["parameter", "value"], [[k, fmt_num(v)] for k, v in last.items()])
    return out


def _offset_clause(gap: Mapping[str, Any]) -> str:
    """The per-trial offsets read into the floor, where the file has them (results before
    ``trial_offset_N`` existed have none)."""
    sd = gap.get("trial_offset_N")
    if not sd:
        return ""
    return "; per-trial force offsets of " + " / ".join(f"{x:.3g}" for x in sd) + " N rms (x / y)"


def format_cart_report(results: Mapping[str, Any], *, data_path: str, figures: Sequence[str] = ()) -> str:
    """The Markdown report of a ``cartesian_online`` diagnosis (see docs/diagnosis_schema.md)."""
    r = results
    sc = r.get("scoring", {})
    lines = [
        "# Sim-to-real diagnosis — protocol `cartesian_online`",
        "",
        f"Data: `{data_path}` — {len(r.get('trials') or [])} perturbations in {sc.get('n_sequences', '?')} "
        f"sequences, sequences {sc.get('held_out_sequences', '?')} held out. Nominal simulation: the "
        "thesis's quadratic stiffness field with D = δ√K (Eqs. 2.2.1-2.2.4, 3.4.1; 12 + 2 parameters) "
        "calibrated on the other sequences. Gap = held-out residual power / measured force power "
        "(1 − VAF); noise floor = the same ratio for what no model can predict on a held-out trial "
        f"({r['gap']['noise_source']}){_offset_clause(r['gap'])}.",
        "",
        verdict_paragraph(r, {**RULES, **(r.get("settings") or {})}),
        "",
    ]
    lines += _where(r) + which_effect_section(r, "sequences") + _how_far(r)
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    return "\n".join(lines) + "\n"
