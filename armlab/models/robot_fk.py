"""Vectorised forward kinematics of the robot: encoders -> cuff contact point and F/T frame.

The paper computes the hand position from the robot's joint sensors by forward kinematics (IV-A,
IV-C). MuJoCo's ``mj_kinematics`` does one configuration per call; for ~10^6 samples per run this
module chains the robot's rigid transforms with NumPy over all samples at once, using the body
offsets and joint axes read from the compiled model (so it stays consistent with the MJCF). The
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
]


def _quat_to_mat(q: np.ndarray) -> np.ndarray:
    m = np.empty(9)
    mujoco.mju_quat2Mat(m, np.asarray(q, float))
    return m.reshape(3, 3)


def _axis_rotation(axis: np.ndarray, angle: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(..., 3, 3) rotations about a fixed unit ``axis`` by ``angle`` (...,) rad (Rodrigues).

    ``out`` (..., 3, 3), if given, receives the result. Entry by entry, I + sin(a) K + (1 - cos(a))
    K² in that order of operations; an entry where K and K² are both zero is I's exactly
    (0 + (±0) + (+0) = +0 for finite angles), so only the others are computed: 4-5 of 9 for the
    robot's axes along a frame direction.
    """
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    kk = k @ k
    if out is None:
        out = np.empty(np.shape(angle) + (3, 3))
    s = np.sin(angle)
    omc = 1 - np.cos(angle)
    for r in range(3):
        for c in range(3):
            eye = 1.0 if r == c else 0.0
            if k[r, c] == 0 and kk[r, c] == 0:
                out[..., r, c] = eye
            else:
                out[..., r, c] = eye + s * k[r, c] + omc * kk[r, c]
    return out


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
            link_rot=np.stack([_quat_to_mat(q) for q in model.body_quat[bodies]]),
            axes=model.jnt_axis[joints].copy(),
            contact_pos=r_last.T @ (data.site_xpos[scene.contact_site] - data.xpos[last]),
            ft_rot=r_last.T @ data.site_xmat[site_ft].reshape(3, 3),
        )

    def forward(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World position of the cuff contact point and orientation of the F/T frame.

        Args:
            q: (..., 7) rad robot joint angles.

        Returns:
            ((..., 3) m contact position, (..., 3, 3) F/T site rotation, columns = site axes).
        """
        q = np.asarray(q, float)
        shape = q.shape[:-1]
        # ~10^6 samples make every (..., 3, 3) product a 50 MB array: the chain writes into
        # buffers reused by every link instead of allocating each product anew (same operations)
        rot_buf, fixed, joint = (np.empty(shape + (3, 3)) for _ in range(3))
        pos_buf, offset = np.empty(shape + (3,)), np.empty(shape + (3,))
        rot = np.broadcast_to(self.base_rot, shape + (3, 3))
        pos = np.broadcast_to(self.base_pos, shape + (3,))
        for i in range(7):
            pos = np.add(pos, np.matmul(rot, self.link_pos[i], out=offset), out=pos_buf)
            np.matmul(rot, self.link_rot[i], out=fixed)
            rot = np.matmul(fixed, _axis_rotation(self.axes[i], q[..., i], out=joint), out=rot_buf)
        return pos + rot @ self.contact_pos, rot @ self.ft_rot
