"""Level B of ``cartesian_online``: the thesis's perturbations played by the LWR on a hand with inertia.

:func:`simulate_level_b_trials` takes the level-A trials of the same config (the same paths,
stops and commanded perturbations: level A on the same paths costs ~0.5 s) and replaces their
channels by what the lab would measure when MuJoCo's LWR plays each commanded perturbation on the
0.966 kg hand held by the Table 3.1 field (:mod:`armlab.sim.cartesian_level_b`):

- ``hand_pos`` m: the robot's encoders (:data:`~armlab.sensors.presets.LWR_ENCODER`: 0.01°
  steps) through the robot's forward kinematics to the (rigid) cuff; ``hand_vel`` m/s: their
  central difference (the thesis's q̇_h is not measured by any sensor);
- ``hand_force`` N: the JR3 F/T sensor (:data:`~armlab.sensors.presets.JR3_FORCE`: noise,
  offset, drift, 125 Hz filter, 1 ms delay, 0.0122 N steps) saturating at its rated ±200 N
  (:data:`JR3_RANGE_N`), turned into the thesis's frame by the encoders' flange orientation, plus
  the case's extra white noise of level A (``simulation.force_noise_std_N``; the noise study's
  ``noise_study_std_N`` on ``exp4_noise``);
- ``pert_pos`` m: measured hand position minus the stopped reference;
- the clean channels beside them: ``true_hand_pos``, ``true_hand_vel``, ``true_hand_force``
  (the F/T sensor's clean reading: the robot's force on the hand, inertia included),
  ``human_force`` (the field's force on the hand) and ``true_stiffness`` at the true hand position.

:func:`clean_trials` swaps the clean channels in (ideal sensors, hand inertia only);
:func:`executed_path_trials` is level A's generator on the path level B executed (the field's
force at level B's states: no inertia, ideal sensors, but the excursions the servos really made,
shortened by their compliance); :func:`inertia_compensated_trials` takes the inertial force of the
mass beyond the F/T sensor out of the clean force with the handle's accelerometer
(``true_hand_acc``). The identification can so be run on level A, level A on the executed path,
level B with ideal sensors and level B as measured, which splits level B's difference from level A
into the executed path, the hand's inertia and the sensors.
"""

from __future__ import annotations

import numpy as np

from armlab.data.trial import TrialSet
from armlab.models.cartesian_field import QuadraticImpedanceField
from armlab.models.cartesian_hand_scene import build_hand_scene
from armlab.models.robot_fk import RobotKinematics
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig
from armlab.sensors.presets import SensorSuite, measure
from armlab.sim.cartesian_level_b import simulate_level_b

__all__ = [
    "JR3_RANGE_N",
    "LEVEL_B_UNITS",
    "clean_trials",
    "executed_path_trials",
    "inertia_compensated_trials",
    "measured_cuff",
    "simulate_level_b_trials",
]

#: N, rated range of the JR3 F/T sensor per force axis: its 16384-count full scale is 200 N
#: (armlab.sensors.presets, JR3 85M35A class); readings beyond it saturate (clipped, per axis)
JR3_RANGE_N = 200.0
LEVEL_B_UNITS = {
    "true_hand_pos": "m",
    "true_hand_vel": "m/s",
    "true_hand_acc": "m/s^2",
    "human_force": "N",
}


def _world_xy(rot: np.ndarray, f_site: np.ndarray) -> np.ndarray:
    """(..., 2) N: a site-frame force (..., 3) in the world's (= the thesis's) x, y."""
    return np.einsum("...ij,...j->...i", rot, f_site)[..., :2]


