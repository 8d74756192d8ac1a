"""The verdict paragraph of ``report.md`` and the *How far* row of an encoder's grid named as a
floor (``gap.accounted`` of :mod:`.diagnose`, :func:`.position_sensor.grid_floor`;
docs/diagnosis_schema.md)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from armlab.diagnosis.report_text import effects_words, fmt_num, fmt_part, fmt_pct, fmt_ratio, fmt_vaf
from armlab.diagnosis.summary import final_gap

__all__ = ["grid_how_far_row", "grid_verdict_paragraph"]


def grid_verdict_paragraph(r: Mapping[str, Any]) -> str | None:
    """The summary paragraph of a verdict that names the grid from its floor, or None for any other."""
    gap = r["gap"]
    if not gap.get("accounted"):
        return None
    final = final_gap(gap)
    nominal, floor = float(gap["nominal"]), float(gap["noise_floor"])
    excess0 = max(nominal - floor, 0.0)
    explained = (nominal - final) / excess0 if excess0 > 0 else 0.0
    pos = gap["position_sensor"]
    others = [e for e in r["verdict"] if e != gap["accounted"]["effect"]]
    step = float(pos["grid_step_rad"])
    before = ""
    if others:
        last = gap["added"][-1]["held_out_gap"]
        before = f" With {effects_words(others)} added (*How far*) the gap is {fmt_pct(last)}."
    return (
        "**Verdict: the gap is the encoder's grid (`encoder_quantisation`), a floor of the recorded "
        f"angle{' with ' + effects_words(others) if others else ''}.** The nominal simulation's "
        f"held-out VAF is {fmt_vaf(nominal)} (gap {fmt_pct(nominal)}), above the noise floor "
        f"{fmt_pct(floor)}. The angle lies on a grid of {fmt_num(step)} rad "
        f"({round(math.tau / step)} counts a turn), and the error that grid leaves in the nominal, "
        f"simulated from the angle's own changes, is {fmt_pct(pos['grid_floor'])} of the measured "
        f"torque's power.{before} No model of the recorded angle removes a grid's error where the "
        "perturbation's spectrum covers the whole band, so it is accounted for, not fitted: with it "
        f"the gap would be {fmt_pct(final)} (VAF {fmt_vaf(final)}, {fmt_ratio(final, floor)} the "
        f"floor), {fmt_part(explained)} of the excess explained. The floor is an estimate within a "
        "factor of about three (where the angle sits within its cells is not recorded). A trial "
        "with a finer encoder, or a multisine whose lines leave room between them, would confirm "
        "it: the gap then falls."
    )


def grid_how_far_row(gap: Mapping[str, Any], floor: float, excess0: float) -> list[str] | None:
    """The *How far* table's row of the accounted grid floor, or None where there is none."""
    if not gap.get("accounted"):
        return None
    final = final_gap(gap)
    return [
        "+ encoder grid (accounted floor)",
        fmt_pct(final),
        fmt_vaf(final),
        fmt_ratio(final, floor),
        f"{100 * (float(gap['nominal']) - final) / excess0:.0f} %" if excess0 > 0 else "–",
        "–",
    ]
