"""Level C of paper 002: the planar Hill arm as the truth of a position-dependent Cartesian impedance.

The thesis (Ch. 3) postulates a diagonal stiffness quadratic in the hand's position (Eq. 2.2.4)
and, as an alternative, a polar model (§2.2.2). Level C asks whether either is adequate for a
musculoskeletal arm: the planar 2-DoF arm with six Hill-type muscles (``models/arm_planar``,
``arm_planar_hill.xml``), composed as the conditioning lab composes it
(:func:`armlab.models.scene.build_scene` with the default configs), every muscle at the
co-contraction activation ``arm.cocontraction`` and held there (frozen: no activation dynamics,
no reflex; the thesis's impedance is intrinsic).

The hand's planar position in the arm's frame (origin at the shoulder, x lateral, y anterior,
models/arm_planar/README.md) maps to the joints by the two-link kinematics (elbow flexed, q2 > 0).
At a reference posture the subject holds (``q_r``), the arm's force on the handle for a hand at
``x`` is, quasi-statically (no inertia: the thesis's model has none; level B studies it),

    F_arm(x, ẋ) = J(q)^-T · (τ(q, q̇) − τ(q_r, 0)),     q = IK(x), q̇ = J(q)^-1 ẋ,

``τ`` the muscles' joint torques (MuJoCo's Hill force-length-velocity curves) minus the torque
that holds the reference (assumption: the subject's command balances it). Its Cartesian
stiffness and damping at the reference (restoring sign) are

    K_C = J^-T K_q J^-1,   D_C = J^-T D_q J^-1

with ``K_q, D_q`` the arm's joint impedance by central differences
(:func:`~armlab.models.ground_truth.impedance_fd`); the term ``∂J^-T/∂x · (τ − τ_r)`` vanishes at
the reference. ``K_C`` is full (the bi-articular muscles and the kinematics couple x and y) and
posture dependent.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.config.schema import ArmConfig, CuffConfig, RobotConfig, SimConfig
from armlab.errors import ConfigError, DataError
from armlab.models import planar_arm
from armlab.models.ground_truth import joint_impedance
from armlab.models.scene import Scene, build_scene

__all__ = [
    "LEVEL_C_CIRCLE_CENTRE_M",
    "LEVEL_C_CIRCLE_RADIUS_M",
    "HillArm",
    "build_hill_arm",
]

#: m, centre of level C's circle in the arm's frame (origin at the shoulder): 0.45 m straight
#: ahead (spec 002, "What armlab adds": "a circle within reach (e.g. centre 0.45 m)"). With the
#: thesis's radius the hand stays 0.35-0.55 m from the shoulder (reach 0.626 m), the postures
#: within q1 0.53-1.16 rad, q2 1.00-1.96 rad (joint ranges -0.7..2.3, 0..2.6 rad), and the
#: Cartesian stiffness positive definite everywhere (smallest eigenvalue 114 N/m, measured)
LEVEL_C_CIRCLE_CENTRE_M = (0.0, 0.45)
#: m, level C's circle radius: the thesis's (§3.2.1)
LEVEL_C_CIRCLE_RADIUS_M = 0.1


@dataclass(frozen=True, kw_only=True, eq=False)
class HillArm:
    """The conditioning lab's planar Hill arm with frozen activations (module docstring).

    Attributes:
        scene: the composed lab scene (:func:`~armlab.models.scene.build_scene`).
        activation: every muscle's activation, held (dimensionless, in (0, 1)).
    """

    scene: Scene
    activation: float

    @property
    def lengths(self) -> tuple[float, float]:
        """m, (l1, l2): shoulder to elbow, elbow to the hand site."""
        return self.scene.l1, self.scene.l2

    def joint_angles(self, x: np.ndarray) -> np.ndarray:
        """Two-link inverse kinematics with the elbow flexed (:func:`planar_arm.inverse`):
        (..., 2) m -> (..., 2) rad.

        Raises:
            ConfigError: a point outside the arm's reach.
        """
        l1, l2 = self.lengths
        try:
            return planar_arm.inverse(x, l1, l2)
        except DataError:
            raise ConfigError(
                f"a point lies outside the arm's reach ({abs(l1 - l2):.3f}-{l1 + l2:.3f} m)"
            ) from None

    def hand_position(self, q: np.ndarray) -> np.ndarray:
        """Forward kinematics (:func:`planar_arm.forward`): (..., 2) rad -> (..., 2) m."""
        return planar_arm.forward(q, *self.lengths)

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """``∂x/∂q`` (:func:`planar_arm.jacobian`): (..., 2) rad -> (..., 2, 2) m/rad."""
        return planar_arm.jacobian(q, *self.lengths)

    def frozen_data(self) -> mujoco.MjData:
        """A fresh ``MjData`` at the model's initial state with every muscle's ``act`` at
        :attr:`activation` (the rest of the lab, robot and cuff, stays at its initial state)."""
        model = self.scene.model
        data = mujoco.MjData(model)
        data.act[model.actuator_actadr[self.scene.muscle_act]] = self.activation
        return data

    def cartesian_impedance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The truth at reference points: ``K_C = J^-T K_q J^-1``, ``D_C = J^-T D_q J^-1``.

        ``K_q, D_q`` by :func:`~armlab.models.ground_truth.joint_impedance` (central differences of
        MuJoCo's actuator + passive joint forces, activations frozen) at each point's posture.

        Args:
            x: (m, 2) m, reference hand positions.

        Returns:
            (K (m, 2, 2) N/m, D (m, 2, 2) N·s/m), restoring sign (F = −K δx − D δẋ).
        """
        x = np.atleast_2d(np.asarray(x, dtype=float))
        q = self.joint_angles(x)
        model, sc = self.scene.model, self.scene
        data = self.frozen_data()
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state = np.empty(mujoco.mj_stateSize(model, spec))
        k_q, d_q = np.empty((len(x), 2, 2)), np.empty((len(x), 2, 2))
        for i, qi in enumerate(q):  # 8 mj_forward calls per point (the truth, not the run's path)
            data.qpos[sc.arm_qpos] = qi
            mujoco.mj_getState(model, data, state, spec)
            k_q[i], d_q[i] = joint_impedance(sc, state)
        j_inv = np.linalg.inv(self.jacobian(q))
        k = np.einsum("nji,njk,nkl->nil", j_inv, k_q, j_inv)
        d = np.einsum("nji,njk,nkl->nil", j_inv, d_q, j_inv)
        return k, d


def build_hill_arm(arm: ArmConfig) -> HillArm:
    """The conditioning lab's arm (``arm.model``/``arm.muscle`` composed by
    :func:`~armlab.models.scene.build_scene` with the default cuff, robot and physics) with
    every muscle held at ``arm.cocontraction`` (the pre-load of the conditioning paper is not
    applied: the thesis's subject only holds the handle)."""
    scene = build_scene(arm, CuffConfig(), RobotConfig(), SimConfig())
    return HillArm(scene=scene, activation=float(arm.cocontraction))
