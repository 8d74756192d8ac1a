"""Inverse kinematics of the robot: joint targets that put the cuff where the hand should be.

The perturbation is planned in the human's joint space (paper IV-B); the hand path follows from
the arm's kinematics, and the robot's joint controller tracks joint targets that place the cuff's
contact site on that path with the flange pointing straight down. Damped least squares on
MuJoCo's site Jacobians; the redundant seventh degree of freedom is pulled towards a nominal
posture in the Jacobian's null space.
"""

from __future__ import annotations

import mujoco
import numpy as np

from armlab.errors import ModelError
from armlab.models.scene import Scene, named_id

__all__ = [
    "FLANGE_DOWN",
    "nominal_robot_posture",
    "solve_ik",
]

# Flange frame in the world: z down (the cuff hangs below the flange), x along world +x.
FLANGE_DOWN = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])


def nominal_robot_posture(scene: Scene, target: np.ndarray) -> np.ndarray:
    """A start posture for IK: base turned towards the target, elbow bent, wrist pointing down.

    Args:
        scene: the composed scene.
        target: (3,) m, world position for the contact site.

    Returns:
        (7,) rad joint angles.
    """
    data = mujoco.MjData(scene.model)
    mujoco.mj_kinematics(scene.model, data)
    link1 = data.xpos[named_id(scene.model, mujoco.mjtObj.mjOBJ_BODY, "lwr/lwr_link1")]
    d = target - link1
    yaw = float(np.arctan2(d[1], d[0]))
    # j2 about -y leans forward for negative angles in the base's turned frame; start bent
    return np.array([yaw, -0.6, 0.0, 1.4, 0.0, -1.0, 0.0])


def solve_ik(
    scene: Scene,
    targets: np.ndarray,
    q_start: np.ndarray,
    *,
    rotation: np.ndarray = FLANGE_DOWN,
    q_nominal: np.ndarray | None = None,
    tol_m: float = 1e-9,
    max_iter: int = 100,
    damping: float = 1e-4,
) -> np.ndarray:
    """Joint targets placing the contact site at each target with the flange at ``rotation``.

    The targets are solved in order, each warm-started from the previous solution, so a smooth
    path gives a smooth joint trajectory.

    Args:
        scene: the composed scene.
        targets: (n, 3) m, world positions of the cuff contact site.
        q_start: (7,) rad, initial guess for the first target.
        rotation: (3, 3) world orientation of the flange site, or (n, 3, 3) one per target (a
            6-D cuff that carries the limb's orientation, e.g. :mod:`armlab.models.arm5_scene`).
        q_nominal: (7,) rad, posture the null-space motion tends to (default: q_start).
        tol_m: convergence tolerance on the position error (m; orientation error in rad).
        max_iter: Newton iterations per target.
        damping: Levenberg damping of the least-squares step.

    Returns:
        (n, 7) rad joint targets.

    Raises:
        ModelError: a target is out of reach (the residual stays above 1e-6).
    """
    model = scene.model
    data = mujoco.MjData(model)
    cols = scene.robot_dof
    q_nom = np.asarray(q_start if q_nominal is None else q_nominal, float)
    q = np.asarray(q_start, float).copy()
    jacp = np.zeros((3, model.nv))
    jacr = np.zeros((3, model.nv))
    targets = np.asarray(targets, float)
    rotations = np.asarray(rotation, float)
    if rotations.shape == (3, 3):
        rotations = np.broadcast_to(rotations, (len(targets), 3, 3))
    elif rotations.shape != (len(targets), 3, 3):
        raise ModelError(f"rotation must be (3, 3) or ({len(targets)}, 3, 3), got {rotations.shape}")
    out = np.empty((len(targets), 7))
    lo, hi = model.jnt_range[model.dof_jntid[cols]].T
    for n, (target, rot_n) in enumerate(zip(targets, rotations, strict=True)):
        err = np.inf
        for _ in range(max_iter):
            data.qpos[scene.robot_qpos] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)
            e_p = target - data.site_xpos[scene.contact_site]
            rot = data.site_xmat[scene.flange_site].reshape(3, 3)
            e_r = 0.5 * np.cross(rot, rot_n, axisa=0, axisb=0).sum(axis=0)
            e = np.concatenate([e_p, e_r])
            err = float(np.max(np.abs(e)))
            if err < tol_m:
                break
            mujoco.mj_jacSite(model, data, jacp, None, scene.contact_site)
            mujoco.mj_jacSite(model, data, None, jacr, scene.flange_site)
            jac = np.vstack([jacp[:, cols], jacr[:, cols]])
            jjt = jac @ jac.T + damping * np.eye(6)
            step = jac.T @ np.linalg.solve(jjt, e)
            null = np.eye(7) - np.linalg.pinv(jac) @ jac  # exact null-space projector
            q = np.clip(q + step + 0.1 * null @ (q_nom - q), lo, hi)
        if err > 1e-6:
            raise ModelError(
                f"robot cannot reach cuff target {np.round(target, 3).tolist()} m (residual {err:.2e}); "
                "move robot.base_pos_m or arm.shoulder_pos_m"
            )
        out[n] = q
    return out
