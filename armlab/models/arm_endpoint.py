"""The relaxed arm on the capstan robot's handle and its Cartesian endpoint impedance (seeds/003).

The paper's subject rests his hand on the handle and relaxes (Sec. II-C-2): no voluntary force,
so the hand's equilibrium ``X_v`` of Eq. (3) is where the hand is. :func:`relaxed_activation`
finds the muscle activations closest to a uniform low level that make the arm's net joint torque
zero at that posture (bounded least squares: MuJoCo's muscle force is affine in activation at zero
velocity). :func:`endpoint_truth` is the ground truth of Eq. (3) there: the joint stiffness and
damping by finite differences of the muscle torques (activations frozen, the same routine as the
conditioning-window truth), the arm's joint inertia from MuJoCo, all mapped through the hand's
Jacobian ``J`` (2×2, robot frame):

    M = J^-T M_q J^-1,   B = J^-T D_q J^-1,   K = J^-T K_q J^-1

(the geometric term ``dJ^T/dq F`` of the stiffness vanishes because the relaxed hand exerts no
static force).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.optimize import lsq_linear

from armlab.errors import ConfigError, ModelError
from armlab.models.capstan_scene import CapstanScene
from armlab.models.ground_truth import joint_impedance

__all__ = [
    "EndpointTruth",
    "endpoint_truth",
    "relaxed_activation",
]

_EQUILIBRIUM_TOL_NM = 1e-6  # N·m, largest net joint torque accepted as "relaxed"
_EQ_WEIGHT = 1e6  # weight of the zero-torque rows in the bounded least squares


@dataclass(frozen=True)
class EndpointTruth:
    """Ground truth of Eq. (3) at the hand (robot frame).

    Attributes:
        M: (2, 2) kg; B: (2, 2) N·s/m; K: (2, 2) N/m.
        xv: (2,) m, the hand's equilibrium (where the relaxed hand rests).
        activation: (6,) the muscle activations that hold it there.
    """

    M: np.ndarray
    B: np.ndarray
    K: np.ndarray
    xv: np.ndarray
    activation: np.ndarray

    def as_dict(self) -> dict:
        return {
            "M_kg": self.M.tolist(),
            "B_Ns_per_m": self.B.tolist(),
            "K_N_per_m": self.K.tolist(),
            "xv_m": self.xv.tolist(),
            "activation": self.activation.tolist(),
        }


def _arm_data(scene: CapstanScene, state: np.ndarray) -> mujoco.MjData:
    if scene.load != "arm":
        raise ModelError("the arm's endpoint needs a scene built with load='arm'")
    data = mujoco.MjData(scene.model)
    mujoco.mj_setState(scene.model, data, np.asarray(state, float), mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return data


def relaxed_activation(scene: CapstanScene, state: np.ndarray, level: float) -> np.ndarray:
    """Muscle activations (6,) closest to ``level`` with zero net arm torque in ``state``.

    Args:
        scene: a capstan scene with ``load='arm'``.
        state: full-physics state with the arm in its posture (velocities are ignored).
        level: the uniform activation the relaxed subject keeps, in [0, 1].

    Raises:
        ConfigError: no activations in [0, 1] cancel the muscles' passive torque there.
    """
    if not 0.0 <= level <= 1.0:
        raise ConfigError(f"a relaxed activation level must lie in [0, 1], got {level}")
    model = scene.model
    data = _arm_data(scene, state)
    data.qvel[:] = 0
    adr = model.actuator_actadr[scene.muscle_act]

    def torque(act: np.ndarray) -> np.ndarray:
        data.act[adr] = act
        mujoco.mj_forward(model, data)
        return (data.qfrc_actuator + data.qfrc_passive)[scene.arm_dof].copy()

    passive = torque(np.zeros(len(adr)))
    gains = np.stack([torque(e) - passive for e in np.eye(len(adr))], axis=1)  # (2, 6) N·m per unit act
    a = np.vstack([_EQ_WEIGHT * gains, np.eye(len(adr))])
    b = np.concatenate([-_EQ_WEIGHT * passive, np.full(len(adr), level)])
    act = lsq_linear(a, b, bounds=(0.0, 1.0)).x
    residual = gains @ act + passive
    if np.max(np.abs(residual)) > _EQUILIBRIUM_TOL_NM:
        raise ConfigError(
            f"no muscle activations in [0, 1] hold the arm relaxed at this posture (net torque "
            f"{residual.round(4).tolist()} N·m); move the handle (vfs.arm_handle_m) or change arm.muscle"
        )
    return act


def endpoint_truth(scene: CapstanScene, state: np.ndarray) -> EndpointTruth:
    """Cartesian M, B, K of the arm at the hand (module docstring) in a full-physics ``state``."""
    model = scene.model
    data = _arm_data(scene, state)
    mujoco.mj_forward(model, data)
    k_q, d_q = joint_impedance(scene, state)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    m_q = full[np.ix_(scene.arm_dof, scene.arm_dof)]
    hand = scene.hand_site
    jacp = np.zeros((3, model.nv))
    mujoco.mj_jacSite(model, data, jacp, None, hand)
    jac = jacp[:2, scene.arm_dof]
    jinv = np.linalg.inv(jac)

    def cart(a: np.ndarray) -> np.ndarray:
        return jinv.T @ a @ jinv

    return EndpointTruth(
        M=cart(m_q),
        B=cart(d_q),
        K=cart(k_q),
        xv=data.site_xpos[hand, :2].copy(),
        activation=data.act[model.actuator_actadr[scene.muscle_act]].copy(),
    )
