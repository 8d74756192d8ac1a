"""Scoring a diagnosis against a referee's truth: the parts every protocol's referee shares.

A referee (a protocol's, see :class:`armlab.protocols.Referee`) simulates pseudo-real datasets
with hidden effects (:class:`Dataset`, magnitudes drawn by :func:`log_uniform`); the runner
diagnoses each from its files alone and scores it here: :func:`expected_verdict` is what a
perfect diagnoser says for a class, :func:`score_case` compares a verdict with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from armlab.diagnosis.summary import final_gap

__all__ = [
    "Dataset",
    "expected_verdict",
    "log_uniform",
    "score_case",
]


def expected_verdict(cls: str, classes: dict) -> set[str]:
    """The verdict a perfect diagnoser gives for a class (as a set of names).

    ``classes``: the protocol's class table, name -> (hidden effects, excluded candidates).
    """
    hidden, excluded = classes[cls]
    if not hidden:
        return {"none"}
    if excluded:
        return {"unknown"}
    return set(hidden)


@dataclass(frozen=True, kw_only=True)
class Dataset:
    """One pseudo-real dataset: where its trials are and what the referee knows about it."""

    cls: str
    replicate: int
    folder: Path
    truth: dict
    enr: float


def log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    """One draw, log-uniform on [lo, hi] (the referees' effect magnitudes)."""
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def score_case(cls: str, results: dict, expected: set[str]) -> dict:
    """Top-1, top-2 and full-verdict correctness of one diagnosis, and its held-out shrink.

    ``expected``: the right verdict as a set of names (:func:`expected_verdict`).
    ``top1_flagged`` also counts a first effect that the diagnosis itself flagged as
    indistinguishable from a right one on these trials (``indistinct``, with the trial that would
    separate them): the answer "A or B, run a step trial to tell" is not wrong, but it is scored
    apart from top-1, which does not count it.
    """
    verdict = list(results["verdict"])
    ranking = [e["name"] for e in results["ranking"]]
    top1 = verdict[0] in expected
    partners = {
        name
        for pair in results.get("indistinct", [])
        if verdict[0] in pair["effects"] and max(pair["reductions"]) > 0
        for name in pair["effects"]
    } - {verdict[0]}
    if expected <= {"none", "unknown"}:
        top2 = top1
    else:
        top2 = top1 or bool(expected & set(ranking[:2]))
    gap = results["gap"]
    nominal, floor = gap["nominal"], gap["noise_floor"]
    # an effect named as a floor (joint_1dof's encoder grid): the gap it accounts for is how far
    # the gap shrinks once it is in the simulation
    final = final_gap(gap)
    excess = nominal - floor
    shrink = (nominal - final) / excess if excess > 0 else float("nan")
    low = results.get("low_band") or {}
    if low.get("named") and not gap["added"] and verdict[0] in low:
        # an effect named below the scoring band (joint_1dof's force_sensor_drift): its own
        # cross-fitted shrink of the slow excess, the band's being that of the nominal alone
        shrink = float(low[verdict[0]]["shrink"])
    return {
        "class": cls,
        "verdict": verdict,
        "predicted": verdict[0],
        "top1": bool(top1),
        "top1_flagged": bool(top1 or expected & partners),
        "flagged": bool(partners),
        "top2": bool(top2),
        "exact": set(verdict) == expected,
        "gap_nominal": nominal,
        "gap_final": final,
        "noise_floor": floor,
        "shrink_of_excess": shrink,
        "shrink_of_gap": (nominal - final) / nominal if nominal > 0 else float("nan"),
    }