def measured_cuff(
    kin: RobotKinematics, robot_q: np.ndarray, ft_force: np.ndarray, fs_hz: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What the lab's sensors record of a level-B simulation: the LWR's encoders (0.01° steps)
    through the robot's kinematics to the cuff, and the JR3 (noise, per-trial offset, drift,
    125 Hz filter, 1 ms delay, 0.0122 N steps) saturating at :data:`JR3_RANGE_N`, turned into the
    thesis's frame by the encoders' flange orientation (the realistic suite of the conditioning
    lab, :meth:`SensorSuite.realistic`).

    Args:
        kin: the scene's robot kinematics; robot_q: (m, n, 7) rad and ft_force: (m, n, 3) N, the
            simulated joint angles and F/T site force; rng: the sensors' only randomness.

    Returns:
        ``(hand_pos (m, n, 2) m, hand_force (m, n, 2) N, f_site (m, n, 3) N)``: the measured cuff
        position and force in the thesis's x, y, and the F/T site reading after saturation.
    """
    measured = measure({"robot_q": robot_q, "ft_force": ft_force}, SensorSuite.realistic(), fs_hz, rng)
    pos_meas, rot_meas = kin.forward(measured["robot_q"])
    f_site = np.clip(measured["ft_force"], -JR3_RANGE_N, JR3_RANGE_N)
    return pos_meas[..., :2], _world_xy(rot_meas, f_site), f_site


def simulate_level_b_trials(
    cfg: CartesianOnlineConfig, trials_a: TrialSet, field: QuadraticImpedanceField
) -> tuple[TrialSet, str, dict]:
    """The level-B trials of ``cfg`` on the paths of its level-A trials (module docstring).

    Randomness: ``default_rng(cfg.seed)`` spawns the sensors' generators after level A's (an
    extra spawn key), so the same seed gives bit-identical trials.

    Returns:
        ``(trials, scene_xml, summary)``: the trials (level A's meta and attrs, ``level`` B),
        the composed MJCF, and per case the peak inertial force (N: the clean F/T reading minus the
        field's force, i.e. what the thesis's massless model misses), the peak |F| and the share
        of force samples at the JR3's range.
    """
    scene = build_hand_scene(cfg.sim, cfg.simulation.hand_mass_kg)
    meta = trials_a.trial_meta
    ref = np.asarray(trials_a.channels["ref_pos"])[:, 0]  # (n, 2) m, stopped during the trial
    stops, stop_of = np.unique(ref, axis=0, return_inverse=True)
    sim = simulate_level_b(
        scene,
        field,
        stops,
        stop_of.ravel(),
        np.asarray(trials_a.channels["pert_pos"]),
        fs_hz=trials_a.fs_hz,
        sigma=float(cfg.simulation.sigma),
    )
    fs = trials_a.fs_hz
    rng_sensors, rng_white = np.random.default_rng([cfg.seed, 2]).spawn(2)
    kin = RobotKinematics.from_scene(scene)
    pos_true, rot_true = kin.forward(sim.robot_q)
    hand_pos, force_meas, f_site = measured_cuff(kin, sim.robot_q, sim.ft_force, fs, rng_sensors)
    force_true = _world_xy(rot_true, sim.ft_force)
    extra = np.asarray(meta["noise_std_N"], float)[:, None, None]  # level A's white noise per case
    force = force_meas + extra * rng_white.standard_normal(force_true.shape)
    channels = dict(trials_a.channels)
    channels.update(
        hand_pos=hand_pos,
        hand_vel=np.gradient(hand_pos, 1.0 / fs, axis=1),
        hand_force=force,
        pert_pos=hand_pos - ref[:, None, :],
        true_hand_force=force_true,
        true_stiffness=field.stiffness(sim.hand_pos, cfg.simulation.sigma),
        true_hand_pos=sim.hand_pos,
        true_hand_vel=sim.hand_vel,
        true_hand_acc=sim.hand_acc,
        human_force=sim.human_force,
    )
    units = {**trials_a.units, **LEVEL_B_UNITS}
    n_logged = np.asarray(meta["n_logged"])
    real = np.arange(sim.hand_pos.shape[1])[None, :] < n_logged[:, None]  # (n, s) logged samples
    inertial = np.linalg.norm(force_true + sim.human_force, axis=-1)  # robot's force − field's = m·a
    summary = {}
    for case in dict.fromkeys(str(c) for c in meta["case"]):
        rows = np.asarray(meta["case"]) == case
        sat = np.abs(f_site[rows]) >= JR3_RANGE_N
        summary[case] = {
            "inertial_force_peak_N": float(inertial[rows][real[rows]].max()),
            "force_peak_N": float(np.abs(force_true[rows][real[rows]]).max()),
            "saturated_fraction": float(sat[real[rows]].any(axis=-1).mean()),
            "excursion_max_m": float(np.abs(sim.hand_pos[rows] - ref[rows][:, None]).max()),
        }
    attrs = {**trials_a.attrs, "level": "B", "ft_load_mass_kg": scene.ft_load_mass_kg}
    trials = TrialSet(
        fs_hz=fs,
        onset_index=np.asarray(trials_a.onset_index),
        channels=channels,
        units=units,
        trial_meta=dict(meta),
        attrs=attrs,
    )
    return trials, scene.xml, summary


def _with_channels(trials: TrialSet, **channels: np.ndarray) -> TrialSet:
    """``trials`` with some channels replaced."""
    return TrialSet(
        fs_hz=trials.fs_hz,
        onset_index=trials.onset_index,
        channels={**trials.channels, **channels},
        units=trials.units,
        trial_meta=trials.trial_meta,
        attrs=trials.attrs,
    )


def clean_trials(trials: TrialSet) -> TrialSet:
    """Level-B trials with ideal sensors: the clean channels in place of the measured ones."""
    ch = trials.channels
    return _with_channels(
        trials,
        hand_pos=ch["true_hand_pos"],
        hand_vel=ch["true_hand_vel"],
        hand_force=ch["true_hand_force"],
        pert_pos=np.asarray(ch["true_hand_pos"]) - np.asarray(ch["ref_pos"]),
    )


def executed_path_trials(trials: TrialSet) -> TrialSet:
    """Level A's generator on the path level B executed: the clean positions and velocities with
    ``hand_force`` = the massless model's force there, ``−human_force`` (Eq. 2.2.1 without inertia;
    the force the hand's field exerts on the robot)."""
    return _with_channels(clean_trials(trials), hand_force=-np.asarray(trials.channels["human_force"]))


def inertia_compensated_trials(trials: TrialSet) -> TrialSet:
    """Level-B trials with ideal sensors and the hand's inertial force taken out.

    The F/T sensor measures the force on everything beyond its site: the field's force plus
    ``m·a`` of the mass ``m`` moving with the hand (``attrs['ft_load_mass_kg']``: the sensor's
    tool-side half, the cuff's mount and the hand). ``hand_force = true_hand_force − m·a`` with
    ``a`` the handle accelerometer's x, y (``true_hand_acc``, the same step as the F/T reading) is
    then the massless model's force on the executed path (Eq. 2.2.1 without inertia, as the
    thesis assumes), up to the rotation of the cuff's bodies about the flange.
    """
    mass = float(trials.attrs["ft_load_mass_kg"])
    ch = trials.channels
    force = np.asarray(ch["true_hand_force"]) - mass * np.asarray(ch["true_hand_acc"])
    return _with_channels(clean_trials(trials), hand_force=force)
