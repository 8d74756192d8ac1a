"""Loading and composing the MJCF models, analytic arm kinematics, and ground truth."""

from armlab.models.arm_endpoint import EndpointTruth, endpoint_truth, relaxed_activation
from armlab.models.capstan_robot import TABLE_VI_ALPHA, CapstanDynamics, CapstanParameters
from armlab.models.capstan_scene import LOADS, CapstanScene, build_capstan_scene
from armlab.models.cartesian_field import (
    QUADRATIC_TERMS,
    THESIS_FIELD,
    QuadraticImpedanceField,
    quadratic_basis,
)
from armlab.models.direct_drive_scene import ELBOW_MUSCLES, DirectDriveScene, build_direct_drive_scene
from armlab.models.elbow_truth import ElbowTruth, elbow_truth
from armlab.models.frame_change import (
    evaluate_matrix_field,
    matrix_field_in_new_frame,
    polynomial_in_new_frame,
    rotation,
)
from armlab.models.ground_truth import (
    GroundTruth,
    base_inertial_parameters,
    ground_truth,
    joint_impedance,
)
from armlab.models.joint_rig_scene import (
    PAYLOAD_OWN_INERTIA_KGM2,
    Joint1DofScene,
    JointSubject,
    build_joint_rig_scene,
)
from armlab.models.oustaloup import FractionalElement, oustaloup_zpk
from armlab.models.robot_fk import (
    RobotKinematics,
)
from armlab.models.scene import (
    MODELS_DIR,
    MUSCLES,
    Scene,
    build_scene,
    model_file,
    named_id,
)
from armlab.models.spring_array import (
    TABLE_I_PAYLOADS_KG,
    TABLE_I_STIFFNESS,
    Spring,
    SpringArray,
    StiffnessField,
    design_spring_array,
    fixture_mjcf,
    table_i_array,
)
from armlab.models.tf_structures import (
    IDENTIFIED_MODELS,
    LITERATURE_MODELS,
    PUBLISHED_BANDWIDTH_HZ,
    CommensurateTF,
    FiveElement,
    FiveElementFit,
    bandwidth_hz,
    check_alpha,
    five_element_from_tf,
    s_power,
    third_order_tf,
)

__all__ = [
    "Joint1DofScene",
    "JointSubject",
    "PAYLOAD_OWN_INERTIA_KGM2",
    "build_joint_rig_scene",
    "named_id",
    "table_i_array",
    "fixture_mjcf",
    "design_spring_array",
    "StiffnessField",
    "SpringArray",
    "Spring",
    "TABLE_I_STIFFNESS",
    "TABLE_I_PAYLOADS_KG",
    "CapstanParameters",
    "CapstanDynamics",
    "TABLE_VI_ALPHA",
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
    "EndpointTruth",
    "endpoint_truth",
    "relaxed_activation",
    "LOADS",
    "CapstanScene",
    "build_capstan_scene",
    "FractionalElement",
    "oustaloup_zpk",
    "IDENTIFIED_MODELS",
    "LITERATURE_MODELS",
    "PUBLISHED_BANDWIDTH_HZ",
    "CommensurateTF",
    "FiveElement",
    "FiveElementFit",
    "bandwidth_hz",
    "check_alpha",
    "five_element_from_tf",
    "s_power",
    "third_order_tf",
    "QUADRATIC_TERMS",
    "THESIS_FIELD",
    "QuadraticImpedanceField",
    "quadratic_basis",
    "evaluate_matrix_field",
    "matrix_field_in_new_frame",
    "polynomial_in_new_frame",
    "rotation",
]
