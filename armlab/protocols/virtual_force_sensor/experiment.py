"""The virtual-force-sensor protocol (seeds/003): simulate the lab, then identify by both methods.

Stages, each a batch of 50 s trials at 1 kHz under joint PD control (Sec. II-C, Appendix):

1. ``robot_id``: the bare robot tracks ten sines over 40 deg per joint around the home pose; the
   least squares of the Appendix gives the alphas of Table VI (from the first 40 s; VAF on the
   last 10 s).
2. ``fixture``: the Table I mass-spring configurations (stiffness field x payload), ten sines over
   10 deg around the robot pose that puts the end effector at X0.
3. ``arm``: the relaxed planar arm holding the handle 50 cm anterior to the shoulder.

:func:`simulate_vfs` returns the measured trials (one :class:`~armlab.data.trial.TrialSet`, the
stage in ``trial_meta["kind"]``) and the ground truth; :func:`estimate_vfs` turns the trials into
the results of Tables III-VI (:mod:`armlab.protocols.virtual_force_sensor.results`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from armlab import progress
from armlab.data.trial import TrialSet
from armlab.models.arm_endpoint import endpoint_truth, relaxed_activation
from armlab.models.capstan_robot import TABLE_VI_ALPHA
from armlab.models.capstan_scene import CapstanScene, build_capstan_scene
from armlab.models.spring_array import TABLE_I_PAYLOADS_KG, TABLE_I_STIFFNESS, table_i_array
from armlab.perturbations.sum_of_sines import sum_of_sines
from armlab.protocols.virtual_force_sensor.config import VirtualForceSensorConfig
from armlab.protocols.virtual_force_sensor.preflight import check_cable
from armlab.sensors.presets import CapstanSensorSuite, measure
from armlab.sim.capstan_lab import CAPSTAN_HINT, CLEAN_UNITS, simulate_capstan
from armlab.sim.stability import TrialLabels
from armlab.sim.subject import activation_commands

__all__ = [
    "HOME_THETA_RAD",
    "MEASURED",
    "VfsRecording",
    "simulate_vfs",
]

HOME_THETA_RAD = (np.pi / 4, np.pi / 4)  # rad, the symmetric pose (end effector at (0.495, 0) m)
MEASURED = ("theta", "tau", "acc_site", "ft_site")  # what the lab records (Table II)
_SAVED_TRUTH = ("true_x", "true_theta", "reference")  # kept beside them for scoring and plots


@dataclass(frozen=True, eq=False)
class VfsRecording:
    """Everything :func:`simulate_vfs` produced.

    Attributes:
        trials: measured channels of every trial (``theta``, ``tau``, ``acc_site``, ``ft_site``)
            and the truth ``true_x``, ``true_theta``, ``reference``; ``trial_meta`` holds
            ``kind`` (robot_id | fixture | arm), ``stiffness`` and ``payload`` (Table I labels or
            ""), ``trial`` (index within its configuration).
        truth: the ground truth (``robot``: the alphas the MJCF realises; ``fixture``: Table I
            per label; ``arm``: the endpoint M, B, K of :mod:`armlab.models.arm_endpoint`).
        scenes: the MJCF of one scene per stage (``robot_id``, ``fixture`` (the first
            configuration), ``arm``).
    """

    trials: TrialSet
    truth: dict
    scenes: dict[str, str]


def _suite(cfg: VirtualForceSensorConfig) -> CapstanSensorSuite:
    return CapstanSensorSuite.ideal() if cfg.sensors.preset == "ideal" else CapstanSensorSuite.realistic()


def _stage(
    cfg: VirtualForceSensorConfig,
    scene: CapstanScene,
    theta0: np.ndarray,
    n_trials: int,
    range_deg: float,
    rng: np.random.Generator,
    band_hz: tuple[float, float],
    arm_q: np.ndarray | None = None,
    activation: np.ndarray | None = None,
    subject_rng: np.random.Generator | None = None,
    stage: str = "",
) -> dict[str, np.ndarray]:
    v, c = cfg.vfs, cfg.capstan
    refs = [
        sum_of_sines(
            rng, n_sines=v.n_sines, band_hz=band_hz, range_rad=np.deg2rad(range_deg), fade_s=v.settle_s
        )
        for _ in range(n_trials)
    ]
    state = scene.initial_state(theta0, arm_q, 0.0 if activation is None else activation)
    muscle_ctrl = activation
    if activation is not None and subject_rng is not None and cfg.subject.active:
        # the subject's fluctuating activation, per trial and physics step (settle steps included)
        sub = round(1.0 / (cfg.sensors.fs_hz * cfg.sim.timestep_s))
        n_steps = (round(v.settle_s * cfg.sensors.fs_hz) + round(v.trial_s * cfg.sensors.fs_hz)) * sub
        muscle_ctrl = activation_commands(
            activation, cfg.subject, n_trials, n_steps, sub, cfg.sensors.fs_hz, subject_rng
        )
    with progress.scope(stage):  # its simulation reported as "<stage>: simulate"
        clean = simulate_capstan(
            scene,
            state,
            theta0,
            refs,
            kp=c.kp_Nm_per_rad,
            kd=c.kd_Nms_per_rad,
            fs_hz=cfg.sensors.fs_hz,
            duration_s=v.trial_s,
            settle_s=v.settle_s,
            muscle_ctrl=muscle_ctrl,
            who=TrialLabels(
                protocol=cfg.protocol_name,
                labels=tuple(f"{stage}, repetition {k + 1} of {n_trials}" for k in range(n_trials)),
                hint=CAPSTAN_HINT,
            ),
        )
    measured = measure({k: clean[k] for k in MEASURED}, _suite(cfg), cfg.sensors.fs_hz, rng)
    return {**measured, **{k: clean[k] for k in _SAVED_TRUTH}}


def _scene(cfg: VirtualForceSensorConfig, load: str, **kw) -> CapstanScene:
    return build_capstan_scene(
        cfg.capstan, load, timestep_s=cfg.sim.timestep_s, integrator=cfg.sim.integrator, **kw
    )


def simulate_vfs(cfg: VirtualForceSensorConfig) -> VfsRecording:
    """Simulate every stage of the protocol (module docstring) with the config's sensors and seed."""
    check_cable(cfg)  # also refused up front (preflight.validate); here for Python callers
    v = cfg.vfs
    rng = np.random.default_rng(cfg.seed)
    # the subject's fluctuation draws from a spawned child: spawning leaves ``rng``'s own stream
    # as it was, so a steady subject (subject.enabled=false) draws exactly the data it always did
    subject_rng = rng.spawn(1)[0]
    batches: list[dict[str, np.ndarray]] = []
    meta: dict[str, list] = {"kind": [], "stiffness": [], "payload": [], "trial": []}
    scenes: dict[str, str] = {}
    truth: dict = {"robot": {"alpha": list(TABLE_VI_ALPHA.alpha)}, "fixture": {}, "arm": None}

    def add(kind: str, batch: dict, k_label: str = "", m_label: str = "") -> None:
        n = len(batch["theta"])
        batches.append(batch)
        meta["kind"] += [kind] * n
        meta["stiffness"] += [k_label] * n
        meta["payload"] += [m_label] * n
        meta["trial"] += list(range(n))

    if v.robot_id_trials:
        robot_cfg = cfg.capstan if v.id_drag else replace(cfg.capstan, drag=False)
        scene = build_capstan_scene(
            robot_cfg, "none", timestep_s=cfg.sim.timestep_s, integrator=cfg.sim.integrator
        )
        scenes["robot_id"] = scene.xml
        add(
            "robot_id",
            _stage(
                cfg,
                scene,
                np.array(HOME_THETA_RAD),
                v.robot_id_trials,
                v.id_range_deg,
                rng,
                v.id_band_hz,
                stage="robot identification",
            ),
        )
    if v.trials_per_config:
        truth["fixture"].update({m: {"m": TABLE_I_PAYLOADS_KG[m]} for m in v.payloads})
        for k_label in v.stiffness:
            field = TABLE_I_STIFFNESS[k_label]
            array = table_i_array(k_label)
            truth["fixture"][k_label] = {
                "k_xx": field.k_xx,
                "k_yy": field.k_yy,
                "k_s": field.k_s,
                "x0": [field.x0, field.y0],
            }
            for m_label in v.payloads:
                scene = _scene(cfg, "fixture", array=array, payload_kg=TABLE_I_PAYLOADS_KG[m_label])
                scenes.setdefault("fixture", scene.xml)
                theta0 = scene.dynamics.ik(np.array([field.x0, field.y0]))
                add(
                    "fixture",
                    _stage(
                        cfg,
                        scene,
                        theta0,
                        v.trials_per_config,
                        v.range_deg,
                        rng,
                        v.band_hz,
                        stage=f"fixture {k_label} with payload {m_label}",
                    ),
                    k_label,
                    m_label,
                )
    if v.arm_trials:
        scene = _scene(cfg, "arm", arm=cfg.arm, handle_xy=v.arm_handle_m, reach_m=v.arm_reach_m)
        scenes["arm"] = scene.xml
        handle = np.asarray(v.arm_handle_m, float)
        theta0, arm_q = scene.dynamics.ik(handle), scene.arm_posture(handle)
        act = relaxed_activation(scene, scene.initial_state(theta0, arm_q), cfg.arm.cocontraction)
        truth["arm"] = endpoint_truth(scene, scene.initial_state(theta0, arm_q, act)).as_dict()
        add(
            "arm",
            _stage(
                cfg,
                scene,
                theta0,
                v.arm_trials,
                v.range_deg,
                rng,
                v.band_hz,
                arm_q,
                act,
                subject_rng,
                stage="relaxed arm",
            ),
        )
    channels = {k: np.concatenate([b[k] for b in batches]) for k in batches[0]}
    n_total = len(channels["theta"])
    trials = TrialSet(
        fs_hz=cfg.sensors.fs_hz,
        onset_index=np.ones(n_total, int),  # the reference runs from the first sample (faded in before)
        channels=channels,
        units={k: CLEAN_UNITS[k] for k in channels},
        trial_meta={k: np.asarray(val) for k, val in meta.items()},
        attrs={"protocol": "virtual_force_sensor", "seed": cfg.seed},
    )
    return VfsRecording(trials=trials, truth=truth, scenes=scenes)
