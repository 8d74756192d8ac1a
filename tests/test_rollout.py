"""Tests for armlab.sim.rollout.simulate: a still hold, determinism and the reflex delay."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import make_lab
from numpy.testing import assert_array_equal

from armlab.config.schema import ReflexConfig, SimConfig
from armlab.sim.rollout import simulate

SUBSTEPS = 2  # SimConfig() timestep 0.5 ms -> 1 kHz samples
DT = SimConfig().timestep_s
N_STEPS = round(0.2 / DT)  # 0.2 s per rollout


@pytest.fixture(scope="module")
def lab():
    return make_lab("hill", False)


def _hold_targets(lab, n_trials: int) -> np.ndarray:
    return np.tile(lab.hold.ctrl[lab.scene.robot_act], (n_trials, N_STEPS, 1))


def _ramped_targets(lab) -> np.ndarray:
    """Two trials whose robot targets start moving at step 0: joints 1 and 2 by 2 t^2 rad (smooth)."""
    t = np.arange(N_STEPS) * DT
    targets = _hold_targets(lab, 2)
    targets[0, :, 0] += 2.0 * t**2
    targets[1, :, 1] -= 2.0 * t**2
    return targets


def test_constant_targets_hold_still(lab):
    res = simulate(
        lab.scene,
        lab.hold.state,
        _hold_targets(lab, 2),
        lab.hold.activation,
        ReflexConfig(enabled=False),
        substeps=SUBSTEPS,
    )
    assert res.qpos.shape == (2, N_STEPS // SUBSTEPS, lab.scene.model.nq)
    assert res.fs_hz == pytest.approx(1000.0)
    q = res.qpos[..., lab.scene.arm_qpos]
    # the hold was settled for 1 s: residual drift is ~1e-13 rad; 1e-6 rad catches any real motion
    assert np.max(np.abs(q - lab.hold.q_arm)) < 1e-6
    assert_array_equal(res.muscle_ctrl, np.broadcast_to(lab.hold.activation, res.muscle_ctrl.shape))


def test_same_inputs_give_identical_outputs(lab):
    args = (lab.scene, lab.hold.state, _ramped_targets(lab), lab.hold.activation, ReflexConfig())
    a = simulate(*args, substeps=SUBSTEPS)
    b = simulate(*args, substeps=SUBSTEPS)
    assert_array_equal(a.sensordata, b.sensordata)
    assert_array_equal(a.muscle_ctrl, b.muscle_ctrl)
    assert np.all(np.isfinite(a.sensordata))


def test_reflex_acts_only_after_its_latency(lab):
    reflex = ReflexConfig()
    base = lab.hold.activation
    res = simulate(lab.scene, lab.hold.state, _ramped_targets(lab), base, reflex, substeps=SUBSTEPS)
    # sample n holds the command of physics step SUBSTEPS * n + SUBSTEPS - 1 (its last step)
    step = SUBSTEPS * np.arange(res.muscle_ctrl.shape[1]) + SUBSTEPS - 1
    t = step * DT
    before = t < reflex.stretch_latency_s
    assert before.any() and (~before).any()
    # motion starts at step 0: no stretch can have reached the commands before the latency
    assert_array_equal(res.muscle_ctrl[:, before], np.broadcast_to(base, res.muscle_ctrl[:, before].shape))
    # after it, the stretched muscles get more activation. The t^2 ramp starts gently: 5 ms past the
    # latency the command has risen by ~1e-6 (2 t^2 -> cubic onset of stretch), while the settled
    # hold's numerical drift alone moves it by ~1e-12, so 1e-8 separates response from drift.
    window = (t >= reflex.stretch_latency_s) & (t < reflex.stretch_latency_s + 0.005)
    dev = res.muscle_ctrl[:, window] - base
    assert np.all(dev >= 0)  # the reflex only adds activation (rectified stretch)
    assert np.all(np.max(dev, axis=(1, 2)) > 1e-8), np.max(dev, axis=(1, 2))
    # by the end of the 0.2 s rollout the reflex is a sizeable part of the command
    assert np.all(np.max(res.muscle_ctrl - base, axis=(1, 2)) > 1e-3)
    # the arm really moved in both trials
    assert np.all(np.max(np.abs(res.qpos[..., lab.scene.arm_qpos] - lab.hold.q_arm), axis=(1, 2)) > 1e-3)


def test_reflex_disabled_keeps_base_commands(lab):
    base = lab.hold.activation
    res = simulate(
        lab.scene, lab.hold.state, _ramped_targets(lab), base, ReflexConfig(enabled=False), substeps=SUBSTEPS
    )
    assert_array_equal(res.muscle_ctrl, np.broadcast_to(base, res.muscle_ctrl.shape))
    on = simulate(lab.scene, lab.hold.state, _ramped_targets(lab), base, ReflexConfig(), substeps=SUBSTEPS)
    # the same perturbation with the reflex changes the motion (the reflex is not a no-op)
    assert np.max(np.abs(on.qpos - res.qpos)) > 1e-6


def _serial_reference(lab, targets: np.ndarray, base: np.ndarray, reflex: ReflexConfig) -> np.ndarray:
    """The reflex-chunked simulation written plainly: one fresh ``mujoco.rollout`` call per chunk,
    no reused buffers, no worker thread. Returns the sampled sensordata (n, n_samples, nsd)."""
    import mujoco
    from mujoco import rollout

    from armlab.models.scene import MUSCLES
    from armlab.sim.rollout import reflex_command

    scene, model = lab.scene, lab.scene.model
    lags = [round(lat / DT) for lat in (reflex.stretch_latency_s, reflex.spinal_latency_s)]
    cols = {k: [scene.sensors[f"{k}_{m}"].start for m in MUSCLES] for k in ("len", "vel")}
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, lab.hold.state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_forward(model, data)
    ref = data.sensordata[cols["len"]].copy()
    n, n_steps, _ = targets.shape
    hist = {k: np.empty((n, n_steps, len(MUSCLES))) for k in cols}
    state, out = np.tile(lab.hold.state, (n, 1)), []

    def lagged(k: str, c0: int, c1: int, lag: int, before) -> np.ndarray:
        i = np.arange(c0, c1) - lag
        return np.where((i >= 0)[None, :, None], hist[k][:, np.maximum(i, 0)], before)

    for c0 in range(0, n_steps, lags[0]):
        c1 = min(n_steps, c0 + lags[0])
        u = reflex_command(
            base,
            np.stack([lagged("len", c0, c1, lag, ref) for lag in lags]),
            np.stack([lagged("vel", c0, c1, lag, 0.0) for lag in lags]),
            ref,
            reflex,
        )
        ctrl = np.zeros((n, c1 - c0, model.nu))
        ctrl[:, :, scene.robot_act] = targets[:, c0:c1]
        ctrl[:, :, scene.muscle_act] = u
        states, sd = rollout.rollout(model, mujoco.MjData(model), state, ctrl)
        for k in cols:
            hist[k][:, c0:c1] = sd[:, :, cols[k]]
        state = states[:, -1]
        out.append(sd)
    return np.concatenate(out, axis=1)[:, SUBSTEPS - 1 :: SUBSTEPS]


def _five_ramps(lab) -> np.ndarray:
    """Five trials whose targets ramp differently (joints 1-3, both signs, three rates)."""
    t = np.arange(N_STEPS) * DT
    targets = _hold_targets(lab, 5)
    for i, (joint, rate) in enumerate([(0, 2.0), (1, -2.0), (2, 1.0), (0, -1.0), (1, 3.0)]):
        targets[i, :, joint] += rate * t**2
    return targets


@pytest.mark.parametrize(("nthread", "n_trials"), [(1, 2), (2, 2), (2, 5), (3, 5)])
def test_shared_out_trials_equal_a_plain_serial_loop(lab, nthread, n_trials):
    # each thread steps its own contiguous share of the trials (shares of 1, 2 or 3 trials, one
    # trial alone included), keeping its samples between its chunks: the record must equal a plain
    # loop over all trials bit for bit (0.2 s = five 35 ms reflex chunks and a shorter last one)
    targets = _ramped_targets(lab) if n_trials == 2 else _five_ramps(lab)
    base, reflex = lab.hold.activation, ReflexConfig()
    res = simulate(lab.scene, lab.hold.state, targets, base, reflex, substeps=SUBSTEPS, nthread=nthread)
    assert_array_equal(res.sensordata, _serial_reference(lab, targets, base, reflex))
    assert not np.array_equal(res.qpos[0], res.qpos[1])  # the trials differ


def test_kept_part_equals_the_same_columns_of_everything(lab):
    from armlab.sim.rollout import Kept

    args = (lab.scene, lab.hold.state, _ramped_targets(lab), lab.hold.activation, ReflexConfig())
    full = simulate(*args, substeps=SUBSTEPS)
    names = ("ft_torque", "p_hand", "lwr_q3", "lwr_q2")  # out of the scene's order: kept in it
    kept = simulate(*args, substeps=SUBSTEPS, kept=Kept(sensors=names, qpos=(1, 0), muscle_ctrl=False))
    for name in names:
        assert_array_equal(
            kept.readout.sensor(kept.sensordata, name), lab.scene.sensor(full.sensordata, name)
        )
    assert kept.sensordata.shape[-1] == 3 + 3 + 1 + 1
    # neighbours in the scene stay neighbours: a view, not a copy
    both = kept.readout.sensors_of(kept.sensordata, ["lwr_q2", "lwr_q3"])
    assert both.base is not None
    assert_array_equal(both, lab.scene.sensors_of(full.sensordata, ["lwr_q2", "lwr_q3"]))
    assert_array_equal(kept.qpos, full.qpos[..., [1, 0]])  # in the order asked
    assert kept.muscle_ctrl is None
    assert_array_equal(kept.activation, full.activation)


def test_kept_sensor_the_scene_lacks_is_refused_by_name(lab):
    from armlab.errors import SimulationError
    from armlab.sim.rollout import Kept

    with pytest.raises(SimulationError, match=r"\['p_nowhere'\].*valid: \[.*'ft_force'"):
        simulate(
            lab.scene,
            lab.hold.state,
            _ramped_targets(lab),
            lab.hold.activation,
            ReflexConfig(),
            substeps=SUBSTEPS,
            kept=Kept(sensors=("ft_force", "p_nowhere")),
        )


def test_the_failure_named_is_the_one_a_check_of_every_row_finds_first():
    # the shares step independently, so a later share may fail first in wall time; the error must
    # still name what one check of all rows, chunk by chunk, finds first: the earliest chunk, then
    # a bad state before a warning alone, then the earliest step, then the lowest row
    from armlab.sim.rollout import _Stop
    from armlab.sim.stability import RolloutFailure

    t = np.arange(1, 11) * 1e-3
    stop = _Stop()
    stop.fail(3, RolloutFailure(5, 7, "late step"), t)
    stop.fail(3, RolloutFailure(400, 2, "early step"), t)
    stop.fail(3, RolloutFailure(None, 10, "warned only"), t)
    assert stop.first()[0].quantity == "early step" and stop.chunk == 3
    stop.fail(3, RolloutFailure(1, 2, "same step, lower row"), t)
    assert stop.first()[0].trial == 1
    stop.fail(2, RolloutFailure(None, 10, "earlier chunk"), t)
    assert stop.first()[0].quantity == "earlier chunk" and stop.chunk == 2


def test_a_batch_of_no_steps_records_no_samples(lab):
    res = simulate(
        lab.scene, lab.hold.state, np.zeros((2, 0, 7)), lab.hold.activation, ReflexConfig(), substeps=2
    )
    assert res.sensordata.shape == (2, 0, lab.scene.model.nsensordata) and res.qpos.shape[:2] == (2, 0)


def test_trials_sharing_a_path_read_it_by_row(lab):
    # target_rows: trials follow rows of a table of paths (the lab's (direction, T_k) pairs)
    paths = _ramped_targets(lab)
    rows = np.array([1, 0, 1])
    args = (lab.scene, lab.hold.state)
    by_row = simulate(*args, paths, lab.hold.activation, ReflexConfig(), substeps=SUBSTEPS, target_rows=rows)
    copied = simulate(*args, paths[rows], lab.hold.activation, ReflexConfig(), substeps=SUBSTEPS)
    assert by_row.sensordata.shape[0] == 3
    assert_array_equal(by_row.sensordata, copied.sensordata)
    assert_array_equal(by_row.qpos, copied.qpos)


@pytest.mark.parametrize("rows", [np.array([0, 2]), np.array([-1]), np.array([[0]]), np.array([0.0])])
def test_target_rows_outside_the_paths_are_refused(lab, rows):
    from armlab.errors import SimulationError

    with pytest.raises(SimulationError, match="target_rows"):
        simulate(
            lab.scene,
            lab.hold.state,
            _ramped_targets(lab),
            lab.hold.activation,
            ReflexConfig(),
            substeps=SUBSTEPS,
            target_rows=rows,
        )


def test_first_bad_step_finds_a_non_finite_state_and_a_clock_that_jumped():
    from armlab.sim._chunk_kernel import first_bad_step

    dt, n, m = 5e-4, 3, 4
    time_in = np.array([0.1, 0.2, 0.3])
    states = np.zeros((n, m, 5))
    states[..., 0] = time_in[:, None] + dt * np.arange(1, m + 1)
    assert first_bad_step(time_in, states, dt) == -1
    bad = states.copy()
    bad[2, 1, 3] = np.nan
    assert first_bad_step(time_in, bad, dt) == 2 * m + 1
    bad[1, 3, 4] = np.inf
    assert first_bad_step(time_in, bad, dt) == 1 * m + 3
    reset = states.copy()
    reset[0, 2, 0] = 0.0  # MuJoCo reset trial 0's state: its clock starts again
    assert first_bad_step(time_in, reset, dt) == 2
    late = states.copy()
    late[1, 0, 0] += 0.6 * dt  # more than half a step off the clock
    assert first_bad_step(time_in, late, dt) == m


@pytest.mark.parametrize(
    ("base_shape", "hold"),
    [((1, 1, 6), 1), ((3, 1, 6), 1), ((3, 30, 6), 1), ((3, 10, 6), 3), ((3, 15, 6), 2)],
)
def test_compiled_reflex_commands_equal_reflex_command_bit_for_bit(base_shape, hold):
    # the kernel reads a ring of the last steps (step j in row j % depth) and the steady state before
    # step 0; reflex_command reads the same values gathered into arrays. Random stretch of both signs,
    # a base that makes some commands clip at 0 and 1, chunks before, across and after step 0's lags;
    # a per-step base whose rows each hold `hold` steps (one command per sample of `hold` steps).
    from armlab.sim._chunk_kernel import muscle_commands, store_history
    from armlab.sim.rollout import REFLEX_LENGTH_SCALE_M, reflex_command

    rng = np.random.default_rng(5)
    n, n_steps, lag_s, lag_sp = 3, 30, 4, 9
    reflex = ReflexConfig(stretch_gain=0.7, velocity_gain=0.03, spinal_gain=0.4)
    ref = 0.1 + 0.01 * rng.random(6)
    lengths = ref + 0.02 * rng.standard_normal((n, n_steps, 6))
    velocities = 0.5 * rng.standard_normal((n, n_steps, 6))
    base = rng.uniform(-0.1, 1.1, base_shape)
    ring = np.empty((n, lag_sp + lag_s, 12))
    cols = np.array([7, 1, 3, 0, 5, 2])  # muscle actuators' columns of ctrl, in muscle order

    def lagged(x, t, lag, before):
        return np.where((t - lag >= 0)[None, :, None], x[:, np.maximum(t - lag, 0)], before)

    for c0 in range(0, n_steps, lag_s):
        t = np.arange(c0, min(n_steps, c0 + lag_s))
        ctrl = np.full((n, t.size, 8), -1.0)
        muscle_commands(
            ctrl,
            cols,
            base,
            hold,
            c0,
            ring,
            lag_s,
            lag_sp,
            ref,
            REFLEX_LENGTH_SCALE_M,
            reflex.stretch_gain,
            reflex.velocity_gain,
            reflex.spinal_gain,
        )
        b = base[:, t // hold] if base_shape[1] > 1 else base
        expected = reflex_command(
            b,
            np.stack([lagged(lengths, t, lag, ref) for lag in (lag_s, lag_sp)]),
            np.stack([lagged(velocities, t, lag, 0.0) for lag in (lag_s, lag_sp)]),
            ref,
            reflex,
        )
        assert_array_equal(ctrl[:, :, cols], np.broadcast_to(expected, (n, t.size, 6)))
        assert np.all(np.delete(ctrl, cols, axis=2) == -1.0)  # the other actuators untouched
        sd = np.concatenate([lengths[:, t], velocities[:, t]], axis=2)  # this chunk's "sensordata"
        store_history(ring, sd, np.arange(12), c0)
    assert np.any(expected == 0.0) or np.any(expected == 1.0)  # the clip was exercised


def test_the_preload_loads_every_kernel_in_the_types_the_simulation_passes(lab):
    # Protocol.preload (armlab.sim.lab.load_compiled) is only worth its thread if the simulation
    # then finds its kernels ready: it must not need another compiled signature
    from armlab.models import _fk_kernel
    from armlab.models.robot_fk import RobotKinematics
    from armlab.sim import _chunk_kernel
    from armlab.sim.lab import load_compiled

    kernels = [getattr(_chunk_kernel, n) for n in _chunk_kernel.__all__ if n != "load"] + [_fk_kernel.chain]
    load_compiled()
    loaded = [list(k.signatures) for k in kernels]
    assert all(loaded)
    res = simulate(
        lab.scene, lab.hold.state, _ramped_targets(lab), lab.hold.activation, ReflexConfig(), substeps=2
    )
    encoders = lab.scene.sensors_of(res.sensordata, [f"lwr_q{i}" for i in range(1, 8)])
    RobotKinematics.from_scene(lab.scene).forward(encoders)
    assert [list(k.signatures) for k in kernels] == loaded


def test_held_rows_equal_the_repeated_commands():
    # without a reflex each chunk copies its steps of a per-sample base held over `hold` steps; the
    # slice must equal the (n, n_steps, k) repeat it replaces, for chunks cut anywhere in a sample
    from armlab.sim.rollout import _held_rows

    base = np.random.default_rng(2).random((2, 7, 3))
    for hold in (1, 2, 3):
        full = np.repeat(base, hold, axis=1)
        n_steps = full.shape[1] - (hold - 1)  # the last sample held only partly
        for c0 in range(n_steps):
            for c1 in range(c0 + 1, n_steps + 1):
                assert_array_equal(_held_rows(base, hold, c0, c1), full[:, c0:c1])
