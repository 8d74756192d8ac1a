"""From recorded stiffness trials to one K_q per pre-load condition (seed paper 001, Eqs. (10),
(14)-(17)).

Per disturbance: interval means before the onset and after the displacement (spec 001's
assumption: [-200, 0] ms and [rise + 100, rise + 300] ms); the wrist frame from the forearm marker
cluster and its calibrated offset; q by the inverse kinematics of Eq. (10); the wrench on the limb
from the wrist JR3 (its frame placed by the same wrist frame, the tool between sensor and cuff
compensated with its known mass); tau_ext = J_limb(q)^T w; then Eqs. (14)-(15) with G(q) of the
identified xi_red, and the SPD solution of Eqs. (16)-(17). The trials are at rest in both intervals,
so means of the interval's samples are the static quantities of Eq. (14).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError
from armlab.estimation.inverse_kinematics import inverse_kinematics
from armlab.estimation.static_inertial import GRAVITY_MS2, gravity_torque_from_fit
from armlab.estimation.static_stiffness import StaticStiffness, external_joint_torque, static_stiffness
from armlab.models.arm5_scene import Arm5Scene
from armlab.models.limb_kinematics import LimbKinematics

__all__ = [
    "ConditionStiffness",
    "WristSensorGeometry",
    "chordal_mean_rotation",
    "condition_stiffness",
    "interval_mean",
    "quat_to_rot",
    "wrist_from_marker",
    "wrench_on_limb",
]


def interval_mean(x: np.ndarray, t_rel: np.ndarray, interval: tuple[float, float]) -> np.ndarray:
    """Mean of ``x`` (n_trials, n_samples, ...) over the samples with t_rel (n_samples,) s in
    [start, end) of ``interval`` (s from the onset), (n_trials, ...).

    Raises:
        DataError: no sample falls in the interval, or shapes disagree.
    """
    x = np.asarray(x, dtype=float)
    t_rel = np.asarray(t_rel, dtype=float)
    if x.ndim < 2 or x.shape[1] != t_rel.size:
        raise DataError(f"x must be (n_trials, n_samples, ...) with n_samples = {t_rel.size}, got {x.shape}")
    sel = (t_rel >= interval[0] - 1e-12) & (t_rel < interval[1] - 1e-12)
    if not sel.any():
        raise DataError(
            f"no sample in the interval {interval} s (record spans {t_rel[0]:.3f}..{t_rel[-1]:.3f} s)"
        )
    return x[:, sel].mean(axis=1)


def quat_to_rot(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4) (w, x, y, z; MuJoCo's order)."""
    w, x, y, z = np.moveaxis(np.asarray(quat, dtype=float), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )


