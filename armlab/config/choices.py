"""The choice sets of the typed configs, each a ``Literal`` type (real at runtime).

The config modules annotate their fields with these types and validate through
:func:`armlab.config.validate.choice`, which reads the values with :func:`typing.get_args`.
OmegaConf 2.3 (under Hydra) rejects ``Literal`` field annotations, so the config modules import
these names for type checkers only and bind them to ``str`` at runtime (see ``schema.py``).
"""

from __future__ import annotations

from typing import Literal

__all__ = [
    "ArmModel",
    "CableMode",
    "CapstanModel",
    "DesignCriterion",
    "DesignEnding",
    "DesignNoise",
    "EffectLevel",
    "ElbowImpedance",
    "ElbowModel",
    "EstimatorMethod",
    "Integrator",
    "MotorModel",
    "MuscleModel",
    "PayloadLabel",
    "RobotModel",
    "SensorPreset",
    "StiffnessLabel",
    "VfsRobotModel",
    "XiSource",
]

# schema.py
ArmModel = Literal["arm_planar"]  # arm.model
MuscleModel = Literal["hill", "linear"]  # arm.muscle
RobotModel = Literal["lwr"]  # robot.model
Integrator = Literal["RK4", "implicitfast", "Euler", "implicit"]  # sim.integrator (MuJoCo's)
SensorPreset = Literal["realistic", "ideal"]  # sensors.preset
EstimatorMethod = Literal["joint_ls"]  # estimator.method
XiSource = Literal["truth", "paper", "full_fit"]  # estimator.xi_source
ElbowModel = Literal["elbow_1dof"]  # elbow.model
ElbowImpedance = Literal["muscle", "five_element", "fractional"]  # elbow.impedance
MotorModel = Literal["direct_drive"]  # motor.model

# capstan.py
CapstanModel = Literal["capstan_planar"]  # capstan.model
CableMode = Literal["rigid", "compliant"]  # capstan.cable
VfsRobotModel = Literal["identified", "table_vi"]  # vfs.robot_model
StiffnessLabel = Literal["K1", "K2", "K3", "K4", "K5"]  # vfs.stiffness, Table I
PayloadLabel = Literal["M1", "M2", "M3", "M4", "M5"]  # vfs.payloads, Table I

# effects.py
EffectLevel = Literal["model", "controller", "sensor"]  # Effect.LEVEL
DesignCriterion = Literal["d_optimal", "e_optimal", "expected_error"]  # design.criterion (issue 23)
DesignNoise = Literal["measured", "sensor"]  # design.noise
DesignEnding = Literal["hold", "free"]  # design.ending
