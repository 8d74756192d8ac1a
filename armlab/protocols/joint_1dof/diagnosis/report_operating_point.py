"""The *Operating point* section of ``report.md`` for a time-varying recording (the
``operating_point`` results of :mod:`.time_varying`; docs/diagnosis_schema.md)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["operating_point_section"]


def operating_point_section(r: Mapping[str, Any], h: str) -> list[str]:
    """The *Operating point* section of a time-varying recording's results (``h``: the heading
    marks), or no lines for a stationary one."""
    op = r.get("operating_point")
    if op is None:
        return []
    b = op["binned"]
    rows = [
        f"{h} Operating point",
        "",
        "The recording carries its operating angle (a perturbation on a slow movement). In "
        f"{b['bins']} bins of the angle, equal in samples, the nominal's parameters were fitted apart "
        f"and tested for constancy (p below {b['p_threshold']:g} = varies):",
        "",
        "| parameter | unit | lowest bin | highest bin | relative range | p (constant) |",
        "|---|---|---|---|---|---|",
    ]
    for k, p in b["parameters"].items():
        rows.append(
            f"| {k} | {p['unit']} | {min(p['values']):.4g} | {max(p['values']):.4g} | "
            f"{100 * p['relative_range']:.0f} % | {p['p_constant']:.2g} |"
        )
    where = op["where"]
    gaps = (100 * op["stationary_nominal_gap"], 100 * op["time_varying_nominal_gap"])
    rows += [
        "",
        (
            f"**{where['parameter']}** varies most: from {where['lowest']['value']:.4g} at "
            f"{where['lowest']['at_rad']:+.3f} rad to {where['highest']['value']:.4g} at "
            f"{where['highest']['at_rad']:+.3f} rad over the recorded {where['from_rad']:+.3f} … "
            f"{where['to_rad']:+.3f} rad. "
            if where
            else "No parameter varies with the operating angle. "
        )
        + f"A nominal whose K and B are quadratics of the angle moves the held-out gap from "
        f"{gaps[0]:.2f} % to {gaps[1]:.2f} % ({100 * op['explained_fraction']:.0f} % of the excess "
        "over the noise floor); "
        + (
            "the diagnosis therefore starts from that time-varying nominal (verdict "
            "`operating_point_impedance`), and the effects after it are scored on top of it."
            if op["varies"]
            else "that is not enough to accept it, and the diagnosis starts from the stationary nominal."
        ),
    ]
    return rows
