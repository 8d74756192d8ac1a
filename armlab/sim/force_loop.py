"""Running one force-control trial's periods: the compiled kernel over blocks, the muscles' reflex
between them, and the checks that fail a trial (seeds/004, Fig. 3; :mod:`.force_control`).

The kernel (:mod:`.force_kernel`) runs a block of control periods at a time: up to the next block of
the muscles' delayed reflex (a latency's worth of periods, computed here by one vectorised
:func:`~armlab.sim.rollout.reflex_command` call), or :data:`_BLOCK_PERIODS` without it. After each
block MuJoCo's clock is checked: MuJoCo resets a diverged state (its clock restarts at 0), and a
trial that reset is replayed from rest one period per call, which names the period of the reset.
A failed check becomes the :class:`SimulationError` that names the trial, the time and the cause.
"""

from __future__ import annotations

import mujoco
import numpy as np

from armlab.config.schema import ElbowConfig, ReflexConfig
from armlab.errors import SimulationError
from armlab.models.direct_drive_scene import DirectDriveScene
from armlab.models.oustaloup import FractionalElement
from armlab.sim.force_kernel import (
    CURRENT_DUTY,
    CURRENT_RUN,
    GRASP,
    N_SATURATED,
    NONFINITE,
    OK,
    SAFETY,
    STATE_SIZE,
    STOP_VALUE,
    ControlParams,
    control_periods,
    mj_pointers,
)
from armlab.sim.rollout import reflex_command
from armlab.sim.stability import TrialLabels, warning_counts

__all__ = ["GRASP_FORCE_BOUND_N", "SATURATION_DUTY_MAX", "SATURATION_RUN_S", "run_periods"]

# N, largest grasp force between hand and handle of a valid trial: the reference never exceeds
# 5 N (seeds/004 Sec. III-A) and the motor's peak torque (12.34 A x K_t over L = 0.35 m) pushes
# at most ~48 N statically; the default runs peak at 4.7 N (20x margin).
GRASP_FORCE_BOUND_N = 100.0
# 1, largest fraction of a trial's control periods with the current at its limit: a force loop
# whose amplifier saturates no longer applies its reference (the paper's <= 5 N multisine needs
# ~1.6 A of the 12.34 A); the default runs never saturate (0 %), an unstable loop sits there most
# of the time (motor.inertia_error=0.5: 88 %).
SATURATION_DUTY_MAX = 0.05
SATURATION_RUN_S = 0.1  # s at the limit without a break: the loop is lost (a failure at once)
# control periods per kernel call without the reflex (whose latency sets the block otherwise): 0.1 s
# at 2 kHz; long enough that a call's Python (~20 us) is negligible, short enough for a quick stop
_BLOCK_PERIODS = 200


def run_periods(
    scene: DirectDriveScene,
    params: ControlParams,
    ref: np.ndarray,
    noise: tuple[np.ndarray, np.ndarray, np.ndarray],
    elbow: ElbowConfig,
    reflex: ReflexConfig,
    muscle_base: np.ndarray | None,
    element: FractionalElement | None,
    fs_hz: float,
    who: TrialLabels,
    trial: int,
    n_settle: int,
) -> tuple[np.ndarray, np.ndarray, mujoco.MjData]:
    """Every control period of one trial from rest, settle included.

    Args:
        scene, params: the direct-drive scene and the controller's constants.
        ref: (total,) N, the force reference; ``noise``: the force, encoder and accelerometer
            noise of every period, (total,) each.
        elbow, reflex, muscle_base: the muscles' co-contraction, reflex and per-period base
            commands (None: the co-contraction).
        element: the fractional element, if the scene has one.
        fs_hz, who, trial, n_settle: the control rate; the labels, trial and settle periods an
            error is named with.

    Returns:
        ``rec`` (7, total): f_measured, f_true, theta_measured, theta, phi, current, tau_dym;
        ``act_rec`` (total, na) the activations; ``data`` after the last period.

    Raises:
        SimulationError: a check failed (its period and cause named).
    """
    args = (scene, params, ref, noise, elbow, reflex, muscle_base, element, fs_hz, who, trial, n_settle)
    try:
        return _periods(_BLOCK_PERIODS, *args)
    except _Reset:  # replayed period by period from the start, it stops at the period of the reset
        return _periods(1, *args)


