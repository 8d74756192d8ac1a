"""The stiffness trials of seed paper 001 in the composed lab (:mod:`armlab.models.arm5_scene`).

Per pre-load condition the subject holds the default posture q0 with the force task's activations
(:mod:`armlab.sim.arm5_force_task`, frozen: no reflex) for a random 1.5-2.5 s; then the robot moves
the wrist along a fifth-order polynomial planned in the limb's joint space, q(s) = q0 + s dq with
dq = +-0.08 rad on one of the five joints (10 directions, chosen at random), and holds it
(paper Sec. 3). The robot is commanded the wrist frame T(q(s)): the integral of
Delta x_robot = J_limb(q) Delta q along the planned path (exact, so the commanded 6-D pose stays on
the arm's 5-D manifold), through the LWR's inverse kinematics (:func:`armlab.sim.robot_ik.solve_ik`,
solved on :data:`PATH_POINTS` points of s and spline-interpolated).

Every trial of every condition is stepped in one batched ``mujoco.rollout`` per chunk of
:data:`CHUNK_STEPS` steps (no per-step Python). A trial starts from its condition's settled hold:
the simulated subject has no anticipation and frozen activations, so its state at the onset does not
depend on how long it held; the random hold enters the record only as the time since the sensors
were tared (their drift, :func:`armlab.sensors.presets.measure`'s ``t0_s``).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout
from scipy.interpolate import CubicSpline

from armlab.config.schema import ReflexConfig
from armlab.cpus import usable_cpus
from armlab.errors import ConfigError
from armlab.models.arm5_scene import Arm5Scene
from armlab.models.limb_kinematics import LimbKinematics
from armlab.perturbations.quintic import quintic_profile
from armlab.sim import _chunk_kernel as kernel
from armlab.sim.arm5_reflex import muscle_length_jacobian, reflex_history
from armlab.sim.robot_ik import nominal_robot_posture, solve_ik
from armlab.sim.rollout import REFLEX_LENGTH_SCALE_M
from armlab.sim.stability import TrialLabels, check_rollout, warning_counts

__all__ = [
    "AMPLITUDE_RAD",
    "CHUNK_STEPS",
    "PATH_POINTS",
    "RECORDED_SENSORS",
    "StiffnessPlan",
    "StiffnessRecord",
    "TrialTiming",
    "directions",
    "plan_stiffness_trials",
    "settle_conditions",
    "simulate_stiffness_trials",
]

AMPLITUDE_RAD = 0.08  # rad, perturbation amplitude (paper Sec. 3: "approximately 0.08 rad")
N_DIRECTIONS = 10  # paper Sec. 3: +- each of the 5 joints
PATH_POINTS = 21  # IK points along each direction's wrist path (spline-interpolated in between)
CHUNK_STEPS = 200  # physics steps per rollout call (bounds the chunk's state/sensor buffers only)
SETTLE_S = 0.5  # s, settling of each condition's hold before its trials (transients < 0.1 s)
# The clean sensors every trial keeps (the rest of sensordata is dropped chunk by chunk).
RECORDED_SENSORS = (
    "wrist_force",
    "wrist_torque",
    "base_force",
    "base_torque",
    "forearm_marker_pos",
    "forearm_marker_quat",
    "q_shoulder_flexion",
    "q_shoulder_abduction",
    "q_shoulder_rotation",
    "q_elbow_flexion",
    "q_pronation",
)


def directions(amplitude: float = AMPLITUDE_RAD) -> np.ndarray:
    """(10, 5) rad: +amplitude on joint j for direction j, -amplitude for direction 5 + j."""
    return amplitude * np.vstack([np.eye(5), -np.eye(5)])


@dataclass(frozen=True, kw_only=True)
class TrialTiming:
    """The timeline of one perturbation (spec 001 assumptions: the paper gives none).

    Attributes:
        pre_s: s recorded before the onset (covers the pre-interval).
        rise_s: s, the quintic's duration (100 ms); hold_s: s held at the displacement (300 ms).
        pre_interval: (start, end) s from the onset, the working-point mean ([-0.2, 0] s).
        post_interval: (start, end) s from the onset, the displaced mean ([rise + 0.1, rise + 0.3] s).
    """

    pre_s: float = 0.25
    rise_s: float = 0.1
    hold_s: float = 0.3
    pre_interval: tuple[float, float] = (-0.2, 0.0)
    post_interval: tuple[float, float] = (0.2, 0.4)

    def __post_init__(self) -> None:
        if not (self.rise_s > 0 and self.hold_s > 0 and self.pre_s > 0):
            raise ConfigError(f"pre_s, rise_s and hold_s must be positive seconds, got {self}")
        a, b = self.pre_interval
        c, d = self.post_interval
        if not (-self.pre_s <= a < b <= 0.0):
            raise ConfigError(
                f"pre_interval {self.pre_interval} must lie in [-pre_s, 0] = [{-self.pre_s}, 0] s"
            )
        if not (self.rise_s <= c < d <= self.rise_s + self.hold_s + 1e-12):
            raise ConfigError(
                f"post_interval {self.post_interval} must lie in the hold [rise_s, rise_s + hold_s] = "
                f"[{self.rise_s}, {self.rise_s + self.hold_s}] s"
            )

    @property
    def record_s(self) -> float:
        """s, the record's length: pre_s + rise_s + hold_s."""
        return self.pre_s + self.rise_s + self.hold_s


