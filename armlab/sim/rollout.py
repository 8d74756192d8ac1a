"""Batched simulation of many trials with ``mujoco.rollout`` and a delayed stretch reflex.

MuJoCo steps every trial of a run in one threaded ``rollout`` call per chunk. The reflex is a
feedback from muscle stretch to activation with latency >= ``stretch_latency_s`` (paper II-B,
Fig. 1), so the control of a chunk no longer than that latency depends only on states already
simulated: between chunks, compiled loops (:mod:`armlab.sim._chunk_kernel`) compute the next
chunk's muscle commands for all trials at once.
This is exact (no approximation of the delay) and keeps Python out of the per-step loop.

The batch is split into one contiguous share of trials per thread, and each thread steps its
share chunk after chunk on its own (MuJoCo's rollout on the calling thread, without the GIL, then
the compiled loops and the copy of the kept samples): no core waits while the other computes the
next chunk's commands. Every trial sees the same operations in the same order whatever the split,
so the trajectories are bit-identical to a serial loop over all trials.
"""

from __future__ import annotations

import threading
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from armlab import progress
from armlab.config.schema import ReflexConfig
from armlab.cpus import usable_cpus
from armlab.errors import SimulationError
from armlab.models.scene import MUSCLES, Scene, SensorReadout
from armlab.sim import _chunk_kernel as kernel
from armlab.sim.stability import RolloutFailure, TrialLabels, failure_error, rollout_failure, warning_counts

__all__ = [
    "REFLEX_LENGTH_SCALE_M",
    "Kept",
    "KeptSensors",
    "SimResult",
    "reflex_command",
    "simulate",
]

# m, normalisation of muscle stretch in the reflex law: the optimal fibre length L0 = 0.10 m of
# the arm's muscles (models/arm_planar/arm_planar_hill.xml).
REFLEX_LENGTH_SCALE_M = 0.10
_CHUNK_NO_REFLEX = 400  # steps per rollout call without reflex (bounds memory only)


@dataclass(frozen=True, kw_only=True)
class Kept:
    """What :func:`simulate` keeps of every sample (default: all of it).

    A caller that reads only part saves copying and holding the rest: the conditioning lab keeps
    neither the muscle lengths and velocities (only the reflex reads them) nor the commands, and of
    the positions only the arm's two joint angles.

    Attributes:
        sensors: names of the scene's sensors (:attr:`Scene.sensors`); None: every sensor.
        qpos: qpos addresses, kept in this order; None: every one.
        muscle_ctrl: keep the muscle commands.
    """

    sensors: tuple[str, ...] | None = None
    qpos: tuple[int, ...] | None = None
    muscle_ctrl: bool = True


@dataclass(frozen=True, kw_only=True)
class KeptSensors(SensorReadout):
    """Named reads of :attr:`SimResult.sensordata` (``sensor(sd, name)``, ``sensors_of``).

    Attributes:
        sensors: kept sensor name -> slice of the kept values, in the scene's order (sensors
            side by side in the scene stay side by side, so ``sensors_of`` returns views).
    """

    sensors: dict[str, slice] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True, eq=False)
class SimResult:
    """Clean (noise-free) simulated signals at the sampling rate.

    Attributes:
        sensordata: (n_trials, n_samples, n_kept) the kept MuJoCo sensor values (all
            ``nsensordata`` by default), one sample every ``substeps`` physics steps (the value
            after the sample's last step); ``readout`` names them.
        readout: where each kept sensor lies in ``sensordata``.
        activation: (n_trials, n_samples, 6) muscle activations (MuJoCo ``act``).
        muscle_ctrl: (n_trials, n_samples, 6) muscle commands (co-contraction + reflex); None
            where not kept.
        qpos: (n_trials, n_samples, n_kept_q) the kept generalised positions (all nq by default).
        fs_hz: Hz, sample rate.
    """

    sensordata: np.ndarray
    readout: KeptSensors
    activation: np.ndarray
    muscle_ctrl: np.ndarray | None
    qpos: np.ndarray
    fs_hz: float


