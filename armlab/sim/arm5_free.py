"""Free movement of the 5-DoF arm (seed paper 001, Sec. 3): the calibration motion and the held
configurations of the inertial trials, in the robot-free scene :mod:`armlab.models.arm5_free`.

- :func:`random_joint_motion`: the subject "moves all joint axes of the limb randomly": every joint
  follows q0 plus a sum of three sines of random frequency, phase and amplitude (smooth, bounded,
  inside the joint ranges; the paper gives no trajectory, spec 001: 30 s).
- :func:`simulate_free_motion`: the arm's servos track that motion in one ``mujoco.rollout`` per
  chunk of :data:`FREE_CHUNK_STEPS` steps (no per-step Python); the three marker clusters and the joint
  angles are kept at the Vicon's 500 Hz.
- :func:`simulate_holds`: every predefined configuration is reached and held, all at once in one
  batched rollout per chunk: the servos start at the configuration, settle, then hold it while the
  base F/T (2 kHz) and the forearm cluster (500 Hz) record.

The servo command is u = q_d + (kv / kp) q̇_d: with MuJoCo's position actuator, kp (u - q) - kv q̇,
that is kp (q_d - q) + kv (q̇_d - q̇), a PD servo with velocity feed-forward.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from armlab.cpus import usable_cpus
from armlab.errors import ConfigError
from armlab.models.arm5_free import Arm5FreeScene
from armlab.models.arm_5dof import ARM5_JOINTS, MARKERS
from armlab.sim.arm5_measure import MARKER_RATE_HZ
from armlab.sim.stability import TrialLabels, check_rollout, warning_counts

__all__ = [
    "FREE_CHUNK_STEPS",
    "FreeMotionRecord",
    "HoldRecord",
    "random_joint_motion",
    "simulate_free_motion",
    "simulate_holds",
]

FREE_CHUNK_STEPS = 2000  # physics steps per rollout call (bounds the chunk's state/sensor buffers only)
_FREQ_HZ = (0.1, 0.8)  # Hz, the sines' frequencies: slow voluntary motion (assumption)
_N_SINES = 3
_Q_NAMES = tuple(f"q_{j}" for j in ARM5_JOINTS)


def random_joint_motion(
    q0: np.ndarray, amplitude_rad: float, seconds: float, fs_hz: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """A smooth random motion about ``q0`` (5,) rad: per joint three sines of frequency
    0.1-0.8 Hz, random phase and amplitudes drawn in [0.15, 1/3] x ``amplitude_rad``, so
    |q - q0| <= ``amplitude_rad`` on every joint.

    Returns:
        ``q`` (n, 5) rad and ``qdot`` (n, 5) rad/s at ``fs_hz`` for ``seconds`` s.
    """
    t = np.arange(int(round(seconds * fs_hz))) / fs_hz
    f = rng.uniform(*_FREQ_HZ, (_N_SINES, 5))
    phase = rng.uniform(0.0, 2.0 * np.pi, (_N_SINES, 5))
    amp = rng.uniform(0.15, 1.0 / _N_SINES, (_N_SINES, 5)) * amplitude_rad
    arg = 2.0 * np.pi * f * t[:, None, None] + phase
    q = np.asarray(q0, float) + np.sum(amp * np.sin(arg), axis=1)
    qdot = np.sum(amp * 2.0 * np.pi * f * np.cos(arg), axis=1)
    return q, qdot


@dataclass(frozen=True, kw_only=True, eq=False)
class FreeMotionRecord:
    """The clean calibration motion at the marker rate.

    Attributes:
        marker_pos: (n, 3, 3) m, the torso, upper-arm and forearm clusters (``MARKERS`` order).
        marker_quat: (n, 3, 4) their orientations (w, x, y, z), world.
        true_q: (n, 5) rad the joint angles (ground truth).
        fs_hz: Hz the rate (500).
    """

    marker_pos: np.ndarray
    marker_quat: np.ndarray
    true_q: np.ndarray
    fs_hz: float


@dataclass(frozen=True, kw_only=True, eq=False)
class HoldRecord:
    """The clean holds of the inertial trials.

    Attributes:
        base_wrench: (n_conf, n_ft, 6) the base F/T (force N, torque N·m, sensor frame) at 2 kHz.
        marker_pos: (n_conf, n_m, 3) m, marker_quat: (n_conf, n_m, 4): the forearm cluster at 500 Hz.
        true_q: (n_conf, n_m, 5) rad the joint angles at the marker frames (ground truth).
        ft_fs_hz, marker_fs_hz: Hz.
    """

    base_wrench: np.ndarray
    marker_pos: np.ndarray
    marker_quat: np.ndarray
    true_q: np.ndarray
    ft_fs_hz: float
    marker_fs_hz: float


def _initial_states(scene: Arm5FreeScene, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    model = scene.model
    data = mujoco.MjData(model)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    out = np.empty((len(q), mujoco.mj_stateSize(model, spec)))
    for i in range(len(q)):  # one state per trial (the batch is the rollout's)
        mujoco.mj_resetData(model, data)
        data.qpos[scene.arm_qpos] = q[i]
        data.qvel[scene.arm_dof] = qdot[i]
        mujoco.mj_forward(model, data)
        mujoco.mj_getState(model, data, out[i], spec)
    return out


def _marker_step(scene: Arm5FreeScene) -> int:
    fs = 1.0 / scene.model.opt.timestep
    step = int(round(fs / MARKER_RATE_HZ))
    if step < 1 or abs(step * MARKER_RATE_HZ - fs) > 1e-9 * fs:
        raise ConfigError(f"the physics rate {fs} Hz must be a whole multiple of the markers' 500 Hz")
    return step


def _run(
    scene: Arm5FreeScene,
    init: np.ndarray,
    command: np.ndarray,
    keep: np.ndarray,
    record_from: int,
    who: TrialLabels,
) -> np.ndarray:
    """Step every trial through ``command`` (n, n_steps, 5) rad servo targets, in chunks; the
    sensors ``keep`` (columns of sensordata) of the steps from ``record_from`` on, (n, m, k)."""
    model = scene.model
    n, n_steps, _ = command.shape
    dt = model.opt.timestep
    out = np.empty((n, n_steps - record_from, keep.size))
    datas = [mujoco.MjData(model) for _ in range(max(1, min(usable_cpus(), n)))]
    state = np.ascontiguousarray(init)
    ctrl = np.zeros((n, FREE_CHUNK_STEPS, model.nu))
    with mj_rollout.Rollout(nthread=len(datas)) as runner:
        for c0 in range(0, n_steps, FREE_CHUNK_STEPS):
            m = min(FREE_CHUNK_STEPS, n_steps - c0)
            ctrl[:, :m, scene.servo_act] = command[:, c0 : c0 + m]
            states, sd = runner.rollout([model] * n, datas, state, np.ascontiguousarray(ctrl[:, :m]), nstep=m)
            t = np.arange(c0 + 1, c0 + m + 1) * dt
            check_rollout(who, state, states, datas, dt, t, warned=warning_counts(datas))
            lo = max(c0, record_from)
            if lo < c0 + m:
                out[:, lo - record_from : c0 + m - record_from] = sd[:, lo - c0 :, keep]
            state = np.ascontiguousarray(states[:, -1])
    return out


def _columns(scene: Arm5FreeScene, names: tuple[str, ...]) -> np.ndarray:
    return np.r_[tuple(np.arange(scene.sensors[s].start, scene.sensors[s].stop) for s in names)]


def simulate_free_motion(scene: Arm5FreeScene, q_d: np.ndarray, qdot_d: np.ndarray) -> FreeMotionRecord:
    """The servos track the motion ``q_d`` (n_steps, 5) rad, ``qdot_d`` rad/s given at the physics
    rate, from the motion's own start state; markers and joint angles every 4th step (500 Hz: the
    frame of sample k ends at (k + 1) dt).

    Raises:
        SimulationError: the rollout diverged or MuJoCo warned.
    """
    q_d, qdot_d = np.asarray(q_d, float), np.asarray(qdot_d, float)
    lead = scene.servo_kv / scene.servo_kp  # s
    command = (q_d + lead * qdot_d)[None]
    names = tuple(f"{m}_{k}" for m in MARKERS for k in ("pos", "quat")) + _Q_NAMES
    who = TrialLabels(
        protocol="kinematic calibration",
        labels=("random motion",),
        hint="the arm's joint servos cannot follow the motion (armlab.models.arm5_free)",
    )
    init = _initial_states(scene, q_d[:1], qdot_d[:1])
    rec = _run(scene, init, command, _columns(scene, names), 0, who)[0]
    step = _marker_step(scene)
    rec = rec[step - 1 :: step]
    pos = np.stack([rec[:, 7 * i : 7 * i + 3] for i in range(len(MARKERS))], axis=1)
    quat = np.stack([rec[:, 7 * i + 3 : 7 * i + 7] for i in range(len(MARKERS))], axis=1)
    return FreeMotionRecord(
        marker_pos=pos, marker_quat=quat, true_q=rec[:, 7 * len(MARKERS) :], fs_hz=MARKER_RATE_HZ
    )


def simulate_holds(
    scene: Arm5FreeScene, configurations: np.ndarray, settle_s: float, hold_s: float
) -> HoldRecord:
    """Hold every configuration (n_conf, 5) rad: the servos start at it at rest, settle
    ``settle_s`` s under gravity, then hold ``hold_s`` s while the sensors record.

    Raises:
        SimulationError: a hold diverged or MuJoCo warned.
    """
    q = np.atleast_2d(np.asarray(configurations, float))
    dt = scene.model.opt.timestep
    n_settle, n_hold = int(round(settle_s / dt)), int(round(hold_s / dt))
    command = np.repeat(q[:, None, :], n_settle + n_hold, axis=1)
    names = ("base_force", "base_torque", "forearm_marker_pos", "forearm_marker_quat", *_Q_NAMES)
    who = TrialLabels(
        protocol="inertial trials",
        labels=tuple(f"configuration {i}" for i in range(len(q))),
        hint="the arm's joint servos cannot hold the configuration (armlab.models.arm5_free)",
    )
    init = _initial_states(scene, q, np.zeros_like(q))
    rec = _run(scene, init, command, _columns(scene, names), n_settle, who)
    step = _marker_step(scene)
    frames = rec[:, step - 1 :: step]
    return HoldRecord(
        base_wrench=rec[..., :6],
        marker_pos=frames[..., 6:9],
        marker_quat=frames[..., 9:13],
        true_q=frames[..., 13:18],
        ft_fs_hz=1.0 / dt,
        marker_fs_hz=MARKER_RATE_HZ,
    )
