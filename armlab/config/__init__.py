"""Typed configuration (dataclass schemas registered in Hydra's ConfigStore)."""

from armlab.config.schema import (
    ArmConfig,
    CuffConfig,
    DirectDriveConfig,
    ElbowConfig,
    EstimatorConfig,
    ExperimentConfig,
    FrfConfig,
    OutputConfig,
    ReflexConfig,
    RobotConfig,
    ScenarioConfig,
    SensorsConfig,
    SimConfig,
)
from armlab.config.store import (
    CONFIG_DIR,
    available_options,
    to_experiment,
)
from armlab.config.subject import SubjectConfig

__all__ = [
    "ArmConfig",
    "CONFIG_DIR",
    "CuffConfig",
    "DirectDriveConfig",
    "ElbowConfig",
    "EstimatorConfig",
    "ExperimentConfig",
    "FrfConfig",
    "OutputConfig",
    "ReflexConfig",
    "RobotConfig",
    "ScenarioConfig",
    "SensorsConfig",
    "SimConfig",
    "SubjectConfig",
    "available_options",
    "to_experiment",
]