def reflex_command(
    base: np.ndarray,
    length: np.ndarray,
    velocity: np.ndarray,
    ref: np.ndarray,
    cfg: ReflexConfig,
) -> np.ndarray:
    """Muscle commands from delayed stretch (arrays already indexed at t - latency).

    ``length``/``velocity`` are (2, ..., n_muscles): [stretch-lagged, spinal-lagged] (the batched
    rollout passes (2, n_trials, n_steps, 6), the force-control loop (2, 2) per step).
    """
    stretch_s = (length[0] - ref) / REFLEX_LENGTH_SCALE_M
    rate_s = velocity[0] / REFLEX_LENGTH_SCALE_M
    stretch_sp = (length[1] - ref) / REFLEX_LENGTH_SCALE_M
    u = (
        base
        + cfg.stretch_gain * np.maximum(stretch_s, 0.0)
        + cfg.velocity_gain * np.maximum(rate_s, 0.0)
        + cfg.spinal_gain * np.maximum(stretch_sp, 0.0)
    )
    return np.clip(u, 0.0, 1.0)


class _ChunkBuffers:
    """Contiguous control, state and sensor arrays of a rollout chunk, reused chunk after chunk
    (no allocation, no page faults per chunk)."""

    def __init__(self, n_trials: int, nu: int, nstate: int, nsd: int) -> None:
        self._shape = (n_trials, nu, nstate, nsd)
        self._sets: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def get(self, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(ctrl (n, m, nu), state (n, m, nstate), sensordata (n, m, nsd)); a shorter last chunk
        gets its own arrays (the rollout needs contiguous ones of exactly m steps)."""
        if m not in self._sets:
            n, nu, nstate, nsd = self._shape
            self._sets[m] = (np.zeros((n, m, nu)), np.empty((n, m, nstate)), np.empty((n, m, nsd)))
        return self._sets[m]


def _as_slice(cols: np.ndarray) -> slice | np.ndarray:
    """``cols`` as a slice when they are consecutive ascending indices (same elements, in order)."""
    cols = np.asarray(cols)
    if cols.size and np.array_equal(cols, np.arange(cols[0], cols[0] + cols.size)):
        return slice(int(cols[0]), int(cols[0]) + cols.size)
    return cols


def _runs(cols: np.ndarray) -> list[tuple[slice, slice]]:
    """(source, destination) slices of the runs of consecutive ascending ``cols``, the
    destinations one after the other: the gather ``out[..., :] = src[..., cols]`` as slice copies."""
    runs, d0 = [], 0
    for part in np.split(np.asarray(cols, dtype=np.intp), np.flatnonzero(np.diff(cols) != 1) + 1):
        if part.size:
            runs.append((slice(int(part[0]), int(part[-1]) + 1), slice(d0, d0 + part.size)))
            d0 += part.size
    return runs


def _kept_sensors(scene: Scene, names: tuple[str, ...] | None) -> tuple[KeptSensors, np.ndarray]:
    """The kept sensors' layout and their columns of MuJoCo's sensordata (in the scene's order)."""
    if names is None:
        names = tuple(scene.sensors)
    unknown = sorted(set(names) - set(scene.sensors))
    if unknown:
        raise SimulationError(
            f"Kept.sensors names {unknown}, not sensors of the scene; valid: {sorted(scene.sensors)}"
        )
    spans = sorted({n: scene.sensors[n] for n in names}.items(), key=lambda kv: kv[1].start)
    layout, cols, d0 = {}, [], 0
    for name, span in spans:
        width = span.stop - span.start
        layout[name] = slice(d0, d0 + width)
        cols.append(np.arange(span.start, span.stop))
        d0 += width
    return KeptSensors(sensors=layout), np.concatenate(cols) if cols else np.zeros(0, np.intp)


def _held_rows(base: np.ndarray, hold: int, c0: int, c1: int) -> np.ndarray:
    """Steps [c0, c1) of ``base`` (n, rows, k) whose rows each hold ``hold`` steps: (n, c1 - c0, k)."""
    r0, r1 = c0 // hold, -(-c1 // hold)
    return np.repeat(base[:, r0:r1], hold, axis=1)[:, c0 - r0 * hold : c1 - r0 * hold]


def _shares(n_trials: int, n_threads: int) -> list[slice]:
    """Contiguous shares of the rows, one per thread, their sizes differing by at most one."""
    k = max(1, min(n_threads, n_trials))
    edges = np.linspace(0, n_trials, k + 1).round().astype(int)
    return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True) if b > a]


