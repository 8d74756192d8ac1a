"""Tests for the free-moving 5-DoF arm (armlab.models.arm5_free, armlab.sim.arm5_free; seed paper
001 Sec. 3): the scene compiles and steps with zero MuJoCo warnings, a settled hold reads the
static base wrench of MuJoCo's inverse dynamics (the ground truth of Eq. (22)), the calibration
motion stays inside its bound with its analytic velocity, and the servos follow it."""

from __future__ import annotations

import mujoco
import numpy as np
from arm5_data import held_wrench
from numpy.testing import assert_allclose

from armlab.models import FREE_SERVO_KP, build_arm5_free_scene, load_arm_5dof
from armlab.sim import random_joint_motion, simulate_free_motion, simulate_holds

ARM = load_arm_5dof()
SCENE = build_arm5_free_scene()


def test_scene_compiles_and_holds_one_second_without_warnings():
    m = SCENE.model
    assert m.nu == 17 and np.allclose(SCENE.servo_kp, FREE_SERVO_KP)  # 12 muscles + 5 servos
    data = mujoco.MjData(m)
    data.qpos[SCENE.arm_qpos] = ARM.q0
    data.ctrl[SCENE.servo_act] = ARM.q0
    for _ in range(round(1.0 / m.opt.timestep)):  # a single trial: Python stepping is fine here
        mujoco.mj_step(m, data)
    assert all(w.number == 0 for w in data.warning), [w.number for w in data.warning]
    assert np.all(np.isfinite(data.qpos))
    # the servos hold the arm near q0 under gravity: sag = G / kp, ~0.05 rad at most
    assert np.abs(data.qpos[SCENE.arm_qpos] - ARM.q0).max() < 0.1


def test_settled_holds_read_the_static_base_wrench():
    q = ARM.q0 + np.random.default_rng(3).uniform(-0.7, 0.7, (4, 5))
    rec = simulate_holds(SCENE, q, settle_s=1.0, hold_s=0.2)
    assert rec.base_wrench.shape == (4, 400, 6) and rec.marker_pos.shape == (4, 100, 3)
    truth = held_wrench(ARM, rec.true_q.mean(axis=1))  # inverse dynamics at rest (qvel = qacc = 0)
    # measured 1e-6 N after 1 s of settling: the servos' residual creep; 1e-4 N is 1e-6 of the
    # 646 N body weight, far below the base JR3's one count (0.12 N)
    assert_allclose(rec.base_wrench.mean(axis=1), truth, atol=1e-4)
    assert np.ptp(rec.true_q, axis=1).max() < 1e-5  # rad: still during the hold


def test_random_motion_is_bounded_and_smooth_and_followed():
    fs = 2000.0
    q, qdot = random_joint_motion(ARM.q0, 0.5, 2.0, fs, np.random.default_rng(4))
    assert q.shape == (4000, 5) and np.abs(q - ARM.q0).max() <= 0.5
    # qdot is the analytic derivative: central differences agree to O(dt^2) (|q'''| dt^2 / 6)
    assert_allclose(qdot[1:-1], (q[2:] - q[:-2]) * fs / 2, atol=1e-4)
    rec = simulate_free_motion(SCENE, q, qdot)
    assert rec.marker_pos.shape == (1000, 3, 3) and rec.fs_hz == 500.0
    # the 500 Hz frame k is the state after physics step 4k + 4 (sample 4k + 3 of the command)
    # the PD servos with velocity feed-forward follow within a few degrees (gravity sag included)
    assert np.degrees(np.abs(rec.true_q - q[3::4]).max()) < 5.0
    assert_allclose(np.linalg.norm(rec.marker_quat, axis=-1), 1.0, atol=1e-9)
