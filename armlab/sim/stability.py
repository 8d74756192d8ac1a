"""Instability of simulated trials, detected while simulating and named in one style.

Every laboratory checks its trials as it steps them and raises :class:`SimulationError` before
anything is written as a result, with one message shape::

    <protocol> trial <i> (<what distinguishes it>): unstable at t = <t> s from the trial's start:
    <the quantity and its bound>; <what to change>

What is checked (docs/reliability.md, "Instability"):

- MuJoCo's warnings (:data:`WATCHED_WARNINGS`). On a bad position, velocity or acceleration
  (NaN, inf or beyond 1e10) MuJoCo *resets* the data to the model's initial state and carries on,
  so a diverged trial would look finite afterwards; the full-physics state's clock then jumps
  back to zero, which names the trial and the step (:func:`check_rollout`).
- Non-finite states or recorded values.
- Forces beyond a physical bound each laboratory states with its unit and reason
  (:func:`check_bound`).

The checks only read the simulated arrays: a valid run is bit-identical with or without them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.errors import SimulationError
from armlab.sim._chunk_kernel import first_bad_step

__all__ = [
    "WATCHED_WARNINGS",
    "RolloutFailure",
    "TrialLabels",
    "check_bound",
    "check_rollout",
    "failure_error",
    "rollout_failure",
    "warning_counts",
]

#: MuJoCo warnings that make a trial invalid: a diverged state (reset by MuJoCo), a bad control,
#: a full constraint or contact buffer (constraints silently dropped), a degenerate inertia.
WATCHED_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC,
    mujoco.mjtWarning.mjWARN_BADCTRL,
    mujoco.mjtWarning.mjWARN_CNSTRFULL,
    mujoco.mjtWarning.mjWARN_CONTACTFULL,
    mujoco.mjtWarning.mjWARN_INERTIA,
)


@dataclass(frozen=True, kw_only=True)
class TrialLabels:
    """Who is simulated: the protocol, one description per trial, and what to change if unstable.

    Attributes:
        protocol: the protocol (or laboratory) name that starts every message.
        labels: (n_trials,) what distinguishes each trial, e.g. ``"direction 2, T_k 0.050 s"``.
        hint: the settings that make a trial unstable, e.g. ``"lower cuff.stiffness_N_per_m"``.
    """

    protocol: str
    labels: tuple[str, ...]
    hint: str

    def error(self, trial: int | None, t_s: float, quantity: str, state: str = "unstable") -> SimulationError:
        """The :class:`SimulationError` of ``trial`` (None: not known within the batch) at ``t_s``.

        ``state`` names what happened (``"unstable"``; ``"aborted"`` for a safety stop).
        """
        if trial is None:
            who = f"one of trials 0-{len(self.labels) - 1}" if len(self.labels) > 1 else "trial 0"
        else:
            who = f"trial {trial} ({self.labels[trial]})"
        return SimulationError(
            f"{self.protocol} {who}: {state} at t = {t_s:.4f} s from the trial's start"
            + (" (negative: while settling, before the recording)" if t_s < 0 else "")
            + f": {quantity}"
            + (f"; {self.hint}" if self.hint else "")
        )


def warning_counts(datas: Sequence[mujoco.MjData]) -> dict[str, int]:
    """The watched MuJoCo warnings raised in ``datas`` since their counters were last cleared."""
    out: dict[str, int] = {}
    for data in datas:
        for w in WATCHED_WARNINGS:
            n = int(data.warning[w].number)
            if n:
                out[w.name] = out.get(w.name, 0) + n
    return out


@dataclass(frozen=True)
class RolloutFailure:
    """What :func:`rollout_failure` found wrong in a chunk.

    Attributes:
        trial: the row of the first trial whose state went bad (earliest step, then lowest row);
            None when MuJoCo only warned (a full constraint buffer: the chunk, not a trial).
        step: the step of the chunk where it went bad (the chunk's length for a warning alone).
        quantity: what went wrong, for :meth:`TrialLabels.error`.
    """

    trial: int | None
    step: int
    quantity: str

    @property
    def order(self) -> tuple[int, int, int]:
        """Sorts failures as one check of all their rows would pick: a bad state before a warning
        alone, then the earliest step, then the lowest row."""
        if self.trial is None:
            return (1, self.step, 0)
        return (0, self.step, self.trial)


def rollout_failure(
    state_in: np.ndarray,
    states: np.ndarray,
    dt: float,
    warned: Mapping[str, int],
) -> RolloutFailure | None:
    """The failure of one ``mujoco.rollout`` chunk (see :func:`check_rollout`), or None.

    Args:
        state_in: (n_trials, nstate) full-physics states the chunk started from.
        states: (n_trials, m, nstate) full-physics states after each step (rollout's output).
        dt: s, physics step.
        warned: :func:`warning_counts` of the rollout's MjData read right after the chunk.
    """
    # the sound chunk, by far the common case, in one compiled pass without temporaries
    if (
        not warned
        and first_bad_step(np.ascontiguousarray(state_in[:, 0]), np.ascontiguousarray(states), dt) < 0
    ):
        return None
    expected = state_in[:, :1] + dt * np.arange(1, states.shape[1] + 1)
    bad = ~np.isfinite(states).all(axis=-1) | (np.abs(states[..., 0] - expected) > 0.5 * dt)
    if bad.any():
        first = np.where(bad.any(axis=1), bad.argmax(axis=1), states.shape[1])
        trial = int(np.argmin(first))
        what = "the state became non-finite or MuJoCo reset it (its acceleration diverged)"
        return RolloutFailure(
            trial, int(first[trial]), f"{what}{'; MuJoCo warned ' + str(warned) if warned else ''}"
        )
    # a warning that did not reset the state (a full constraint buffer): the chunk, not the trial
    return RolloutFailure(None, states.shape[1], f"MuJoCo warned {dict(warned)} by this time")


def failure_error(who: TrialLabels, failure: RolloutFailure, t_steps: np.ndarray) -> SimulationError:
    """The :class:`SimulationError` of ``failure`` (its trial a row of ``who``), at the time of its
    step in ``t_steps`` (m,) s (the chunk's last step for a warning alone)."""
    return who.error(failure.trial, float(t_steps[min(failure.step, len(t_steps) - 1)]), failure.quantity)


def check_rollout(
    who: TrialLabels,
    state_in: np.ndarray,
    states: np.ndarray,
    datas: Sequence[mujoco.MjData],
    dt: float,
    t_steps: np.ndarray,
    *,
    warned: Mapping[str, int] | None = None,
) -> None:
    """Check one ``mujoco.rollout`` chunk of a batch.

    Args:
        who: the trials of the batch.
        state_in: (n_trials, nstate) full-physics states the chunk started from.
        states: (n_trials, m, nstate) full-physics states after each step (rollout's output).
        datas: the rollout's MjData (their warning counters, cleared by every rollout call).
        dt: s, physics step.
        t_steps: (m,) s, time of each step's end from the trial's start.
        warned: :func:`warning_counts` of ``datas`` read right after this chunk's rollout, for a
            caller that checks the chunk once the next rollout has cleared the counters (``datas``
            is then not read); None reads them from ``datas`` now.

    Raises:
        SimulationError: a trial's state was reset by MuJoCo (its clock jumps back), became
            non-finite, or MuJoCo warned.
    """
    failure = rollout_failure(state_in, states, dt, warning_counts(datas) if warned is None else warned)
    if failure is not None:
        raise failure_error(who, failure, t_steps)


def check_bound(
    who: TrialLabels,
    values: np.ndarray,
    t_s: np.ndarray,
    bound: float,
    quantity: str,
    unit: str,
    reason: str,
) -> None:
    """Refuse the first sample whose magnitude exceeds ``bound`` (or is not finite).

    Args:
        who: the trials.
        values: (n_trials, n) or (n_trials, n, k) samples; the norm over the last axis for 3-D.
        t_s: (n,) s, time of each sample from the trial's start.
        bound: the largest physical magnitude, in ``unit``.
        quantity, unit, reason: named in the message (e.g. ``"cuff force"``, ``"N"``, why).

    Raises:
        SimulationError: naming the trial, the time, the value and the bound.
    """
    mag = np.linalg.norm(values, axis=-1) if values.ndim == 3 else np.abs(values)
    over = ~(mag <= bound)  # NaN counts as over
    if not over.any():
        return
    first = np.where(over.any(axis=1), over.argmax(axis=1), mag.shape[1])
    trial = int(np.argmin(first))
    k = int(first[trial])
    raise who.error(
        trial,
        float(t_s[k]),
        f"{quantity} |{mag[trial, k]:.4g}| {unit} beyond its {bound:g} {unit} bound ({reason})",
    )
