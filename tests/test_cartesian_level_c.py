"""Level C of ``cartesian_online`` (paper 002): the planar Hill arm as the truth, its Cartesian
impedance against MuJoCo's finite differences, and the diagonal quadratic vs the polar model."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.cli import main
from armlab.config.schema import ArmConfig
from armlab.estimation.cartesian_regressors import quadratic_field_regressor
from armlab.estimation.field_adequacy import fit_field_models, polar_field_regressor
from armlab.estimation.polar import polar_signals
from armlab.models.hill_arm_field import LEVEL_C_CIRCLE_CENTRE_M, LEVEL_C_CIRCLE_RADIUS_M, build_hill_arm
from armlab.protocols.cartesian_online.config import (
    CartesianOnlineConfig,
    IdentificationConfig,
    SimulationConfig,
)
from armlab.protocols.cartesian_online.level_c import estimate_level_c, simulate_level_c_trials
from armlab.sim._mujoco_calls import joint_forces
from armlab.sim.cartesian_level_c import hill_arm_force


@pytest.fixture(scope="module")
def arm():
    return build_hill_arm(ArmConfig())


def _circle(n: int) -> np.ndarray:
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.asarray(LEVEL_C_CIRCLE_CENTRE_M) + LEVEL_C_CIRCLE_RADIUS_M * np.c_[np.cos(a), np.sin(a)]


def test_kinematics_match_the_composed_scene(arm):
    """The analytic two-link kinematics against MuJoCo's hand site (relative to the shoulder)."""
    model, sc = arm.scene.model, arm.scene
    data = mujoco.MjData(model)
    x = _circle(7)
    q = arm.joint_angles(x)
    assert_allclose(arm.hand_position(q), x, atol=1e-12)
    shoulder = np.asarray(ArmConfig().shoulder_pos_m[:2])
    for qi, xi in zip(q, x, strict=True):
        data.qpos[sc.arm_qpos] = qi
        mujoco.mj_kinematics(model, data)
        assert_allclose(data.site_xpos[sc.hand_site][:2] - shoulder, xi, atol=1e-12)


def test_batched_joint_forces_equal_mj_forward(arm):
    """The compiled batch (mj_fwdPosition, mj_fwdVelocity, mj_fwdActuation) against mj_forward's
    qfrc_actuator + qfrc_passive, activations frozen: the same MuJoCo code, so equal to rounding."""
    model, sc = arm.scene.model, arm.scene
    rng = np.random.default_rng(0)
    q = arm.joint_angles(_circle(5)) + rng.normal(0, 0.02, (5, 2))
    qd = rng.normal(0, 0.3, (5, 2))
    got = joint_forces(model, arm.frozen_data(), sc.arm_qpos, sc.arm_dof, q, qd)
    data = arm.frozen_data()
    for i in range(5):
        data.qpos[sc.arm_qpos], data.qvel[sc.arm_dof] = q[i], qd[i]
        mujoco.mj_forward(model, data)
        assert_allclose(got[i], (data.qfrc_actuator + data.qfrc_passive)[sc.arm_dof], rtol=1e-12, atol=1e-12)


def test_level_c_truth_equals_the_models_finite_difference_impedance(arm):
    """The truth K_C = J^-T K_q J^-1 (K_q from ground_truth.impedance_fd) against central
    differences, in Cartesian coordinates, of the force the level-C generator applies (the whole
    chain: IK, MuJoCo's Hill muscles, J^-T)."""
    x = _circle(4)
    k, d = arm.cartesian_impedance(x)
    eps = 1e-6  # m, m/s (ENGINE_NOTES: central differences at ~1e-6)
    zero = np.zeros((1, 2))
    for i, xi in enumerate(x):
        k_fd, d_fd = np.empty((2, 2)), np.empty((2, 2))
        for j, e in enumerate(np.eye(2) * eps):
            k_fd[:, j] = (
                hill_arm_force(arm, xi + e[None], zero, xi[None])
                - hill_arm_force(arm, xi - e[None], zero, xi[None])
            )[0] / (2 * eps)
            d_fd[:, j] = (
                hill_arm_force(arm, xi[None], e[None], xi[None])
                - hill_arm_force(arm, xi[None], -e[None], xi[None])
            )[0] / (2 * eps)
        # measured 1e-10 (K) and 4e-7 (D: the joint FD inside the Cartesian FD); 1e-6 / 1e-5 leave
        # room for the nested rounding, while a missing Jacobian factor is off by ~30 %
        assert_allclose(k_fd, k[i], rtol=0, atol=1e-6 * np.abs(k[i]).max())
        assert_allclose(d_fd, d[i], rtol=0, atol=1e-5 * np.abs(d[i]).max())
    assert np.all(np.linalg.eigvalsh(k) > 0)  # the circle's postures are stable (K positive definite)
    coupling = np.abs(k[:, 0, 1]) / np.sqrt(k[:, 0, 0] * k[:, 1, 1])
    assert coupling.max() > 0.1  # a full K: the diagonal model's assumption does not hold


