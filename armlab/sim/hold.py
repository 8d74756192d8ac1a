"""The held posture before the perturbations: pre-load activations, robot targets, settling.

The subject holds q0 and pushes ``preload_N`` distally (from the shoulder towards the hand) on the
robot with least effort (paper IV-B). The muscle activations are the co-contraction level plus the
least-norm change that produces the joint torque ``J(q0)^T f`` of that push; the robot holds the
hand at q0; the scene then settles so that every trial starts from the same steady state.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout

from armlab.config.schema import ArmConfig
from armlab.errors import ConfigError
from armlab.models import planar_arm
from armlab.models.scene import Scene
from armlab.sim.robot_ik import nominal_robot_posture, solve_ik
from armlab.sim.stability import TrialLabels, check_rollout

__all__ = [
    "HoldState",
    "hand_world",
    "preload_activations",
    "settle",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class HoldState:
    """The settled pre-perturbation state shared by every trial.

    Attributes:
        state: (nstate,) MuJoCo full-physics state after settling.
        ctrl: (nu,) controls held during settling (muscle activations, robot targets).
        activation: (6,) muscle activation commands.
        robot_target: (7,) rad robot joint targets.
        q_arm: (2,) rad arm posture after settling (the operating point).
    """

    state: np.ndarray
    ctrl: np.ndarray
    activation: np.ndarray
    robot_target: np.ndarray
    q_arm: np.ndarray


def hand_world(scene: Scene, q: np.ndarray) -> np.ndarray:
    """(..., 3) m, world position of the hand for arm angles ``q`` (..., 2) rad."""
    xy = planar_arm.forward(np.asarray(q, float), scene.l1, scene.l2)
    z = np.zeros(xy.shape[:-1] + (1,))
    return np.concatenate([xy, z], axis=-1) + scene.shoulder_pos


def _arm_torque(scene: Scene, data: mujoco.MjData, act: np.ndarray) -> np.ndarray:
    data.act[scene.muscle_act] = act
    mujoco.mj_forward(scene.model, data)
    return data.qfrc_actuator[scene.arm_dof].copy()


def preload_activations(scene: Scene, arm: ArmConfig) -> np.ndarray:
    """Muscle activations for the co-contraction level plus the distal pre-load.

    Returns:
        (6,) activations in [0, 1].

    Raises:
        ConfigError: the pre-load needs activations outside [0, 1].
    """
    q0 = np.asarray(arm.q0, float)
    x = planar_arm.forward(q0, scene.l1, scene.l2)
    push = arm.preload_N * x / np.linalg.norm(x)  # N, force of the hand on the robot, distal
    tau_req = planar_arm.jacobian(q0, scene.l1, scene.l2).T @ push  # muscle torque balancing it
    data = mujoco.MjData(scene.model)
    data.qpos[scene.arm_qpos] = q0
    base = np.full(len(scene.muscle_act), arm.cocontraction)
    tau0 = _arm_torque(scene, data, np.zeros_like(base))
    gain = np.stack([_arm_torque(scene, data, e) - tau0 for e in np.eye(len(base))], axis=1)
    act = base + np.linalg.pinv(gain) @ (tau_req - tau0 - gain @ base)
    if np.any(act < 0) or np.any(act > 1):
        raise ConfigError(
            f"arm.preload_N={arm.preload_N} at arm.cocontraction={arm.cocontraction} needs activations "
            f"{np.round(act, 3).tolist()} outside [0, 1]; lower the pre-load or change the co-contraction"
        )
    return act


def settle(scene: Scene, arm: ArmConfig, duration_s: float, *, protocol: str = "laboratory") -> HoldState:
    """Place arm and robot at q0 with the pre-load and let the scene settle.

    Args:
        scene: the composed scene.
        arm: arm configuration (q0, co-contraction, pre-load).
        duration_s: s, settling time.
        protocol: named in a :class:`SimulationError`.

    Raises:
        SimulationError: the hold diverged while settling (MuJoCo warned or reset the state).
    """
    model = scene.model
    q0 = np.asarray(arm.q0, float)
    target = hand_world(scene, q0)
    robot_q = solve_ik(scene, target[None], nominal_robot_posture(scene, target))[0]
    act = preload_activations(scene, arm)
    data = mujoco.MjData(model)
    data.qpos[scene.arm_qpos] = q0
    data.qpos[scene.robot_qpos] = robot_q
    data.act[scene.muscle_act] = act
    ctrl = np.zeros(model.nu)
    ctrl[scene.muscle_act] = act
    ctrl[scene.robot_act] = robot_q
    data.ctrl[:] = ctrl
    mujoco.mj_forward(model, data)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state0, spec)
    nstep = int(round(duration_s / model.opt.timestep))

    states, _ = rollout.rollout(model, data, state0[None], ctrl[None, None, :], nstep=nstep)
    who = TrialLabels(
        protocol=protocol,
        labels=("the settling hold before the trials",),
        hint="lower the cuff stiffness (cuff.stiffness_N_per_m) or sim.timestep_s",
    )
    dt = model.opt.timestep
    check_rollout(who, state0[None], states, [data], dt, np.arange(1, nstep + 1) * dt)
    final = states[0, -1].copy()
    final[0] = 0.0  # trials start their clocks at zero
    q_arm = final[1 + scene.arm_qpos]
    return HoldState(state=final, ctrl=ctrl, activation=act, robot_target=robot_q, q_arm=q_arm)
