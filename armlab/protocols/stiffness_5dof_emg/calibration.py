"""The kinematic-calibration stage of ``stiffness_5dof_emg`` (seed paper 001, Secs. 2.1-2.2, 3).

Simulation (:func:`simulate_calibration`): the arm moves every joint at random
(:func:`armlab.sim.arm5_free.random_joint_motion`, batched rollout) while the three Vicon clusters
(torso, upper arm, forearm) record at 500 Hz through the suite's marker models. What it returns is
stored in the trial file under ``attrs['calibration']`` (docs/trial_format.md).

Estimation (:func:`estimate_calibration`): on the first ``1 - holdout_fraction`` of the record the
shoulder centre (torso and upper-arm clusters) and the elbow centre (upper-arm and forearm clusters)
by the linear least squares of Eqs. (7)-(9); the chain (:meth:`LimbKinematics.with_centres`) from
them and the clusters' placement on their segments (measured once by the lab; the joint axes in the
segment frames are the model's); then Eq. (10)'s IK of the held-out part with that chain against
the true joint angles. Spec 001 checks 1 (centres within 0.5 mm ideal / 3 mm noisy) and 2 (IK within
0.2 deg / 1 deg RMS).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError
from armlab.estimation.inverse_kinematics import inverse_kinematics
from armlab.estimation.joint_centres import joint_centre
from armlab.estimation.stiffness_trials import quat_to_rot, wrist_from_marker
from armlab.models.arm5_free import Arm5FreeScene
from armlab.models.arm_5dof import Arm5Dof, limb_kinematics
from armlab.models.limb_kinematics import LimbKinematics
from armlab.models.robot_fk import quat_to_mat
from armlab.protocols.stiffness_5dof_emg.config import CalibrationConfig
from armlab.sensors.channel import apply_channel
from armlab.sensors.presets import Arm5SensorSuite
from armlab.sim.arm5_free import random_joint_motion, simulate_free_motion

__all__ = [
    "CALIBRATION_TOLERANCES",
    "CalibrationEstimate",
    "estimate_calibration",
    "simulate_calibration",
]

#: spec 001 checks 1 (joint centres, m) and 2 (IK RMS, deg), per sensor preset
CALIBRATION_TOLERANCES: dict[str, float] = {
    "check1_ideal": 0.5e-3,
    "check1_realistic": 3e-3,
    "check2_ideal": 0.2,
    "check2_realistic": 1.0,
}
_TORSO, _UPPER, _FOREARM = 0, 1, 2  # armlab.models.arm_5dof.MARKERS order


def _placement(arm: Arm5Dof, site: str) -> np.ndarray:
    """(3, 3) a cluster's orientation in its segment's body frame (the lab measures it once)."""
    return quat_to_mat(arm.model.site_quat[arm.sites[site]])


def simulate_calibration(
    cfg: CalibrationConfig,
    arm: Arm5Dof,
    scene: Arm5FreeScene,
    suite: Arm5SensorSuite,
    rng: np.random.Generator,
) -> dict:
    """The random motion, measured: ``attrs['calibration']`` of the trial file.

    Returns:
        ``marker_fs_hz`` Hz; ``marker_pos`` (n, 3, 3) m and ``marker_quat`` (n, 3, 4) (w, x, y, z)
        of the torso, upper-arm and forearm clusters; ``holdout_fraction``; the clusters' placement
        ``upper_arm_marker_rot``, ``forearm_marker_rot`` (3, 3) in their segment frames; and
        ``ground_truth``: ``true_q`` (n, 5) rad, ``shoulder_m`` (3,), ``elbow_offset_m`` (3,),
        ``wrist_offset_m`` (3,) (the true chain's centres, :class:`LimbKinematics`).
    """
    fs = 1.0 / scene.model.opt.timestep
    q_d, qdot_d = random_joint_motion(arm.q0, cfg.amplitude_rad, cfg.duration_s, fs, rng)
    rec = simulate_free_motion(scene, q_d, qdot_d)
    n = len(rec.true_q)
    pos = apply_channel(rec.marker_pos.reshape(1, n, 9), rec.fs_hz, suite.marker_pos, rng)
    quat = apply_channel(rec.marker_quat.reshape(1, n, 12), rec.fs_hz, suite.marker_quat, rng)
    quat = quat.reshape(n, 3, 4)
    kin = limb_kinematics(arm)
    return {
        "marker_fs_hz": rec.fs_hz,
        "marker_pos": pos.reshape(n, 3, 3),
        "marker_quat": quat / np.linalg.norm(quat, axis=-1, keepdims=True),
        "holdout_fraction": float(cfg.holdout_fraction),
        "upper_arm_marker_rot": _placement(arm, "upper_arm_marker"),
        "forearm_marker_rot": _placement(arm, "forearm_marker"),
        "ground_truth": {
            "true_q": rec.true_q,
            "shoulder_m": np.asarray(kin.shoulder, float),
            "elbow_offset_m": np.asarray(kin.elbow_offset, float),
            "wrist_offset_m": np.asarray(kin.wrist_offset, float),
        },
    }


@dataclass(frozen=True, kw_only=True, eq=False)
class CalibrationEstimate:
    """The calibrated chain and its report.

    Attributes:
        kin: the chain with the estimated centres.
        results: JSON-able (docs/results_schema.md, ``calibration``).
        checks: spec 001 checks 1 and 2 (rows of ``results['checks']``).
    """

    kin: LimbKinematics
    results: dict
    checks: list[dict]


def _get(cal: dict, key: str):
    try:
        return cal[key]
    except KeyError:
        raise DataError(
            f"the trial file's attrs['calibration'] lacks {key!r} (docs/trial_format.md lists what it holds)"
        ) from None


def estimate_calibration(
    cal: dict,
    nominal: LimbKinematics,
    marker_to_wrist: tuple[np.ndarray, np.ndarray],
    q_start: np.ndarray,
    preset: str,
) -> CalibrationEstimate:
    """Eqs. (7)-(10) on the stored calibration record (module docstring).

    Args:
        cal: ``attrs['calibration']`` (:func:`simulate_calibration`).
        nominal: the chain whose axes and segment frames are kept (its centres are replaced).
        marker_to_wrist: (rotation (3, 3), offset (3,) m) of the wrist frame in the forearm cluster.
        q_start: (5,) rad the IK's start (the default posture the motion is centred on).
        preset: the sensor preset (``ideal`` / ``realistic``): which tolerances apply.
    """
    pos = np.asarray(_get(cal, "marker_pos"), float)
    rot = quat_to_rot(np.asarray(_get(cal, "marker_quat"), float))
    truth = _get(cal, "ground_truth")
    true_q = np.asarray(truth["true_q"], float)
    n = len(pos)
    n_fit = int(round(n * (1.0 - float(_get(cal, "holdout_fraction")))))
    fit, held = slice(0, n_fit), slice(n_fit, n)
    sh = joint_centre(pos[fit, _TORSO], rot[fit, _TORSO], pos[fit, _UPPER], rot[fit, _UPPER])
    el = joint_centre(pos[fit, _UPPER], rot[fit, _UPPER], pos[fit, _FOREARM], rot[fit, _FOREARM])
    up_rot = np.asarray(_get(cal, "upper_arm_marker_rot"), float)
    fa_rot = np.asarray(_get(cal, "forearm_marker_rot"), float)
    r_w, p_w = (np.asarray(a, float) for a in marker_to_wrist)
    # elbow - shoulder in the upper-arm cluster's frame, turned into the upper-arm segment frame;
    # the wrist - elbow in the forearm cluster's frame, turned into the forearm segment frame
    kin = nominal.with_centres(
        shoulder=sh.centre.mean(axis=0),
        elbow_offset=up_rot @ (el.d1 - sh.d2),
        wrist_offset=fa_rot @ (p_w - el.d2),
    )
    err_sh = float(np.linalg.norm(kin.shoulder - np.asarray(truth["shoulder_m"], float)))
    err_el = float(np.linalg.norm(kin.elbow_offset - np.asarray(truth["elbow_offset_m"], float)))
    err_wr = float(np.linalg.norm(kin.wrist_offset - np.asarray(truth["wrist_offset_m"], float)))
    rot_d, pos_d = wrist_from_marker(rot[held, _FOREARM], pos[held, _FOREARM], (r_w, p_w))
    ik = inverse_kinematics(kin, rot_d, pos_d, np.asarray(q_start, float))
    ik_err = ik.q - true_q[held]
    rms_deg = float(np.degrees(np.sqrt(np.mean(ik_err**2))))
    tol1, tol2 = CALIBRATION_TOLERANCES[f"check1_{preset}"], CALIBRATION_TOLERANCES[f"check2_{preset}"]
    centre_err = max(err_sh, err_el)
    results = {
        "n_frames": n,
        "n_fit": n_fit,
        "n_held_out": n - n_fit,
        "shoulder_m": kin.shoulder.tolist(),
        "elbow_offset_m": kin.elbow_offset.tolist(),
        "wrist_offset_m": kin.wrist_offset.tolist(),
        "shoulder_error_m": err_sh,
        "elbow_error_m": err_el,
        "wrist_offset_error_m": err_wr,
        "rms_gap_m": [sh.rms_gap, el.rms_gap],
        "ik_rms_deg": rms_deg,
        "ik_rms_per_joint_deg": np.degrees(np.sqrt(np.mean(ik_err**2, axis=0))).tolist(),
    }
    checks = [
        {
            "check": 1,
            "what": f"joint centres (shoulder, elbow) vs truth, {preset} markers (m)",
            "value": centre_err,
            "tolerance": tol1,
            "passed": centre_err < tol1,
        },
        {
            "check": 2,
            "what": f"IK joint angles RMS on the held-out motion, calibrated chain, {preset} markers (deg)",
            "value": rms_deg,
            "tolerance": tol2,
            "passed": rms_deg < tol2,
        },
    ]
    return CalibrationEstimate(kin=kin, results=results, checks=checks)
