"""The typed experiment of ``virtual_force_sensor`` (seeds/003): the groups it reads, nothing else."""

from __future__ import annotations

from dataclasses import dataclass, field

from armlab.config.schema import ArmConfig, CapstanConfig, ExperimentConfig, VfsConfig

__all__ = ["VirtualForceSensorConfig"]


@dataclass(kw_only=True)
class VirtualForceSensorConfig(ExperimentConfig):
    """The capstan planar robot with mass-spring fixtures and the relaxed planar arm."""

    protocol_name: str = "virtual_force_sensor"
    arm: ArmConfig = field(default_factory=ArmConfig)
    capstan: CapstanConfig = field(default_factory=CapstanConfig)
    vfs: VfsConfig = field(default_factory=VfsConfig)