@dataclass(frozen=True, kw_only=True, eq=False)
class StiffnessPlan:
    """The drawn trials.

    Attributes:
        condition: (n_trials,) index of each trial's pre-load condition.
        direction: (n_trials,) 0..9, see :func:`directions`.
        wait_s: (n_trials,) s, the random hold before each onset (1.5-2.5 s).
    """

    condition: np.ndarray
    direction: np.ndarray
    wait_s: np.ndarray

    @property
    def n_trials(self) -> int:
        """Number of trials."""
        return int(self.condition.size)


def plan_stiffness_trials(
    n_conditions: int,
    n_per_condition: int,
    rng: np.random.Generator,
    wait_s: tuple[float, float] = (1.5, 2.5),
) -> StiffnessPlan:
    """Draw each condition's trials: directions in random order, each of the 10 equally often
    (n_per_condition // 10 times, the remainder drawn at random; so every joint is displaced
    both ways and A^T A of Eq. (15) is regular), and uniform random holds.

    Raises:
        ConfigError: fewer than 10 trials per condition, or a bad hold range.
    """
    if n_per_condition < N_DIRECTIONS or n_conditions < 1:
        raise ConfigError(
            f"need at least {N_DIRECTIONS} trials per condition (one per direction) and one condition, "
            f"got {n_per_condition} x {n_conditions}"
        )
    lo, hi = wait_s
    if not 0.0 <= lo <= hi:
        raise ConfigError(f"wait_s must be (low, high) seconds with 0 <= low <= high, got {wait_s!r}")
    reps, extra = divmod(n_per_condition, N_DIRECTIONS)
    dirs = []
    for _ in range(n_conditions):
        d = np.r_[np.repeat(np.arange(N_DIRECTIONS), reps), rng.integers(0, N_DIRECTIONS, extra)]
        dirs.append(rng.permutation(d))
    n = n_conditions * n_per_condition
    return StiffnessPlan(
        condition=np.repeat(np.arange(n_conditions), n_per_condition),
        direction=np.concatenate(dirs),
        wait_s=rng.uniform(lo, hi, n),
    )


def _state_spec() -> mujoco.mjtState:
    return mujoco.mjtState.mjSTATE_FULLPHYSICS


def settle_conditions(
    scene: Arm5Scene,
    kin: LimbKinematics,
    q0: np.ndarray,
    activations: np.ndarray,
    settle_s: float = SETTLE_S,
) -> tuple[np.ndarray, np.ndarray]:
    """Hold q0 with each condition's activations: the robot at the IK of the wrist frame T(q0).

    Args:
        activations: (n_conditions, 12) muscle activations (``ARM5_MUSCLES`` order).

    Returns:
        ``states`` (n_conditions, nstate) full-physics states after ``settle_s`` (clock reset to
        zero) and ``robot_q`` (7,) rad the robot's hold targets.
    """
    model = scene.model
    rot, pos = kin.forward(q0)
    robot_q = solve_ik(scene, pos[None], nominal_robot_posture(scene, pos), rotation=rot[None])[0]
    acts = np.atleast_2d(np.asarray(activations, float))
    data = mujoco.MjData(model)
    spec = _state_spec()
    n_state = mujoco.mj_stateSize(model, spec)
    init = np.empty((len(acts), n_state))
    ctrl = np.zeros((len(acts), 1, model.nu))
    for c, a in enumerate(acts):  # one state per condition (8): the batch is the rollout's
        mujoco.mj_resetData(model, data)
        data.qpos[scene.arm_qpos] = q0
        data.qpos[scene.robot_qpos] = robot_q
        data.act[scene.muscle_actadr] = a
        mujoco.mj_forward(model, data)
        mujoco.mj_getState(model, data, init[c], spec)
        ctrl[c, 0, scene.muscle_act] = a
        ctrl[c, 0, scene.robot_act] = robot_q
    nstep = int(round(settle_s / model.opt.timestep))
    ctrl = np.repeat(ctrl, nstep, axis=1)
    datas = [mujoco.MjData(model) for _ in range(usable_cpus())]
    states, _ = mj_rollout.rollout(model, datas, init, ctrl, nstep=nstep)
    who = TrialLabels(
        protocol="stiffness trials",
        labels=tuple(f"settling condition {c}" for c in range(len(acts))),
        hint="the 6-D cuff weld or the robot servos cannot hold the arm; check models/arm_5dof/cuff_6d.xml",
    )
    dt = model.opt.timestep
    check_rollout(who, init, states, datas, dt, np.arange(1, nstep + 1) * dt - settle_s)
    final = states[:, -1].copy()
    final[:, 0] = 0.0  # every trial's clock starts at zero
    return final, robot_q