class _MuscleCommands:
    """The elbow muscles' commands, a block of control periods at a time: the base (co-contraction
    or a subject's fluctuating commands) plus the delayed stretch reflex.

    The reflex of period ``k`` reads the muscle lengths and velocities of period
    ``k - lag >= k - lag_stretch`` (the shorter latency, at least one period), all recorded by
    then, so the commands of ``lag_stretch`` periods are computed at once by one vectorised
    :func:`reflex_command` call (the same element-wise operations as one call per period, so the
    same numbers) before the kernel runs them; the kernel records the state of every period into
    ``hist_len``/``hist_vel`` and writes each period's row.
    """

    def __init__(
        self,
        data: mujoco.MjData,
        muscles: np.ndarray,
        elbow: ElbowConfig,
        reflex: ReflexConfig,
        muscle_base: np.ndarray | None,
        total: int,
        fs_hz: float,
    ) -> None:
        self.base = elbow.cocontraction if muscle_base is None else np.asarray(muscle_base, float)
        self.reflex = reflex if reflex.enabled else None
        self.total = total
        self.data, self.muscles = data, muscles
        # the actuators' state the kernel records each period: only the reflex reads it
        n = data.actuator_length.size if self.reflex is not None else 0
        self.hist_len, self.hist_vel = np.empty((total, n)), np.empty((total, n))
        if self.reflex is None:  # the base commands, row by row (muscle_base, since no reflex)
            self.rows, self.row0, self.stop = np.ascontiguousarray(self.base, dtype=float), 0, total
        else:
            self.lag1 = max(1, int(round(reflex.stretch_latency_s * fs_hz)))
            self.lag2 = max(1, int(round(reflex.spinal_latency_s * fs_hz)))
            self.len_ref = data.actuator_length[muscles].copy()

    def block(self, k: int) -> tuple[np.ndarray, int, int]:
        """``(rows, row0, stop)``: period ``j``'s commands are ``rows[j - row0]`` for ``k <= j < stop``."""
        if self.reflex is not None and k % self.lag1 == 0:  # the next lag1 periods', from periods <= k
            self.hist_len[k] = self.data.actuator_length
            self.hist_vel[k] = self.data.actuator_velocity
            ks = np.arange(k, min(k + self.lag1, self.total))
            lagged = np.stack([np.maximum(ks - self.lag1, 0), np.maximum(ks - self.lag2, 0)])
            cols = self.muscles
            base = self.base if np.ndim(self.base) == 0 else self.base[ks]
            rows = reflex_command(
                base,
                self.hist_len[lagged][..., cols],
                self.hist_vel[lagged][..., cols],
                self.len_ref,
                self.reflex,
            )
            self.rows, self.row0, self.stop = np.ascontiguousarray(rows, dtype=float), k, int(ks[-1]) + 1
        return self.rows, self.row0, self.stop


class _Reset(Exception):
    """MuJoCo reset a diverged state somewhere in a block of periods."""


