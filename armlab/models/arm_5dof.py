"""Load the seated 5-DoF arm of seed paper 001 (``models/arm_5dof/``) and index what armlab uses.

The model file's constants (moment arms, muscle stiffness, passive joint stiffness, segment
inertias) are read back from the compiled model, never restated here.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.errors import ModelError
from armlab.models.limb_kinematics import LimbKinematics
from armlab.models.robot_fk import quat_to_mat
from armlab.models.scene import model_file, named_id, sensor_slices

__all__ = [
    "ARM5_JOINTS",
    "ARM5_MUSCLES",
    "ELECTRODE_MUSCLES",
    "MARKERS",
    "Arm5Dof",
    "limb_kinematics",
    "load_arm_5dof",
]

ARM5_JOINTS = ("shoulder_flexion", "shoulder_abduction", "shoulder_rotation", "elbow_flexion", "pronation")
# The paper's eight electrodes (Fig. 1b; its abbreviation -> the muscle's name in the MJCF).
ELECTRODE_MUSCLES = {
    "BRAD": "brachioradialis",
    "BILH": "biceps_long",
    "DELC": "deltoid_anterior",
    "PMJC": "pectoralis_clav",
    "DELS": "deltoid_posterior",
    "TRIO": "triceps_long",
    "TRIA": "triceps_lateral",
    "TRIM": "triceps_medial",
}
# Muscles without an electrode (they shape K_q but no EMG channel sees them).
_SILENT = ("deltoid_lateral", "infraspinatus", "pronator_teres", "supinator")
ARM5_MUSCLES = tuple(ELECTRODE_MUSCLES.values()) + _SILENT
MARKERS = ("torso_marker", "upper_arm_marker", "forearm_marker")


@dataclass(frozen=True, kw_only=True, eq=False)
class Arm5Dof:
    """The compiled 5-DoF arm and its addresses.

    Attributes:
        model: the compiled MjModel; ``path`` its file.
        qpos, dof: (5,) qpos / dof addresses in :data:`ARM5_JOINTS` order.
        muscle_act: (12,) actuator ids in :data:`ARM5_MUSCLES` order.
        muscle_actadr: (12,) their activation addresses in ``data.act`` (``actuator_actadr``).
        moment_arms: (12, 5) m, r_i: joint torque per newton of muscle tension (= -tendon coef).
        muscle_stiffness, muscle_damping: (12,) N/m, N·s/m per unit activation (k_i, b_i).
        passive_stiffness, passive_damping: (5,) N·m/rad, N·m·s/rad of the joints.
        q0: (5,) rad the default posture (keyframe ``q0``).
        sites: site name -> id (markers, wrist, joint centres, base_ft).
        sensors: sensor name -> slice into ``sensordata``.
    """

    model: mujoco.MjModel
    path: str
    qpos: np.ndarray
    dof: np.ndarray
    muscle_act: np.ndarray
    muscle_actadr: np.ndarray
    moment_arms: np.ndarray
    muscle_stiffness: np.ndarray
    muscle_damping: np.ndarray
    passive_stiffness: np.ndarray
    passive_damping: np.ndarray
    q0: np.ndarray
    sites: dict[str, int]
    sensors: dict[str, slice]

    def data_at(self, q: np.ndarray, act: np.ndarray | None = None) -> mujoco.MjData:
        """MjData at joint angles ``q`` (5,) rad, zero velocity, activations ``act`` (12,), forward run."""
        data = mujoco.MjData(self.model)
        data.qpos[self.qpos] = q
        if act is not None:
            data.act[self.muscle_actadr] = act
        mujoco.mj_forward(self.model, data)
        return data


def load_arm_5dof() -> Arm5Dof:
    """Compile ``models/arm_5dof/arm_5dof.xml`` and index it."""
    path = model_file("arm_5dof", "arm_5dof.xml")
    model = mujoco.MjModel.from_xml_path(str(path))
    joints = [named_id(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in ARM5_JOINTS]
    acts = np.array([named_id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, m) for m in ARM5_MUSCLES])
    r = np.zeros((len(ARM5_MUSCLES), 5))
    for i, a in enumerate(acts):
        if model.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_TENDON:
            raise ModelError(f"muscle {ARM5_MUSCLES[i]!r} must act on a fixed tendon")
        t = model.actuator_trnid[a, 0]
        for w in range(model.tendon_adr[t], model.tendon_adr[t] + model.tendon_num[t]):
            r[i, joints.index(int(model.wrap_objid[w]))] = -model.wrap_prm[w]
    sites = {
        name: named_id(model, mujoco.mjtObj.mjOBJ_SITE, name)
        for name in (*MARKERS, "wrist", "shoulder_centre", "elbow_centre", "base_ft")
    }
    key = named_id(model, mujoco.mjtObj.mjOBJ_KEY, "q0")
    qpos = model.jnt_qposadr[joints].copy()
    return Arm5Dof(
        model=model,
        path=str(path),
        qpos=qpos,
        dof=model.jnt_dofadr[joints].copy(),
        muscle_act=acts,
        muscle_actadr=model.actuator_actadr[acts].copy(),
        moment_arms=r,
        muscle_stiffness=-model.actuator_gainprm[acts, 1].copy(),
        muscle_damping=-model.actuator_gainprm[acts, 2].copy(),
        passive_stiffness=model.jnt_stiffness[joints].copy(),
        passive_damping=model.dof_damping[model.jnt_dofadr[joints]].copy(),
        q0=model.key_qpos[key, qpos].copy(),
        sites=sites,
        sensors=sensor_slices(model),
    )


def limb_kinematics(arm: Arm5Dof) -> LimbKinematics:
    """The true kinematic chain of the model (joint centres, axes, wrist frame) at q = 0."""
    m = arm.model
    data = mujoco.MjData(m)
    mujoco.mj_kinematics(m, data)  # qpos0 = 0: the chain's reference configuration
    joints = m.dof_jntid[arm.dof]
    upper, forearm = int(m.jnt_bodyid[joints[0]]), int(m.jnt_bodyid[joints[3]])
    if any(m.jnt_bodyid[j] != upper for j in joints[:3]) or m.jnt_bodyid[joints[4]] != forearm:
        raise ModelError(
            "arm_5dof: the three shoulder hinges must share one body, elbow and pronation another"
        )
    if np.any(m.jnt_pos[joints] != 0.0):
        raise ModelError("arm_5dof: the hinges must sit at their body's origin (intersecting axes)")
    wrist = arm.sites["wrist"]
    if m.site_bodyid[wrist] != forearm:
        raise ModelError("arm_5dof: the wrist site must be on the forearm")
    return LimbKinematics(
        base_rot=data.xmat[upper].reshape(3, 3).copy(),
        shoulder=data.xpos[upper].copy(),
        elbow_offset=m.body_pos[forearm].copy(),
        forearm_rot0=quat_to_mat(m.body_quat[forearm]),
        wrist_offset=m.site_pos[wrist].copy(),
        wrist_rot0=quat_to_mat(m.site_quat[wrist]),
        axes=m.jnt_axis[joints].copy(),
    )
