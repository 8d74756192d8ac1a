"""``report.md`` and the terminal summary of ``armlab diagnose``: the results dict in words.

Pure string building over the results dict of :func:`armlab.diagnosis.diagnose.diagnose_joint`
(or the same keys read back from ``results.json``; see ``docs/diagnosis_schema.md``). The report
is meant to be read on its own by someone who has not read the code: a summary paragraph with the
verdict, then **Where** the gap lies, **Which** effect explains it, **How far** it shrinks, the
settings and the figures.

All gaps are fractions of the measured torque power in the scoring band, printed in %:
``gap = 1 - VAF`` on the held-out part of every trial; the noise floor is the gap that sensor noise
alone would leave.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from armlab.config.effects import EFFECTS
from armlab.diagnosis.report_text import (
    UNITS,
    WHITE_FRACTION,
    figure_lines,
    finite_or_none,
    fmt_ms,
    fmt_num,
    fmt_pct,
    fmt_ratio,
    fmt_score,
    fmt_share,
    fmt_vaf,
    gap_cells,
    md_table,
    own_params,
    settings_lines,
    stage_name,
    verdict_paragraph,
    window_meaning,
    xcorr_meaning,
)
from armlab.protocols.joint_1dof.diagnosis.report_grid import grid_how_far_row, grid_verdict_paragraph
from armlab.protocols.joint_1dof.diagnosis.report_low_band import drift_verdict_paragraph, low_band_section
from armlab.protocols.joint_1dof.diagnosis.report_operating_point import operating_point_section
from armlab.protocols.joint_1dof.diagnosis.report_tonic import held_verdict_paragraph, tonic_cue_lines
from armlab.protocols.joint_1dof.diagnosis.rules import RULES

__all__ = [
    "format_report",
]


def _where(r: Mapping[str, Any], h: str) -> list[str]:
    w = r["where"]
    floor = r["gap"]["noise_floor"]
    out = [
        f"{h} Where: the nominal model's held-out residual",
        "",
        "Each gap is the held-out residual power of the nominal simulation in that slice, as a fraction of "
        "the measured torque power in the same slice; *floor* is what the sensor noise alone would leave "
        "there.",
        "",
    ]
    bands = w.get("bands") or []
    total = sum(finite_or_none(b.get("residual_power")) or 0.0 for b in bands)
    out += [f"{h}# By frequency band", ""]
    out += md_table(
        ["band (Hz)", "gap", "noise floor", "gap / floor", "share of the residual power"],
        [
            [
                f"{b['band_hz'][0]:g}–{b['band_hz'][1]:g}",
                *gap_cells(b["gap"], b["floor"]),
                fmt_pct((finite_or_none(b.get("residual_power")) or 0.0) / total) if total > 0 else "–",
            ]
            for b in bands
        ],
    )
    valid = [b for b in bands if finite_or_none(b.get("gap")) is not None]
    if valid and total > 0:
        worst = max(valid, key=lambda b: b["gap"])
        most = max(valid, key=lambda b: finite_or_none(b.get("residual_power")) or 0.0)
        out += [
            "",
            f"The relative gap is largest in {worst['band_hz'][0]:g}–{worst['band_hz'][1]:g} Hz "
            f"({fmt_pct(worst['gap'])} of the measured power there); most residual power lies in "
            f"{most['band_hz'][0]:g}–{most['band_hz'][1]:g} Hz "
            f"({fmt_pct((finite_or_none(most.get('residual_power')) or 0.0) / total)} of it).",
        ]
    windows = w.get("windows") or []
    out += ["", f"{h}# By time after perturbation onset", ""]
    out += md_table(
        ["window (ms)", "gap", "noise floor", "gap / floor", "samples"],
        [
            [
                f"{x['window_ms'][0]:g}–{x['window_ms'][1]:g}",
                *gap_cells(x["gap"], x["floor"]),
                x.get("samples", "–"),
            ]
            for x in windows
        ],
    )
    filled = [x for x in windows if finite_or_none(x.get("gap")) is not None]
    if filled:
        worst = max(filled, key=lambda x: x["gap"])
        lo, hi = worst["window_ms"]
        out += [
            "",
            f"The gap is largest {lo:g}–{hi:g} ms after onset ({fmt_pct(worst['gap'])}; "
            f"{fmt_pct(r['gap']['nominal'])} over the whole held-out part): {window_meaning(lo, hi)}.",
        ]
    out += ["", f"{h}# By trial", ""]
    out += md_table(
        ["trial", "held-out gap", "held-out VAF", "gap / floor"],
        [
            [
                p["trial"],
                fmt_pct(p["held_out_gap"]),
                fmt_vaf(p["held_out_gap"]),
                fmt_ratio(p["held_out_gap"], floor),
            ]
            for p in w.get("per_trial") or []
        ],
    )
    t = w.get("residual_tests") or {}
    if t:
        frac = float(t["whiteness_fraction_outside"])
        white = frac <= WHITE_FRACTION
        lags = [x for x in t.get("lags_s") or [] if x > 0]
        meaning = xcorr_meaning(float(t["peak_cross_lag_s"]), float(t["peak_cross_value"]), float(t["bound"]))
        span = f"{fmt_ms(min(lags))}–{fmt_ms(max(lags))}" if lags else "positive lags"
        out += [
            "",
            f"{h}# Residual tests",
            "",
            f"- **Whiteness:** {100 * frac:.0f} % of the residual autocorrelation lags ({span}) lie outside "
            f"the ±{fmt_num(t['bound'])} band a white residual stays in 95 % of the time (≈ 5 % expected if "
            "white): "
            + (
                "the residual is consistent with noise."
                if white
                else "the residual is coloured — the nominal model misses structured dynamics."
            ),
            f"- **Residual–velocity cross-correlation:** peak {fmt_num(t['peak_cross_value'])} at a lag of "
            f"{fmt_ms(t['peak_cross_lag_s'])} (bound ±{fmt_num(t['bound'])}; a positive lag means "
            "the residual "
            f"follows the velocity): {meaning}.",
        ]
    bias = w.get("parameter_bias") or []
    if bias:
        out += [
            "",
            f"{h}# Parameter bias (FRF fit)",
            "",
            "The protocol's own frequency-response fit (I, B, K of `K − I·ω² + j·B·ω`, 1–20 Hz) applied to "
            "the measured torque and to the nominal simulation's torque; the bias is measured − simulated, "
            "i.e. how the model error shows up in the parameters a lab would identify.",
            "",
        ]
        rows = []
        for name, b in zip(r.get("trials") or [str(i) for i in range(len(bias))], bias, strict=False):
            for k in ("I", "B", "K"):
                m = finite_or_none(b["measured"][k])
                rel = f"{100 * b[k] / m:+.0f} %" if m else "–"
                rows.append(
                    [name, f"{k} ({UNITS[k]})", fmt_num(m), fmt_num(b["simulated"][k]), fmt_num(b[k]), rel]
                )
        out += md_table(
            ["trial", "parameter", "measured", "nominal simulation", "bias", "bias / measured"], rows
        )
    return out


def _which(r: Mapping[str, Any], h: str, settings: Mapping[str, Any] | None) -> list[str]:
    s = settings or r.get("settings") or {}
    verdict = list(r.get("verdict") or [])
    # the effects selected step by step: the verdict's, or with an unknown its partial explanation
    effects = [n for n in verdict if n not in ("none", "unknown")] or list(r.get("partial") or [])
    out = [
        f"{h} Which: the candidate effects",
        "",
        "Each candidate is added to the current model, refitted on the training parts and scored on the "
        "held-out parts. *Reduction* is the drop of the held-out gap, *% of excess* its share of the nominal "
        "gap above the noise floor, *Δ penalised score* a BIC-like score against the current model "
        "(`n_eff·ln(RSS_new/RSS_old) + Δp·ln(n_eff)`, negative is better) and *added parameters* Δp (the "
        "linear ones once per trial plus the shared nonlinear ones; negative when the effect replaces "
        f"parameters). An effect is accepted when Δ < −{fmt_num(s.get('bic_margin', 10.0))}, its "
        "reduction is "
        f"at least {100 * float(s.get('min_step_fraction', 0.1)):.0f} % of the nominal excess and "
        f"{100 * float(s.get('min_floor_fraction', 0.1)):.0f} % of the floor, and the first one explains at "
        f"least {100 * float(s.get('min_first_explained', 0.4)):.0f} % of the excess; up to "
        f"{s.get('max_effects', 3)} effects are added greedily.",
    ]
    out += tonic_cue_lines(r.get("tonic_cue") or {})
    for step, entries in enumerate(r.get("ranking_steps") or [r.get("ranking") or []]):
        base = stage_name(effects[:step])
        out += ["", f"{h}# Step {step + 1}: candidates added to the {base} model", ""]
        rows = []
        for i, e in enumerate(entries, start=1):
            chosen = step < len(effects) and e["name"] == effects[step]
            if not e.get("identifiable", True):
                rows.append([i, f"`{e['name']}`", "not identifiable", "–", "–", "–", "–", "–", ""])
                continue
            rows.append(
                [
                    i,
                    f"**`{e['name']}`**" if chosen else f"`{e['name']}`",
                    fmt_pct(e["held_out_gap"]),
                    fmt_pct(e["gap_reduction"]),
                    fmt_share(e["explained_fraction"]),
                    fmt_score(e["delta_bic"]),
                    e["added_params"],
                    own_params(e["name"], e.get("params") or {}),
                    "selected" if chosen else "",
                ]
            )
        out += md_table(
            [
                "rank",
                "candidate",
                "held-out gap",
                "reduction",
                "% of excess",
                "Δ penalised score",
                "added parameters",
                "fitted nonlinear parameters",
                "",
            ],
            rows,
        )
        if step >= len(effects):
            out += ["", "No candidate passed the acceptance rules at this step: the selection stops here."]

    if effects:
        out += ["", f"{h}# The selected effects (from the catalogue)", ""]
        for n in effects:
            cls = EFFECTS.get(n)
            if cls is None:
                out.append(f"- **`{n}`**: not in the catalogue.")
                continue
            out.append(f"- **`{n}`** ({cls.LEVEL} level): {cls.PHYSICS}. *Typical magnitude:* {cls.SOURCE}.")
    pairs = r.get("indistinct") or []
    hidden = [p for p in pairs if p["effects"][1] == "limb inertia"]
    twins = [p for p in pairs if p["effects"][1] != "limb inertia"]
    out += ["", f"{h}# What these trials cannot tell apart", ""]
    if not pairs:
        out.append("Every candidate could be told apart from the others with these trials.")
    for p in hidden:
        out.append(
            f"- `{p['effects'][0]}` is not identifiable: the calibrated {p['effects'][1]} absorbs it. "
            f"Separating trial: {p['separating_trial']}."
        )
    if twins:
        out += [""] if hidden else []
        out += md_table(
            ["selected", "runner-up", "reductions", "trial that would separate them"],
            [
                [
                    f"`{p['effects'][0]}`",
                    f"`{p['effects'][1]}`",
                    " vs ".join(fmt_pct(x) for x in p["reductions"]),
                    p["separating_trial"],
                ]
                for p in twins
            ],
        )
    return out


def _how_far(r: Mapping[str, Any], h: str) -> list[str]:
    stages = r.get("how_far") or []
    floor = r["gap"]["noise_floor"]
    nominal = float(r["gap"]["nominal"])
    excess0 = max(nominal - float(floor), 0.0)
    names = [stage_name(s["effects"]) for s in stages]
    out = [f"{h} How far: the gap after each added effect", ""]
    out += md_table(
        [
            "stage",
            "held-out gap",
            "held-out VAF",
            "gap / floor",
            "% of the nominal excess removed",
            "parameters",
        ],
        [
            [
                n,
                fmt_pct(s["held_out_gap"]),
                fmt_vaf(s["held_out_gap"]),
                fmt_ratio(s["held_out_gap"], floor),
                f"{100 * (nominal - s['held_out_gap']) / excess0:.0f} %" if excess0 > 0 else "–",
                s.get("n_params", "–"),
            ]
            for n, s in zip(names, stages, strict=True)
        ]
        + [row for row in [grid_how_far_row(r["gap"], floor, excess0)] if row]
        + [["noise floor", fmt_pct(floor), fmt_vaf(floor), "1×", "", ""]],
    )
    trials = [p["trial"] for p in stages[0]["per_trial"]] if stages else []
    if trials:
        out += ["", f"{h}# Per trial (held-out VAF)", ""]
        out += md_table(
            ["trial", *names],
            [
                [t, *(fmt_vaf(s["per_trial"][i]["held_out_gap"]) for s in stages)]
                for i, t in enumerate(trials)
            ],
        )
    for key, edges, title, label in (
        ("bands", "band_hz", "Per band (held-out gap)", "band (Hz)"),
        ("windows", "window_ms", "Per window after onset (held-out gap)", "window (ms)"),
    ):
        if stages and stages[0].get(key):
            out += ["", f"{h}# {title}", ""]
            out += md_table(
                [label, *names, "noise floor"],
                [
                    [
                        f"{x[edges][0]:g}–{x[edges][1]:g}",
                        *(fmt_pct(s[key][j]["gap"]) for s in stages),
                        fmt_pct(x["floor"]),
                    ]
                    for j, x in enumerate(stages[0][key])
                ],
            )
    if len(stages) >= 1:
        first, last = stages[0], stages[-1]
        out += [
            "",
            f"{h}# Parameters before and after",
            "",
            "Fitted per trial on the training parts (the torque sign folded in: "
            f"{r.get('torque_sign', 'as recorded')}). A compliance effect replaces I, B, K by its own "
            "parameters.",
            "",
        ]
        rows = []
        for i, t in enumerate(trials):
            before, after = first["parameters"][i], last["parameters"][i]
            for k in dict.fromkeys([*before, *after]):
                unit = UNITS.get(k, "")
                rows.append(
                    [t, f"{k} ({unit})" if unit else k, fmt_num(before.get(k), 4), fmt_num(after.get(k), 4)]
                )
        out += md_table(["trial", "parameter", "nominal", stage_name(last["effects"])], rows)
        nl = last.get("nonlinear_parameters") or {}
        if nl:
            out += [
                "",
                "Shared nonlinear parameters of the final model: "
                + ", ".join(f"`{k}` = {fmt_num(v)}" for k, v in nl.items())
                + ".",
            ]
        if len(stages) > 1 and first.get("frf_bias") and last.get("frf_bias"):
            out += ["", "Bias of the FRF-identified parameters (measured − simulated), before and after:", ""]
            rows = [
                [t, f"{k} ({UNITS[k]})", fmt_num(first["frf_bias"][i][k]), fmt_num(last["frf_bias"][i][k])]
                for i, t in enumerate(trials)
                for k in ("I", "B", "K")
            ]
            out += md_table(["trial", "parameter", "nominal", stage_name(last["effects"])], rows)
    return out


def _one(r: Mapping[str, Any], h: str, settings: Mapping[str, Any] | None) -> list[str]:
    op = operating_point_section(r, h)
    low = low_band_section(r, h)
    return [
        held_verdict_paragraph(r)
        or drift_verdict_paragraph(r)
        or grid_verdict_paragraph(r)
        or verdict_paragraph(r, settings),
        "",
        *([*op, ""] if op else []),
        *_where(r, h),
        "",
        *_which(r, h, settings),
        "",
        *_how_far(r, h),
        *(["", *low] if low else []),
    ]


def format_report(results: Mapping[str, Any], *, data_path: str, figures: Sequence[str]) -> str:
    """The Markdown ``report.md`` of one ``armlab diagnose`` run.

    Pooled results: a summary paragraph (the verdict in words, held-out VAF nominal → final, the noise
    floor), then *Where* (gap per band, per window after onset, per trial; residual whiteness and the
    residual–velocity cross-correlation peak with its meaning; FRF parameter bias), *Which* (one ranking
    table per greedy step, the catalogue's physics and typical magnitude of the selected effects, what
    cannot be told apart and the trial that would separate it), *How far* (gap and VAF per stage, per
    trial, per band and per window beside the noise floor; parameters before/after), the settings with
    the noise-floor source, and the figures. Per-trial results (a ``per_trial`` key): a summary table
    (trial, verdict, top-ranked candidate, VAF nominal → final) and then one such section per trial.

    Args:
        results: the results dict of :func:`armlab.diagnosis.diagnose.diagnose_joint` (or read back
            from ``results.json``).
        data_path: the measured data the run read (printed, not opened).
        figures: figure paths relative to the report's folder, linked and embedded in order.

    Returns:
        The report text (ends with a newline).
    """
    per = results.get("per_trial")
    settings = {**RULES, **(results.get("settings") or {})}
    if per is None:
        lines = [
            f"# Sim-to-real gap diagnosis ({results.get('protocol', 'joint_1dof')})",
            "",
            f"Trials {', '.join(f'`{t}`' for t in results.get('trials') or [])} from `{data_path}`, pooled: "
            "one set of effects for all trials, the linear parameters fitted per trial.",
            "",
            "## Summary",
            "",
            *_one(results, "##", settings),
        ]
        sources = [results["gap"].get("noise_source", "unknown")]
    else:
        lines = [
            f"# Sim-to-real gap diagnosis ({results.get('protocol', 'joint_1dof')}, per trial)",
            "",
            f"{len(per)} trials from `{data_path}`, each diagnosed on its own (its own effects and "
            "parameters).",
            "",
            "## Summary",
            "",
        ]
        rows = []
        for p in per:
            stages = p.get("how_far") or []
            final = stages[-1]["held_out_gap"] if stages else p["gap"]["nominal"]
            first = (p.get("ranking") or [{}])[0]
            top = first.get("name")
            rows.append(
                [
                    f"`{p['trial']}`",
                    ", then ".join(p["verdict"]),
                    f"`{top}`" if top else "–",
                    # shown whether or not it was accepted: the gain the first-ranked effect alone gives
                    fmt_vaf(first["held_out_gap"]) if first.get("identifiable", True) and top else "–",
                    f"{fmt_vaf(p['gap']['nominal'])} → {fmt_vaf(final)}",
                    fmt_pct(p["gap"]["noise_floor"]),
                ]
            )
        lines += md_table(
            [
                "trial",
                "verdict",
                "top-ranked candidate",
                "held-out VAF with it alone",
                "held-out VAF nominal → final",
                "noise floor",
            ],
            rows,
        )
        verdicts = {tuple(p["verdict"]) for p in per}
        lines += [
            "",
            (
                f"All trials agree: {', then '.join(next(iter(verdicts)))}."
                if len(verdicts) == 1
                else "The trials disagree: the effect differs between subjects or conditions (see each "
                "trial below)."
            ),
        ]
        for p in per:
            lines += ["", f"## Trial `{p['trial']}`", "", *_one(p, "###", settings)]
        sources = [p["gap"].get("noise_source", "unknown") for p in per]
    lines += ["", *settings_lines(results, data_path, sources), "", *figure_lines(figures)]
    return "\n".join(lines).rstrip() + "\n"