class _Stop:
    """The chunk at which the shares stop: the earliest one in which a share failed (the other
    shares still step and check up to it, so the failure named is the batch's first)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.chunk = np.inf
        self.failures: list[tuple[int, RolloutFailure, np.ndarray]] = []

    def fail(
        self, chunk: int, failure: RolloutFailure | None = None, t_steps: np.ndarray | None = None
    ) -> None:
        with self._lock:
            self.chunk = min(self.chunk, chunk)
            if failure is not None:
                self.failures.append((chunk, failure, t_steps))

    def first(self) -> tuple[RolloutFailure, np.ndarray] | None:
        """The failure a check of every row chunk by chunk would have found first."""
        if not self.failures:
            return None
        _, failure, t_steps = min(self.failures, key=lambda f: (f[0], *f[1].order))
        return failure, t_steps


def simulate(
    scene: Scene,
    initial_state: np.ndarray,
    robot_targets: np.ndarray,
    muscle_base: np.ndarray,
    reflex: ReflexConfig,
    *,
    substeps: int,
    nthread: int | None = None,
    who: TrialLabels | None = None,
    target_rows: np.ndarray | None = None,
    kept: Kept | None = None,
) -> SimResult:
    """Simulate a batch of trials from one settled state.

    Args:
        scene: the composed scene.
        initial_state: (nstate,) full-physics state every trial starts from.
        robot_targets: (n_trials, n_steps, 7) rad robot joint targets at every physics step, or
            (n_paths, n_steps, 7) with ``target_rows``.
        muscle_base: (6,) activation commands without reflex, or (n_trials, ceil(n_steps / substeps), 6)
            per trial and sample, each held over the sample's ``substeps`` physics steps (a subject
            whose activation fluctuates, see :mod:`armlab.sim.subject`).
        reflex: reflex pathways (``enabled=False`` for none).
        substeps: physics steps per recorded sample.
        nthread: threads, each stepping its own share of the trials (default: the usable cores).
        who: the trials, named in a :class:`SimulationError` (default: "row <i> of the batch").
        target_rows: (n_trials,) the row of ``robot_targets`` each trial follows (trials sharing
            a path share a row: each chunk gathers its targets, no (n_trials, n_steps, 7) copy);
            None: row i for trial i.
        kept: what to keep of every sample (default: everything).

    Returns:
        The clean signals, sampled every ``substeps`` steps.

    Raises:
        SimulationError: a trial diverged (MuJoCo warned or reset its state; :mod:`.stability`),
            or ``kept`` names a sensor the scene lacks.
    """
    model = scene.model
    _, n_steps, _ = robot_targets.shape
    if target_rows is None:
        n_trials = robot_targets.shape[0]
        rows = np.arange(n_trials, dtype=np.intp)
    else:
        target_rows = np.asarray(target_rows)
        n_paths = robot_targets.shape[0]
        if target_rows.ndim != 1 or target_rows.dtype.kind not in "iu":
            raise SimulationError(f"target_rows must be a 1-D array of row indices, got {target_rows!r}")
        if target_rows.size and not (target_rows.min() >= 0 and target_rows.max() < n_paths):
            raise SimulationError(
                f"target_rows must index the {n_paths} rows of robot_targets (0..{n_paths - 1}), "
                f"got rows {target_rows.min()}..{target_rows.max()}"
            )
        n_trials = target_rows.size
        rows = np.ascontiguousarray(target_rows, dtype=np.intp)
    muscle_base = np.asarray(muscle_base, float)
    per_step = muscle_base.ndim == 3
    n_rows = -(-n_steps // substeps)  # the samples the steps reach (the kernel reads row step // substeps)
    if per_step and muscle_base.shape != (n_trials, n_rows, len(MUSCLES)):
        raise SimulationError(
            f"muscle_base must be ({len(MUSCLES)},) or {(n_trials, n_rows, len(MUSCLES))} "
            f"(one row per sample of {substeps} physics steps), got {muscle_base.shape}"
        )
    kept = Kept() if kept is None else kept
    readout, sensor_cols = _kept_sensors(scene, kept.sensors)
    sensor_runs = _runs(sensor_cols)
    qpos_runs = _runs(np.arange(model.nq) if kept.qpos is None else np.asarray(kept.qpos, dtype=np.intp))
    dt = model.opt.timestep
    if who is None:
        who = TrialLabels(
            protocol="simulation", labels=tuple(f"row {i} of the batch" for i in range(n_trials)), hint=""
        )
    if reflex.enabled:
        lag_s = int(round(reflex.stretch_latency_s / dt))
        lag_sp = int(round(reflex.spinal_latency_s / dt))
        chunk = max(1, lag_s)
    else:
        lag_s = lag_sp = 0
        chunk = _CHUNK_NO_REFLEX
    len_sl = np.r_[
        tuple(np.arange(scene.sensors[f"len_{m}"].start, scene.sensors[f"len_{m}"].stop) for m in MUSCLES)
    ]
    vel_sl = np.r_[
        tuple(np.arange(scene.sensors[f"vel_{m}"].start, scene.sensors[f"vel_{m}"].stop) for m in MUSCLES)
    ]

    shares = _shares(n_trials, nthread or usable_cpus())
    data = [mujoco.MjData(model) for _ in range(max(1, len(shares)))]
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    mujoco.mj_setState(model, data[0], initial_state, spec)
    mujoco.mj_forward(model, data[0])
    ref_len = data[0].sensordata[len_sl].copy()

    nsd = model.nsensordata
    nstate = mujoco.mj_stateSize(model, spec)
    if np.size(initial_state) != nstate:
        raise SimulationError(
            f"initial_state must hold {nstate} full-physics values, got {np.size(initial_state)}"
        )
    act_cols = 1 + model.nq + model.nv + model.actuator_actadr[scene.muscle_act]  # activations' places
    # consecutive columns as slices: the copies read them without a fancy-index gather
    act_cols = _as_slice(act_cols)
    robot_cols = np.asarray(scene.robot_act, dtype=np.intp)
    muscle_cols = np.asarray(scene.muscle_act, dtype=np.intp)
    n_samples = n_steps // substeps
    sensordata = np.empty((n_trials, n_samples, sensor_cols.size))
    activation = np.empty((n_trials, n_samples, len(MUSCLES)))
    muscle_ctrl = np.empty((n_trials, n_samples, len(MUSCLES))) if kept.muscle_ctrl else None
    qpos = np.empty((n_trials, n_samples, sum(d.stop - d.start for _, d in qpos_runs)))
    # the muscle lengths then velocities of the last steps, as far back as the longest reflex lag
    # reads (step j in row j % depth; the steady state before t = 0 is the kernel's)
    hist = np.empty((n_trials, lag_sp + chunk if reflex.enabled else 0, 2 * len(MUSCLES)))
    hist_cols = np.r_[len_sl, vel_sl].astype(np.intp)
    table = np.ascontiguousarray(robot_targets, dtype=float)
    base3 = muscle_base if per_step else muscle_base.reshape(1, 1, -1)
    starts = range(0, n_steps, chunk)
    stepped = [0] * len(shares)  # the steps each share has stepped and kept
    stop = _Stop()

    def keep(g: slice, c0: int, c1: int, states: np.ndarray, sd: np.ndarray, ctrl: np.ndarray) -> None:
        """Keep the samples of share ``g`` whose last physics step falls in chunk [c0, c1): steps
        c0 + o, c0 + o + substeps, ... (step s ends sample (s + 1) / substeps - 1)."""
        o = (substeps - 1 - c0) % substeps
        s0 = (c0 + o + 1) // substeps - 1
        s1 = min(n_samples, s0 + len(range(o, c1 - c0, substeps)))
        k = slice(o, o + (s1 - s0) * substeps, substeps)
        for src, dst in sensor_runs:
            sensordata[g, s0:s1, dst] = sd[:, k, src]
        activation[g, s0:s1] = states[:, k, act_cols]
        if muscle_ctrl is not None:
            muscle_ctrl[g, s0:s1] = ctrl[:, k, muscle_cols]
        for src, dst in qpos_runs:
            qpos[g, s0:s1, dst] = states[:, k, 1 + src.start : 1 + src.stop]

    def step_share(i: int) -> None:
        """Step share ``i`` through every chunk: its controls, MuJoCo's steps, the check, the
        reflex history and the kept samples, in that order."""
        g = shares[i]
        n = g.stop - g.start
        bufs = _ChunkBuffers(n, model.nu, nstate, nsd)
        state = np.tile(np.asarray(initial_state, float), (n, 1))
        models, share_data = [model] * n, [data[i]]
        share_rows, share_hist = rows[g], hist[g]
        share_base = base3[g] if per_step else base3
        try:
            with mj_rollout.Rollout(nthread=0) as runner:  # on this thread, without the GIL
                for j, c0 in enumerate(starts):
                    if j > stop.chunk:
                        return
                    c1 = min(n_steps, c0 + chunk)
                    ctrl, states, sd = bufs.get(c1 - c0)
                    kernel.robot_targets(ctrl, robot_cols, table, share_rows, c0)
                    if reflex.enabled:  # stretch lagged by >= one chunk: only chunks already stepped
                        kernel.muscle_commands(
                            ctrl,
                            muscle_cols,
                            share_base,
                            substeps,
                            c0,
                            share_hist,
                            lag_s,
                            lag_sp,
                            ref_len,
                            REFLEX_LENGTH_SCALE_M,
                            reflex.stretch_gain,
                            reflex.velocity_gain,
                            reflex.spinal_gain,
                        )
                    else:
                        ctrl[:, :, muscle_cols] = (
                            _held_rows(share_base, substeps, c0, c1) if per_step else share_base
                        )
                    runner.rollout(
                        models,
                        share_data,
                        state,
                        ctrl,
                        nstep=c1 - c0,
                        state=states,
                        sensordata=sd,
                        skip_checks=True,
                    )
                    failure = rollout_failure(state, states, dt, warning_counts(share_data))
                    if failure is not None:
                        if failure.trial is not None:  # a row of the share -> a row of the batch
                            failure = replace(failure, trial=g.start + failure.trial)
                        stop.fail(j, failure, np.arange(c0 + 1, c1 + 1) * dt)
                        return
                    if reflex.enabled:
                        kernel.store_history(share_hist, sd, hist_cols, c0)
                    keep(g, c0, c1, states, sd, ctrl)
                    state = states[:, -1].copy()  # not a view (one trial is contiguous): the buffer is reused
                    stepped[i] = c1
        except BaseException:
            stop.fail(-1)  # the other shares stop at their next chunk
            raise

    # the trials advance together: n_trials * (steps stepped) / n_steps trials' worth
    progress.stage("simulate", n_trials, "trials")
    done = 0.0
    if shares and len(starts):
        with ThreadPoolExecutor(len(shares)) as pool:
            running = [pool.submit(step_share, i) for i in range(len(shares))]
            while running:
                finished, running = wait(running, timeout=0.1, return_when=FIRST_EXCEPTION)
                for f in finished:
                    f.result()  # raises what the share raised
                now = sum((g.stop - g.start) * s / n_steps for g, s in zip(shares, stepped, strict=True))
                progress.advance(now - done)
                done = now
    first = stop.first()
    if first is not None:
        raise failure_error(who, *first)
    return SimResult(
        sensordata=sensordata,
        readout=readout,
        activation=activation,
        muscle_ctrl=muscle_ctrl,
        qpos=qpos,
        fs_hz=1.0 / (dt * substeps),
    )