def _robot_paths(
    scene: Arm5Scene,
    kin: LimbKinematics,
    q0: np.ndarray,
    robot_q: np.ndarray,
    dirs: np.ndarray,
    s_t: np.ndarray,
    sd_t: np.ndarray,
) -> np.ndarray:
    """(n_dirs, n_steps, 7) rad robot servo commands along T(q0 + s dq).

    The joint path x(s) is the IK on PATH_POINTS values of s, spline-interpolated, at the profile
    ``s_t`` (n_steps,) with rate ``sd_t`` (1/s). The LWR's servos are MuJoCo position actuators,
    force kp (u - x) - kv x', which damp towards zero velocity and so lag a moving target; the
    command u = x + (kv / kp) x' gives kp (x - q) + kv (x' - q') exactly: a PD servo with velocity
    feed-forward, as a robot's joint controller tracks a planned trajectory.
    """
    model = scene.model
    kp, kv = model.actuator_gainprm[scene.robot_act, 0], -model.actuator_biasprm[scene.robot_act, 2]
    lead = kv / kp  # s
    s_grid = np.linspace(0.0, 1.0, PATH_POINTS)
    out = np.empty((len(dirs), s_t.size, 7))
    for k, dq in enumerate(dirs):
        rot, pos = kin.forward(q0 + s_grid[:, None] * dq)
        spline = CubicSpline(s_grid, solve_ik(scene, pos, robot_q, rotation=rot, q_nominal=robot_q), axis=0)
        out[k] = spline(s_t) + lead * spline(s_t, 1) * sd_t[:, None]
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class StiffnessRecord:
    """Clean signals of every trial at the physics rate (2 kHz).

    Attributes:
        fs_hz: Hz. onset_index: sample of the onset (the same in every trial).
        channels: name (:data:`RECORDED_SENSORS`, ``q_*`` merged into ``true_q`` (5,)) ->
            (n_trials, n_samples, k): ``wrist_force`` N and ``wrist_torque`` N·m in the wrist JR3
            frame (what the flange exerts on the cuff), ``base_force`` N / ``base_torque`` N·m in the
            base F/T frame, ``forearm_marker_pos`` m / ``forearm_marker_quat`` (w, x, y, z) world,
            ``true_q`` rad the arm's joint angles (ground truth).
        robot_q_hold: (7,) rad the robot's hold targets.
        commanded_dq: (n_trials, 5) rad the planned displacement of each trial.
        muscle_ctrl: (n_trials, n_samples, 12) the muscle commands (neural drive, 0..1,
            ``ARM5_MUSCLES`` order) applied at each step when the reflex moved them; None with the
            reflex off, when every trial's commands are its condition's activations throughout.
    """

    fs_hz: float
    onset_index: int
    channels: dict[str, np.ndarray]
    robot_q_hold: np.ndarray
    commanded_dq: np.ndarray
    muscle_ctrl: np.ndarray | None = None


