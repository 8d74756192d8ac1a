"""Vectorised forward kinematics of the robot: encoders -> cuff contact point and F/T frame.

The paper computes the hand position from the robot's joint sensors by forward kinematics (IV-A,
IV-C). MuJoCo's ``mj_kinematics`` does one configuration per call (with the whole scene); for
~10^6 samples per run this module chains the robot's rigid transforms alone, compiled
(:mod:`armlab.models._fk_kernel`), using the body offsets and joint axes read from the compiled
model (so it stays consistent with the MJCF). The
cuff is taken at its nominal (undeflected) geometry: a real lab does not measure cuff deflection.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.errors import ModelError
from armlab.models.scene import Scene, named_id

__all__ = [
    "RobotKinematics",
    "quat_to_mat",
]


def quat_to_mat(q: np.ndarray) -> np.ndarray:
    """(3, 3) rotation matrix of a unit quaternion (4,) (w, x, y, z; MuJoCo's ``mju_quat2Mat``)."""
    m = np.empty(9)
    mujoco.mju_quat2Mat(m, np.asarray(q, float))
    return m.reshape(3, 3)


def _cross_matrices(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(7, 3, 3) K (the cross-product matrix of each unit joint axis), K², and where either is
    non-zero: Rodrigues' rotation I + sin(a) K + (1 - cos(a)) K² is the identity's entry elsewhere
    (0 + (±0) + (+0) = +0 for finite angles), so only 4-5 of 9 entries are computed for the
    robot's axes along a frame direction."""
    k = np.zeros((len(axes), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axes[:, 2], axes[:, 1], -axes[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = axes[:, 2], -axes[:, 1], axes[:, 0]
    kk = k @ k
    return k, kk, (k != 0) | (kk != 0)


@dataclass(frozen=True, kw_only=True, eq=False)
class RobotKinematics:
    """The robot chain as constant transforms read from a compiled scene.

    Attributes:
        base_pos, base_rot: world pose of the first moving link's parent frame.
        link_pos, link_rot: (7, 3), (7, 3, 3) offset of each link in its parent.
        axes: (7, 3) joint axes in the link frames.
        contact_pos: (3,) cuff contact site in the last link's frame (undeflected cuff).
        ft_rot: (3, 3) F/T site orientation in the last link's frame.
    """

    base_pos: np.ndarray
    base_rot: np.ndarray
    link_pos: np.ndarray
    link_rot: np.ndarray
    axes: np.ndarray
    contact_pos: np.ndarray
    ft_rot: np.ndarray

    @classmethod
    def from_scene(cls, scene: Scene) -> RobotKinematics:
        """Read the chain lwr_link1..7 and the cuff offsets from the scene at zero cuff deflection."""
        model = scene.model
        joints = model.dof_jntid[scene.robot_dof]
        bodies = model.jnt_bodyid[joints]
        if np.any(np.abs(model.jnt_pos[joints]) > 0):
            raise ModelError("robot joints must sit at their body origins for RobotKinematics")
        if np.any(model.body_parentid[bodies[1:]] != bodies[:-1]):
            raise ModelError("robot joints must form a serial chain lwr_link1..lwr_link7")
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)  # qpos0: cuff slides at zero, robot at zero
        parent = model.body_parentid[bodies[0]]
        last = bodies[-1]
        r_last = data.xmat[last].reshape(3, 3)
        site_ft = named_id(model, mujoco.mjtObj.mjOBJ_SITE, "lwr/cuff/ft_site")
        return cls(
            base_pos=data.xpos[parent].copy(),
            base_rot=data.xmat[parent].reshape(3, 3).copy(),
            link_pos=model.body_pos[bodies].copy(),
            link_rot=np.stack([quat_to_mat(q) for q in model.body_quat[bodies]]),
            axes=model.jnt_axis[joints].copy(),
            contact_pos=r_last.T @ (data.site_xpos[scene.contact_site] - data.xpos[last]),
            ft_rot=r_last.T @ data.site_xmat[site_ft].reshape(3, 3),
        )

    @staticmethod
    def load_compiled() -> None:
        """Load the compiled chain (:mod:`armlab.models._fk_kernel`) from numba's cache (compiled
        there on a first use) without a scene: :meth:`forward` of an identity chain."""
        eye = np.eye(3)
        RobotKinematics(
            base_pos=np.zeros(3),
            base_rot=eye,
            link_pos=np.zeros((7, 3)),
            link_rot=np.tile(eye, (7, 1, 1)),
            axes=np.tile([0.0, 0.0, 1.0], (7, 1)),
            contact_pos=np.zeros(3),
            ft_rot=eye,
        ).forward(np.zeros((1, 7)))

    def forward(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World position of the cuff contact point and orientation of the F/T frame.

        Compiled, one sample at a time (:mod:`armlab.models._fk_kernel`; numba is imported on
        the first call).

        Args:
            q: (..., 7) rad robot joint angles.

        Returns:
            ((..., 3) m contact position, (..., 3, 3) F/T site rotation, columns = site axes).
        """
        from armlab.models._fk_kernel import chain

        q = np.asarray(q, float)
        shape = q.shape[:-1]
        rows = np.ascontiguousarray(q.reshape(-1, 7))
        contact, rot = np.empty((rows.shape[0], 3)), np.empty((rows.shape[0], 3, 3))
        k, kk, used = _cross_matrices(self.axes)
        chain(
            self.base_pos,
            self.base_rot,
            self.link_pos,
            self.link_rot,
            k,
            kk,
            used,
            self.contact_pos,
            self.ft_rot,
            rows,
            contact,
            rot,
        )
        return contact.reshape(shape + (3,)), rot.reshape(shape + (3, 3))
