"""Wording and number formatting of the diagnosis report (``report.md``, terminal summary).

Labels of the candidates, percentages/VAF/score formatting, Markdown tables, and the sentences
that say what a verdict, a cross-correlation peak or an onset window means. Shared by every
protocol's diagnosis report; pure string building.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import PurePath
from typing import Any

from armlab.diagnosis.summary import final_gap

#: Readable names of the catalogue candidates (the catalogue key is printed beside them).
LABELS = {
    "reflex": "a stretch reflex",
    "cuff_compliance": "cuff (limb–pedal interface) compliance",
    "transmission_compliance": "transmission compliance",
    "joint_friction": "joint friction",
    "force_sensor_bandwidth": "the torque sensor's bandwidth",
    "channel_delay": "a delay between the torque and position channels",
    "cocontraction_variation": "slow co-contraction variation",
    "voluntary_torque": "a slow voluntary torque",
    "payload_mass": "an unmodelled payload mass",
}
#: Units of the linear (per-trial) parameters.
UNITS = {
    "I": "kg·m²",
    "B": "N·m·s/rad",
    "K": "N·m/rad",
    "reflex.gain": "N·m·s/rad",
    "joint_friction.coulomb": "N·m",
    "cocontraction_variation.stiffness_slope": "N·m/rad",
    "cocontraction_variation.damping_slope": "N·m·s/rad",
    "cocontraction_variation.local_stiffness_gain": "1",
    "cocontraction_variation.local_damping_gain": "1",
    "voluntary_torque.gain": "1",
    "compliance.gain": "N·m/rad",
    "cuff_compliance.pedal_inertia": "kg·m²",
}
FIGURE_CAPTIONS = {
    "gap_by_band": "Held-out gap per frequency band, nominal and after each added effect, vs the noise floor",
    "gap_by_window": "Held-out gap per window after perturbation onset, per stage, vs the noise floor",
    "residual_correlation": (
        "Residual autocorrelation (whiteness) and residual–velocity cross-correlation with the ±95 % bound"
    ),
    "time_overlay": "A few held-out seconds: measured, nominal and corrected torque",
    "vaf_per_trial": "Held-out VAF per trial and stage, with the best VAF the noise allows",
}
WHITE_FRACTION = 0.1  # autocorrelation lags outside the 95 % bound above which the residual is coloured


# ---------------------------------------------------------------------------------------------
# number formatting
# ---------------------------------------------------------------------------------------------


def finite_or_none(x: Any) -> float | None:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def fmt_pct(gap: Any) -> str:
    """A gap fraction as a percentage with enough digits to be non-zero ("–" when missing)."""
    v = finite_or_none(gap)
    if v is None:
        return "–"
    p = 100.0 * v
    if abs(p) < 5e-4:
        return "≈ 0 %"
    if abs(p) >= 10:
        return f"{p:.1f} %"
    if abs(p) >= 0.1:
        return f"{p:.2f} %"
    return f"{p:.2g} %"


def fmt_vaf(gap: Any) -> str:
    """VAF = 100 (1 - gap) % with as many decimals as the gap needs to show."""
    v = finite_or_none(gap)
    if v is None:
        return "–"
    g = abs(100.0 * v)
    digits = 1 if g >= 1 else 2 if g >= 0.1 else 3 if g >= 0.01 else 4
    return f"{100.0 * (1.0 - v):.{digits}f} %"


def fmt_num(x: Any, sig: int = 3) -> str:
    v = finite_or_none(x)
    if v is None:
        return "–"
    return f"{(v if abs(v) > 1e-12 else 0.0):.{sig}g}"


def fmt_score(x: Any) -> str:
    """A penalised score (ΔBIC): whole numbers once it is large."""
    v = finite_or_none(x)
    if v is None:
        return "–"
    return f"{v:.0f}" if abs(v) >= 100 else f"{v:.3g}"


def fmt_share(x: Any) -> str:
    """A fraction (of the excess gap) as a percentage with one decimal, never "-0.0 %"."""
    v = finite_or_none(x)
    return "–" if v is None else f"{round(100.0 * v, 1) + 0.0:.1f} %"


def fmt_ms(seconds: Any) -> str:
    v = finite_or_none(seconds)
    return "–" if v is None else f"{1e3 * v:.0f} ms"


def fmt_part(x: float) -> str:
    """A share in % with whole numbers in 1-99 % and two decimals near 0 or 100 %."""
    p = 100.0 * x
    return f"{p:.0f} %" if 1 <= p <= 99 else f"{p:.2f} %"


def fmt_ratio(gap: Any, floor: Any) -> str:
    g, f = finite_or_none(gap), finite_or_none(floor)
    if g is None or f is None or f <= 0:
        return "–"
    return f"{g / f:,.0f}×" if g / f >= 100 else f"{g / f:.3g}×"


def gap_cells(gap: Any, floor: Any) -> list[str]:
    """The cells ``gap | noise floor | gap / floor`` of a where-table row."""
    return [fmt_pct(gap), fmt_pct(floor), fmt_ratio(gap, floor)]


def effect_label(name: str) -> str:
    return f"{LABELS.get(name, name.replace('_', ' '))} (`{name}`)"


def effects_words(names: Sequence[str]) -> str:
    if not names:
        return "nominal"
    return ", then ".join(effect_label(n) for n in names)


def stage_name(effects: Sequence[str]) -> str:
    return "nominal" if not effects else "nominal + " + " + ".join(effects)


def md_table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return out


def own_params(name: str, params: Mapping[str, Any]) -> str:
    """The candidate's own nonlinear parameters (``params`` also holds the earlier effects')."""
    own = [(k.split(".", 1)[1], v) for k, v in params.items() if k.startswith(name + ".")]
    return ", ".join(f"{k} = {fmt_num(v)}" for k, v in own) or "–"


# ---------------------------------------------------------------------------------------------
# wording of the verdict and of the residual tests
# ---------------------------------------------------------------------------------------------


def why_rejected(best: Mapping[str, Any], r: Mapping[str, Any], settings: Mapping[str, Any] | None) -> str:
    """The acceptance rule (attribution.select_effects) the best first candidate failed, in words."""
    s = settings or r.get("settings") or {}
    share, dbic = finite_or_none(best.get("explained_fraction")), finite_or_none(best.get("delta_bic"))
    excess = f"{fmt_share(share)} of the excess over the floor"
    need, margin = finite_or_none(s.get("min_first_explained")), finite_or_none(s.get("bic_margin"))
    if dbic is not None and margin is not None and dbic >= -margin:
        return f"{excess}, but its Δ penalised score {fmt_score(dbic)} does not beat the margin −{margin:g}"
    if share is not None and need is not None and share < need:
        # two decimals: a share just under the rule must not print as the rule itself
        return (
            f"{100.0 * share:.2f} % of the excess over the floor, under the {fmt_part(need)} a first "
            f"effect must explain (Δ penalised score {fmt_score(dbic)})"
        )
    return f"{excess}, under the smallest step the selection accepts (Δ penalised score {fmt_score(dbic)})"


def rule_value(results: Mapping[str, Any], settings: Mapping[str, Any] | None, name: str) -> float:
    """A selection threshold as the diagnosis used it (the protocol's report fills in its own
    rules for results that predate their recording)."""
    s = settings or results.get("settings") or {}
    value = s.get(name)
    if value is None:
        raise KeyError(f"the diagnosis settings lack {name!r}; valid results carry it in 'settings'")
    return float(value)


def verdict_paragraph(r: Mapping[str, Any], settings: Mapping[str, Any] | None) -> str:
    verdict = list(r.get("verdict") or [])
    gap = r["gap"]
    nominal, floor = float(gap["nominal"]), float(gap["noise_floor"])
    stages = r.get("how_far") or []
    final = float(stages[-1]["held_out_gap"]) if stages else nominal
    floor_words = f"noise floor {fmt_pct(floor)} (the best VAF the sensor noise allows is {fmt_vaf(floor)})"
    excess0 = max(nominal - floor, 0.0)
    if verdict == ["none"]:
        return (
            "**Verdict: no gap beyond measurement noise.** The nominal simulation already reaches a "
            f"held-out VAF of {fmt_vaf(nominal)} (gap {fmt_pct(nominal)}) at the {floor_words}: its "
            "excess over "
            f"the floor is within the {100 * rule_value(r, settings, 'none_tolerance'):.0f} % tolerance. "
            "No unmodelled effect is needed; the candidate ranking below is shown for completeness."
        )
    partial = list(r.get("partial") or [])
    removed = (nominal - final) / excess0 if excess0 > 0 else 0.0
    # ["unknown"], or a time-varying [operating_point_impedance, ..., "unknown"]: a partial explanation
    if verdict[-1:] == ["unknown"] and partial:
        final_words = f"gap {fmt_pct(final)}, {fmt_ratio(final, floor)} the floor"
        return (
            f"**Verdict: unknown — the gap is real and the catalogue explains only part of it.** The "
            f"nominal simulation's held-out VAF is {fmt_vaf(nominal)} (gap {fmt_pct(nominal)}), above the "
            f"{floor_words}. {effects_words(partial).capitalize()} passed the acceptance rules but "
            f"remove{'s' if len(partial) == 1 else ''} only {fmt_part(removed)} "
            f"of the gap above the floor ({final_words} after them), less than the "
            f"{fmt_part(rule_value(r, settings, 'min_explained'))} the diagnosis asks of an explanation: "
            f"{'it is' if len(partial) == 1 else 'they are'} probably standing in for an effect that is not "
            "in the candidate list (a delay or a low-pass also mimics a reflex loop). See *Where* for the "
            "band and the time after onset that hold the gap, and *How far* for what the partial "
            "explanation changes."
        )
    if verdict == ["unknown"] or not verdict:
        ranking = r.get("ranking") or []
        best = next((e for e in ranking if e.get("identifiable", True)), None)
        best_words = (
            f" The best candidate, {effect_label(best['name'])}, would lower the gap by "
            f"{fmt_pct(best['gap_reduction'])}: {why_rejected(best, r, settings)}."
            if best
            else ""
        )
        return (
            f"**Verdict: unknown — the gap is real but no catalogue effect explains it.** The nominal "
            f"simulation's held-out VAF is {fmt_vaf(nominal)} (gap {fmt_pct(nominal)}), well above the "
            f"{floor_words}, yet no candidate effect passed the acceptance rules.{best_words} See *Where* "
            "for the band and the time after onset that hold the gap: the missing effect is probably not in "
            "the catalogue, or it was left out by `candidates`/`exclude` in the settings."
        )
    if final - floor <= rule_value(r, settings, "none_tolerance") * floor:
        rest = "The corrected model reaches the noise floor: nothing measurable is left unexplained."
    else:
        rest = (
            f"{'Together they remove' if len(verdict) > 1 else 'It removes'} {fmt_part(removed)} of the "
            f"gap above the noise floor; the remaining {fmt_part(1 - removed)} (gap {fmt_pct(final)}, "
            f"{fmt_ratio(final, floor)} the floor) is not explained by any catalogue effect (see *How far*)."
        )
    text = (
        f"**Verdict: the gap is explained by {effects_words(verdict)}.** Held-out VAF "
        f"{fmt_vaf(nominal)} → {fmt_vaf(final)} (gap {fmt_pct(nominal)} → {fmt_pct(final)} of the "
        "measured torque "
        f"power), {floor_words}. {rest}"
    )
    caution = [
        p
        for p in r.get("indistinct") or []
        if p["effects"][0] in verdict and p["effects"][1] != "limb inertia"
    ]
    for p in caution:
        a, b = p["effects"]
        text += (
            f" Caution: with these trials `{a}` cannot be told apart from `{b}`; {p['separating_trial']} "
            "would separate them."
        )
    return text


def xcorr_meaning(lag_s: float, value: float, bound: float) -> str:
    """What the peak of the residual–velocity cross-correlation points to."""
    if abs(value) <= bound:
        return (
            "no significant residual–velocity correlation at any lag: what is left is not linearly related "
            "to the recent joint motion"
        )
    ms = 1e3 * lag_s
    if lag_s < -0.01:
        return (
            f"the residual *precedes* the velocity by {-ms:.0f} ms: the torque channel leads the position "
            "channel (a delayed position channel) or anticipatory/voluntary activity"
        )
    if abs(lag_s) <= 0.01:
        return (
            "the residual moves with the velocity at (near) zero lag: an error in the instantaneous "
            "impedance — damping, friction — or a channel skew or sensor low-pass of a few ms"
        )
    if lag_s < 0.025:
        return (
            f"the residual follows the velocity by {ms:.0f} ms: a torque-sensor low-pass or channel delay, "
            "or a short-latency reflex component"
        )
    if lag_s <= 0.12:
        return (
            f"the residual follows the velocity by {ms:.0f} ms: a delayed response to stretch velocity, as a "
            "stretch-reflex pathway leaves (40–50 ms latency at the ankle, Kearney et al. 1997)"
        )
    return (
        f"the residual follows the velocity by {ms:.0f} ms: a slow or long-loop response (voluntary "
        "reaction, co-contraction change)"
    )


def window_meaning(lo: float, hi: float) -> str:
    if hi <= 20:
        return "right at onset: inertial or sensor dynamics (bandwidth, channel delay, compliance)"
    if lo >= 20 and hi <= 120:
        return "a delayed response after onset, at the latency of a stretch reflex"
    return "late after onset: slow responses, or friction and tonic changes during the holds"


# ---------------------------------------------------------------------------------------------
# sections of one diagnosis
# ---------------------------------------------------------------------------------------------


def noise_words(source: str) -> str:
    if source.startswith("repeats"):
        return (
            "from repeated trials (trials whose positions correlate above 0.99 repeat one perturbation): "
            "var(y_i − y_j)/2 in the scoring band — the most direct estimate."
        )
    return (
        f"{source}: E[(Δ²y)²] = 6σ² for white noise (Rice 1984), scaled to the scoring band. With no "
        "repeated trials this assumes white sensor noise; coloured noise or tremor would raise the true "
        "floor."
    )


def settings_lines(results: Mapping[str, Any], data_path: str, sources: Sequence[str]) -> list[str]:
    s = results.get("settings") or {}
    out = ["## Settings and noise floor", ""]
    out.append(f"- **Data:** `{data_path}`; protocol `{results.get('protocol', '?')}`.")
    if s:
        hold = float(s.get("holdout_fraction", 1 / 3))
        out.append(
            f"- **Scoring:** models fitted at {fmt_num(s.get('fs_fit_hz'))} Hz on the first "
            f"{100 * (1 - hold):.0f} % of every trial and scored on the last {100 * hold:.0f} %, in the band "
            f"{fmt_num(s.get('highpass_hz'))}–{fmt_num(s.get('band_hz'))} Hz (below the high-pass "
            "the torque is "
            "the subject's voluntary/tonic activity)."
        )
    for src in dict.fromkeys(sources):
        out.append(f"- **Noise floor:** {noise_words(src)}")
    if s:
        out += ["", *md_table(["setting", "value"], [[f"`{k}`", f"`{v}`"] for k, v in s.items()])]
    return out


def figure_lines(figures: Sequence[str]) -> list[str]:
    out = ["## Figures", ""]
    if not figures:
        return out + ["No figures were written for this run."]
    for f in figures:
        stem = PurePath(f).stem
        caption = FIGURE_CAPTIONS.get(stem, stem.replace("_", " "))
        out += [f"- [{caption}]({f})", "", f"  ![{caption}]({f})", ""]
    return out


def summary_lines(r: Mapping[str, Any], indent: str) -> list[str]:
    nominal = r["gap"]["nominal"]
    final = final_gap(r["gap"])  # an accounted floor (joint_1dof's encoder grid) included
    top = [
        f"{e['name']} ({fmt_score(e['delta_bic'])})" if e.get("identifiable", True) else f"{e['name']} (n/i)"
        for e in (r.get("ranking") or [])[:3]
    ]
    return [
        f"{indent}held-out VAF {fmt_vaf(nominal)} -> {fmt_vaf(final)} (gap {fmt_pct(nominal)} -> "
        f"{fmt_pct(final)}); "
        f"noise floor {fmt_pct(r['gap']['noise_floor'])}",
        f"{indent}ranking (Δ penalised score): {', '.join(top) or '–'}",
    ]


def format_summary(results: Mapping[str, Any]) -> str:
    """A few lines for the terminal: the verdict, VAF nominal → final, the floor, the top candidates."""
    per = results.get("per_trial")
    if per is None:
        n = len(results.get("trials") or [])
        lines = [f"diagnosis ({n} trials pooled): verdict {' -> '.join(results['verdict'])}"]
        lines += summary_lines(results, "  ")
    else:
        lines = [f"diagnosis ({len(per)} trials, each on its own):"]
        for p in per:
            lines.append(f"  {p['trial']}: verdict {' -> '.join(p['verdict'])}")
            lines += summary_lines(p, "    ")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# report sections every protocol's report shares
# ---------------------------------------------------------------------------------------------


def which_effect_section(r: Mapping[str, Any], what: str = "trials") -> list[str]:
    """``## Which effect``: each greedy step's ranking of the candidates (an absorbed one marked
    so), then the pairs the data cannot tell apart (``what``: what the data are called, e.g.
    ``trials`` or ``sequences``)."""
    out = ["", "## Which effect", ""]
    for step, ranking in enumerate(r.get("ranking_steps") or [], start=1):
        out += [f"### Greedy step {step}", ""]
        out += md_table(
            [
                "candidate",
                "held-out gap",
                "reduction",
                "share of the nominal excess",
                "Δ penalised score (BIC)",
                "added parameters",
                "fitted",
            ],
            [
                [
                    effect_label(e["name"]),
                    fmt_pct(e["held_out_gap"]) if e.get("identifiable", True) else "absorbed",
                    fmt_pct(e["gap_reduction"]),
                    fmt_share(e["explained_fraction"]),
                    fmt_score(e["delta_bic"]),
                    e["added_params"],
                    own_params(e["name"], e["params"]),
                ]
                for e in ranking
            ],
        )
        out.append("")
    if r.get("indistinct"):
        out += [f"### Effects these {what} cannot tell apart", ""]
        for p in r["indistinct"]:
            a, b = p["effects"]
            out.append(f"- `{a}` vs {b}: {p['separating_trial']}.")
    return out


def how_far_table(stages: Sequence[Mapping[str, Any]]) -> list[str]:
    """``## How far the gap shrinks``: held-out VAF, gap, gap over the floor and parameters of
    each stage (``results['how_far']``), nominal first."""
    out = ["", "## How far the gap shrinks", ""]
    return out + md_table(
        ["model", "held-out VAF", "gap", "gap / floor", "parameters"],
        [
            [
                stage_name(s["effects"]),
                fmt_vaf(s["held_out_gap"]),
                fmt_pct(s["held_out_gap"]),
                fmt_ratio(s["held_out_gap"], s["noise_floor"]),
                s["n_params"],
            ]
            for s in stages
        ],
    )
