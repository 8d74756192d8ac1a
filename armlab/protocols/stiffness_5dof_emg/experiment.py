"""The stages of seed paper 001 simulated into a :class:`~armlab.data.trial.TrialSet`.

:func:`simulate_stages` runs the stages of ``cfg.stages`` in the paper's order: the kinematic
calibration (:mod:`.calibration`) and the inertial trials (:mod:`.inertial`) in the robot-free
scene (:mod:`armlab.models.arm5_free`), stored as ``attrs['calibration']`` and
``attrs['inertial']``, and the stiffness trials (:func:`simulate_stiffness_stage`), whose channels
are the trial file's. Each stage draws from its own generator (seeded ``seed`` for the stiffness
trials, as before the other stages existed; ``[seed, 1]`` and ``[seed, 2]`` for calibration and
inertial), so adding or leaving out a stage changes no other stage's data.

The stiffness stage:

Per pre-load condition the force task's least-effort activations (:mod:`armlab.sim.arm5_force_task`)
hold the default posture while the subject pushes the displayed force; the robot then applies the
paper's quintic joint-space disturbances (:mod:`armlab.sim.arm5_trials`), and the lab's sensors
record them (:mod:`armlab.sim.arm5_measure`, ``sensors.preset``). One generator seeded with
``seed`` draws the plan first, then the sensor noise: the same seed gives the same trials.

The trial file holds every channel at the F/T rate (2 kHz). The Vicon channels are sampled at
500 Hz and stored as the logging system sees them at 2 kHz: each frame held until the next
(zero-order hold; the first frame also over the record's first samples before it), the frame
times being samples ``step - 1 + k step`` with ``step = fs_hz / marker_fs_hz`` (``attrs``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from armlab.data.trial import TrialSet
from armlab.estimation.stiffness_trials import WristSensorGeometry
from armlab.models.arm5_free import build_arm5_free_scene
from armlab.models.arm5_scene import Arm5Scene, build_arm5_scene
from armlab.models.arm5_truth import analytic_damping, analytic_stiffness, inertial_truth
from armlab.models.arm_5dof import ARM5_MUSCLES, ELECTRODE_MUSCLES, Arm5Dof, limb_kinematics, load_arm_5dof
from armlab.models.limb_kinematics import LimbKinematics
from armlab.protocols.stiffness_5dof_emg.calibration import simulate_calibration
from armlab.protocols.stiffness_5dof_emg.config import Stiffness5dofConfig, trial_timing
from armlab.protocols.stiffness_5dof_emg.inertial import simulate_inertial
from armlab.sensors.channel import ChannelSpec
from armlab.sensors.emg import ELECTRODES, TRIGNO_EMG, EmgSpec, neural_drive, synthesize_emg
from armlab.sensors.presets import Arm5SensorSuite
from armlab.sim.arm5_force_task import PRELOAD_CONDITIONS, force_task_activations
from armlab.sim.arm5_measure import MARKER_RATE_HZ, measure_stiffness_record
from armlab.sim.arm5_reflex import reflex_stiffness_fd
from armlab.sim.arm5_trials import (
    plan_stiffness_trials,
    simulate_stiffness_trials,
)

__all__ = [
    "CHANNEL_UNITS",
    "StiffnessLab",
    "build_lab",
    "emg_spec",
    "hold_markers",
    "record_emg",
    "simulate_stages",
    "simulate_stiffness_stage",
]

#: The trial file's channels and their units (docs/trial_format.md).
CHANNEL_UNITS = {
    "wrist_force": "N",
    "wrist_torque": "N·m",
    "base_force": "N",
    "base_torque": "N·m",
    "forearm_marker_pos": "m",
    "forearm_marker_quat": "1",
    "true_q": "rad",
}


@dataclass(frozen=True, kw_only=True, eq=False)
class StiffnessLab:
    """The arm, its true kinematic chain and the composed lab (built once per run)."""

    arm: Arm5Dof
    kin: LimbKinematics
    scene: Arm5Scene


def build_lab() -> StiffnessLab:
    """Load the 5-DoF arm (``models/arm_5dof``) and compose the lab with the LWR and the 6-D cuff."""
    arm = load_arm_5dof()
    return StiffnessLab(arm=arm, kin=limb_kinematics(arm), scene=build_arm5_scene())


def hold_markers(frames: np.ndarray, step: int, n_samples: int) -> np.ndarray:
    """Zero-order hold of marker frames (n_trials, n_frames, k) taken at samples
    ``step - 1 + j step`` onto every sample (n_trials, n_samples, k): sample i carries the last
    frame taken at or before it (frame 0 before the first)."""
    idx = np.maximum((np.arange(n_samples) + 1) // step - 1, 0)
    return frames[:, np.minimum(idx, frames.shape[1] - 1)]


def _suite(cfg: Stiffness5dofConfig) -> Arm5SensorSuite:
    return Arm5SensorSuite.ideal() if cfg.sensors.preset == "ideal" else Arm5SensorSuite.realistic()


def emg_spec(cfg: Stiffness5dofConfig) -> EmgSpec:
    """The electrodes of ``cfg.emg``; their own noise and converter per ``sensors.preset``."""
    e = cfg.emg
    sensor = ChannelSpec.ideal() if cfg.sensors.preset == "ideal" else TRIGNO_EMG
    return EmgSpec(band_hz=tuple(e.band_hz), gain_mV=e.gain_mV, crosstalk=e.crosstalk, sensor=sensor)


def record_emg(cfg: Stiffness5dofConfig, record, acts: np.ndarray, condition: np.ndarray) -> np.ndarray:
    """The 8 electrodes over every stiffness trial's record, (n_trials, n_samples, 8) mV.

    The drive of each electrode's muscle is the neural drive behind the command the simulation
    applied (:func:`armlab.sensors.neural_drive` with ``emg.shape_factor``; the command itself at
    the default 0): with the reflex off the condition's force-task activation, constant over the
    record (the paper's frozen activation); with it on, the commands the reflex moved, sample by
    sample. Its own generator
    (``[seed, 3]``), so the other stages' data do not change with or without it.
    """
    cols = [ARM5_MUSCLES.index(ELECTRODE_MUSCLES[e]) for e in ELECTRODES]
    n_samples = record.channels["true_q"].shape[1]
    if record.muscle_ctrl is not None:
        drive = neural_drive(record.muscle_ctrl[..., cols], cfg.emg.shape_factor)
    else:
        u = neural_drive(acts[:, cols], cfg.emg.shape_factor)
        drive = np.broadcast_to(u[condition][:, None, :], (condition.size, n_samples, len(cols)))
    return synthesize_emg(drive, record.fs_hz, emg_spec(cfg), np.random.default_rng([cfg.seed, 3]))


def simulate_stages(cfg: Stiffness5dofConfig, lab: StiffnessLab | None = None) -> TrialSet:
    """Every stage of ``cfg.stages`` (module docstring): the stiffness trials with
    ``attrs['calibration']`` / ``attrs['inertial']`` added for the earlier stages that ran."""
    lab = lab or build_lab()
    trials = simulate_stiffness_stage(cfg, lab)
    extra = {}
    if "calibration" in cfg.stages or "inertial" in cfg.stages:
        free = build_arm5_free_scene()
        suite = _suite(cfg)
        if "calibration" in cfg.stages:
            rng = np.random.default_rng([cfg.seed, 1])
            extra["calibration"] = simulate_calibration(cfg.calibration, lab.arm, free, suite, rng)
        if "inertial" in cfg.stages:
            rng = np.random.default_rng([cfg.seed, 2])
            extra["inertial"] = simulate_inertial(cfg.inertial, lab.arm, free, suite, rng)
    return replace(trials, attrs={**trials.attrs, **extra}) if extra else trials


def simulate_stiffness_stage(cfg: Stiffness5dofConfig, lab: StiffnessLab | None = None) -> TrialSet:
    """The stiffness trials of every condition in ``cfg.trials.conditions``, measured.

    Returns:
        The trials: channels of :data:`CHANNEL_UNITS` (n_trials, n_samples, k) at 2 kHz;
        ``trial_meta`` ``condition`` (index into ``attrs['condition_names']``), ``direction``
        (0..9: +amplitude on joint d, -amplitude on joint d - 5), ``wait_s`` s; ``attrs`` with the
        working point, the conditions, the lab's geometry and the ground truth (docs/trial_format.md).
    """
    lab = lab or build_lab()
    arm, kin, scene = lab.arm, lab.kin, lab.scene
    tc = cfg.trials
    names = list(tc.conditions)
    forces = np.array([PRELOAD_CONDITIONS[n] for n in names], dtype=float)
    acts = np.array([force_task_activations(arm, arm.q0, f, tc.a_min).activation for f in forces])
    rng = np.random.default_rng(cfg.seed)
    plan = plan_stiffness_trials(len(names), tc.n_per_condition, rng, tuple(tc.wait_s))
    timing = trial_timing(cfg)
    record = simulate_stiffness_trials(
        scene, kin, arm.q0, acts, plan, timing, tc.amplitude_rad, settle_s=cfg.sim.settle_s, reflex=cfg.reflex
    )
    suite = _suite(cfg)
    meas = measure_stiffness_record(record, suite, rng, t0_s=plan.wait_s)
    n_samples = record.channels["true_q"].shape[1]
    step = int(round(record.fs_hz / MARKER_RATE_HZ))
    channels = {k: meas.ft[k] for k in ("wrist_force", "wrist_torque", "base_force", "base_torque")}
    channels["forearm_marker_pos"] = hold_markers(meas.marker_pos, step, n_samples)
    channels["forearm_marker_quat"] = hold_markers(meas.marker_quat, step, n_samples)
    channels["true_q"] = record.channels["true_q"]
    units = dict(CHANNEL_UNITS)
    if "emg" in cfg.stages:
        channels["emg"] = record_emg(cfg, record, acts, plan.condition)
        units["emg"] = "mV"
    geo = WristSensorGeometry.from_scene(scene)
    K_int = analytic_stiffness(arm, acts)
    K_reflex = np.array(
        [
            reflex_stiffness_fd(
                arm.model,
                arm.muscle_act,
                arm.muscle_actadr,
                arm.qpos,
                arm.dof,
                arm.q0,
                a,
                cfg.reflex,
                tc.amplitude_rad,
            )
            for a in acts
        ]
    )
    r_off, p_off = scene.marker_to_wrist
    attrs = {
        "protocol": cfg.protocol_name,
        "seed": int(cfg.seed),
        "stages": list(cfg.stages),
        "sensor_preset": cfg.sensors.preset,
        "reflex_enabled": bool(cfg.reflex.enabled),
        "marker_fs_hz": MARKER_RATE_HZ,
        "q0_rad": np.asarray(arm.q0, float),
        "amplitude_rad": float(tc.amplitude_rad),
        "rise_s": float(tc.rise_s),
        "condition_names": names,
        "condition_forces_N": forces,
        "robot_q_hold_rad": record.robot_q_hold,
        "marker_to_wrist_rot": np.asarray(r_off, float),
        "marker_to_wrist_m": np.asarray(p_off, float),
        "wrist_ft_pos_m": np.asarray(geo.ft_pos, float),
        "wrist_ft_rot": np.asarray(geo.ft_rot, float),
        "wrist_tool_mass_kg": geo.tool_mass,
        "wrist_tool_com_m": np.asarray(geo.tool_com, float),
        "gravity_ms2": np.asarray(geo.gravity, float),
        **(
            {
                "emg_electrodes": list(ELECTRODES),
                "emg_crosstalk": float(cfg.emg.crosstalk),
                "emg_shape_factor": float(cfg.emg.shape_factor),
            }
            if "emg" in cfg.stages
            else {}
        ),
        "ground_truth": {
            "activation": acts,
            # linear muscles with constant moment arms: K_q = sum a_i k_i r_i r_i^T + K_passive,
            # exact and posture independent (armlab.models.arm5_truth)
            "K_intrinsic_Nm_per_rad": K_int,
            # the static reflex's secant stiffness over the amplitude (zero when off) and intrinsic
            # + reflex: the truth a static estimate measures with the reflex on (armlab.sim.arm5_reflex)
            "K_reflex_Nm_per_rad": K_reflex,
            "K_effective_Nm_per_rad": K_int + K_reflex,
            "D_intrinsic_Nms_per_rad": analytic_damping(arm, acts),
            # the true identifiable combinations (Eq. (22)); the stiffness stage uses them when the
            # inertial stage did not run
            "xi_red": inertial_truth(arm).xi_red,
        },
    }
    return TrialSet(
        fs_hz=record.fs_hz,
        onset_index=np.full(plan.n_trials, record.onset_index),
        channels=channels,
        units=units,
        trial_meta={
            "condition": plan.condition.astype(np.int64),
            "direction": plan.direction.astype(np.int64),
            "wait_s": plan.wait_s,
        },
        attrs=attrs,
    )
