"""Simulation: the held posture, robot IK, batched rollout with reflexes, the simulated lab,
trials stepped from Python on threads."""

from armlab.sim.arm5_force_task import (
    A_MIN,
    PRELOAD_CONDITIONS,
    ForceTask,
    force_task_activations,
    muscle_torque_matrix,
    preload_conditions,
)
from armlab.sim.arm5_free import (
    FREE_CHUNK_STEPS,
    FreeMotionRecord,
    HoldRecord,
    random_joint_motion,
    simulate_free_motion,
    simulate_holds,
)
from armlab.sim.arm5_measure import (
    MARKER_RATE_HZ,
    MeasuredTrials,
    measure_stiffness_record,
)
from armlab.sim.arm5_reflex import (
    muscle_length_jacobian,
    reflex_history,
    reflex_stiffness_fd,
)
from armlab.sim.arm5_trials import (
    AMPLITUDE_RAD,
    CHUNK_STEPS,
    RECORDED_SENSORS,
    StiffnessPlan,
    StiffnessRecord,
    TrialTiming,
    directions,
    plan_stiffness_trials,
    settle_conditions,
    simulate_stiffness_trials,
)
from armlab.sim.capstan_lab import CLEAN_UNITS, simulate_capstan
from armlab.sim.cartesian_level_a import (
    CartesianRecord,
    simulate_level_a,
)
from armlab.sim.cartesian_level_b import (
    SETTLE_S,
    LevelBTrials,
    load_level_b_compiled,
    simulate_level_b,
    stop_postures,
)
from armlab.sim.cartesian_level_c import (
    LevelCRecord,
    hill_arm_force,
    simulate_level_c,
)
from armlab.sim.force_control import ForceTrial, simulate_force_trial
from armlab.sim.hold import (
    HoldState,
    preload_activations,
    settle,
)
from armlab.sim.joint_ode import (
    OdeJoint,
    OdeRecording,
    OdeServo,
    simulate_joint_ode,
)
from armlab.sim.joint_ode_effects import (
    LuGre,
    OdeEffects,
    OdeReflex,
    SensorDynamics,
    SeriesSpring,
    SlowSignal,
    StiffnessModulation,
    TorqueDrift,
    VoluntaryTorque,
    drift_signal,
    slow_signal,
)
from armlab.sim.joint_rig import JointRecording, JointSubject, simulate_joint_rig
from armlab.sim.lab import (
    LabRecording,
    record_trials,
    robot_target_paths,
)
from armlab.sim.robot_ik import (
    solve_ik,
)
from armlab.sim.rollout import (
    SimResult,
    simulate,
)
from armlab.sim.subject import activation_commands
from armlab.sim.threads import run_trials

__all__ = [
    "activation_commands",
    "simulate_force_trial",
    "ForceTrial",
    "HoldState",
    "JointRecording",
    "JointSubject",
    "simulate_joint_rig",
    "LuGre",
    "OdeEffects",
    "OdeJoint",
    "OdeRecording",
    "OdeReflex",
    "OdeServo",
    "SensorDynamics",
    "SeriesSpring",
    "SlowSignal",
    "StiffnessModulation",
    "TorqueDrift",
    "VoluntaryTorque",
    "simulate_joint_ode",
    "drift_signal",
    "slow_signal",
    "LabRecording",
    "SimResult",
    "preload_activations",
    "record_trials",
    "robot_target_paths",
    "settle",
    "simulate",
    "solve_ik",
    "CLEAN_UNITS",
    "simulate_capstan",
    "run_trials",
    "CartesianRecord",
    "SETTLE_S",
    "LevelBTrials",
    "load_level_b_compiled",
    "simulate_level_b",
    "stop_postures",
    "LevelCRecord",
    "hill_arm_force",
    "simulate_level_c",
    "simulate_level_a",
    "A_MIN",
    "FREE_CHUNK_STEPS",
    "FreeMotionRecord",
    "HoldRecord",
    "random_joint_motion",
    "simulate_free_motion",
    "simulate_holds",
    "PRELOAD_CONDITIONS",
    "ForceTask",
    "force_task_activations",
    "muscle_torque_matrix",
    "preload_conditions",
    "MARKER_RATE_HZ",
    "MeasuredTrials",
    "measure_stiffness_record",
    "muscle_length_jacobian",
    "reflex_history",
    "reflex_stiffness_fd",
    "AMPLITUDE_RAD",
    "CHUNK_STEPS",
    "RECORDED_SENSORS",
    "StiffnessPlan",
    "StiffnessRecord",
    "TrialTiming",
    "directions",
    "plan_stiffness_trials",
    "settle_conditions",
    "simulate_stiffness_trials",
]
