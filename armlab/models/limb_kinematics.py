"""Analytic kinematics of the 5-DoF arm: forward kinematics T(q) to the wrist and J_limb(q).

The chain of seed paper 001 (Sec. 2.2, 4.2): three intersecting shoulder hinges at the shoulder
centre, then elbow flexion and forearm pronation/supination about two axes intersecting at the
elbow centre. Each hinge axis is given in its segment's frame and the hinges of one segment are
applied in order (intrinsic), as MuJoCo composes several joints of one body, so the numbers read
from ``models/arm_5dof/arm_5dof.xml`` reproduce MuJoCo's kinematics exactly.

Every function broadcasts over leading dimensions (samples, trials, ...).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from armlab.errors import DataError

__all__ = [
    "LimbKinematics",
    "LimbPose",
    "axis_rotation",
]


def axis_rotation(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices about a unit ``axis`` (3,) by ``angle`` (...,) rad (Rodrigues), (..., 3, 3)."""
    a = np.asarray(axis, dtype=float)
    t = np.asarray(angle, dtype=float)[..., None, None]
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.outer(a, a) + np.cos(t) * (np.eye(3) - np.outer(a, a)) + np.sin(t) * k


@dataclass(frozen=True)
class LimbPose:
    """Segment frames of the 5-DoF arm at joint angles q (world frame).

    Attributes:
        upper_rot: (..., 3, 3) upper-arm orientation (columns: its axes in the world).
        forearm_rot: (..., 3, 3) forearm orientation.
        shoulder: (3,) m shoulder centre; elbow: (..., 3) m elbow centre.
        wrist_rot: (..., 3, 3), wrist: (..., 3) m, the wrist frame T(q) of Eq. (10).
        axes: (..., 5, 3) unit joint axes in the world; origins: (..., 5, 3) m points on them.
    """

    upper_rot: np.ndarray
    forearm_rot: np.ndarray
    shoulder: np.ndarray
    elbow: np.ndarray
    wrist_rot: np.ndarray
    wrist: np.ndarray
    axes: np.ndarray
    origins: np.ndarray


@dataclass(frozen=True, kw_only=True, eq=False)
class LimbKinematics:
    """Kinematic parameters of the 5-DoF arm.

    Attributes:
        base_rot: (3, 3) orientation of the upper-arm frame at q = 0 (world).
        shoulder: (3,) m shoulder centre (world).
        elbow_offset: (3,) m elbow centre in the upper-arm frame.
        forearm_rot0: (3, 3) forearm frame in the upper-arm frame at q = 0.
        wrist_offset: (3,) m wrist point in the forearm frame.
        wrist_rot0: (3, 3) wrist frame in the forearm frame.
        axes: (5, 3) unit hinge axes, the first three in the upper-arm frame, the last two in the
            forearm frame, in the order (shoulder flexion, abduction, rotation, elbow flexion,
            pronation).
    """

    base_rot: np.ndarray
    shoulder: np.ndarray
    elbow_offset: np.ndarray
    forearm_rot0: np.ndarray
    wrist_offset: np.ndarray
    wrist_rot0: np.ndarray
    axes: np.ndarray

    def with_centres(
        self, shoulder: np.ndarray, elbow_offset: np.ndarray, wrist_offset: np.ndarray | None = None
    ) -> LimbKinematics:
        """The same chain with the shoulder centre (3,) m (world), the elbow offset (3,) m
        (upper-arm frame) and optionally the wrist offset (3,) m (forearm frame) replaced, e.g. by
        the joint-centre estimates of Eqs. (7)-(9)."""
        wrist = self.wrist_offset if wrist_offset is None else wrist_offset
        return replace(
            self,
            shoulder=np.asarray(shoulder, float).copy(),
            elbow_offset=np.asarray(elbow_offset, float).copy(),
            wrist_offset=np.asarray(wrist, float).copy(),
        )

    def pose(self, q: np.ndarray) -> LimbPose:
        """Segment frames at joint angles ``q`` (..., 5) rad."""
        q = np.asarray(q, dtype=float)
        if q.shape[-1:] != (5,):
            raise DataError(f"q must have shape (..., 5) (the five joint angles, rad), got {q.shape}")
        rots = [axis_rotation(self.axes[j], q[..., j]) for j in range(5)]
        r1 = self.base_rot @ rots[0]
        r2 = r1 @ rots[1]
        upper = r2 @ rots[2]
        f0 = upper @ self.forearm_rot0
        forearm = f0 @ rots[3] @ rots[4]
        elbow = self.shoulder + upper @ self.elbow_offset
        wrist = elbow + forearm @ self.wrist_offset
        frames = (self.base_rot, r1, r2, f0, f0 @ rots[3])
        axes = np.stack(
            [np.broadcast_to(f @ a, elbow.shape) for f, a in zip(frames, self.axes, strict=True)], axis=-2
        )
        sh = np.broadcast_to(self.shoulder, elbow.shape)
        origins = np.stack([sh, sh, sh, elbow, elbow], axis=-2)
        return LimbPose(
            upper_rot=upper,
            forearm_rot=forearm,
            shoulder=np.asarray(self.shoulder, float),
            elbow=elbow,
            wrist_rot=forearm @ self.wrist_rot0,
            wrist=wrist,
            axes=axes,
            origins=origins,
        )

    def forward(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Wrist frame T(q) of Eq. (10): rotation (..., 3, 3) and position (..., 3) m."""
        p = self.pose(q)
        return p.wrist_rot, p.wrist

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """Geometric wrist Jacobian J_limb(q), (..., 6, 5): rows (v; omega) in the world frame,
        so that tau_ext = J_limb^T w for a wrench w = (f N, m N·m) at the wrist and
        Delta x_robot = J_limb Delta q (paper Sec. 3)."""
        p = self.pose(q)
        lever = p.wrist[..., None, :] - p.origins
        jv = np.cross(p.axes, lever)
        return np.concatenate([np.swapaxes(jv, -1, -2), np.swapaxes(p.axes, -1, -2)], axis=-2)
