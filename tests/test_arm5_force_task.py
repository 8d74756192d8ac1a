"""Tests for armlab.sim.arm5_force_task (seed paper 001's displayed force levels): the held torque
balance against MuJoCo's own forces, least effort against a general constrained minimiser, and
that the 8 conditions give different joint stiffnesses."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import minimize

from armlab.errors import ConfigError
from armlab.models import analytic_stiffness, limb_kinematics, load_arm_5dof
from armlab.sim import A_MIN, force_task_activations, muscle_torque_matrix, preload_conditions

ARM = load_arm_5dof()
KIN = limb_kinematics(ARM)
NAMES, FORCES = preload_conditions()
TASKS = [force_task_activations(ARM, ARM.q0, f) for f in FORCES]


def test_the_eight_conditions_of_the_spec():
    # spec 001: 4 levels in X and 4 in Z, +-5 and +-10 N (assumption)
    assert len(NAMES) == 8
    assert sorted(np.abs(FORCES).sum(axis=1).tolist()) == [5.0] * 4 + [10.0] * 4
    assert np.count_nonzero(FORCES[:, 0]) == 4 and np.count_nonzero(FORCES[:, 2]) == 4
    assert not FORCES[:, 1].any()


@pytest.mark.parametrize("c", range(8))
def test_torque_balance_holds_in_mujoco(c):
    """MuJoCo's forces at q0 with the activations: muscles + passive + J^T w - bias = 0."""
    task = TASKS[c]
    assert task.activation.min() >= A_MIN - 1e-12 and task.activation.max() <= 1.0
    data = ARM.data_at(ARM.q0, task.activation)
    wrench = np.r_[-task.force, 0.0, 0.0, 0.0]  # the robot's push on the limb
    net = (
        data.qfrc_actuator[ARM.dof]
        + data.qfrc_passive[ARM.dof]
        + KIN.jacobian(ARM.q0).T @ wrench
        - data.qfrc_bias[ARM.dof]
    )
    # linear in the activations and exact after the polish: rounding of ~10 N m torques
    assert np.abs(net).max() < 1e-9


@pytest.mark.parametrize("c", [0, 5, 7])
def test_least_effort_equals_a_general_constrained_minimiser(c):
    M, tau_p = muscle_torque_matrix(ARM, ARM.q0)
    task = TASKS[c]
    res = minimize(
        lambda a: a @ a,
        np.full(12, 0.5),
        jac=lambda a: 2 * a,
        constraints=[{"type": "eq", "fun": lambda a: M @ a - task.tau_required, "jac": lambda a: M}],
        bounds=[(A_MIN, 1.0)] * 12,
        method="SLSQP",
        options={"ftol": 1e-14, "maxiter": 500},
    )
    assert res.success
    # a strictly convex problem has one minimiser; SLSQP stops at ~1e-7 in a
    assert_allclose(task.activation, res.x, atol=1e-5)


def test_stiffness_differs_per_condition():
    K = np.array([analytic_stiffness(ARM, t.activation) for t in TASKS])
    for i in range(8):
        for j in range(i + 1, 8):
            # the pushes recruit different muscles: every pair differs by > 5 % (Frobenius)
            assert np.linalg.norm(K[i] - K[j]) > 0.05 * np.linalg.norm(K[i]), (NAMES[i], NAMES[j])
        assert np.linalg.eigvalsh(K[i]).min() > 0


def test_impossible_force_and_bad_bounds_are_refused():
    with pytest.raises(ConfigError, match="more than full activation"):
        force_task_activations(ARM, ARM.q0, np.array([0.0, 0.0, 200.0]))
    with pytest.raises(ConfigError, match=r"a_min must lie in \[0, 1\)"):
        force_task_activations(ARM, ARM.q0, FORCES[0], a_min=1.0)
    with pytest.raises(ConfigError, match=r"\(3,\) vector"):
        force_task_activations(ARM, ARM.q0, np.ones(2))
