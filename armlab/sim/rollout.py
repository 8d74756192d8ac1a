"""Batched simulation of many trials with ``mujoco.rollout`` and a delayed stretch reflex.

MuJoCo steps every trial of a run in one threaded ``rollout`` call per chunk. The reflex is a
feedback from muscle stretch to activation with latency >= ``stretch_latency_s`` (paper II-B,
Fig. 1), so the control of a chunk no longer than that latency depends only on states already
simulated: between chunks, compiled loops (:mod:`armlab.sim._chunk_kernel`) compute the next
chunk's muscle commands for all trials at once.
This is exact (no approximation of the delay) and keeps Python out of the per-step loop.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor, wait
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from armlab import progress
from armlab.config.schema import ReflexConfig
from armlab.cpus import usable_cpus
from armlab.errors import SimulationError
from armlab.models.scene import MUSCLES, Scene
from armlab.sim import _chunk_kernel as kernel
from armlab.sim.stability import TrialLabels, check_rollout, warning_counts

__all__ = [
    "REFLEX_LENGTH_SCALE_M",
    "SimResult",
    "reflex_command",
    "simulate",
]

# m, normalisation of muscle stretch in the reflex law: the optimal fibre length L0 = 0.10 m of
# the arm's muscles (models/arm_planar/arm_planar_hill.xml).
REFLEX_LENGTH_SCALE_M = 0.10
_CHUNK_NO_REFLEX = 400  # steps per rollout call without reflex (bounds memory only)


@dataclass(frozen=True, kw_only=True, eq=False)
class SimResult:
    """Clean (noise-free) simulated signals at the sampling rate.

    Attributes:
        sensordata: (n_trials, n_samples, nsensordata) MuJoCo sensor values, one sample every
            ``substeps`` physics steps (the value after the sample's last step).
        activation: (n_trials, n_samples, 6) muscle activations (MuJoCo ``act``).
        muscle_ctrl: (n_trials, n_samples, 6) muscle commands (co-contraction + reflex).
        qpos: (n_trials, n_samples, nq) generalised positions.
        fs_hz: Hz, sample rate.
    """

    sensordata: np.ndarray
    activation: np.ndarray
    muscle_ctrl: np.ndarray
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
    """Two sets of contiguous control, state and sensor arrays of a rollout chunk, reused across
    chunks (one is stepped into while the other's outputs are read)."""

    def __init__(self, n_trials: int, chunk: int, nu: int, nstate: int, nsd: int) -> None:
        self._shape = (n_trials, nu, nstate, nsd)
        self._sets: dict[tuple[int, int], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def _alloc(self, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n, nu, nstate, nsd = self._shape
        return np.zeros((n, m, nu)), np.empty((n, m, nstate)), np.empty((n, m, nsd))

    def get(self, m: int, which: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Set ``which`` (0 or 1) of (ctrl (n, m, nu), state (n, m, nstate), sensordata (n, m,
        nsd)); a shorter last chunk gets its own arrays (the rollout needs contiguous ones of
        exactly m steps)."""
        key = (m, which)
        if key not in self._sets:
            self._sets[key] = self._alloc(m)
        return self._sets[key]


def _as_slice(cols: np.ndarray) -> slice | np.ndarray:
    """``cols`` as a slice when they are consecutive ascending indices (same elements, in order)."""
    cols = np.asarray(cols)
    if cols.size and np.array_equal(cols, np.arange(cols[0], cols[0] + cols.size)):
        return slice(int(cols[0]), int(cols[0]) + cols.size)
    return cols


def _held_rows(base: np.ndarray, hold: int, c0: int, c1: int) -> np.ndarray:
    """Steps [c0, c1) of ``base`` (n, rows, k) whose rows each hold ``hold`` steps: (n, c1 - c0, k)."""
    r0, r1 = c0 // hold, -(-c1 // hold)
    return np.repeat(base[:, r0:r1], hold, axis=1)[:, c0 - r0 * hold : c1 - r0 * hold]


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
        nthread: rollout threads (default: all cores).
        who: the trials, named in a :class:`SimulationError` (default: "row <i> of the batch").
        target_rows: (n_trials,) the row of ``robot_targets`` each trial follows (trials sharing
            a path share a row: each chunk gathers its targets, no (n_trials, n_steps, 7) copy);
            None: row i for trial i.

    Returns:
        The clean signals, sampled every ``substeps`` steps.

    Raises:
        SimulationError: a trial diverged (MuJoCo warned or reset its state; :mod:`.stability`).
    """
    model = scene.model
    _, n_steps, _ = robot_targets.shape
    if target_rows is None:
        n_trials = robot_targets.shape[0]
        target_rows = slice(None)
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
    muscle_base = np.asarray(muscle_base, float)
    per_step = muscle_base.ndim == 3
    n_rows = -(-n_steps // substeps)  # the samples the steps reach (the kernel reads row step // substeps)
    if per_step and muscle_base.shape != (n_trials, n_rows, len(MUSCLES)):
        raise SimulationError(
            f"muscle_base must be ({len(MUSCLES)},) or {(n_trials, n_rows, len(MUSCLES))} "
            f"(one row per sample of {substeps} physics steps), got {muscle_base.shape}"
        )
    dt = model.opt.timestep
    if who is None:
        rows = tuple(f"row {i} of the batch" for i in range(n_trials))
        who = TrialLabels(protocol="simulation", labels=rows, hint="")
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

    data = [mujoco.MjData(model) for _ in range(nthread or usable_cpus())]
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    mujoco.mj_setState(model, data[0], initial_state, spec)
    mujoco.mj_forward(model, data[0])
    ref_len = data[0].sensordata[len_sl].copy()

    nsd = model.nsensordata
    nstate = mujoco.mj_stateSize(model, spec)
    act_cols = 1 + model.nq + model.nv + model.actuator_actadr[scene.muscle_act]  # activations' places
    # consecutive columns as slices: the chunks' copies read them without a fancy-index gather
    act_cols = _as_slice(act_cols)
    n_samples = n_steps // substeps
    sensordata = np.empty((n_trials, n_samples, nsd))
    activation = np.empty((n_trials, n_samples, len(MUSCLES)))
    muscle_ctrl = np.empty((n_trials, n_samples, len(MUSCLES)))
    qpos = np.empty((n_trials, n_samples, model.nq))
    # the muscle lengths then velocities of the last steps, as far back as the longest reflex lag
    # reads (step j in row j % depth; the steady state before t = 0 is the kernel's)
    hist = np.empty((n_trials, lag_sp + chunk if reflex.enabled else 0, 2 * len(MUSCLES)))
    hist_cols = np.r_[len_sl, vel_sl].astype(np.intp)

    # Two sets of buffers, reused chunk after chunk: the rollout writes into one while the other
    # chunk's outputs are checked and kept (no allocation, no page faults per chunk); the inputs
    # are checked once here, so each call skips the checks.
    bufs = _ChunkBuffers(n_trials, chunk, model.nu, nstate, nsd)
    state = np.ascontiguousarray(np.tile(initial_state, (n_trials, 1)), dtype=float)
    if state.shape[1] != nstate:
        raise SimulationError(f"initial_state must hold {nstate} full-physics values, got {state.shape[1]}")
    models = [model] * n_trials  # the unchecked call takes one model per trial
    starts = range(0, n_steps, chunk)
    robot_cols = np.asarray(scene.robot_act, dtype=np.intp)
    muscle_cols = np.asarray(scene.muscle_act, dtype=np.intp)
    rows = np.arange(n_trials) if isinstance(target_rows, slice) else target_rows.astype(np.intp)
    table = np.ascontiguousarray(robot_targets, dtype=float)
    base3 = muscle_base if per_step else muscle_base.reshape(1, 1, -1)

    def robot_ctrl(j: int) -> None:  # the robot's part of chunk j's controls (known in advance)
        c0 = starts[j]
        c1 = min(n_steps, c0 + chunk)
        kernel.robot_targets(bufs.get(c1 - c0, j % 2)[0], robot_cols, table, rows, c0)

    def keep(c0: int, c1: int, state_in, states, sd, ctrl, warned) -> None:
        """Check chunk [c0, c1) and keep its samples (while the next chunk steps)."""
        check_rollout(who, state_in, states, data, dt, np.arange(c0 + 1, c1 + 1) * dt, warned=warned)
        # keep the samples whose last physics step falls in this chunk: steps c0 + o,
        # c0 + o + substeps, ... (step s ends sample (s + 1) / substeps - 1)
        o = (substeps - 1 - c0) % substeps
        s0 = (c0 + o + 1) // substeps - 1
        s1 = min(n_samples, s0 + len(range(o, c1 - c0, substeps)))
        kept = slice(o, o + (s1 - s0) * substeps, substeps)
        sensordata[:, s0:s1] = sd[:, kept]
        activation[:, s0:s1] = states[:, kept, act_cols]
        muscle_ctrl[:, s0:s1] = ctrl[:, kept, muscle_cols]
        qpos[:, s0:s1] = states[:, kept, 1 : 1 + model.nq]
        progress.advance(n_trials * c1 / n_steps - n_trials * c0 / n_steps)

    # the trials advance together: after a chunk ending at step c1, n_trials * c1 / n_steps trials' worth
    progress.stage("simulate", n_trials, "trials")
    pending = None  # the chunk stepped last, its outputs not yet kept
    if len(starts):
        robot_ctrl(0)
    # One worker thread runs each chunk's rollout (MuJoCo releases the GIL while it steps); this
    # thread meanwhile keeps the previous chunk's samples and prepares the next chunk's robot
    # controls. The chunks, their inputs and the order of every operation on a trial are those of a
    # serial loop, so the trajectories are bit-identical to it.
    with mj_rollout.Rollout(nthread=len(data)) as runner, ThreadPoolExecutor(1) as stepper:
        for j, c0 in enumerate(starts):
            c1 = min(n_steps, c0 + chunk)
            m = c1 - c0
            ctrl, states, sd = bufs.get(m, j % 2)
            if reflex.enabled:  # stretch lagged by >= one chunk: only chunks already stepped
                kernel.muscle_commands(
                    ctrl,
                    muscle_cols,
                    base3,
                    substeps,
                    c0,
                    hist,
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
                    _held_rows(muscle_base, substeps, c0, c1) if per_step else muscle_base
                )
            step_args = dict(nstep=m, state=states, sensordata=sd, skip_checks=True)
            stepping = stepper.submit(runner.rollout, models, data, state, ctrl, **step_args)
            try:
                if pending is not None:
                    keep(*pending)
                    pending = None
                if j + 1 < len(starts):
                    robot_ctrl(j + 1)  # the other buffer set: the chunk it held is kept
            finally:
                wait([stepping])  # never leave a rollout writing into the buffers while raising
            stepping.result()
            warned = warning_counts(data)  # the next rollout call clears the counters
            if reflex.enabled:
                kernel.store_history(hist, sd, hist_cols, c0)
            pending = (c0, c1, state, states, sd, ctrl, warned)
            state = np.ascontiguousarray(states[:, -1])  # a copy: the buffer is reused
        if pending is not None:
            keep(*pending)
    return SimResult(
        sensordata=sensordata,
        activation=activation,
        muscle_ctrl=muscle_ctrl,
        qpos=qpos,
        fs_hz=1.0 / (dt * substeps),
    )
