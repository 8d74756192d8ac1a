"""Protocols: one module per paper's protocol, and the runner that writes a run's outputs."""

from armlab.protocols.conditioning_window import (
    PAPER_THRESHOLDS_S,
    PAPER_XI,
    estimate_protocol,
    simulate_protocol,
    window_specs,
)
from armlab.protocols.fractional_elbow import (
    PAPER_TABLE_I,
    FractionalRecording,
    estimate_fractional,
    simulate_fractional,
    time_overlay,
)
from armlab.protocols.joint_frf import JOINT_BAND_HZ, fit_joint_frf
from armlab.protocols.joint_report import fit_joint_recordings, format_joint_table, joint_frf_config
from armlab.protocols.runner import (
    PROTOCOLS,
    format_table,
    reestimate,
    run_protocol,
)
from armlab.protocols.vfs_results import METHODS, estimate_vfs, smoothing_spec
from armlab.protocols.virtual_force_sensor import VfsRecording, simulate_vfs

__all__ = [
    "JOINT_BAND_HZ",
    "PAPER_TABLE_I",
    "FractionalRecording",
    "estimate_fractional",
    "fit_joint_frf",
    "fit_joint_recordings",
    "format_joint_table",
    "joint_frf_config",
    "simulate_fractional",
    "time_overlay",
    "PAPER_THRESHOLDS_S",
    "PAPER_XI",
    "PROTOCOLS",
    "estimate_protocol",
    "format_table",
    "reestimate",
    "run_protocol",
    "simulate_protocol",
    "window_specs",
    "METHODS",
    "estimate_vfs",
    "smoothing_spec",
    "VfsRecording",
    "simulate_vfs",
]
