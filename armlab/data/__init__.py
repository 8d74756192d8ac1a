"""The trial schema and trial files: what simulation and real labs hand to estimation."""

from armlab.data.h5io import (
    FORMAT_NAME,
    FORMAT_VERSION,
    read_trials,
    write_trials,
)
from armlab.data.reklab import (
    DEFAULT_REKLAB_ROOT,
    AnkleTrial,
    list_ankle_trials,
    load_ankle_trial,
)
from armlab.data.trial import TrialSet

__all__ = [
    "TrialSet",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "read_trials",
    "write_trials",
    "DEFAULT_REKLAB_ROOT",
    "AnkleTrial",
    "list_ankle_trials",
    "load_ankle_trial",
]
