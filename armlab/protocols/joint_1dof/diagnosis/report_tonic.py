"""The tonic cue in ``report.md``: the verdict paragraph where a driven tonic level held the verdict
back (``results.tonic_cue.held``, :func:`.tonic_cue.held_verdict`) and the lines of *Which* that say
whether ``cocontraction_variation`` was tried (docs/diagnosis_schema.md)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from armlab.diagnosis.report_text import effects_words, fmt_num, fmt_part, fmt_pct, fmt_vaf
from armlab.protocols.joint_1dof.diagnosis.tonic_cue import RECTIFYING_EFFECTS

__all__ = ["held_verdict_paragraph", "tonic_cue_lines"]


def held_verdict_paragraph(r: Mapping[str, Any]) -> str | None:
    """The summary paragraph of an ``unknown`` that the tonic cue made, or None for any other."""
    cue = r.get("tonic_cue") or {}
    held = list(cue.get("held") or [])
    if not held:
        return None
    gap = r["gap"]
    nominal, floor = float(gap["nominal"]), float(gap["noise_floor"])
    stages = r.get("how_far") or []
    final = float(stages[-1]["held_out_gap"]) if stages else nominal
    excess0 = max(nominal - floor, 0.0)
    removed = (nominal - final) / excess0 if excess0 > 0 else 0.0
    tried = {e["name"] for step in r.get("ranking_steps") or [] for e in step}
    rect = [e for e in RECTIFYING_EFFECTS if e in tried]
    which = "the candidate that rectifies" if len(RECTIFYING_EFFECTS) == 1 else "the candidates that rectify"
    rival = cue.get("rectifier_explained")
    alone = (
        ""
        if rival is None
        else f" (alone it explains {fmt_part(float(rival))} of the excess: it shows in the scoring band)"
    )
    rect_words = (
        f"{effects_words(rect)}, {which}, was tried and not accepted{alone}"
        if rect
        else f"{effects_words(list(RECTIFYING_EFFECTS))}, {which}, was not among this diagnosis's candidates"
    )
    one = len(held) == 1
    return (
        "**Verdict: unknown — the perturbation drives a slow torque that the named effects cannot "
        f"make.** The nominal simulation's held-out VAF is {fmt_vaf(nominal)} (gap {fmt_pct(nominal)}), "
        f"above the noise floor {fmt_pct(floor)}. {effects_words(held).capitalize()} passed the "
        f"acceptance rules and remove{'s' if one else ''} {fmt_part(removed)} of the gap above the floor "
        f"(gap {fmt_pct(final)} after {'it' if one else 'them'}), but the perturbation's own slow speed "
        f"envelope explains {fmt_num(100 * float(cue['perturbation_share']))} % of the tonic torque's "
        f"variance (at least {fmt_num(100 * float(cue['max_share']))} % counts as driven)"
        f"{_follow_words(cue)}: something "
        "rectifies the perturbation, as a stretch reflex does, while "
        f"{'the named effect is' if one else 'the named effects are'} linear, odd in the velocity or "
        "not driven by the perturbation: "
        f"{'it is' if one else 'they are'} at most part of the explanation, and a linear effect that "
        "removes most of the gap stands in for the linear part of the rectifying one. "
        f"{rect_words[0].upper()}{rect_words[1:]}. A trial of one-sided stretches (pulses in one "
        "direction) would separate them: a rectifier answers them and their reversal differently, a "
        "linear effect alike."
    )


def tonic_cue_lines(cue: Mapping[str, Any]) -> list[str]:
    """The lines of *Which* on the co-contraction candidate: not tried where the tonic level is
    rectified (``excluded``), tried where it is driven but follows no reflex; else none."""
    out: list[str] = []
    if cue.get("excluded"):
        out += [
            "",
            f"`{'`, `'.join(cue['excluded'])}` was not tried: the perturbation's own slow speed envelope "
            f"explains {fmt_num(100 * float(cue['perturbation_share']))} % of the tonic torque's variance "
            f"(at least {fmt_num(100 * float(cue['max_share']))} % counts as driven by the perturbation)"
            f"{_follow_words(cue)}, so "
            "the tonic level is a response to the perturbation (e.g. a stretch reflex's mean), not the "
            "subject's co-contraction that candidate reads from it.",
        ]
    elif cue.get("driven") and not cue.get("rectified", True):
        out += [
            "",
            f"The perturbation's slow speed envelope explains "
            f"{fmt_num(100 * float(cue['perturbation_share']))} % of the tonic torque's variance, but the "
            f"residual does not follow the envelope's faster swells as a rectifier's output does "
            f"(partial R² {fmt_num(float(cue['envelope_follow']))}, below "
            f"{fmt_num(float(cue['min_follow']))}): "
            "the tonic level and the speed move together without a reflex making one of the other (a "
            "co-contraction changes how far the servo moves the joint), so `cocontraction_variation` "
            "was tried.",
        ]
    return out


def _follow_words(cue: Mapping[str, Any]) -> str:
    """`` and the residual follows ...`` where the cue carries the envelope check (results written
    before it do not)."""
    if cue.get("envelope_follow") is None:
        return ""
    return (
        f", and the residual follows the envelope's 0.5-2 Hz swells a reflex's lag later (partial R² "
        f"{fmt_num(float(cue['envelope_follow']))}, at least {fmt_num(float(cue['min_follow']))})"
    )
