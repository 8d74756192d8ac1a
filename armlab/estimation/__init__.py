"""Estimation of arm impedance from processed trial data."""

from armlab.estimation.criteria import (
    CriteriaConfig,
    asymmetry,
    condition_number,
    eig_symmetric_part,
    first_satisfied,
    is_positive_definite,
    quasi_constant_flags,
    relative_error,
    symmetric_part,
)
from armlab.estimation.joint_ls import (
    PARAM_NAMES,
    REDUCED_PARAM_NAMES,
    LSEstimate,
    ValidationFit,
    estimate,
    estimate_windows,
    regressor,
    validate,
)
from armlab.estimation.processing import (
    JointSignals,
    ProcessingConfig,
    differentiate,
    joint_signals,
    lowpass_zero_phase,
)

__all__ = [
    "CriteriaConfig",
    "asymmetry",
    "condition_number",
    "eig_symmetric_part",
    "first_satisfied",
    "is_positive_definite",
    "quasi_constant_flags",
    "relative_error",
    "symmetric_part",
    "PARAM_NAMES",
    "REDUCED_PARAM_NAMES",
    "LSEstimate",
    "ValidationFit",
    "estimate",
    "estimate_windows",
    "regressor",
    "validate",
    "JointSignals",
    "ProcessingConfig",
    "differentiate",
    "joint_signals",
    "lowpass_zero_phase",
]
