"""Simulation: the held posture, robot IK, batched rollout with reflexes, the simulated lab,
trials stepped from Python on threads."""

from armlab.sim.capstan_lab import CLEAN_UNITS, simulate_capstan
from armlab.sim.cartesian_level_a import (
    CartesianRecord,
    simulate_level_a,
)
from armlab.sim.cartesian_level_b import (
    SETTLE_S,
    LevelBTrials,
    simulate_level_b,
    stop_postures,
)
from armlab.sim.force_control import ForceTrial, simulate_force_trial
from armlab.sim.hold import (
    HoldState,
    preload_activations,
    settle,
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
    "simulate_level_b",
    "stop_postures",
    "simulate_level_a",
]