def wrist_from_marker(
    rot_m: np.ndarray, pos_m: np.ndarray, marker_to_wrist: tuple[np.ndarray, np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """The wrist frame (rotations (n, 3, 3), positions (n, 3) m) carried by the forearm cluster at
    ``rot_m`` (n, 3, 3), ``pos_m`` (n, 3) m, with the wrist's (rotation (3, 3), offset (3,) m) in
    the cluster's frame (measured once by the lab)."""
    r_off, p_off = (np.asarray(a, dtype=float) for a in marker_to_wrist)
    return rot_m @ r_off, pos_m + np.einsum("nij,j->ni", rot_m, p_off)


def chordal_mean_rotation(rot: np.ndarray) -> np.ndarray:
    """The rotation nearest (Frobenius) to the arithmetic mean of rotations (..., n, 3, 3) over
    axis -3, (..., 3, 3): the chordal L2 mean (equal to the geodesic mean to second order in the
    spread, here ~0.3 deg of marker noise)."""
    u, _, vt = np.linalg.svd(np.asarray(rot, dtype=float).mean(axis=-3))
    d = np.sign(np.linalg.det(u @ vt))
    u[..., :, 2] *= d[..., None]
    return u @ vt


@dataclass(frozen=True, kw_only=True)
class WristSensorGeometry:
    """The wrist JR3 and the tool it carries, in the wrist (= cuff centre) frame.

    Attributes:
        ft_pos: (3,) m, ft_rot: (3, 3) the sensor site's pose.
        tool_mass: kg, everything between the sensor and the cuff's grip (sensor half, cuff).
        tool_com: (3,) m its centre of mass.
        gravity: (3,) m/s² in the world.
    """

    ft_pos: tuple[float, float, float]
    ft_rot: tuple[tuple[float, float, float], ...]
    tool_mass: float
    tool_com: tuple[float, float, float]
    gravity: tuple[float, float, float] = (0.0, 0.0, -GRAVITY_MS2)

    @classmethod
    def from_scene(cls, scene: Arm5Scene) -> WristSensorGeometry:
        """The composed lab's numbers (read from its model, :class:`Arm5Scene`)."""
        return cls(
            ft_pos=tuple(float(v) for v in scene.ft_pos),
            ft_rot=tuple(tuple(float(v) for v in row) for row in scene.ft_rot),
            tool_mass=float(scene.tool_mass),
            tool_com=tuple(float(v) for v in scene.tool_com),
            gravity=tuple(float(v) for v in scene.model.opt.gravity),
        )


def wrench_on_limb(
    force: np.ndarray, torque: np.ndarray, wrist_rot: np.ndarray, geo: WristSensorGeometry
) -> np.ndarray:
    """The wrench the cuff exerts on the limb, (..., 6) (f N, m N·m about the wrist point, world).

    The JR3 reads what the flange exerts on the tool (``force`` (..., 3) N, ``torque`` (..., 3)
    N·m, sensor frame, moment about its site); the tool at rest passes on that plus its weight:
    f = f_s + m g, m = n_s + (p_s - p_w) x f_s + (c - p_w) x m g.
    """
    r_s = wrist_rot @ np.asarray(geo.ft_rot)
    f_s = np.einsum("...ij,...j->...i", r_s, force)
    n_s = np.einsum("...ij,...j->...i", r_s, torque)
    lever_s = np.einsum("...ij,j->...i", wrist_rot, np.asarray(geo.ft_pos))
    lever_c = np.einsum("...ij,j->...i", wrist_rot, np.asarray(geo.tool_com))
    weight = geo.tool_mass * np.asarray(geo.gravity)
    f = f_s + weight
    # moments about the wrist point (the wrist_rot frame's origin)
    m = n_s + np.cross(lever_s, f_s) + np.cross(lever_c, np.broadcast_to(weight, lever_c.shape))
    return np.concatenate([f, m], axis=-1)


@dataclass(frozen=True, kw_only=True, eq=False)
class ConditionStiffness:
    """K_q of one pre-load condition.

    Attributes:
        estimate: with gravity compensation (Eqs. (14)-(17)); uncompensated: G ignored (check 6).
        q_pre, q_post: (N, 5) rad interval means; tau_pre, tau_post: (N, 5) N·m J^T w.
        q_work: (5,) rad the working point (mean of q_pre); J_work: (6, 5) J_limb there.
        force_pre: (3,) N the mean force the limb exerts on the robot before the onsets.
    """

    estimate: StaticStiffness
    uncompensated: StaticStiffness
    q_pre: np.ndarray
    q_post: np.ndarray
    tau_pre: np.ndarray
    tau_post: np.ndarray
    q_work: np.ndarray
    J_work: np.ndarray
    force_pre: np.ndarray


def condition_stiffness(
    kin: LimbKinematics,
    xi_red: np.ndarray,
    marker_pos: np.ndarray,
    marker_quat: np.ndarray,
    marker_t: np.ndarray,
    wrist_force: np.ndarray,
    wrist_torque: np.ndarray,
    ft_t: np.ndarray,
    marker_to_wrist: tuple[np.ndarray, np.ndarray],
    geo: WristSensorGeometry,
    q_guess_pre: np.ndarray,
    q_guess_post: np.ndarray,
    pre_interval: tuple[float, float] = (-0.2, 0.0),
    post_interval: tuple[float, float] = (0.2, 0.4),
) -> ConditionStiffness:
    """Eqs. (10), (14)-(17) for the N disturbances of one condition.

    Args:
        kin: the (calibrated) kinematic chain; xi_red: (9,) the identified inertial parameters.
        marker_pos: (N, n_m, 3) m, marker_quat: (N, n_m, 4) the forearm cluster; marker_t (n_m,) s
            from the onset.
        wrist_force: (N, n_ft, 3) N, wrist_torque: (N, n_ft, 3) N·m the wrist JR3; ft_t (n_ft,) s.
        marker_to_wrist: (rotation (3, 3), offset (3,) m) of the wrist frame in the marker frame
            (from the kinematic calibration).
        geo: the wrist sensor's geometry.
        q_guess_pre, q_guess_post: (N, 5) rad IK starts (the commanded configurations).
        pre_interval, post_interval: s from the onset.
    """
    qs, taus, forces = [], [], []
    for interval, guess in ((pre_interval, q_guess_pre), (post_interval, q_guess_post)):
        sel = (marker_t >= interval[0] - 1e-12) & (marker_t < interval[1] - 1e-12)
        if not sel.any():
            raise DataError(f"no marker sample in the interval {interval} s")
        r_m = chordal_mean_rotation(quat_to_rot(marker_quat[:, sel]))
        p_m = marker_pos[:, sel].mean(axis=1)
        r_w, p_w = wrist_from_marker(r_m, p_m, marker_to_wrist)
        q = inverse_kinematics(kin, r_w, p_w, guess).q
        f = interval_mean(wrist_force, ft_t, interval)
        n = interval_mean(wrist_torque, ft_t, interval)
        w = wrench_on_limb(f, n, r_w, geo)
        qs.append(q)
        taus.append(external_joint_torque(kin.jacobian(q), w))
        forces.append(-w[:, :3])
    g = -float(np.asarray(geo.gravity)[2])  # m/s², the same gravity as the tool's weight above
    g_pre = gravity_torque_from_fit(kin, xi_red, qs[0], g)
    g_post = gravity_torque_from_fit(kin, xi_red, qs[1], g)
    q_work = qs[0].mean(axis=0)
    return ConditionStiffness(
        estimate=static_stiffness(qs[0], qs[1], taus[0], taus[1], g_pre, g_post),
        uncompensated=static_stiffness(qs[0], qs[1], taus[0], taus[1]),
        q_pre=qs[0],
        q_post=qs[1],
        tau_pre=taus[0],
        tau_post=taus[1],
        q_work=q_work,
        J_work=kin.jacobian(q_work),
        force_pre=forces[0].mean(axis=0),
    )
