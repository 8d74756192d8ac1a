"""The trial schema and trial files: what simulation and real labs hand to estimation."""

from armlab.data.h5io import (
    FORMAT_NAME,
    FORMAT_VERSION,
    read_trials,
    write_trials,
)
from armlab.data.trial import TrialSet

__all__ = [
    "TrialSet",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "read_trials",
    "write_trials",
]
