"""Loading and composing the MJCF models, analytic arm kinematics, and ground truth."""

from armlab.models.direct_drive_scene import ELBOW_MUSCLES, DirectDriveScene, build_direct_drive_scene
from armlab.models.elbow_truth import ElbowTruth, elbow_truth
from armlab.models.ground_truth import (
    GroundTruth,
    base_inertial_parameters,
    ground_truth,
    joint_impedance,
)
from armlab.models.robot_fk import (
    RobotKinematics,
)
from armlab.models.scene import (
    MODELS_DIR,
    MUSCLES,
    Scene,
    build_scene,
    model_file,
)

__all__ = [
    "elbow_truth",
    "ElbowTruth",
    "build_direct_drive_scene",
    "DirectDriveScene",
    "ELBOW_MUSCLES",
    "GroundTruth",
    "MODELS_DIR",
    "MUSCLES",
    "RobotKinematics",
    "Scene",
    "base_inertial_parameters",
    "build_scene",
    "ground_truth",
    "joint_impedance",
    "model_file",
]
