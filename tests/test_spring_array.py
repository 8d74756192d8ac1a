"""The seeds/003 mass-spring fixture: designed spring arrays reproduce Table I, in NumPy and in MuJoCo."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from armlab.errors import ConfigError
from armlab.models.spring_array import (
    TABLE_I_PAYLOADS_KG,
    TABLE_I_STIFFNESS,
    Spring,
    SpringArray,
    design_spring_array,
    fixture_mjcf,
    table_i_array,
)

LABELS = sorted(TABLE_I_STIFFNESS)
_ARRAYS = {label: table_i_array(label) for label in LABELS}


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def test_table_i_values():
    assert TABLE_I_STIFFNESS["K5"].K.tolist() == [[373.81, 73.16], [73.16, 377.10]]
    assert TABLE_I_STIFFNESS["K3"].X0.tolist() == [0.394, 0.053]
    assert list(TABLE_I_PAYLOADS_KG.values()) == [0.539, 0.786, 1.031, 1.279, 1.527]


@pytest.mark.parametrize("label", LABELS)
def test_design_reproduces_table_i(label):
    field, array = TABLE_I_STIFFNESS[label], _ARRAYS[label]
    assert array.X0 == (field.x0, field.y0)
    assert _rel(array.stiffness(), field.K) < 1e-8
    assert np.linalg.norm(array.force(field.X0)) < 1e-9
    # a bench-like layout: 8 tension springs 0.2 m from X0, stock spring constants
    k = np.array([s.stiffness for s in array.springs])
    assert len(array.springs) == 8
    assert np.allclose(array.lengths(), 0.2)
    assert np.all((k >= 20.0 - 1e-6) & (k <= 400.0 + 1e-6))
    assert np.all(array.tensions() > 0)
    # still in tension anywhere in the paper's 5 cm-diameter perturbation region
    for ang in np.linspace(0, 2 * np.pi, 16, endpoint=False):
        X = field.X0 + 0.025 * np.array([np.cos(ang), np.sin(ang)])
        assert all(s.tension(X) > 0 for s in array.springs)


@pytest.mark.parametrize("label", ["K1", "K5"])
def test_analytic_stiffness_matches_finite_differences(label):
    array = _ARRAYS[label]
    eps = 1e-6
    for X in (np.array(array.X0), np.array(array.X0) + [0.02, -0.015]):
        fd = np.column_stack(
            [-(array.force(X + e) - array.force(X - e)) / (2 * eps) for e in (eps * np.eye(2))]
        )
        assert _rel(fd, array.stiffness(X)) < 1e-7


def _passive(model: mujoco.MjModel, data: mujoco.MjData, q) -> np.ndarray:
    data.qpos[:] = q
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)
    return data.qfrc_passive.copy()


@pytest.mark.parametrize(("k_label", "m_label"), [("K1", "M1"), ("K5", "M5"), ("K3", "M3")])
def test_mujoco_fixture(k_label, m_label):
    field, array, mass = TABLE_I_STIFFNESS[k_label], _ARRAYS[k_label], TABLE_I_PAYLOADS_KG[m_label]
    model = mujoco.MjModel.from_xml_string(fixture_mjcf(array, mass))
    data = mujoco.MjData(model)
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "payload")
    assert model.body_mass[body] == pytest.approx(mass, rel=1e-12)
    assert model.nv == 2 and model.ntendon == len(array.springs)
    # (b) X0 is the equilibrium
    assert np.linalg.norm(_passive(model, data, [0.0, 0.0])) < 1e-9
    # (c) stiffness by central differences of qfrc_passive (qpos = X - X0)
    eps = 1e-5
    K = np.column_stack(
        [-(_passive(model, data, e) - _passive(model, data, -e)) / (2 * eps) for e in (eps * np.eye(2))]
    )
    assert _rel(K, field.K) < 1e-6
    # MuJoCo's spring force equals the NumPy model away from X0 too
    dq = np.array([0.012, -0.02])
    assert np.allclose(_passive(model, data, dq), array.force(field.X0 + dq), rtol=1e-9, atol=1e-12)
    # (a) steps without warnings; the undamped payload oscillates about X0 at sqrt(K/m)
    mujoco.mj_resetData(model, data)
    data.qpos[:] = [0.01, -0.005]
    for _ in range(1000):
        mujoco.mj_step(model, data)
    assert all(w.number == 0 for w in data.warning)
    assert np.all(np.isfinite(data.qpos)) and np.max(np.abs(data.qpos)) < 0.02


@pytest.mark.parametrize("k_s", [250.0, -300.0])
def test_non_positive_definite_target_rejected(k_s):
    # k_xx k_yy < k_s²: a saddle, which no passive array in equilibrium can produce
    with pytest.raises(ConfigError, match="not positive definite"):
        design_spring_array(200.0, 300.0, k_s, 0.36, 0.0)
    with pytest.raises(ConfigError, match="not positive definite"):
        design_spring_array(-200.0, 300.0, 0.0, 0.36, 0.0)


def test_nan_inputs_rejected():
    with pytest.raises(ConfigError, match="finite"):
        design_spring_array(math.nan, 300.0, 0.0, 0.36, 0.0)
    with pytest.raises(ConfigError, match="finite"):
        design_spring_array(200.0, 300.0, 0.0, 0.36, math.inf)
    with pytest.raises(ConfigError, match="finite"):
        Spring(anchor=(math.nan, 0.0), stiffness=100.0, rest_length=0.1)
    with pytest.raises(ConfigError, match="finite"):
        _ARRAYS["K1"].force([math.nan, 0.0])


@pytest.mark.parametrize("payload", [0.0, -0.5, math.nan, math.inf, "heavy"])
def test_bad_payload_rejected(payload):
    with pytest.raises(ConfigError, match="payload_kg"):
        fixture_mjcf(_ARRAYS["K1"], payload)


def test_bad_springs_rejected():
    with pytest.raises(ConfigError, match="stiffness"):
        Spring(anchor=(0.0, 0.0), stiffness=0.0, rest_length=0.1)
    with pytest.raises(ConfigError, match="rest_length"):
        Spring(anchor=(0.0, 0.0), stiffness=100.0, rest_length=-0.1)
    with pytest.raises(ConfigError, match="unknown Table I"):
        table_i_array("K6")


def test_user_array_validated():
    def pair(k2: float, rest: float = 0.1) -> tuple[Spring, ...]:
        return (
            Spring(anchor=(0.2, 0.0), stiffness=100.0, rest_length=rest),
            Spring(anchor=(0.6, 0.0), stiffness=k2, rest_length=rest),
        )

    ok = SpringArray(springs=pair(100.0), X0=(0.4, 0.0))
    # opposed pair stretched 0.1 m: K_xx = 2 k, K_yy = 2 k (1 - l0 / l) = k
    assert np.allclose(ok.stiffness(), [[200.0, 0.0], [0.0, 100.0]])
    # the same pair compressed by 0.1 m balances, but buckles sideways: K_yy = -100 N/m
    with pytest.raises(ConfigError, match=r"not positive definite: eigenvalues \[-100"):
        SpringArray(springs=pair(100.0, rest=0.3), X0=(0.4, 0.0))
    with pytest.raises(ConfigError, match="net force"):
        SpringArray(springs=pair(120.0), X0=(0.4, 0.0))
    with pytest.raises(ConfigError, match="anchored at X0"):
        SpringArray(springs=pair(100.0), X0=(0.2, 0.0))
