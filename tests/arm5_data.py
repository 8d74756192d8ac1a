"""Marker data of the seated 5-DoF arm generated with MuJoCo, shared by the estimator tests:
random smooth motion of every joint (the paper's kinematic calibration, Sec. 3) and the marker
noise of the spec (0.2 mm, 0.3 deg; ../shared/specs/001_stiffness_5dof_emg.md, Set-up)."""

from __future__ import annotations

import mujoco
import numpy as np

from armlab.models import MARKERS, Arm5Dof

MARKER_RATE_HZ = 500.0  # paper Sec. 3: Vicon T10 at 500 Hz
CALIBRATION_S = 30.0  # spec: kinematic calibration duration (assumption, 30 s)
POS_NOISE_M = 0.2e-3  # spec: marker position noise 0.2 mm
ROT_NOISE_RAD = np.radians(0.3)  # spec: marker orientation noise 0.3 deg (per axis)


def random_motion(arm: Arm5Dof, rng: np.random.Generator, seconds: float = CALIBRATION_S) -> np.ndarray:
    """(N, 5) rad: q0 plus three sines per joint (0.1-0.8 Hz, total amplitude <= 0.5 rad)."""
    t = np.arange(round(seconds * MARKER_RATE_HZ)) / MARKER_RATE_HZ
    f = rng.uniform(0.1, 0.8, (3, 5))
    phase = rng.uniform(0, 2 * np.pi, (3, 5))
    amp = rng.uniform(0.08, 0.5 / 3, (3, 5))
    return arm.q0 + np.sum(amp * np.sin(2 * np.pi * f * t[:, None, None] + phase), axis=1)


def site_frames(arm: Arm5Dof, q: np.ndarray, sites: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Site positions (N, k, 3) m and orientations (N, k, 3, 3) from MuJoCo's kinematics."""
    data = mujoco.MjData(arm.model)
    ids = [arm.sites[s] for s in sites]
    pos = np.empty((len(q), len(ids), 3))
    rot = np.empty((len(q), len(ids), 3, 3))
    for i, qi in enumerate(q):  # one kinematics pass per sample: how the data are generated
        data.qpos[arm.qpos] = qi
        mujoco.mj_kinematics(arm.model, data)
        pos[i] = data.site_xpos[ids]
        rot[i] = data.site_xmat[ids].reshape(-1, 3, 3)
    return pos, rot


def wrist_frames(arm: Arm5Dof, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The wrist site's positions (N, 3) m and orientations (N, 3, 3) from MuJoCo's kinematics."""
    pos, rot = site_frames(arm, q, ("wrist",))
    return pos[:, 0], rot[:, 0]


def postures(arm: Arm5Dof, n: int, seed: int, spread_rad: float) -> np.ndarray:
    """(n, 5) rad: the default posture q0 +- spread_rad, uniform per joint (inside every joint
    range for spread_rad <= 0.7; the paper's predefined configurations are not given, Sec. 3)."""
    return arm.q0 + np.random.default_rng(seed).uniform(-spread_rad, spread_rad, (n, 5))


def held_still(arm: Arm5Dof, q: np.ndarray, act: np.ndarray | None = None) -> mujoco.MjData:
    """MuJoCo data of the arm held still at q (5,) rad with activations act: the static inverse
    (qvel = qacc = 0; mj_inverse also evaluates the sensors, so the base F/T reads the hold)."""
    data = arm.data_at(q, act)
    data.qacc[:] = 0.0
    mujoco.mj_inverse(arm.model, data)
    return data


def base_wrench(arm: Arm5Dof, data: mujoco.MjData) -> np.ndarray:
    """(6,) the base F/T reading (f N, n N m) of data."""
    return np.r_[data.sensordata[arm.sensors["base_force"]], data.sensordata[arm.sensors["base_torque"]]]


def held_wrench(arm: Arm5Dof, q: np.ndarray) -> np.ndarray:
    """(n, 6) the base wrench (f N, n N m) of the passive arm held still at each q (n, 5) rad."""
    return np.array([base_wrench(arm, held_still(arm, qi)) for qi in q]).reshape(len(q), 6)


def markers(arm: Arm5Dof, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ideal marker positions (N, 3, 3) and orientations (N, 3, 3, 3) in the order of MARKERS."""
    return site_frames(arm, q, MARKERS)


def add_marker_noise(
    pos: np.ndarray, rot: np.ndarray, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Position noise POS_NOISE_M per axis, orientation noise: a rotation by a vector of
    ROT_NOISE_RAD per axis in the marker frame."""
    pos = pos + rng.normal(0.0, POS_NOISE_M, pos.shape)
    v = rng.normal(0.0, ROT_NOISE_RAD, rot.shape[:-1])
    angle = np.linalg.norm(v, axis=-1)[..., None, None]
    axis = v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)
    k = np.zeros(rot.shape)
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -axis[..., 2], axis[..., 1], -axis[..., 0]
    k = k - np.swapaxes(k, -1, -2)
    dr = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)
    return pos, rot @ dr
