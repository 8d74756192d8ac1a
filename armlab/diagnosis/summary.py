"""The sections every diagnosis plug-in writes the same way (docs/diagnosis_schema.md).

A plug-in scores its selection's stages on held-out rows and reports the verdict, the gap of the
nominal and of each added effect against the noise floor, and where the gap lies. The shared
parts are built here, in the schema's key order; each plug-in adds its own sections (where the
gap lies, its parameters, its noise source).
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from armlab.config.diagnosis import DiagnosisConfig
from armlab.diagnosis.attribution import Selection, held_out_gap
from armlab.diagnosis.families import FittedModel

__all__ = ["final_gap", "gap_section", "row_floor", "stage_entry", "verdict_section"]


def row_floor(scoring_set, y: np.ndarray) -> float:
    """The noise floor as a share of the measured power: the summed noise variance of the held-out
    rows (``scoring_set.row_noise_var``, ``.held``) over their measured power ``sum(y**2)``."""
    held = scoring_set.held
    return float(np.sum(scoring_set.row_noise_var[held])) / float(np.sum(y[held] ** 2))


def stage_entry(model: FittedModel, sets, ys, floor: float) -> tuple[dict, list[float]]:
    """The head of one stage's entry (its effects, held-out gap and VAF, the floor) and its
    per-set gaps (:func:`~armlab.diagnosis.attribution.held_out_gap`)."""
    gap, _, per_set = held_out_gap(model, sets, ys)
    entry = {
        "effects": list(model.effects),
        "held_out_gap": gap,
        "held_out_vaf_percent": 100.0 * (1.0 - gap),
        "noise_floor": floor,
    }
    return entry, per_set


def verdict_section(protocol: str, cfg: DiagnosisConfig, sel: Selection) -> dict:
    """``protocol``, ``settings``, ``verdict``, ``ranking`` (the first step's) and ``ranking_steps``."""
    strip = sel.ranking_steps()
    return {
        "protocol": protocol,
        "settings": asdict(cfg),
        "verdict": sel.verdict,
        "ranking": strip[0] if strip else [],
        "ranking_steps": strip,
    }


def final_gap(gap) -> float:
    """The held-out gap of the verdict's model from a ``results["gap"]`` section: the last added
    effect's (the nominal's if none), less the floor an ``accounted`` effect stands for (joint_1dof's
    encoder grid: an error no model removes, named in the verdict), not below the noise floor."""
    last = float(gap["added"][-1]["held_out_gap"]) if gap["added"] else float(gap["nominal"])
    acc = gap.get("accounted")
    if not acc:
        return last
    return max(last - float(acc["floor"]), min(last, float(gap["noise_floor"])))


def gap_section(metric: str, stages: list[dict], floor: float) -> dict:
    """``metric``, the nominal's held-out gap, each added effect's, and the floor."""
    return {
        "metric": metric,
        "nominal": stages[0]["held_out_gap"],
        "added": [{"effects": s["effects"], "held_out_gap": s["held_out_gap"]} for s in stages[1:]],
        "noise_floor": floor,
    }
