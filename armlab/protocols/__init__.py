"""Protocols: one module per paper's protocol, and the runner that writes a run's outputs."""

from armlab.protocols.conditioning_window import (
    PAPER_THRESHOLDS_S,
    PAPER_XI,
    estimate_protocol,
    simulate_protocol,
    window_specs,
)
from armlab.protocols.runner import (
    PROTOCOLS,
    format_table,
    reestimate,
    run_protocol,
)

__all__ = [
    "PAPER_THRESHOLDS_S",
    "PAPER_XI",
    "PROTOCOLS",
    "estimate_protocol",
    "format_table",
    "reestimate",
    "run_protocol",
    "simulate_protocol",
    "window_specs",
]
