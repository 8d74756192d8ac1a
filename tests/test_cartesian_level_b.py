"""Level B of ``cartesian_online`` (paper 002): the LWR + hand scene, the exact per-step field, the
sensors, and the comparison with level A."""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.testing import assert_array_equal

from armlab.config.schema import SimConfig
from armlab.models.cartesian_hand_scene import build_hand_scene
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig, SimulationConfig
from armlab.protocols.cartesian_online.experiment import simulate_cartesian
from armlab.protocols.cartesian_online.level_b import simulate_level_b_trials
from armlab.sim.stability import warning_counts


def test_level_b_scene_compiles_and_steps_without_warnings():
    scene = build_hand_scene(SimConfig())
    data = mujoco.MjData(scene.model)
    mujoco.mj_resetData(scene.model, data)
    for _ in range(500):
        mujoco.mj_step(scene.model, data)
    assert warning_counts([data]) == {}
    assert np.all(np.isfinite(data.qpos))
    # the hand's slides are the thesis's coordinates: its site sits at (x, y, HAND_HEIGHT_M)
    data.qpos[scene.hand_qpos] = [0.95, 0.1, 0.0]
    mujoco.mj_kinematics(scene.model, data)
    np.testing.assert_allclose(data.site_xpos[scene.hand_site][:2], [0.95, 0.1], atol=1e-12)


def test_same_seed_gives_bit_identical_level_b_trials():
    cfg = CartesianOnlineConfig(seed=5, simulation=SimulationConfig(n_stops=3))
    a = simulate_cartesian(cfg)
    one, _, _ = simulate_level_b_trials(cfg, a.trials, a.field)
    two, _, _ = simulate_level_b_trials(cfg, a.trials, a.field)
    for name, arr in one.channels.items():
        assert_array_equal(arr, two.channels[name])
    other, _, _ = simulate_level_b_trials(
        CartesianOnlineConfig(seed=6, simulation=cfg.simulation), a.trials, a.field
    )
    assert not np.array_equal(other.channels["hand_force"], one.channels["hand_force"])
    assert_array_equal(other.channels["true_hand_force"], one.channels["true_hand_force"])
