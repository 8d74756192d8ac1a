"""The typed experiment of ``fractional_elbow`` (seeds/004): the groups it reads, nothing else."""

from __future__ import annotations

from dataclasses import dataclass, field

from armlab.config.schema import (
    DirectDriveConfig,
    ElbowConfig,
    ExperimentConfig,
    FrfConfig,
    ReflexConfig,
    ScenarioConfig,
)

__all__ = ["FractionalElbowConfig"]


@dataclass(kw_only=True)
class FractionalElbowConfig(ExperimentConfig):
    """The direct-drive motor pushing the 1-DoF elbow; FRF and Levy fits."""

    protocol_name: str = "fractional_elbow"
    elbow: ElbowConfig = field(default_factory=ElbowConfig)
    motor: DirectDriveConfig = field(default_factory=DirectDriveConfig)
    frf: FrfConfig = field(default_factory=FrfConfig)
    reflex: ReflexConfig = field(default_factory=ReflexConfig)  # of the Hill elbow (impedance=muscle)
    scenario: ScenarioConfig = field(default_factory=lambda: ScenarioConfig(name="fractional_elbow"))
