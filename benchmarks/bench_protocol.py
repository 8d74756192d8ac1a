"""Benchmark of the conditioning-window protocol (issues 2 and 21; run by `make bench`).

Prints each budget and ratio as ``<what>: <value> (target <op> <value>) OK|MISSED``:

- the full protocol (780 trials, 29 windows, trial file, figures and recording): <= 15 s wall on
  the 2-core machine (issue 21);
- its simulation against a bare ``mujoco.rollout`` of the same scene, trials, steps and thread
  count, in this process, under the same memory policy (the run's
  :func:`armlab.runner.memory.small_pages`): >= 0.9 (issue 21). The simulation is everything the
  simulate stage does to produce the trials' trajectories: build and settle the scene, solve the
  robot paths, draw the subject, and step the trials as the run does it (the reflex chunks, their
  controls, the state checks, the kept samples). The bare call only steps the settled state with
  its hold controls. Each side is timed twice, interleaved (the run's simulation, one bare call,
  the protocol's simulation again, the bare steps in reflex-length chunks), and the faster of each
  pair is compared, so a slow spell of a shared machine during one of them does not decide the
  ratio; every time is printed. The stage's remaining part, the measurement (the sensor models
  and the kinematics of the readings, which no rollout does), is printed beside it with the
  stepping alone, for information;
- the outputs (trial file, figures and recording): <= 3 s (issue 21);
- estimating all windows against the longest single window: <= 2x (issue 2).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from armlab.cpus import usable_cpus
from armlab.data.h5io import read_trials
from armlab.estimation.joint_ls import estimate, estimate_windows
from armlab.estimation.processing import ProcessingConfig, joint_signals
from armlab.models.scene import build_scene
from armlab.perturbations.scenario import load_scenario
from armlab.protocols import registry
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.experiment import window_specs
from armlab.runner.memory import small_pages
from armlab.runner.run import run_protocol
from armlab.sim.hold import settle


def _mean_time(fn, reps: int = 20) -> float:
    """Mean wall time of ``fn()`` in s over ``reps`` calls."""
    t0 = time.perf_counter()
    for _ in range(reps):
        fn()
    return (time.perf_counter() - t0) / reps


TOTAL_S = 15.0  # s, issue 21: the conditioning protocol with figures and recording
SIM_RATIO = 0.9  # issue 21: protocol simulation against a bare mujoco.rollout, same threads
OUTPUTS_S = 3.0  # s, issue 21: figures + recording (here also the trial file)
ESTIMATE_RATIO = 2.0  # issue 2: all windows against the longest single window


def _verdict(what: str, value: float, op: str, target: float, fmt: str = ".2f", unit: str = "") -> str:
    ok = value <= target if op == "<=" else value >= target
    return f"{what}: {value:{fmt}}{unit} (target {op} {target:g}{unit}) {'OK' if ok else 'MISSED'}"


def _timed(module, name: str) -> list[float]:
    """Time every call of ``module.name`` from now on (wall s of each, appended to the list)."""
    times: list[float] = []
    fn = getattr(module, name)

    def timed(*args, **kwargs):
        t = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            times.append(time.perf_counter() - t)

    setattr(module, name, timed)
    return times


def main() -> None:
    import armlab.sim.lab as lab

    cfg = ConditioningWindowConfig()
    # the lab's batched rollout (armlab.sim.rollout.simulate): the stepping loop alone
    stepping = _timed(lab, "simulate")
    # the measurement after it: the force bound, the sensor models, the readings' kinematics
    measuring = [_timed(lab, n) for n in ("check_bound", "measure", "_forward_by_halves")]
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = run_protocol(cfg, Path(tmp) / "run")
        wall = time.perf_counter() - t0
        tr = read_trials(Path(tmp) / "run" / "trials.h5")  # the run's own trials: no second simulation
    tim = res["timing"]
    sim_s = res["simulated_s"]
    print(
        f"full protocol: {wall:.1f} s wall; simulate {tim['simulate_s']:.1f} s, "
        f"estimate {tim['estimate_s']:.2f} s, outputs {tim['outputs_s']:.1f} s; "
        f"{sim_s / tim['simulate_s']:.1f} simulated s per wall s"
    )

    scene = build_scene(cfg.arm, cfg.cuff, cfg.robot, cfg.sim)
    hold = settle(scene, cfg.arm, cfg.sim.settle_s)
    n = tr.n_trials
    nstep = int(round(sim_s / n / scene.model.opt.timestep))
    ctrl = np.broadcast_to(hold.ctrl, (n, nstep, scene.model.nu))
    nthread = usable_cpus()  # armlab's rollout default (armlab.sim.rollout.simulate)
    data = [mujoco.MjData(scene.model) for _ in range(nthread)]
    with small_pages():  # the run's memory policy (without it the first touch of the 1 GB output stalls)
        t1 = time.perf_counter()
        outputs = rollout.rollout(scene.model, data, np.tile(hold.state, (n, 1)), ctrl)
        one_call = time.perf_counter() - t1
        del outputs

    # the protocol's simulation a second time, as the run's simulate stage calls it
    protocol = registry.get(cfg.protocol_name, need="run")
    with small_pages():
        t1 = time.perf_counter()
        again = protocol.simulate(cfg)
        stage_again = time.perf_counter() - t1
        del again

    # the same steps as the engine runs fastest here: chunks of the reflex latency's length into
    # reused output buffers (as armlab does), no Python between them
    chunk = int(round(cfg.reflex.stretch_latency_s / scene.model.opt.timestep))
    bufs = {}
    state = np.tile(hold.state, (n, 1))
    t1 = time.perf_counter()
    with small_pages(), rollout.Rollout(nthread=nthread) as runner:
        for c0 in range(0, nstep, chunk):
            m = min(nstep, c0 + chunk) - c0
            if m not in bufs:
                bufs[m] = [np.empty((n, m, k)) for k in (len(hold.state), scene.model.nsensordata)]
            st, sd = bufs[m]
            runner.rollout(scene.model, data, state, ctrl[:, :m], state=st, sensordata=sd)
            state = np.ascontiguousarray(st[:, -1])
    chunked = time.perf_counter() - t1
    bare = min(one_call, chunked)
    print(
        f"bare mujoco.rollout, {n} trials x {nstep} steps, {nthread} threads: one call {one_call:.1f} s, "
        f"in {chunk}-step chunks {chunked:.1f} s; reference: the faster, {bare:.1f} s"
    )
    print(_verdict("conditioning protocol total", wall, "<=", TOTAL_S, ".1f", " s"))
    # each timer holds one entry per simulation: the run's, then the second
    stages = [tim["simulate_s"], stage_again]
    measured = [sum(t[i] for t in measuring) for i in range(2)]
    simulations = [stage - m for stage, m in zip(stages, measured, strict=True)]
    best = int(np.argmin(simulations))
    print(
        f"protocol simulation (scene, settling, robot paths, subject, stepping): in the run "
        f"{simulations[0]:.1f} s, again {simulations[1]:.1f} s; the faster, {simulations[best]:.1f} s"
    )
    print(
        _verdict(
            f"simulation ({simulations[best]:.1f} s) / bare rollout ({bare:.1f} s, {nthread} threads)",
            bare / simulations[best],
            ">=",
            SIM_RATIO,
        )
    )
    print(
        f"  (for information, in that simulation: the stepping alone, {stepping[best]:.1f} s, is "
        f"{bare / stepping[best]:.2f}x the bare rollout; the measurement after it, {measured[best]:.2f} s, "
        f"models the sensors and the kinematics of the readings; the whole simulate stage, "
        f"{stages[best]:.1f} s, is {bare / stages[best]:.2f}x the bare rollout)"
    )
    print(
        _verdict("outputs (trials.h5 + figures + recording)", tim["outputs_s"], "<=", OUTPUTS_S, ".1f", " s")
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
        f"({wins[longest]} samples) by estimate() {one_qr * 1e3:.1f} ms; by the same batched solver "
        f"{one_ne * 1e3:.2f} ms -> ratio {all_w / one_ne:.1f}; the windows hold {data_ratio:.1f}x the "
        "longest window's samples (disjoint trial groups)"
    )
    print(
        _verdict(
            "estimation all windows / longest window by estimate()",
            all_w / one_qr,
            "<=",
            ESTIMATE_RATIO,
            ".1f",
        )
    )
    nested = np.repeat(masks[longest : longest + 1], len(wins), axis=0)
    all_nested = _mean_time(lambda: estimate_windows(sig, nested, wins))
    print(
        f"estimation, all {len(specs)} windows on one shared trial group: {all_nested * 1e3:.1f} ms "
        f"-> ratio {all_nested / one_qr:.1f} against estimate() of the longest"
    )


if __name__ == "__main__":
    main()
