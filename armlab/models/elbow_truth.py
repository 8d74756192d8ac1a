"""Ground truth of the fractional-elbow lab: the elbow's impedance and the true ``theta / F``.

Computed from the compiled scene, never copied from the config: the elbow's stiffness K and
damping D by central finite differences of its actuator and passive joint forces (activations
frozen) while motor and elbow move together (so the grasp is not deflected), its inertia I from
the mass matrix, and the grasp's rotational k_g, d_g from the tendon. With
``Za = I s² + D s + K`` (+ the fractional element ``c H(s)``) and ``Zg = k_g + d_g s``, the force
at the handle ``F`` and the motor angle ``theta`` obey

    theta / F = L (1 / Zg + 1 / Za),

the five-element structure of Eqs. (31)-(37) of seeds/004 with, at the handle,
``M = I / L²``, ``k1 = k_g / L²``, ``d1 = d_g / L²``, ``k2 = K / L²``, ``d2 = D / L²`` — or, for
the fractional element, ``d2 = c / L²`` (N·s^beta/m) of the arm damper ``d2 s^beta``.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.config.schema import ElbowConfig
from armlab.models.direct_drive_scene import DirectDriveScene
from armlab.models.oustaloup import FractionalElement
from armlab.models.tf_structures import FiveElement

__all__ = [
    "ElbowTruth",
    "elbow_truth",
]

_EPS = 1e-6  # rad, rad/s: finite-difference step (central differences, error O(eps²))


@dataclass(frozen=True, kw_only=True, eq=False)
class ElbowTruth:
    """The elbow's true impedance and the true frequency response ``theta / F`` (rad/N).

    Attributes:
        impedance: the ground-truth option.
        I: kg·m², elbow inertia; K N·m/rad; D N·m·s/rad (0 for the fractional option).
        grasp_k: N·m/rad, grasp_d N·m·s/rad (rotational).
        L: m, link length.
        element: the fractional element (fractional option only).
        sensed_mass: kg, handle mass beyond the force sensor: the measured response is
            ``1 / (1 / G + m L s²)`` (0: the sensor at the skin).
    """

    impedance: str
    I: float
    K: float
    D: float
    grasp_k: float
    grasp_d: float
    L: float
    element: FractionalElement | None = None
    sensed_mass: float = 0.0

    def response(self, f_hz: np.ndarray, realised: bool = True) -> np.ndarray:
        """True ``theta / F`` (rad/N); ``realised=False`` uses ``c s^beta`` instead of Oustaloup's H."""
        s = 2j * np.pi * np.asarray(f_hz, dtype=float)
        za = self.I * s**2 + self.D * s + self.K
        if self.element is not None:
            za = za + self.element.response(f_hz, realised=realised)
        zg = self.grasp_k + self.grasp_d * s
        g = self.L * (1.0 / zg + 1.0 / za)
        if self.sensed_mass:
            g = 1.0 / (1.0 / g + self.sensed_mass * self.L * s**2)
        return g

    @property
    def fractional_order(self) -> float | None:
        """Order ``beta`` of the fractional element (None unless the fractional option)."""
        return None if self.element is None else float(self.element.beta)

    @property
    def five_element(self) -> FiveElement:
        """Translational five-element parameters at the handle.

        For the fractional option ``d2`` is the springpot's coefficient ``c / L²`` (N·s^beta/m) of
        the fractional five-element model (arm damper ``d2 s^beta``); its joint damping is zero.
        """
        L2 = self.L**2
        d2 = self.D if self.element is None else self.element.coeff
        return FiveElement(
            M=self.I / L2, k1=self.grasp_k / L2, k2=self.K / L2, d1=self.grasp_d / L2, d2=d2 / L2
        )

    def as_dict(self) -> dict:
        out = {
            "impedance": self.impedance,
            "I_kgm2": self.I,
            "K_Nm_per_rad": self.K,
            "D_Nms_per_rad": self.D,
            "grasp_k_Nm_per_rad": self.grasp_k,
            "grasp_d_Nms_per_rad": self.grasp_d,
            "L_m": self.L,
            "sensed_mass_kg": self.sensed_mass,
        }
        fe = self.five_element
        out["five_element"] = {"M": fe.M, "k1": fe.k1, "k2": fe.k2, "d1": fe.d1, "d2": fe.d2}
        if self.element is not None:
            out["fractional"] = {"order": self.element.beta, "coeff": self.element.coeff}
        return out


def elbow_truth(
    scene: DirectDriveScene, elbow: ElbowConfig, fs_hz: float, sensed_mass_kg: float = 0.0
) -> ElbowTruth:
    """Linearise the elbow of ``scene`` at the hold posture (both angles 0, muscles at co-contraction);
    ``sensed_mass_kg`` is the handle mass beyond the force sensor (``motor.sensed_mass_kg``)."""
    m = scene.model
    data = mujoco.MjData(m)
    if scene.muscle_act.size:
        data.act[m.actuator_actadr[scene.muscle_act]] = elbow.cocontraction
    qs, qe = scene.motor_qpos, scene.elbow_qpos
    vs, ve = scene.motor_dof, scene.elbow_dof

    def torque(dq: float, dv: float) -> float:
        data.qpos[[qs, qe]] = dq
        data.qvel[[vs, ve]] = dv
        mujoco.mj_forward(m, data)
        return float(data.qfrc_actuator[ve] + data.qfrc_passive[ve])

    K = -(torque(_EPS, 0.0) - torque(-_EPS, 0.0)) / (2 * _EPS)
    D = -(torque(0.0, _EPS) - torque(0.0, -_EPS)) / (2 * _EPS)
    element = None
    if scene.element_act >= 0:
        element = FractionalElement.build(
            elbow.fractional_order,
            elbow.fractional_coeff,
            elbow.oustaloup_band_hz,
            elbow.oustaloup_order,
            1 / fs_hz,
        )
    return ElbowTruth(
        impedance=elbow.impedance,
        I=scene.elbow_inertia,
        K=K,
        D=D,
        grasp_k=scene.grasp_k,
        grasp_d=scene.grasp_d,
        L=scene.link_length,
        element=element,
        sensed_mass=float(sensed_mass_kg),
    )
