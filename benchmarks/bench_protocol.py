"""Benchmark of the conditioning-window protocol (issue 2 targets; run by `make bench`).

Reports: wall time of the full protocol (780 trials, 29 windows, all outputs; target < 30 s on a
2-core machine), simulated seconds per wall second against a bare ``mujoco.rollout`` of the same
scene and control length (the engine's limit), and the time of estimating all windows against the
longest single window (target <= 2x).
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from armlab.data.h5io import read_trials
from armlab.estimation.joint_ls import estimate, estimate_windows
from armlab.estimation.processing import ProcessingConfig, joint_signals
from armlab.models.scene import build_scene
from armlab.perturbations.scenario import load_scenario
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.experiment import window_specs
from armlab.runner.run import run_protocol
from armlab.sim.hold import settle


def _mean_time(fn, reps: int = 20) -> float:
    """Mean wall time of ``fn()`` in s over ``reps`` calls."""
    t0 = time.perf_counter()
    for _ in range(reps):
        fn()
    return (time.perf_counter() - t0) / reps


def main() -> None:
    cfg = ConditioningWindowConfig()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = run_protocol(cfg, Path(tmp) / "run")
        wall = time.perf_counter() - t0
        tr = read_trials(Path(tmp) / "run" / "trials.h5")  # the run's own trials: no second simulation
    tim = res["timing"]
    sim_s = res["simulated_s"]
    print(
        f"full protocol: {wall:.1f} s wall (target < 30 s); simulate {tim['simulate_s']:.1f} s, "
        f"estimate {tim['estimate_s']:.2f} s, outputs {tim['outputs_s']:.1f} s"
    )
    print(f"simulation: {sim_s / tim['simulate_s']:.1f} simulated s per wall s")

    scene = build_scene(cfg.arm, cfg.cuff, cfg.robot, cfg.sim)
    hold = settle(scene, cfg.arm, cfg.sim.settle_s)
    n = tr.n_trials
    nstep = int(round(sim_s / n / scene.model.opt.timestep))
    ctrl = np.broadcast_to(hold.ctrl, (n, nstep, scene.model.nu))
    data = [mujoco.MjData(scene.model) for _ in range(os.cpu_count() or 1)]  # as armlab's rollout
    t1 = time.perf_counter()
    rollout.rollout(scene.model, data, np.tile(hold.state, (n, 1)), ctrl)
    bare = time.perf_counter() - t1
    print(
        f"bare mujoco.rollout of the same scene and length: {bare:.1f} s "
        f"-> armlab simulation at {bare / tim['simulate_s']:.2f} of the engine's limit"
    )

    scenario = load_scenario(cfg.scenario.name)
    sig = joint_signals(
        tr.channel("hand_pos"),
        tr.channel("hand_force"),
        tr.fs_hz,
        tr.onset_index,
        tr.attrs["arm_l1_m"],
        tr.attrs["arm_l2_m"],
        ProcessingConfig(lowpass_hz=20.0),
    )
    specs = window_specs(scenario, cfg.estimator)
    group, val = tr.trial_meta["group"], tr.trial_meta["validate"]
    masks = np.stack([(group == s.k) & ~val for s in specs])
    wins = np.array([int(round(s.t_obs_s * tr.fs_hz)) for s in specs])
    longest = int(np.argmax(wins))
    all_w = _mean_time(lambda: estimate_windows(sig, masks, wins))
    one_qr = _mean_time(lambda: estimate(sig, masks[longest], int(wins[longest])))
    one_ne = _mean_time(
        lambda: estimate_windows(sig, masks[longest : longest + 1], wins[longest : longest + 1])
    )
    # Samples each window's data holds; the extension windows reuse the longest group's trials.
    used = np.max(np.where(masks, wins[:, None], 0), axis=0).sum()
    data_ratio = used / (masks[longest].sum() * wins[longest])
    print(
        f"estimation: all {len(specs)} windows {all_w * 1e3:.1f} ms; longest single window "
        f"({wins[longest]} samples) by estimate() {one_qr * 1e3:.1f} ms -> ratio {all_w / one_qr:.1f} "
        f"(target <= 2); by the same batched solver {one_ne * 1e3:.2f} ms -> ratio {all_w / one_ne:.1f}; "
        f"the windows hold {data_ratio:.1f}x the longest window's samples (disjoint trial groups)"
    )
    nested = np.repeat(masks[longest : longest + 1], len(wins), axis=0)
    all_nested = _mean_time(lambda: estimate_windows(sig, nested, wins))
    print(
        f"estimation, all {len(specs)} windows on one shared trial group: {all_nested * 1e3:.1f} ms "
        f"-> ratio {all_nested / one_qr:.1f} against estimate() of the longest"
    )


if __name__ == "__main__":
    main()
