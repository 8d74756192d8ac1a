"""Tests for armlab.models.joint_rig_scene: every combination of model-level effects compiles and
steps without a MuJoCo warning; the builder puts the subject and the effects where they belong."""

from __future__ import annotations

import itertools
import math

import mujoco
import numpy as np
import pytest

from armlab.config.effects import (
    CocontractionVariation,
    CuffCompliance,
    EffectsConfig,
    JointFriction,
    PayloadMass,
    Reflex,
    TransmissionCompliance,
)
from armlab.errors import ConfigError
from armlab.models.joint_rig_scene import PAYLOAD_OWN_INERTIA_KGM2, JointSubject, build_joint_rig_scene
from armlab.perturbations import prbs_position
from armlab.sim.joint_rig import MODEL_EFFECTS, simulate_joint_rig

SUBJECT = JointSubject(0.02, 0.8, 120.0, 2.0)
_ON = {
    "reflex": Reflex(gain_Nms_per_rad=5.0),
    "cuff_compliance": CuffCompliance(),
    "transmission_compliance": TransmissionCompliance(),
    "joint_friction": JointFriction(coulomb_Nm=0.3, stribeck_Nm=0.1),
    "payload_mass": PayloadMass(),
    "cocontraction_variation": CocontractionVariation(depth=0.3, bandwidth_hz=1.0),
}
COMBOS = list(itertools.product((False, True), repeat=len(MODEL_EFFECTS)))


def _effects(flags) -> EffectsConfig:
    return EffectsConfig(**{name: _ON[name] for name, on in zip(MODEL_EFFECTS, flags, strict=True) if on})


def _warnings(data: mujoco.MjData) -> dict[str, int]:
    return {mujoco.mjtWarning(i).name: int(n) for i, n in enumerate(data.warning.number) if n}


@pytest.mark.parametrize(
    "flags", COMBOS, ids=lambda f: "+".join(n for n, on in zip(MODEL_EFFECTS, f, strict=True) if on) or "none"
)
def test_every_combination_compiles_and_steps_without_warnings(flags):
    effects = _effects(flags)
    scene = build_joint_rig_scene(SUBJECT, effects, timestep_s=1.25e-4)
    data = mujoco.MjData(scene.model)
    data.ctrl[scene.servo_act] = 0.01  # a 10 mrad step of the servo: the stiffest transient
    data.ctrl[scene.activation_act] = 0.3
    for _ in range(1600):  # 0.2 s
        mujoco.mj_step(scene.model, data)
    assert _warnings(data) == {}
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.sensordata))
    # and through the chunked rollout (which raises SimulationError on any MuJoCo warning)
    ref = prbs_position(300, 1000.0, switch_interval_s=0.05, rng=np.random.default_rng(0))[None]
    rec = simulate_joint_rig(ref, 1000.0, SUBJECT, effects, noise_std_Nm=0.0, rng=np.random.default_rng(1))
    assert np.all(np.isfinite(rec.torque))


@pytest.mark.parametrize(("cuff", "trans"), [(False, False), (True, False), (False, True), (True, True)])
def test_rigid_interfaces_delete_their_hinges_and_the_tendon_follows(cuff, trans):
    eff = EffectsConfig(
        cuff_compliance=CuffCompliance(stiffness_Nm_per_rad=700.0, damping_Nms_per_rad=0.4) if cuff else None,
        transmission_compliance=TransmissionCompliance(stiffness_Nm_per_rad=3000.0) if trans else None,
    )
    scene = build_joint_rig_scene(SUBJECT, eff)
    m = scene.model
    assert m.nv == 1 + cuff + trans
    assert scene.rigid_cuff is not cuff and scene.rigid_transmission is not trans
    assert m.ntendon == 1 and m.tendon_num[0] == m.nv  # motor angle = sum of every hinge
    np.testing.assert_array_equal(m.wrap_prm[: m.nv], 1.0)
    assert ("cuff_deflection" in scene.sensors) is cuff
    assert ("transmission_deflection" in scene.sensors) is trans
    if cuff:
        assert m.jnt_stiffness[scene.cuff_dof] == 700.0 and m.dof_damping[scene.cuff_dof] == 0.4
        assert scene.cuff_stiffness == 700.0 and scene.cuff_damping == 0.4
    if trans:
        assert m.jnt_stiffness[scene.transmission_dof] == 3000.0
        assert scene.transmission_stiffness == 3000.0
    # the subject sits on the root hinge: absolute limb angle
    assert m.jnt_stiffness[scene.limb_dof] == 120.0 and m.dof_damping[scene.limb_dof] == 0.8
    # the saved MJCF is the compiled model
    again = mujoco.MjModel.from_xml_string(scene.xml)
    assert again.nv == m.nv and again.nu == m.nu and again.nsensordata == m.nsensordata