def test_field_models_recover_forces_of_their_own_form():
    """Ground truth for the estimator: forces generated exactly in one model's form are explained
    by it (held-out VAF 100 % to rounding) on a circle's sequences."""
    rng = np.random.default_rng(1)
    n = 4000
    ref = _circle(20)[np.repeat(np.arange(20), n // 20)]
    q_p = rng.normal(0, 0.005, (n, 2))
    q_h, qd_h = ref + q_p, rng.normal(0, 0.03, (n, 2))
    train = np.repeat(np.arange(20) % 2 == 0, n // 20)
    diag = np.stack(
        [quadratic_field_regressor(q_h, q_p, qd_h, a)[0] @ rng.uniform(1, 2, 8) for a in (0, 1)], 1
    )
    assert_allclose(
        fit_field_models(q_h, ref, qd_h, diag, train)["diagonal_quadratic"].vaf_held_out_pct, 100, atol=1e-8
    )
    sig = polar_signals(q_h, ref, qd_h, np.zeros((n, 2)))
    centre = sig.q_pol.mean(axis=0)
    pol = np.stack(
        [
            polar_field_regressor(sig.q_pol, sig.q_p, sig.qd, r, centre) @ rng.uniform(1, 2, 14)
            for r in (0, 1)
        ],
        1,
    )
    theta = sig.q_pol[:, 1]
    cart = (
        pol[:, :1] * np.c_[np.cos(theta), np.sin(theta)]
        + pol[:, 1:] / sig.q_pol[:, :1] * np.c_[-np.sin(theta), np.cos(theta)]
    )
    fits = fit_field_models(q_h, ref, qd_h, cart, train)
    assert_allclose(fits["polar"].vaf_held_out_pct, 100, atol=1e-8)
    assert fits["polar"].n_parameters == 28  # §3.5.2's orders: the thesis's 28


def test_level_c_polar_model_fits_the_hill_arm_better():
    """The done-when question of issue 20 for level C, measured: held-out force VAF (x, y) of the
    diagonal quadratic 83.0 / 89.1 %, of the polar model 99.1 / 97.0 % (the arm's stiffness is
    nearly constant in joint space, which polar coordinates about the shoulder follow, and its
    x-y coupling reaches 38 %). Limits: each model within 3 points of the measured mean VAF (a
    regression margin: the run is deterministic, so any move is a change of the lab or the fit;
    3 points is a quarter of the 12-point lead the verdict rests on), and the polar model ahead by
    at least 5 points (measured 12)."""
    cfg = CartesianOnlineConfig(simulation=SimulationConfig(level="C"))
    trials, _ = simulate_level_c_trials(cfg)
    results, _ = estimate_level_c(trials, IdentificationConfig())
    vaf = {m: r["vaf_held_out_mean_pct"] for m, r in results["models"].items()}
    assert results["better_model"] == "polar"
    assert vaf["polar"] - vaf["diagonal_quadratic"] >= 5.0
    assert vaf["diagonal_quadratic"] == pytest.approx(86.1, abs=3.0)
    assert vaf["polar"] == pytest.approx(98.0, abs=3.0)
    assert results["truth"]["coupling_pct_max"] > 10.0


def test_cli_runs_level_c(tmp_path):
    assert (
        main(
            [
                "run",
                "protocol=cartesian_online",
                "simulation=level_c",
                "simulation.n_stops=6",
                f"out={tmp_path / 'r'}",
            ]
        )
        == 0
    )
    results = json.loads((tmp_path / "r" / "results.json").read_text())
    assert results["level"] == "C" and results["n_stops"] == 6
    assert set(results["models"]) == {"diagonal_quadratic", "polar", "full_quadratic"}
    assert "better of the thesis's models" in (tmp_path / "r" / "table.txt").read_text()
