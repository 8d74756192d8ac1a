"""Tests for armlab.estimation.stiffness_ellipsoid (seed paper 001, Fig. 3): the wrist compliance
C_x = J_t K_q^-1 J_t^T against the displacement MuJoCo's arm (models/arm_5dof, gravity off,
activations frozen) settles to under a wrist force, and the ellipsoid's geometry."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import DataError
from armlab.estimation import FIG3_RADIUS_M, axis_angle_deg, ellipsoid_surface, stiffness_ellipsoid
from armlab.models import analytic_stiffness, limb_kinematics, load_arm_5dof

ARM = load_arm_5dof()
KIN = limb_kinematics(ARM)
ACT = np.random.default_rng(50).uniform(0.05, 0.3, 12)


def test_compliance_equals_the_settled_displacement_under_a_wrist_force():
    ell = stiffness_ellipsoid(analytic_stiffness(ARM, ACT), KIN.jacobian(ARM.q0))
    model = ARM.model
    model_g0 = mujoco.MjModel.from_xml_path(ARM.path)
    model_g0.opt.gravity[:] = 0.0  # compliance of the muscles alone
    data = mujoco.MjData(model_g0)
    data.qpos[ARM.qpos] = ARM.q0
    data.act[ARM.muscle_actadr] = ACT
    data.ctrl[ARM.muscle_act] = ACT  # activation dynamics stay at ACT
    mujoco.mj_forward(model_g0, data)
    hold = -(data.qfrc_actuator + data.qfrc_passive)  # cancels the muscles' tone: q0 an equilibrium
    wrist = ARM.sites["wrist"]
    x0 = data.site_xpos[wrist].copy()
    body = model.site_bodyid[wrist]
    # N: ~1 mm of displacement (the softest axis is ~20 N/m at these activations), small enough
    # for the wrist's kinematics to stay linear
    force = 0.01 * np.array([1.0, -1.5, 2.0])
    for _ in range(round(10.0 / model.opt.timestep)):  # 10 s: the slowest mode settles
        data.qfrc_applied[:] = hold
        mujoco.mj_applyFT(model_g0, data, force, np.zeros(3), data.site_xpos[wrist], body, data.qfrc_applied)
        mujoco.mj_step(model_g0, data)
    dx = data.site_xpos[wrist] - x0
    assert np.linalg.norm(data.qvel) < 1e-3 * np.linalg.norm(data.qpos[ARM.qpos] - ARM.q0)  # at rest
    # linear muscles: the joint side is exact; the wrist's kinematics bends at second order over
    # ~1 mm (< 1 %), so 3 %
    assert_allclose(dx, ell.C_x @ force, rtol=0.03, atol=0.03 * np.linalg.norm(dx))
    assert_allclose(ell.K_x @ ell.C_x, np.eye(3), atol=1e-9)


def test_ellipsoid_geometry():
    K = analytic_stiffness(ARM, ACT)
    centre = np.array([0.0, 0.0, 10.0])  # N, a Z pre-load
    ell = stiffness_ellipsoid(K, KIN.jacobian(ARM.q0), centre=centre)
    assert ell.radius == FIG3_RADIUS_M == 0.005  # Fig. 3: r = 5 mm
    assert np.all(np.diff(ell.semi_axes) <= 0) and ell.semi_axes[-1] > 0
    assert_allclose(ell.K_x @ ell.major_axis, ell.semi_axes[0] / ell.radius * ell.major_axis, rtol=1e-10)
    pts = ellipsoid_surface(ell).reshape(-1, 3)
    d = np.linalg.solve(ell.K_x, (pts - centre).T).T
    assert_allclose(np.linalg.norm(d, axis=1), ell.radius, rtol=1e-10)  # displacements on the sphere
    # the 3 x 5 translational rows give the same ellipsoid as the full 6 x 5 Jacobian
    assert_allclose(stiffness_ellipsoid(K, KIN.jacobian(ARM.q0)[:3]).K_x, ell.K_x)


def test_axis_angle_is_sign_free():
    a = np.array([1.0, 0.0, 0.0])
    assert axis_angle_deg(a, -a) == pytest.approx(0.0)
    assert axis_angle_deg(a, [0.0, 1.0, 0.0]) == pytest.approx(90.0)
    assert axis_angle_deg(a, [1.0, 1.0, 0.0]) == pytest.approx(45.0)


def test_bad_input_is_refused():
    J = KIN.jacobian(ARM.q0)
    with pytest.raises(DataError, match="not symmetric positive definite"):
        stiffness_ellipsoid(-np.eye(5), J)
    with pytest.raises(DataError, match=r"\(6, n\) or \(3, n\)"):
        stiffness_ellipsoid(np.eye(5), J[:, :4])
    with pytest.raises(DataError, match="radius"):
        stiffness_ellipsoid(np.eye(5), J, radius=0.0)