def _periods(block, scene, p, ref, noise, elbow, reflex, muscle_base, element, fs_hz, who, trial, n_settle):
    """:func:`run_periods`, ``block`` periods per kernel call.

    Raises:
        _Reset: MuJoCo reset the state within a block of more than one period.
        SimulationError: a check failed (with its period), or a reset with ``block == 1``.
    """
    m = scene.model
    total = ref.size
    data = mujoco.MjData(m)
    muscles = scene.muscle_act
    if muscles.size:
        data.act[m.actuator_actadr[muscles]] = elbow.cocontraction
        data.ctrl[muscles] = elbow.cocontraction
    el = (np.zeros((0, 0)), np.zeros(0), np.zeros(0), np.zeros(0))
    if element is not None:
        states = (element.A, element.B, element.C, element.initial_state(0.0))
        el = tuple(np.ascontiguousarray(a, dtype=float) for a in states)
    mujoco.mj_forward(m, data)
    commands = None  # without reflex or a subject's commands the co-contraction written above holds
    midx, rows, row0, stop = np.zeros(0, np.int64), np.zeros((1, 0)), 0, total
    if muscles.size and (reflex.enabled or muscle_base is not None):
        commands = _MuscleCommands(data, muscles, elbow, reflex, muscle_base, total, fs_hz)
        midx = np.asarray(muscles, np.int64)
    no_history = np.empty((total, 0))  # nothing reads the actuators' history
    hist_len = commands.hist_len if commands else no_history
    hist_vel = commands.hist_vel if commands else no_history
    st = np.zeros(STATE_SIZE)
    rec, act_rec = np.empty((7, total)), np.zeros((total, m.na))
    step, mp, dp = mj_pointers(m, data)
    views = (
        data.qpos,
        data.sensordata,
        data.ctrl,
        data.act,
        data.actuator_length,
        data.actuator_velocity,
    )
    period_s = p.substeps * m.opt.timestep
    k = 0
    while k < total:
        if commands is not None:
            rows, row0, stop = commands.block(k)
        end = min(k + block, stop, total)
        status, k_stop = control_periods(
            step,
            mp,
            dp,
            k,
            end,
            p,
            st,
            ref,
            *noise,
            *views,
            rec,
            act_rec,
            hist_len,
            hist_vel,
            rows,
            row0,
            midx,
            *el,
        )
        stepped = k_stop + 1 if status == NONFINITE else k_stop
        # MuJoCo resets a diverged state (its clock restarts at 0) and warns
        if not abs(data.time - stepped * period_s) < 0.5 * m.opt.timestep:
            if block > 1:
                raise _Reset
            status = NONFINITE
        if status != OK:
            raise _failure(status, k_stop, st, p, data, who, trial, n_settle, total, fs_hz)
        k = end
    return rec, act_rec, data


def _failure(status, k, st, p, data, who, trial, n_settle, total, fs_hz) -> SimulationError:
    """The error of a failed check at period ``k``."""
    t = (k - n_settle) * p.dt
    if status == SAFETY:
        return who.error(
            trial,
            t,
            f"the motor angle reached {st[STOP_VALUE]:+.3f} rad, outside the safety range "
            f"±{p.safety} rad; the trial is aborted (lower the force peak, raise the "
            "co-contraction or the arm stiffness)",
            state="aborted",
        )
    if status == GRASP:
        return who.error(
            trial,
            t,
            f"grasp force |{st[STOP_VALUE]:.4g}| N beyond its {GRASP_FORCE_BOUND_N:g} N bound (the reference "
            "stays within 5 N, the motor pushes at most ~48 N)",
        )
    if status == CURRENT_RUN:
        return who.error(
            trial,
            t,
            f"the motor current stayed at its ±{p.i_max:.2f} A limit for {SATURATION_RUN_S:g} s "
            "without a break (the force loop is unstable or the force exceeds the motor's peak "
            "torque)",
        )
    if status == CURRENT_DUTY:
        return who.error(
            trial,
            t,
            f"the motor current was at its ±{p.i_max:.2f} A limit for {st[N_SATURATED] / fs_hz:.2f} s, "
            f"more than the {SATURATION_DUTY_MAX:.0%} saturation duty allowed over the "
            f"{total / fs_hz:g} s trial (the force loop oscillates against the current limit)",
        )
    return who.error(
        trial,
        t + p.dt,
        "the state became non-finite or MuJoCo reset it (its acceleration diverged); "
        f"MuJoCo warned {warning_counts([data])}",
    )
