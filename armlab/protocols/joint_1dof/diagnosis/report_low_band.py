"""The *Below the scoring band* section of ``report.md`` and the verdict paragraph of a drift (the
``low_band`` results of :mod:`.low_band`; docs/diagnosis_schema.md)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from armlab.diagnosis.report_text import fmt_num, fmt_part, fmt_pct, fmt_vaf

__all__ = ["drift_verdict_paragraph", "low_band_section"]


def drift_verdict_paragraph(r: Mapping[str, Any]) -> str | None:
    """The summary paragraph of a verdict named below the scoring band, or None for any other."""
    low = r.get("low_band")
    if list(r.get("verdict") or []) != ["force_sensor_drift"] or not low or not low.get("named"):
        return None
    d = low["force_sensor_drift"]
    gap = r["gap"]
    return (
        "**Verdict: a drift of the torque sensor's bias (`force_sensor_drift`), below the scoring "
        f"band.** In the scoring band the nominal simulation reaches a held-out VAF of "
        f"{fmt_vaf(gap['nominal'])} (gap {fmt_pct(gap['nominal'])}) at the noise floor "
        f"{fmt_pct(gap['noise_floor'])}: nothing to explain there. Below "
        f"{fmt_num(low['band_hz'][1])} Hz the torque the position does not predict holds "
        f"{_ratio(low['residual_power_Nm2'], low['noise_power_Nm2'])} times the noise's "
        f"power, and a slow drift (cosines of time below {fmt_num(d['band_hz'][1])} Hz) holds "
        f"{fmt_part(d['share_of_excess'])} of that excess, {fmt_num(d['enr'])} times the noise's rms in its "
        f"band; each 2 s block predicted from the others, it removes {fmt_part(d['shrink'])} "
        "of the slow excess. A trial with the subject at rest or the pedal empty would confirm it (a "
        "drift stays)."
    )


def low_band_section(r: Mapping[str, Any], h: str) -> list[str]:
    """The *Below the scoring band* section (``h``: the heading marks), or no lines without it."""
    low = r.get("low_band")
    if not low:
        return []
    d = low["force_sensor_drift"]
    ratio = _ratio(low["residual_power_Nm2"], low["noise_power_Nm2"])
    captured = _ratio(d["captured_power_Nm2"], d["noise_power_Nm2"])
    threshold = _ratio(d["threshold_power_Nm2"], d["noise_power_Nm2"])
    return [
        f"{h} Below the scoring band",
        "",
        f"The nominal's residual below {fmt_num(low['band_hz'][1])} Hz (what the scoring band leaves out), "
        f"against white noise of density {fmt_num(low['noise_density_Nm2_per_Hz'])} N·m²/Hz:",
        "",
        "| quantity | value |",
        "|---|---|",
        f"| residual power / noise power | {ratio} |",
        f"| drift cosines (below {fmt_num(d['band_hz'][1])} Hz, all trials) | {d['components']} |",
        f"| captured power / noise's share | {captured} (detection above {threshold}) |",
        f"| drift ENR | {fmt_num(d['enr'])} |",
        f"| drift's share of the slow excess | {fmt_part(d['share_of_excess'])} |",
        f"| cross-fitted shrink of the slow excess | {fmt_part(d['shrink'])} |",
        f"| drift named | {'yes' if low['named'] else 'no'} |",
    ]


def _ratio(a: float, b: float) -> str:
    return fmt_num(a / b) if b > 0 else "–"
