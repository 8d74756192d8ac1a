"""The direct-drive + elbow scene: compiles, steps without warnings, carries the configured grasp."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from contact_check import assert_contacts_off_changes_nothing

from armlab.config.schema import ElbowConfig, SimConfig
from armlab.models.direct_drive_scene import build_direct_drive_scene
from armlab.models.elbow_truth import elbow_truth


@pytest.mark.parametrize("impedance", ["muscle", "five_element", "fractional"])
def test_scene_compiles_and_steps_one_second_without_warnings(impedance):
    cfg = ElbowConfig(impedance=impedance)
    scene = build_direct_drive_scene(cfg, SimConfig())
    data = mujoco.MjData(scene.model)
    if scene.muscle_act.size:
        data.act[scene.model.actuator_actadr[scene.muscle_act]] = cfg.cocontraction
        data.ctrl[scene.muscle_act] = cfg.cocontraction
    data.qpos[scene.motor_qpos] = 0.02  # a deflected start: the grasp and the arm pull back
    mujoco.mj_step(scene.model, data, nstep=int(round(1.0 / scene.model.opt.timestep)))
    assert all(w.number == 0 for w in data.warning)
    # pulled back from 0.02 rad: measured 4-6e-4 rad after 1 s
    assert np.all(np.isfinite(data.qpos)) and abs(data.qpos[scene.motor_qpos]) < 2e-3
    # the link of the paper (L = 0.35 m) and the grasp as k L², d L²
    assert scene.link_length == pytest.approx(0.35)
    assert scene.grasp_k == pytest.approx(cfg.grasp_stiffness_N_per_m * 0.35**2)
    assert scene.grasp_d == pytest.approx(cfg.grasp_damping_Ns_per_m * 0.35**2)
    assert (scene.element_act >= 0) == (impedance == "fractional")


def test_five_element_truth_is_the_configured_spring_and_damper():
    cfg = ElbowConfig(impedance="five_element", arm_stiffness_Nm_per_rad=55.0, arm_damping_Nms_per_rad=2.5)
    scene = build_direct_drive_scene(cfg, SimConfig())
    truth = elbow_truth(scene, cfg, 2000.0)
    assert truth.K == pytest.approx(55.0, rel=1e-6) and truth.D == pytest.approx(2.5, rel=1e-6)
    # forearm + hand about the elbow: 0.0235 + 1.65 * 0.174² kg m² (Winter 2009, models/elbow_1dof)
    assert truth.I == pytest.approx(0.0235 + 1.65 * 0.174**2, rel=1e-6)
    # theta/F = (1/L) x/F of the five-element model at the handle, Eqs. (31)-(37)
    f = np.array([0.2, 2.0, 9.0, 15.0])
    np.testing.assert_allclose(
        truth.response(f), truth.five_element.to_tf().response(f) / truth.L, rtol=1e-10
    )


def test_muscle_truth_matches_the_hill_design_within_its_approximations():
    # models/elbow_1dof: K = 2 a F0 dFL/dl r² / L0 = 57.6 N m/rad at a = 0.5 with the FL slope 2.4
    # at l = 0.85 (measured by finite differences: 57.6 to 2e-10); D = 2 a F0 FL dFV/dV r² / (L0 vmax)
    # = 3.9 N m s/rad from the README's arithmetic (measured 3.94)
    cfg = ElbowConfig()
    truth = elbow_truth(build_direct_drive_scene(cfg, SimConfig()), cfg, 2000.0)
    assert truth.K == pytest.approx(57.6, rel=1e-6)
    assert truth.D == pytest.approx(3.9, rel=0.02)


def test_disabling_contacts_changes_no_trajectory():
    # the lab skips collision detection (no geom collides); with it switched back on the
    # trajectory must be the same bit for bit, and the scene must carry the flag (the speed)
    scene = build_direct_drive_scene(ElbowConfig(), SimConfig())

    def swing(data):
        data.qpos[scene.motor_qpos] = 0.3  # a swing of the link and the hand
        data.ctrl[scene.motor_act] = 2.0

    assert_contacts_off_changes_nothing(scene, swing, 2000)


def test_a_scene_without_contacts_refuses_a_geom_that_could_collide():
    from dm_control import mjcf

    from armlab.errors import ModelError
    from armlab.models.scene import compile_mjcf

    def two_boxes():
        root = mjcf.RootElement(model="two_boxes")
        root.worldbody.add("geom", name="floor", type="box", size=[1, 1, 0.1], contype=0, conaffinity=0)
        body = root.worldbody.add("body", pos=[0, 0, 0.5])
        body.add("freejoint")
        body.add("geom", name="block", type="box", size=[0.1, 0.1, 0.1])  # contype 1 by default
        return root

    with pytest.raises(ModelError, match=r"geoms \['block'\] could collide.*contype=\"0\""):
        compile_mjcf(two_boxes(), "toy scene", contacts=False)
    model, _, _ = compile_mjcf(two_boxes(), "toy scene")  # with contacts: compiles as before
    assert not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
