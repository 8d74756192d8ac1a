"""The typed experiment of ``conditioning_window`` (seeds/000): the groups it reads, nothing else."""

from __future__ import annotations

from dataclasses import dataclass, field

from armlab.config.schema import (
    ArmConfig,
    CuffConfig,
    EstimatorConfig,
    ExperimentConfig,
    ReflexConfig,
    RobotConfig,
    ScenarioConfig,
)

__all__ = ["ConditioningWindowConfig"]


@dataclass(kw_only=True)
class ConditioningWindowConfig(ExperimentConfig):
    """The LWR perturbing the planar arm through the cuff; joint-space least squares per window."""

    protocol_name: str = "conditioning_window"
    arm: ArmConfig = field(default_factory=ArmConfig)
    reflex: ReflexConfig = field(default_factory=ReflexConfig)
    cuff: CuffConfig = field(default_factory=CuffConfig)
    robot: RobotConfig = field(default_factory=RobotConfig)
    scenario: ScenarioConfig = field(default_factory=lambda: ScenarioConfig(name="conditioning_window"))
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
