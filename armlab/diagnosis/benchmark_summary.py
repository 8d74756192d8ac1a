"""Scores of the referee's benchmark: confusion matrix, accuracies, false alarms, shrink.

Targets of issue 5 (per protocol): at least 9 classes × 10 replicates; top-1 ≥ 90 % where the
effect-to-noise ratio (ENR) ≥ 1; false alarms on ``none`` ≤ 5 %; median held-out shrink ≥ 70 %
on correctly attributed cases. The shrink is of the gap above the noise floor
(``(nominal − final) / (nominal − floor)``): the floor is what no model can remove.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "ENR_BINS",
    "TARGETS",
    "format_benchmark",
    "summarise",
]

#: ENR bin edges of the accuracy-against-ENR table.
ENR_BINS = (0.0, 0.5, 1.0, 2.0, 4.0, np.inf)
#: The issue's targets.
TARGETS = {"top1_enr_ge_1": 0.90, "false_alarm_none": 0.05, "median_shrink": 0.70}


def _rate(flags) -> float | None:
    flags = list(flags)
    return float(np.mean(flags)) if flags else None


def summarise(cases: list[dict]) -> dict:
    """Aggregate per-case scores (see :func:`armlab.diagnosis.scoring.score_case`)."""
    classes = list(dict.fromkeys(c["class"] for c in cases))
    labels = sorted({c["predicted"] for c in cases} | {"none", "unknown"})
    confusion = {k: {lab: 0 for lab in labels} for k in classes}
    for c in cases:
        confusion[c["class"]][c["predicted"]] += 1
    effect_cases = [c for c in cases if c["class"] != "none"]
    strong = [c for c in effect_cases if c["enr"] >= 1.0]
    none_cases = [c for c in cases if c["class"] == "none"]
    # shrink of the cases correctly attributed to effects ("unknown" on a left-out class is correct
    # but adds nothing, so it has no shrink to score)
    shrink = [c["shrink_of_excess"] for c in cases if c["top1"] and c["predicted"] not in ("none", "unknown")]
    shrink = [s for s in shrink if np.isfinite(s)]
    by_enr = []
    for lo, hi in zip(ENR_BINS[:-1], ENR_BINS[1:], strict=True):
        sel = [c for c in effect_cases if lo <= c["enr"] < hi]
        by_enr.append({"enr": [lo, hi], "n": len(sel), "top1": _rate(c["top1"] for c in sel)})
    per_class = {
        k: {
            "n": sum(1 for c in cases if c["class"] == k),
            "top1": _rate(c["top1"] for c in cases if c["class"] == k),
            "top1_enr_ge_1": _rate(c["top1"] for c in strong if c["class"] == k),
            "exact": _rate(c["exact"] for c in cases if c["class"] == k),
        }
        for k in classes
    }
    out = {
        "n_cases": len(cases),
        "n_classes": len(classes),
        "confusion": confusion,
        "top1": _rate(c["top1"] for c in cases),
        "top2": _rate(c["top2"] for c in cases),
        "exact": _rate(c["exact"] for c in cases),
        "top1_enr_ge_1": _rate(c["top1"] for c in strong + none_cases),
        "top1_enr_ge_1_flagged": _rate(c.get("top1_flagged", c["top1"]) for c in strong + none_cases),
        "flagged": _rate(c.get("flagged", False) for c in cases),
        "false_alarm_none": _rate(not c["top1"] for c in none_cases),
        "median_shrink": float(np.median(shrink)) if shrink else None,
        "accuracy_vs_enr": by_enr,
        "per_class": per_class,
    }
    out["targets"] = {
        "top1_enr_ge_1": _meets(out["top1_enr_ge_1"], TARGETS["top1_enr_ge_1"], higher=True),
        "false_alarm_none": _meets(out["false_alarm_none"], TARGETS["false_alarm_none"], higher=False),
        "median_shrink": _meets(out["median_shrink"], TARGETS["median_shrink"], higher=True),
    }
    return out


def _meets(value, target, *, higher: bool) -> dict:
    ok = None if value is None else (value >= target if higher else value <= target)
    return {"value": value, "target": target, "met": ok}


def _pct(x) -> str:
    return "—" if x is None else f"{100 * x:.0f} %"


def format_benchmark(summary: dict, ref, data: str) -> str:
    """The benchmark as Markdown (``benchmark.md``); ``data`` describes the referee's datasets
    (the protocol's :attr:`Referee.describe`)."""
    lines = [
        f"# Diagnosis benchmark — protocol `{ref.protocol}`",
        "",
        f"{summary['n_classes']} classes × {ref.replicates} replicates = {summary['n_cases']} datasets "
        f"(evaluation seed {ref.seed}; {data}). Wall time {summary.get('timing_s', 0):.0f} s, "
        f"median diagnosis {summary.get('median_diagnosis_s', 0):.1f} s.",
        "",
        "| figure | measured | target | met |",
        "|---|---|---|---|",
    ]
    for key, label in (
        ("top1_enr_ge_1", "top-1 accuracy where ENR ≥ 1 (incl. none)"),
        ("false_alarm_none", "false alarms on none"),
        ("median_shrink", "median shrink of the gap above the floor (correct cases)"),
    ):
        t = summary["targets"][key]
        lines.append(f"| {label} | {_pct(t['value'])} | {_pct(t['target'])} | {t['met']} |")
    lines += [
        f"| top-1 where ENR ≥ 1, counting a first effect flagged indistinct from the right one "
        f"| {_pct(summary.get('top1_enr_ge_1_flagged'))} | | |",
        f"| datasets whose first effect was flagged indistinct from another "
        f"| {_pct(summary.get('flagged'))} | | |",
        f"| top-1 accuracy, all | {_pct(summary['top1'])} | | |",
        f"| top-2 accuracy, all | {_pct(summary['top2'])} | | |",
        f"| exact verdict, all | {_pct(summary['exact'])} | | |",
        "",
        "## Confusion matrix (rows: hidden class; columns: first name of the verdict)",
        "",
    ]
    labels = list(next(iter(summary["confusion"].values())))
    lines.append("| class | " + " | ".join(labels) + " |")
    lines.append("|---|" + "---|" * len(labels))
    for cls, row in summary["confusion"].items():
        lines.append(f"| {cls} | " + " | ".join(str(row[lab]) or "" for lab in labels) + " |")
    lines += [
        "",
        "## Accuracy against effect-to-noise ratio",
        "",
        "| ENR | datasets | top-1 |",
        "|---|---|---|",
    ]
    for b in summary["accuracy_vs_enr"]:
        lo, hi = b["enr"]
        lines.append(f"| {lo:g}–{hi:g} | {b['n']} | {_pct(b['top1'])} |")
    lines += [
        "",
        "## Per class",
        "",
        "| class | n | top-1 | top-1 (ENR ≥ 1) | exact |",
        "|---|---|---|---|---|",
    ]
    for cls, p in summary["per_class"].items():
        lines.append(
            f"| {cls} | {p['n']} | {_pct(p['top1'])} | {_pct(p['top1_enr_ge_1'])} | {_pct(p['exact'])} |"
        )
    return "\n".join(lines) + "\n"
