"""Scripted perturbation timelines (``scenarios/*.yaml``) as validated, frozen data.

A scenario says *what* the robot does to the arm — directions, amplitudes, durations, waits and
repetitions — and :func:`draw_trials` turns it into a concrete, seeded trial plan.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from armlab.errors import ConfigError
from armlab.perturbations.segments import SegmentWaveform

__all__ = [
    "SCENARIO_DIR",
    "Scenario",
    "TrialPlan",
    "available_scenarios",
    "draw_trials",
    "load_scenario",
]

SCENARIO_DIR = Path(__file__).resolve().parents[2] / "scenarios"


@dataclass(frozen=True, kw_only=True)
class Scenario:
    """A perturbation timeline.

    Attributes:
        name: scenario name (file stem).
        directions_rad: (n_dir, 2) rad, joint-space amplitudes dq_f.
        k_values: (n_windows,) window indices k.
        t_k_s: (n_windows,) s, interpolation time T_k of each window.
        t_obs_s: (n_windows,) s, observation window T_obs = T_k + extra.
        trials_per_window, validation_trials: repetitions per window.
        wait_s: (lo, hi) s, uniform random wait before onset.
        pre_onset_record_s, post_window_record_s: s, recorded margins.
        extension_t_obs_s: s, extra observation windows on the longest-T_k trials.
        waveform: the designed multi-segment waveform (``profile: segments``, issue 23) every
            direction follows over T_k; None: the paper's quintic, Eq. (16).
    """

    name: str
    directions_rad: np.ndarray
    k_values: np.ndarray
    t_k_s: np.ndarray
    t_obs_s: np.ndarray
    trials_per_window: int
    validation_trials: int
    wait_s: tuple[float, float]
    pre_onset_record_s: float
    post_window_record_s: float
    extension_t_obs_s: tuple[float, ...] = ()
    waveform: SegmentWaveform | None = None

    @property
    def record_s(self) -> float:
        """s, length of every trial record (pre-onset hold + longest window + margin)."""
        longest = max([float(self.t_obs_s.max()), *self.extension_t_obs_s])
        return self.pre_onset_record_s + longest + self.post_window_record_s

    def subset(self, k_values: list[int] | None = None, n_trials: int | None = None) -> Scenario:
        """Restrict to some windows and/or a different number of trials per window."""
        keep = np.ones(self.k_values.shape, bool)
        if k_values is not None:
            unknown = sorted(set(k_values) - set(self.k_values.tolist()))
            if unknown:
                raise ConfigError(
                    f"scenario.k_values {unknown} not in scenario {self.name!r}; valid: "
                    f"{int(self.k_values.min())}..{int(self.k_values.max())}"
                )
            keep = np.isin(self.k_values, k_values)
        n = self.trials_per_window if n_trials is None else int(n_trials)
        if n <= self.validation_trials:
            raise ConfigError(
                f"scenario.n_trials={n} leaves no identification trial (validation: {self.validation_trials})"
            )
        return Scenario(
            name=self.name,
            directions_rad=self.directions_rad,
            k_values=self.k_values[keep],
            t_k_s=self.t_k_s[keep],
            t_obs_s=self.t_obs_s[keep],
            trials_per_window=n,
            validation_trials=self.validation_trials,
            wait_s=self.wait_s,
            pre_onset_record_s=self.pre_onset_record_s,
            post_window_record_s=self.post_window_record_s,
            extension_t_obs_s=self.extension_t_obs_s,
            waveform=self.waveform,
        )


@dataclass(frozen=True, kw_only=True)
class TrialPlan:
    """The concrete trials of a run, one entry per trial.

    Attributes:
        group: (n,) window index k of each trial.
        direction: (n,) index into ``Scenario.directions_rad``.
        amplitude_rad: (n, 2) rad, dq_f.
        t_k_s: (n,) s, perturbation duration.
        wait_s: (n,) s, random wait before onset.
        validate: (n,) bool, trial held out for validation.
    """

    group: np.ndarray
    direction: np.ndarray
    amplitude_rad: np.ndarray
    t_k_s: np.ndarray
    wait_s: np.ndarray
    validate: np.ndarray

    @property
    def n_trials(self) -> int:
        return int(self.group.shape[0])


def available_scenarios() -> list[str]:
    return sorted(p.stem for p in SCENARIO_DIR.glob("*.yaml"))


def _need(raw: dict, key: str, path: Path):
    if key not in raw:
        raise ConfigError(f"{path.name}: missing key {key!r}")
    return raw[key]


def load_scenario(name: str) -> Scenario:
    """Load and validate ``scenarios/<name>.yaml``."""
    path = SCENARIO_DIR / f"{name}.yaml"
    if not path.is_file():
        raise ConfigError(f"unknown scenario {name!r}; available: {available_scenarios()}")
    raw = yaml.safe_load(path.read_text()) or {}
    profile = _need(raw, "profile", path)
    if profile not in ("quintic", "segments"):
        raise ConfigError(f"{path.name}: profile {profile!r} unknown; valid: ['quintic', 'segments']")
    waveform = None
    if profile == "segments":  # a designed chain of quintics (armlab.perturbations.segments)
        try:
            waveform = SegmentWaveform(
                knots=tuple(float(v) for v in _need(raw, "knots", path)),
                fraction=float(raw.get("active_fraction", 1.0)),
            )
        except (TypeError, ValueError) as err:
            raise ConfigError(f"{path.name}: knots must be a list of numbers in [-1, 1] ({err})") from None
    directions = np.asarray(_need(raw, "directions_rad", path), float)
    if directions.ndim != 2 or directions.shape[1] != 2 or not np.all(np.isfinite(directions)):
        raise ConfigError(f"{path.name}: directions_rad must be a list of [dq1, dq2] pairs in rad")
    interp = _need(raw, "interpolation", path)
    k_lo, k_hi = (int(v) for v in _need(interp, "k", path))
    if not (1 <= k_lo <= k_hi):
        raise ConfigError(f"{path.name}: interpolation.k must be [first, last] with 1 <= first <= last")
    k = np.arange(k_lo, k_hi + 1)
    t_k = float(_need(interp, "base_s", path)) + k * float(_need(interp, "step_s", path))
    if np.any(t_k <= 0):
        raise ConfigError(f"{path.name}: interpolation times must be positive, got {t_k.min()} s")
    wait = tuple(float(v) for v in _need(raw, "wait_s", path))
    if len(wait) != 2 or not (0 <= wait[0] <= wait[1]):
        raise ConfigError(f"{path.name}: wait_s must be [lo, hi] with 0 <= lo <= hi, got {wait}")
    scen = Scenario(
        name=str(raw.get("name", name)),
        directions_rad=directions,
        k_values=k,
        t_k_s=t_k,
        t_obs_s=t_k + float(_need(raw, "observation_extra_s", path)),
        trials_per_window=int(_need(raw, "trials_per_window", path)),
        validation_trials=int(_need(raw, "validation_trials", path)),
        wait_s=wait,
        pre_onset_record_s=float(_need(raw, "pre_onset_record_s", path)),
        post_window_record_s=float(_need(raw, "post_window_record_s", path)),
        extension_t_obs_s=tuple(float(t) for t in raw.get("extension_t_obs_s", [])),
        waveform=waveform,
    )
    if any(t <= 0 for t in scen.extension_t_obs_s):
        raise ConfigError(f"{path.name}: extension_t_obs_s must be positive times in s")
    return scen.subset()


def draw_trials(scenario: Scenario, rng: np.random.Generator) -> TrialPlan:
    """Draw the seeded trial plan: per window, directions balanced and shuffled, random waits.

    Each window gets ``trials_per_window`` trials cycling through the directions in a random order
    (the paper's "one of six randomly chosen directions"); the last ``validation_trials`` of each
    window are held out.
    """
    n_dir = scenario.directions_rad.shape[0]
    n = scenario.trials_per_window
    groups, dirs, validate = [], [], []
    for k in scenario.k_values:
        d = np.resize(np.arange(n_dir), n)
        rng.shuffle(d)
        groups.append(np.full(n, k))
        dirs.append(d)
        validate.append(np.arange(n) >= n - scenario.validation_trials)
    group = np.concatenate(groups)
    direction = np.concatenate(dirs)
    t_k = scenario.t_k_s[np.searchsorted(scenario.k_values, group)]
    wait = rng.uniform(scenario.wait_s[0], scenario.wait_s[1], size=group.shape[0])
    return TrialPlan(
        group=group,
        direction=direction,
        amplitude_rad=scenario.directions_rad[direction],
        t_k_s=t_k,
        wait_s=wait,
        validate=np.concatenate(validate),
    )
