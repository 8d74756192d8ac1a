"""Tests for armlab.models.robot_fk (vectorised forward kinematics) and armlab.sim.robot_ik."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from conftest import make_lab
from numpy.testing import assert_allclose

from armlab.errors import ModelError
from armlab.models.robot_fk import RobotKinematics
from armlab.sim.hold import hand_world
from armlab.sim.robot_ik import FLANGE_DOWN, nominal_robot_posture, solve_ik


@pytest.mark.parametrize("rigid", [True, False])
def test_forward_matches_mj_kinematics(rigid):
    scene = make_lab("hill", rigid).scene
    model = scene.model
    kin = RobotKinematics.from_scene(scene)
    lo, hi = model.jnt_range[model.dof_jntid[scene.robot_dof]].T
    rng = np.random.default_rng(0)
    q = rng.uniform(lo, hi, size=(20, 7))
    pos, rot = kin.forward(q)
    assert pos.shape == (20, 3) and rot.shape == (20, 3, 3)
    ft_site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "lwr/cuff/ft_site")
    data = mujoco.MjData(model)
    for n in range(len(q)):
        data.qpos[scene.robot_qpos] = q[n]  # cuff slides stay at zero (undeflected)
        mujoco.mj_kinematics(model, data)
        # the same products of O(1) rotations in a different order: rounding ~1e-15 m
        assert_allclose(pos[n], data.site_xpos[scene.contact_site], rtol=0, atol=1e-12)
        assert_allclose(rot[n], data.site_xmat[ft_site].reshape(3, 3), rtol=0, atol=1e-12)
    # one configuration at a time gives the batch rows
    p1, r1 = kin.forward(q[3])
    assert_allclose(p1, pos[3], rtol=0, atol=1e-15)
    assert_allclose(r1, rot[3], rtol=0, atol=1e-15)


def test_solve_ik_reaches_target_with_flange_down():
    lab = make_lab("hill", False)
    scene, model = lab.scene, lab.scene.model
    hand = hand_world(scene, np.asarray(lab.arm.q0))
    targets = hand + np.array([[0.0, 0.0, 0.0], [0.03, -0.02, 0.0], [0.06, -0.04, 0.01]])  # m
    q = solve_ik(scene, targets, nominal_robot_posture(scene, hand))
    assert q.shape == (3, 7)
    lo, hi = model.jnt_range[model.dof_jntid[scene.robot_dof]].T
    assert np.all(q >= lo) and np.all(q <= hi)
    data = mujoco.MjData(model)
    for target, qn in zip(targets, q, strict=True):
        data.qpos[scene.robot_qpos] = qn
        mujoco.mj_kinematics(model, data)
        # solve_ik iterates to 1e-9 (position m, orientation rad); 1e-8 leaves margin for the check
        assert_allclose(data.site_xpos[scene.contact_site], target, rtol=0, atol=1e-8)
        flange = data.site_xmat[scene.flange_site].reshape(3, 3)
        assert_allclose(flange, FLANGE_DOWN, rtol=0, atol=1e-8)
        assert_allclose(flange[:, 2], [0.0, 0.0, -1.0], rtol=0, atol=1e-8)


def test_solve_ik_rejects_unreachable_target():
    scene = make_lab("hill", False).scene
    far = hand_world(scene, np.array([0.08, 1.0])) + np.array([3.0, 0.0, 0.0])  # m, beyond the ~1.2 m reach
    with pytest.raises(ModelError, match="cannot reach"):
        solve_ik(scene, far[None], nominal_robot_posture(scene, far))


def test_kinematics_by_trial_halves_on_threads_equal_one_call(monkeypatch):
    # the lab computes the chain for the two halves of the trials on two threads: bit-identical
    from armlab.sim.lab import _forward_by_halves

    monkeypatch.setattr("armlab.dsp.usable_cpus", lambda: 2)  # the threaded path even on a 1-core machine
    lab = make_lab("hill", False)
    fk = RobotKinematics.from_scene(lab.scene)
    q = lab.hold.robot_target + 0.1 * np.random.default_rng(0).standard_normal((5, 40, 7))
    contact, rot = _forward_by_halves(fk, q)
    ref_contact, ref_rot = fk.forward(q)
    np.testing.assert_array_equal(contact, ref_contact)
    np.testing.assert_array_equal(rot, ref_rot)
