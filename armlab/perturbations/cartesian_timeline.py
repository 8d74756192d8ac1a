"""Stop-and-perturb timelines of paper 002's five experiments (thesis Ch. 3), sampled at ``fs``.

The reference path moves in path time; at each *stop* it halts and one or more perturbations are
played, separated by pauses (§3.2.1: +x, 0.5 s, −y, 0.5 s, then both together), after which the
path resumes where it stopped. The hand is ``q_h = q_r + q_p`` (Eq. 3.1.1).

Experiment layouts (spec 002's table; the *assumptions* are the thesis's silences):

====  =====================  ===========================================================
exp   path                   stops (20 over 100 s of path time, centred in 5 s slots)
====  =====================  ===========================================================
1     Table 3.3 waypoints    one perturbation each, alternating +x / +y, either waveform
2, 4  circle                 one sequence each: +x, −y, (+x, −y), triangular
3     sinusoid in x, y = 0   one +x triangle each
5     spiral 100 % → 10 %    as 2
====  =====================  ===========================================================

Stops sit at path times ``(k + ½)·100/20`` s: evenly spread, and on the closed circle no two
stops share a point (stops at 0 and 100 s would). The combined perturbation moves both axes by
the full waveform (8 mm each, 11.3 mm diagonal): the thesis says only "a combination of the
first two".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError
from armlab.perturbations.ramp_waveforms import RampWaveform, Shape, ramp_waveform
from armlab.perturbations.reference_paths import (
    MOTION_DURATION_S,
    ReferencePath,
    circle_path,
    sinusoid_path,
    spiral_path,
    table_3_3_path,
)

__all__ = [
    "EXPERIMENTS",
    "SEQUENCE_DIRECTIONS",
    "StopTimeline",
    "experiment_timeline",
    "stop_path_times",
    "stop_timeline",
]

#: §3.2.1: the three directions of one perturbation sequence (+x, −y, then both together).
SEQUENCE_DIRECTIONS: tuple[tuple[float, float], ...] = ((1.0, 0.0), (0.0, -1.0), (1.0, -1.0))
#: The five experiments of thesis Ch. 3.
EXPERIMENTS: tuple[int, ...] = (1, 2, 3, 4, 5)


@dataclass(frozen=True, kw_only=True, eq=False)
class StopTimeline:
    """A sampled stop-and-perturb timeline (read-only arrays).

    Attributes:
        fs: Hz, sample rate.
        t: (n,) s, wall time.
        s: (n,) s, path time (constant during stops).
        q_r: (n, 2) m, reference position; qd_r: (n, 2) m/s, reference velocity (0 during stops).
        q_p: (n, 2) m, perturbation displacement; qd_p: (n, 2) m/s, its velocity.
        perturbation: (n,) int, index of the perturbation a sample belongs to, −1 outside.
        stop: (n,) int, index of the stop a sample belongs to (pauses included), −1 while moving.
        directions: (m, 2), direction of each perturbation (unit per axis: (1, −1) moves both).
        perturbation_stop: (m,) int, stop of each perturbation.
        stop_position: (n_stops, 2) m, reference position at each stop.
        waveform: the perturbation waveform.
    """

    fs: float
    t: np.ndarray
    s: np.ndarray
    q_r: np.ndarray
    qd_r: np.ndarray
    q_p: np.ndarray
    qd_p: np.ndarray
    perturbation: np.ndarray
    stop: np.ndarray
    directions: np.ndarray
    perturbation_stop: np.ndarray
    stop_position: np.ndarray
    waveform: RampWaveform

    @property
    def q_h(self) -> np.ndarray:
        """(n, 2) m, hand position ``q_r + q_p`` (Eq. 3.1.1)."""
        return self.q_r + self.q_p

    @property
    def qd_h(self) -> np.ndarray:
        """(n, 2) m/s, hand velocity."""
        return self.qd_r + self.qd_p

    @property
    def n_stops(self) -> int:
        """Number of stops."""
        return len(self.stop_position)


def stop_path_times(n_stops: int = 20, duration_s: float = MOTION_DURATION_S) -> np.ndarray:
    """Path times of ``n_stops`` stops centred in equal slots of ``duration_s``: (n_stops,) s."""
    if not (isinstance(n_stops, int | np.integer) and n_stops >= 1):
        raise ConfigError(f"n_stops must be a positive integer, got {n_stops!r}")
    return (np.arange(n_stops) + 0.5) * duration_s / n_stops


def stop_timeline(
    path: ReferencePath,
    waveform: RampWaveform,
    stop_times: np.ndarray,
    stop_directions: list[np.ndarray] | tuple[np.ndarray, ...],
    *,
    pause_s: float = 0.5,
    fs: float = 1000.0,
) -> StopTimeline:
    """Sample a path that stops at ``stop_times`` to play perturbations (thesis §3.1–3.5).

    Args:
        path: the reference path.
        waveform: the 1-D perturbation displacement, scaled per axis by each direction.
        stop_times: (n_stops,) s, increasing path times in ``[0, path.duration_s]``.
        stop_directions: one (m_j, 2) array per stop, the directions played there in order.
        pause_s: s, pause between perturbations of one stop (§3.2.1: 0.5 s).
        fs: Hz, sample rate (§3.2.2: 1 kHz).

    Returns:
        The :class:`StopTimeline`; it has ``round(duration·fs) + 1 + Σ stop samples`` samples.
    """
    if not (np.isfinite(fs) and fs > 0) or not (np.isfinite(pause_s) and pause_s >= 0):
        raise ConfigError(f"fs must be positive and pause_s non-negative, got fs={fs!r}, pause_s={pause_s!r}")
    st = np.asarray(stop_times, dtype=float)
    if st.ndim != 1 or len(st) != len(stop_directions) or len(st) == 0:
        raise ConfigError("stop_times must be 1-D with one direction list per stop")
    if np.any(np.diff(st) <= 0) or st[0] < 0 or st[-1] > path.duration_s:
        raise ConfigError(f"stop_times must increase within [0, {path.duration_s}] s")
    dirs = [np.atleast_2d(np.asarray(d, dtype=float)) for d in stop_directions]
    if any(d.shape[1] != 2 or len(d) == 0 for d in dirs):
        raise ConfigError("each stop needs at least one (x, y) direction")
    _, p_w, v_w = waveform.sample(fs)
    n_w, n_pause = len(p_w), int(round(pause_s * fs))
    n_pert = np.array([len(d) for d in dirs])
    n_stop = n_pert * n_w + (n_pert - 1) * n_pause  # samples each stop holds the path
    p_idx = np.round(st * fs).astype(int)  # path-time sample of each stop
    a_idx = p_idx + np.concatenate([[0], np.cumsum(n_stop)[:-1]])  # wall sample where each stop starts
    n_path = int(round(path.duration_s * fs))
    n = n_path + int(n_stop.sum()) + 1
    idx = np.arange(n)
    wall_breaks = np.concatenate([[0], np.ravel(np.c_[a_idx, a_idx + n_stop]), [n - 1]])
    path_breaks = np.concatenate([[0], np.repeat(p_idx, 2), [n_path]])
    s = np.interp(idx, wall_breaks, path_breaks) / fs
    stop = np.full(n, -1)
    stop[np.concatenate([np.arange(a, a + m) for a, m in zip(a_idx, n_stop, strict=True)])] = np.repeat(
        np.arange(len(st)), n_stop
    )
    moving = stop < 0
    q_r = path.position(s)
    qd_r = path.velocity(s) * moving[:, None]
    # perturbation m of stop j starts at a_j + i·(n_w + n_pause), i its rank within the stop
    rank = np.concatenate([np.arange(k) for k in n_pert])
    pert_stop = np.repeat(np.arange(len(st)), n_pert)
    starts = a_idx[pert_stop] + rank * (n_w + n_pause)
    directions = np.concatenate(dirs)
    samples = (starts[:, None] + np.arange(n_w)).ravel()
    perturbation = np.full(n, -1)
    perturbation[samples] = np.repeat(np.arange(len(starts)), n_w)
    q_p = np.zeros((n, 2))
    qd_p = np.zeros((n, 2))
    q_p[samples] = (directions[:, None, :] * p_w[None, :, None]).reshape(-1, 2)
    qd_p[samples] = (directions[:, None, :] * v_w[None, :, None]).reshape(-1, 2)
    arrays = dict(
        t=idx / fs, s=s, q_r=q_r, qd_r=qd_r, q_p=q_p, qd_p=qd_p, perturbation=perturbation, stop=stop
    )
    for a in arrays.values():
        a.flags.writeable = False
    stop_position = path.position(p_idx / fs)
    directions.flags.writeable = False
    pert_stop.flags.writeable = False
    stop_position.flags.writeable = False
    return StopTimeline(
        fs=fs,
        directions=directions,
        perturbation_stop=pert_stop,
        stop_position=stop_position,
        waveform=waveform,
        **arrays,
    )


def experiment_timeline(
    experiment: int,
    *,
    shape: Shape = "triangular",
    corner_s: float = 0.0,
    n_stops: int = 20,
    pause_s: float = 0.5,
    fs: float = 1000.0,
    sinusoid_omega_rad_s: float | None = None,
    spiral_end_fraction: float = 0.1,
) -> StopTimeline:
    """The timeline of thesis experiment ``experiment`` (1–5), with the module's documented defaults.

    Args:
        experiment: 1–5 (§3.1–3.5).
        shape: ``triangular`` or ``trapezoidal`` (only Exp. 1 uses both; §3.1.2 keeps the triangle).
        corner_s: s, quintic corner blend of the waveform (0: the thesis's sharp corners).
        n_stops: stops over the 100 s path (thesis: 20).
        pause_s: s, pause within a sequence (thesis: 0.5 s).
        fs: Hz (thesis: 1 kHz).
        sinusoid_omega_rad_s: rad/s for Exp. 3; default the golden-angle rate of the stop spacing.
        spiral_end_fraction: Exp. 5's final radius fraction (thesis: 10 %).

    Raises:
        ConfigError: for an experiment outside 1–5 or a bad value.
    """
    if experiment not in EXPERIMENTS:
        raise ConfigError(f"unknown experiment {experiment!r}; valid: {', '.join(map(str, EXPERIMENTS))}")
    waveform = ramp_waveform(shape, corner_s)
    seq = np.asarray(SEQUENCE_DIRECTIONS)
    if experiment == 1:
        path = table_3_3_path()
        dirs = [np.array([[1.0, 0.0]]) if k % 2 == 0 else np.array([[0.0, 1.0]]) for k in range(n_stops)]
    elif experiment == 3:
        path = sinusoid_path(sinusoid_omega_rad_s, spacing_s=MOTION_DURATION_S / n_stops)
        dirs = [np.array([[1.0, 0.0]])] * n_stops
    else:
        path = spiral_path(spiral_end_fraction) if experiment == 5 else circle_path()
        dirs = [seq] * n_stops
    st = stop_path_times(n_stops, path.duration_s)  # equal slots of this path's own duration
    return stop_timeline(path, waveform, st, dirs, pause_s=pause_s, fs=fs)
