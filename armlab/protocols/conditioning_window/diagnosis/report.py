"""``report.md`` of a conditioning-window diagnosis: readable on its own, built from results.json."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from armlab.diagnosis.report_text import (
    fmt_num,
    fmt_pct,
    fmt_ratio,
    fmt_share,
    gap_cells,
    how_far_table,
    md_table,
    stage_name,
    verdict_paragraph,
    which_effect_section,
    window_meaning,
)
from armlab.protocols.conditioning_window.diagnosis.rules import RULES

__all__ = ["format_cond_report"]

_DIRECTIONS = ("+q1", "-q1", "+q2", "-q2", "+q1-q2", "-q1+q2")  # scenarios/conditioning_window.yaml order
_BIAS_KEYS = ("K11", "K12", "K21", "K22", "D11", "D12", "D21", "D22", "xi1", "xi2", "xi3")


def _gap_rows(entries: Sequence[Mapping[str, Any]], label) -> list[list[str]]:
    return [
        [
            label(e),
            *gap_cells(e["held_out_gap"], e["noise_floor"]),
        ]
        for e in entries
    ]


def _where(r: Mapping[str, Any]) -> list[str]:
    w = r["where"]
    out = ["## Where the gap lies (nominal model, held-out trials)", ""]
    out += ["### Time after perturbation onset", ""]
    out += md_table(
        ["window", "gap", "noise floor", "gap / floor", "what acts there"],
        [
            [
                f"{e['window_ms'][0]:g}–{e['window_ms'][1]:g} ms",
                *gap_cells(e["held_out_gap"], e["noise_floor"]),
                window_meaning(*e["window_ms"]),
            ]
            for e in w["windows"]
        ],
    )
    out += ["", "### Joint (channel)", ""]
    out += md_table(
        ["channel", "gap", "noise floor", "gap / floor"], _gap_rows(w["channels"], lambda e: e["axis"])
    )
    out += ["", "### Perturbation direction (condition)", ""]
    out += md_table(
        ["direction", "gap", "noise floor", "gap / floor"],
        _gap_rows(
            w["conditions"],
            lambda e: (
                _DIRECTIONS[e["direction"]] if 0 <= e["direction"] < len(_DIRECTIONS) else str(e["direction"])
            ),
        ),
    )
    out += ["", "### Frequency band (spectra of the 0–400 ms held-out records)", ""]
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
        "### Residual tests",
        "",
        "- Whiteness: largest residual autocorrelation at lags 1–20 ms "
        f"{fmt_num(t['whiteness_lag_1_to_20ms'])} "
        f"(a white residual stays within ±{fmt_num(t['bound_95'])}; band-limiting alone correlates "
        "neighbouring samples).",
        f"- Residual–joint-velocity cross-correlation: peak {fmt_num(t['max_cross_correlation'])} at "
        f"{1e3 * t['max_cross_correlation_lag_s']:.0f} ms (bound ±{fmt_num(t['bound_95'])}). A peak "
        "well after "
        "zero lag points to a delayed pathway (reflex); one at zero lag to a missing instantaneous term.",
        "",
        "### Parameter bias: the same least squares on measured and on nominal-simulated torque",
        "",
        "Eq. (9) fitted on the training trials over growing observation windows; the nominal "
        "simulation's torque gives the calibrated values at every window, so a drift of the measured "
        "estimates with the window is the signature of an effect that is not in the model.",
        "",
    ]
    rows = [
        [f"{1e3 * b['t_obs_s']:.0f} ms"]
        + [f"{fmt_num(b['measured'][k])} ({fmt_num(b[k], 2)})" for k in _BIAS_KEYS[:8]]
        for b in w["parameter_bias"]
    ]
    out += md_table(["T_obs"] + [f"{k} meas. (bias)" for k in _BIAS_KEYS[:8]], rows)
    return out


def _how_far(r: Mapping[str, Any]) -> list[str]:
    stages = r["how_far"]
    out = how_far_table(stages)
    out += ["", "Per window after onset (gap / floor):", ""]
    windows = [f"{w['window_ms'][0]:g}–{w['window_ms'][1]:g} ms" for w in stages[0]["windows"]]
    out += md_table(
        ["model", *windows],
        [
            [stage_name(s["effects"])]
            + [fmt_ratio(w["held_out_gap"], w["noise_floor"]) for w in s["windows"]]
            for s in stages
        ],
    )
    out += ["", "Calibrated parameters per stage (K N·m/rad, D N·m·s/rad, xi kg·m²):", ""]
    out += md_table(
        ["model", *_BIAS_KEYS],
        [[stage_name(s["effects"])] + [fmt_num(s["parameters"].get(k)) for k in _BIAS_KEYS] for s in stages],
    )
    return out


def format_cond_report(results: Mapping[str, Any], *, data_path: str, figures: Sequence[str] = ()) -> str:
    """The Markdown report of a conditioning-window diagnosis (see docs/diagnosis_schema.md)."""
    r = results
    scoring = r.get("scoring", {})
    lines = [
        "# Sim-to-real diagnosis — protocol `conditioning_window`",
        "",
        f"Data: `{data_path}` — {len(r.get('trials') or [])} trials, "
        f"{scoring.get('held_out_trials', '?')} held out, scored "
        f"0–{1e3 * float(scoring.get('window_s', 0.4)):.0f} ms after each onset, both joints. "
        "Nominal simulation: the linearised arm of Eq. (9) (inertia xi, damping D, stiffness K; 11 "
        "parameters) calibrated on the training trials. Gap = held-out residual power / measured "
        "power (1 − VAF); noise floor = the same ratio for the pre-onset sensor noise "
        f"({r['gap']['noise_source']}).",
        "",
        verdict_paragraph(r, {**RULES, **(r.get("settings") or {})}),
        "",
    ]
    lines += _where(r) + which_effect_section(r, "trials") + _how_far(r)
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    return "\n".join(lines) + "\n"
