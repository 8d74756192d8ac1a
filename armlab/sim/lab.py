"""The simulated laboratory: a trial plan in, recorded trials (and the model's truth) out.

config -> scene -> settled hold -> robot joint targets for every trial -> batched rollout ->
sensor models -> the measurement processing a real lab does on its robot (hand position from the
encoders by forward kinematics, the F/T reading rotated into the shoulder frame) -> channel arrays
(:class:`LabRecording`; the protocol assembles them into a TrialSet).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from armlab.config.effects import EffectsConfig, enabled_effects
from armlab.config.schema import ExperimentConfig
from armlab.config.subject import SubjectConfig
from armlab.dsp import by_row_halves
from armlab.errors import ConfigError
from armlab.models.ground_truth import GroundTruth, ground_truth
from armlab.models.robot_fk import RobotKinematics
from armlab.models.scene import MUSCLES, ROBOT_POINTS, Scene, build_scene
from armlab.perturbations.quintic import quintic_profile
from armlab.perturbations.scenario import Scenario, TrialPlan
from armlab.perturbations.segments import SegmentWaveform
from armlab.sensors.channel import ChannelSpec, apply_channel
from armlab.sensors.presets import SensorSuite, measure
from armlab.sim import _chunk_kernel
from armlab.sim.hold import HoldState, hand_world, settle
from armlab.sim.robot_ik import solve_ik
from armlab.sim.rollout import Kept, simulate
from armlab.sim.stability import TrialLabels, check_bound
from armlab.sim.subject import fluctuation, sample_commands

__all__ = [
    "CUFF_FORCE_BOUND_N",
    "LAB_EFFECTS",
    "LabRecording",
    "PATH_POINTS",
    "load_compiled",
    "record_trials",
    "robot_target_paths",
    "settled_scene",
]

PATH_POINTS = 41  # IK points along each direction's hand path (spline-interpolated in between)
#: Catalogue effects (``effects=[...]``) this laboratory applies; the reflex and the cuff
#: compliance are part of the lab, switched by its own ``reflex.enabled`` and ``cuff.rigid``.
LAB_EFFECTS = ("joint_friction", "force_sensor_bandwidth", "channel_delay", "force_sensor_noise")
# N, largest cuff force (clean F/T reading) of a valid trial. No human-arm perturbation applies
# it: the paper's perturbations move the hand a few cm against a 5 N pre-load, the LWR's joint
# torque limits (176 N m at joints 1-2 over its ~0.5 m reach) cap its flange force near 350 N, and
# 1 kN on a forearm cuff would injure. The default runs peak at about 48 N (20x margin); a cuff
# spring the step cannot integrate reaches kN at once (1e7 N/m undamped: 25 kN).
CUFF_FORCE_BOUND_N = 1000.0
_UNSTABLE_HINT = (
    "lower cuff.stiffness_N_per_m or sim.timestep_s, or raise cuff.damping_Ns_per_m "
    "(docs/reliability.md, Instability)"
)


def _apply_model_effects(scene: Scene, effects: EffectsConfig) -> None:
    """Coulomb friction (MuJoCo ``frictionloss``, N·m) at the shoulder and elbow."""
    if effects.joint_friction is not None:
        scene.model.dof_frictionloss[scene.arm_dof] = effects.joint_friction.coulomb_Nm


def settled_scene(cfg: ExperimentConfig) -> tuple[Scene, HoldState, GroundTruth]:
    """The lab's scene as :func:`record_trials` simulates it: composed from ``cfg``, its model
    effects applied (joint friction), settled at q0 (the robot's hold), and its ground truth
    (:func:`armlab.models.ground_truth.ground_truth`, with the cuff when it is compliant)."""
    scene = build_scene(cfg.arm, cfg.cuff, cfg.robot, cfg.sim)
    _apply_model_effects(scene, cfg.effects)
    hold = settle(scene, cfg.arm, cfg.sim.settle_s, protocol=cfg.protocol_name)
    return scene, hold, ground_truth(scene, hold.state, cfg.cuff.rigid)


def _force_effects(z: np.ndarray, effects: EffectsConfig, fs: float) -> np.ndarray:
    """(n_trials, n, k) clean F/T channel through the sensor-level effects, by the sensor model.

    ``force_sensor_bandwidth``: causal 2nd-order Butterworth (steady state at the first sample);
    ``channel_delay``: the force channel lags by round(delay·fs) whole samples (a negative delay
    is refused by :class:`ChannelSpec`). Deterministic: the spec has no bias, drift or noise.
    """
    bw, delay = effects.force_sensor_bandwidth, effects.channel_delay
    if bw is None and delay is None:
        return z
    spec = ChannelSpec(
        bandwidth_hz=None if bw is None else bw.cutoff_hz,
        delay_s=0.0 if delay is None else delay.delay_s,
    )
    # no random draw reaches the output (bias, drift and noise are zero): any generator will do
    return apply_channel(z, fs, spec, np.random.default_rng(0))


def _forward_by_halves(fk: RobotKinematics, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``fk.forward(q)`` of (n_trials, n_samples, 7) encoder angles, the two halves of the trials
    on two threads (:func:`~armlab.dsp.by_row_halves`; the compiled kernel runs without the GIL).
    Every sample's chain is computed alone, so the result is bit-identical to one call."""
    contact, rot = np.empty(q.shape[:-1] + (3,)), np.empty(q.shape[:-1] + (3, 3))

    def part(rows: slice) -> None:
        contact[rows], rot[rows] = fk.forward(q[rows])

    by_row_halves(part, q.shape[0])
    return contact, rot


@dataclass(frozen=True, kw_only=True, eq=False)
class LabRecording:
    """What a simulated session produced, as arrays.

    Attributes:
        fs_hz: Hz, sample rate of every channel.
        onset_index: (n_trials,) sample index of each trial's perturbation onset.
        channels: name -> (n_trials, n_samples, n_axes), the measured channels (``hand_pos``,
            ``hand_force``, ``robot_q``, ``robot_tau``, ``ft_force``, ``ft_torque``) and the
            noiseless ``true_*`` ones; names and axes as in :mod:`armlab.data.trial`.
        units: name -> unit of each channel.
        truth: ground truth at the operating point.
        scene: the compiled scene (its MJCF is saved with the run).
        hold: the settled pre-perturbation state.
    """

    fs_hz: float
    onset_index: np.ndarray
    channels: dict[str, np.ndarray]
    units: dict[str, str]
    truth: GroundTruth
    scene: Scene
    hold: HoldState


_ARM_POINTS = tuple(f"p_{s}" for s in ("shoulder_site", "elbow_site", "hand"))
_ROBOT_POINTS = tuple(f"p_{b}" for b in ROBOT_POINTS) + ("p_flange",)
_ENCODERS = tuple(f"lwr_q{i}" for i in range(1, 8))
_TORQUES = tuple(f"lwr_tau{i}" for i in range(1, 8))


def _kept(scene: Scene) -> Kept:
    """What the lab reads of every sample: the sensors its channels come from (not the muscle
    lengths and velocities, which only the reflex reads, nor the commands) and the arm's angles."""
    return Kept(
        sensors=(*_ARM_POINTS, *_ROBOT_POINTS, *_ENCODERS, *_TORQUES, "ft_force", "ft_torque"),
        qpos=tuple(int(a) for a in scene.arm_qpos),
        muscle_ctrl=False,
    )


def load_compiled() -> None:
    """Load the compiled loops this laboratory runs from numba's cache (compiling them on a first
    use): the stepping's chunk kernels (:mod:`armlab.sim._chunk_kernel`) and the readings'
    kinematics (:mod:`armlab.models._fk_kernel`), about 0.35 CPU-s in a new process. A protocol
    declares it as its ``preload`` (the runner calls it where a core is idle); otherwise
    :func:`record_trials` loads it beside the first chunks."""
    _chunk_kernel.load()
    RobotKinematics.load_compiled()


def robot_target_paths(
    scene: Scene,
    hold: HoldState,
    q0: np.ndarray,
    plan: TrialPlan,
    directions: np.ndarray,
    t_rel: np.ndarray,
    waveform: SegmentWaveform | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Robot joint targets at every physics step, once per (direction, T_k) pair of the plan.

    The hand path of each direction, x(s) = f(q0 + s dq_f) for s in [0, 1], is solved by IK once
    on :data:`PATH_POINTS` points and spline-interpolated in s; each pair then evaluates it at
    s(t) = quintic((t - t_onset) / T_k) (eq. 16), so durations share the path. Trials of the same
    direction and T_k have the same targets: ``paths[pair_of[i]]`` are trial i's (what
    ``simulate(..., target_rows=pair_of)`` reads, without a per-trial copy).

    Args:
        t_rel: (n_steps,) s, time of each physics step relative to the onset.
        waveform: a designed multi-segment s(t) (its range may leave [0, 1]: the path is solved
            over that range); None: the paper's quintic.

    Returns:
        ``paths`` (n_pairs, n_steps, 7) rad and ``pair_of`` (n_trials,) the pair of each trial.
    """
    s_grid = np.linspace(*((0.0, 1.0) if waveform is None else waveform.s_range), PATH_POINTS)
    splines = []
    for dq_f in directions:
        path = hand_world(scene, q0 + s_grid[:, None] * dq_f)
        splines.append(CubicSpline(s_grid, solve_ik(scene, path, hold.robot_target), axis=0))
    pairs, which = np.unique(
        np.stack([np.asarray(plan.direction, float), np.asarray(plan.t_k_s, float)], axis=1),
        axis=0,
        return_inverse=True,
    )
    table = np.empty((len(pairs), t_rel.size, 7))
    for j, (direction, t_k) in enumerate(pairs):
        profile = quintic_profile if waveform is None else waveform.evaluate
        s, _, _ = profile(t_rel, float(t_k))
        table[j] = splines[int(direction)](s)
    return table, np.asarray(which).reshape(-1)


def record_trials(
    cfg: ExperimentConfig,
    scenario: Scenario,
    plan: TrialPlan,
    rng: np.random.Generator,
    subject: SubjectConfig | None = None,
    subject_rng: np.random.Generator | None = None,
) -> LabRecording:
    """Simulate and record every trial of ``plan``.

    Args:
        cfg: the experiment configuration.
        scenario: the perturbation timeline (record length, pre-onset hold).
        plan: the concrete trials.
        rng: generator for the sensor noise (the plan was drawn before).
        subject: the subject's activation fluctuation; None or inactive: an ideal subject.
        subject_rng: generator of that fluctuation (needed when ``subject`` is active).
    """
    other = [n for n in enabled_effects(cfg.effects) if n not in LAB_EFFECTS]
    if other:
        raise ConfigError(
            f"effects {other} are not simulated by the {cfg.protocol_name} laboratory; it applies "
            f"{list(LAB_EFFECTS)} (reflex and cuff compliance are its reflex.* and cuff.* settings)"
        )
    fs = cfg.sensors.fs_hz
    n_samples = int(round(scenario.record_s * fs))
    active = subject is not None and subject.active
    # The subject's fluctuation needs no scene: it is drawn on a second thread while the scene is
    # built and settled and the robot paths are solved (its own generator: the same numbers).
    if active and subject_rng is None:
        raise ConfigError("an active subject fluctuation needs its own generator (subject_rng)")
    with ThreadPoolExecutor(max_workers=1) as early:
        drawing = (
            early.submit(fluctuation, subject, plan.n_trials, n_samples, len(MUSCLES), fs, subject_rng)
            if active
            else None
        )
        scene, hold, truth = settled_scene(cfg)

        dt = scene.model.opt.timestep
        substeps = int(round(1.0 / (fs * dt)))
        if substeps < 1 or abs(substeps * fs * dt - 1.0) > 1e-9:
            raise ConfigError(
                f"sensors.fs_hz={fs} must divide the physics rate 1/sim.timestep_s={1 / dt:g} Hz "
                "into whole steps"
            )
        onset = int(round(scenario.pre_onset_record_s * fs))
        n_steps = n_samples * substeps
        # sample j is the state after physics step (j + 1) * substeps - 1, i.e. at (j + 1) / fs on the
        # step clock; the perturbation starts at sample `onset`, so at (onset + 1) / fs
        t_rel = (np.arange(n_steps) + 1) * dt - (onset + 1) / fs
        q0 = np.asarray(cfg.arm.q0, float)
        paths, path_of = robot_target_paths(
            scene, hold, q0, plan, scenario.directions_rad, t_rel, scenario.waveform
        )
        muscle_base = hold.activation
        if active:  # one command per sample, held over its substeps by the rollout
            muscle_base = sample_commands(hold.activation, drawing.result(), overwrite=True)
    who = TrialLabels(
        protocol=cfg.protocol_name,
        labels=tuple(
            f"T_k {1e3 * plan.t_k_s[i]:.0f} ms, direction {plan.direction[i]}, onset at "
            f"{(onset + 1) / fs:.3f} s"
            for i in range(plan.n_trials)
        ),
        hint=_UNSTABLE_HINT,
    )
    kinematics = RobotKinematics.from_scene(scene)
    # the compiled loops (numba's cached machine code) load beside the first chunks, if no preload
    # (Protocol.preload) has loaded them already
    with ThreadPoolExecutor(max_workers=1) as loader:
        loaded = loader.submit(load_compiled)
        sim = simulate(
            scene,
            hold.state,
            paths,
            muscle_base,
            cfg.reflex,
            substeps=substeps,
            who=who,
            target_rows=path_of,
            kept=_kept(scene),
        )
        loaded.result()

    sd, readout = sim.sensordata, sim.readout
    check_bound(
        who,
        readout.sensor(sd, "ft_force"),
        (np.arange(n_samples) + 1) / fs,
        CUFF_FORCE_BOUND_N,
        "cuff force",
        "N",
        "no arm perturbation applies it; valid runs stay below 50 N",
    )

    # the noiseless channels and the sensors' inputs: views of the kept sensor data where the
    # sensors lie side by side in it (KeptSensors.sensors_of), no copies
    true = {
        "true_arm_q": sim.qpos,
        "true_hand_pos": (readout.sensor(sd, "p_hand") - scene.shoulder_pos)[..., :2],
        "true_activation": sim.activation,
        "true_arm_points": readout.sensors_of(sd, _ARM_POINTS),
        "true_robot_points": readout.sensors_of(sd, _ROBOT_POINTS),
    }
    clean = {
        "robot_q": readout.sensors_of(sd, _ENCODERS),
        "robot_tau": readout.sensors_of(sd, _TORQUES),
        "ft_force": _force_effects(readout.sensor(sd, "ft_force"), cfg.effects, fs),
        "ft_torque": _force_effects(readout.sensor(sd, "ft_torque"), cfg.effects, fs),
    }
    suite = SensorSuite.realistic() if cfg.sensors.preset == "realistic" else SensorSuite.ideal()
    # drift accumulates from taring, before the random wait
    measured = measure(clean, suite, fs, rng, t0_s=plan.wait_s)
    if cfg.effects.force_sensor_noise is not None:  # extra white noise, N, after the sensor suite
        measured["ft_force"] = measured["ft_force"] + rng.normal(
            0.0, cfg.effects.force_sensor_noise.std, measured["ft_force"].shape
        )
    contact, ft_rot = _forward_by_halves(kinematics, measured["robot_q"])
    hand_pos = (contact - scene.shoulder_pos)[..., :2]
    hand_force = np.einsum("...ij,...j->...i", ft_rot, measured["ft_force"])[..., :2]
    channels = {"hand_pos": hand_pos, "hand_force": hand_force, **measured, **true}
    units = {
        "hand_pos": "m",
        "hand_force": "N",
        "robot_q": "rad",
        "robot_tau": "N*m",
        "ft_force": "N",
        "ft_torque": "N*m",
        "true_arm_q": "rad",
        "true_hand_pos": "m",
        "true_activation": "1",
        "true_arm_points": "m",
        "true_robot_points": "m",
    }
    return LabRecording(
        fs_hz=fs,
        onset_index=np.full(plan.n_trials, onset),
        channels=channels,
        units=units,
        truth=truth,
        scene=scene,
        hold=hold,
    )