def simulate_stiffness_trials(
    scene: Arm5Scene,
    kin: LimbKinematics,
    q0: np.ndarray,
    activations: np.ndarray,
    plan: StiffnessPlan,
    timing: TrialTiming = TrialTiming(),
    amplitude: float = AMPLITUDE_RAD,
    nthread: int | None = None,
    settle_s: float = SETTLE_S,
    reflex: ReflexConfig | None = None,
) -> StiffnessRecord:
    """Settle every condition, then step all trials of the plan in batched rollout chunks.

    Args:
        scene: the composed lab; kin: the arm's true kinematic chain (the robot's path planner).
        q0: (5,) rad the held posture.
        activations: (n_conditions, 12) the force task's activations per condition.
        plan: the drawn trials (its condition indices address ``activations``' rows).
        timing: the trial timeline; amplitude: rad the joint displacement.
        nthread: rollout threads (default: all cores).
        settle_s: s each condition's hold settles before its trials (:func:`settle_conditions`).
        reflex: the stretch reflex (:mod:`armlab.sim.arm5_reflex`); None or ``enabled=False``:
            activations frozen at the force task's. On, the rollout chunks are no longer than its
            shorter latency and each chunk's muscle commands come from the stretch already stepped,
            relative to each trial's posture at the start of its record.

    Raises:
        SimulationError: a trial diverged or MuJoCo warned.
    """
    model = scene.model
    dt = model.opt.timestep
    acts = np.atleast_2d(np.asarray(activations, float))
    if plan.condition.max() >= len(acts):
        raise ConfigError(f"the plan has {plan.condition.max() + 1} conditions, activations only {len(acts)}")
    held, robot_q = settle_conditions(scene, kin, q0, acts, settle_s)
    n_steps = int(round(timing.record_s / dt))
    onset = int(round(timing.pre_s / dt))
    # sample k is the state after step k + 1, i.e. at (k + 1) dt; the onset at sample `onset`
    t_rel = (np.arange(n_steps) + 1 - onset) * dt
    s_t, sd_t, _ = quintic_profile(t_rel, timing.rise_s)
    dirs = directions(amplitude)
    paths = _robot_paths(scene, kin, np.asarray(q0, float), robot_q, dirs, s_t, sd_t)
    n = plan.n_trials
    state = np.ascontiguousarray(held[plan.condition])
    keep = np.r_[tuple(np.arange(scene.sensors[s].start, scene.sensors[s].stop) for s in RECORDED_SENSORS)]
    out = np.empty((n, n_steps, keep.size))
    datas = [mujoco.MjData(model) for _ in range(nthread or usable_cpus())]
    ctrl = np.zeros((n, CHUNK_STEPS, model.nu))
    ctrl[:, :, scene.muscle_act] = acts[plan.condition][:, None, :]
    who = TrialLabels(
        protocol="stiffness trials",
        labels=tuple(
            f"condition {c}, direction {d}" for c, d in zip(plan.condition, plan.direction, strict=True)
        ),
        hint="the 6-D cuff weld or the robot servos cannot follow the path (models/arm_5dof/cuff_6d.xml)",
    )
    reflex_on = reflex is not None and reflex.enabled
    chunk = CHUNK_STEPS
    if reflex_on:
        lag_s = int(round(reflex.stretch_latency_s / dt))
        lag_sp = int(round(reflex.spinal_latency_s / dt))
        chunk = max(1, lag_s)  # a chunk's commands read only stretch already stepped
        R = muscle_length_jacobian(model, scene.muscle_act, scene.arm_qpos, np.asarray(q0, float))
        q_cols, qd_cols = 1 + scene.arm_qpos, 1 + model.nq + scene.arm_dof  # full-physics layout
        q_ref = state[:, q_cols].copy()
        hist = np.zeros((n, lag_sp + chunk, 2 * R.shape[0]))
        base3 = np.ascontiguousarray(acts[plan.condition][:, None, :])
        muscle_cols = np.asarray(scene.muscle_act, dtype=np.intp)
        zero_ref = np.zeros(R.shape[0])
        muscle_ctrl = np.empty((n, n_steps, muscle_cols.size))
    with mj_rollout.Rollout(nthread=len(datas)) as runner:
        for c0 in range(0, n_steps, chunk):
            m = min(chunk, n_steps - c0)
            if reflex_on:
                chunk_ctrl = np.zeros((n, m, model.nu))
                kernel.muscle_commands(
                    chunk_ctrl,
                    muscle_cols,
                    base3,
                    1,
                    c0,
                    hist,
                    lag_s,
                    lag_sp,
                    zero_ref,
                    REFLEX_LENGTH_SCALE_M,
                    reflex.stretch_gain,
                    reflex.velocity_gain,
                    reflex.spinal_gain,
                )
                muscle_ctrl[:, c0 : c0 + m] = chunk_ctrl[:, :, muscle_cols]
            else:
                chunk_ctrl = ctrl[:, :m]
            chunk_ctrl[:, :, scene.robot_act] = paths[plan.direction, c0 : c0 + m]
            states, sd = runner.rollout([model] * n, datas, state, np.ascontiguousarray(chunk_ctrl), nstep=m)
            check_rollout(
                who,
                state,
                states,
                datas,
                dt,
                np.arange(c0 + 1, c0 + m + 1) * dt - timing.pre_s,
                warned=warning_counts(datas),
            )
            if reflex_on:
                reflex_history(hist, states, c0, q_cols, qd_cols, q_ref, R)
            out[:, c0 : c0 + m] = sd[:, :, keep]
            state = np.ascontiguousarray(states[:, -1])
    channels: dict[str, np.ndarray] = {}
    col = 0
    for name in RECORDED_SENSORS[:6]:
        width = scene.sensors[name].stop - scene.sensors[name].start
        channels[name] = out[..., col : col + width]
        col += width
    channels["true_q"] = out[..., col : col + 5]
    return StiffnessRecord(
        fs_hz=1.0 / dt,
        onset_index=onset,
        channels=channels,
        robot_q_hold=robot_q,
        commanded_dq=dirs[plan.direction],
        muscle_ctrl=muscle_ctrl if reflex_on else None,
    )