def test_inertias_servo_friction_and_activation_gains():
    pm = PayloadMass(mass_kg=0.25, lever_m=0.12)
    cv = CocontractionVariation(tonic_torque_Nm=1.5)
    eff = EffectsConfig(
        payload_mass=pm, joint_friction=JointFriction(coulomb_Nm=0.2), cocontraction_variation=cv
    )
    scene = build_joint_rig_scene(SUBJECT, eff)
    m, data = scene.model, mujoco.MjData(scene.model)
    mujoco.mj_forward(m, data)
    mass = np.zeros((1, 1))
    mujoco.mj_fullM(m, data, mass)
    # rigid chain: limb + pedal + payload m·r² + motor, exactly (the payload's own inertia aside)
    pedal = 0.005 + 0.25 * 0.12**2 + PAYLOAD_OWN_INERTIA_KGM2
    assert scene.pedal_inertia == pytest.approx(pedal, rel=1e-12)
    assert mass[0, 0] == pytest.approx(0.02 + pedal + scene.motor_inertia, rel=1e-12)
    assert scene.motor_inertia == 0.05 and scene.servo_kp == 1e5 and scene.servo_kv == 120.0
    assert scene.coulomb == 0.2 and m.dof_frictionloss[scene.limb_dof] == 0.2
    np.testing.assert_array_equal(m.actuator_gainprm[scene.activation_act, :3], [-1.5, -120.0, -0.8])
    assert m.actuator_biasprm[scene.activation_act, 0] == -2.0  # −tonic on the limb
    # the rigid chain's only mode: sqrt((kp + K) / J) rad/s, and the servo's kv / J
    omega, rate = scene.linear_rates()
    j = 0.02 + pedal + 0.05
    assert omega == pytest.approx(math.sqrt((1e5 + 120.0) / j), rel=1e-6)
    assert rate == pytest.approx((120.0 + 0.8) / j, rel=1e-6)


def test_no_friction_disables_the_constraint_solver_and_friction_enables_it():
    flag = mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    off = build_joint_rig_scene(SUBJECT, EffectsConfig())
    on = build_joint_rig_scene(SUBJECT, EffectsConfig(joint_friction=JointFriction()))
    assert off.model.opt.disableflags & flag and not on.model.opt.disableflags & flag
    # dry friction's constraint time constant is two steps (MuJoCo's stiffest safe value)
    assert on.model.dof_solref[on.limb_dof, 0] == pytest.approx(2 * on.model.opt.timestep)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"inertia_kgm2": 0.0}, "inertia_kgm2"),
        ({"damping_Nms_per_rad": -1.0}, "damping_Nms_per_rad"),
        ({"stiffness_Nm_per_rad": float("nan")}, "stiffness_Nm_per_rad"),
        ({"tonic_torque_Nm": float("inf")}, "tonic_torque_Nm"),
        ({"pedal_inertia_kgm2": -0.1}, "pedal_inertia_kgm2"),
    ],
)
def test_subject_validation_names_the_field(kwargs, match):
    base = {"inertia_kgm2": 0.02, "damping_Nms_per_rad": 0.8, "stiffness_Nm_per_rad": 100.0}
    with pytest.raises(ConfigError, match=match):
        JointSubject(**{**base, **kwargs})


def test_bad_timestep_raises():
    with pytest.raises(ConfigError, match="timestep_s"):
        build_joint_rig_scene(SUBJECT, EffectsConfig(), timestep_s=0.0)
