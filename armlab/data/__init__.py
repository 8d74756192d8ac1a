"""The trial schema and trial files: what simulation and real labs hand to estimation."""

from armlab.data.atomic import atomic_path
from armlab.data.h5io import (
    FORMAT_NAME,
    FORMAT_VERSION,
    read_trials,
    write_trials,
)
from armlab.data.joint_import import (
    JOINT_COLUMNS,
    SUPPORTED_SUFFIXES,
    TIME_VARYING_COLUMNS,
    load_joint_data,
    write_joint_csv,
)
from armlab.data.joint_record import JointRecord
from armlab.data.joint_units import (
    JointUnits,
    apply_units,
    parse_units,
)
from armlab.data.reklab import (
    DEFAULT_REKLAB_ROOT,
    AnkleTrial,
    list_ankle_trials,
    load_ankle_trial,
)
from armlab.data.rundir import require_complete, run_state
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
    "JOINT_COLUMNS",
    "TIME_VARYING_COLUMNS",
    "SUPPORTED_SUFFIXES",
    "JointRecord",
    "JointUnits",
    "apply_units",
    "parse_units",
    "load_joint_data",
    "write_joint_csv",
    "atomic_path",
    "run_state",
    "require_complete",
]
