"""The checks of a ``stiffness_5dof_emg`` config that need no simulation (``Protocol.validate``).

Run by :func:`armlab.protocols.compose.compose`, so ``armlab run`` refuses before its run folder
exists: the lab's fixed physics step and recording rate (the composed lab's MJCF sets them), the
averaging intervals and the EMG map's stretch against the trial's record, and the force task of
every chosen condition.
"""

from __future__ import annotations

import numpy as np

from armlab.config.validate import check
from armlab.errors import ConfigError
from armlab.estimation.emg_features import MAP_SAMPLES
from armlab.models.arm5_scene import ARM5_LAB_TIMESTEP_S
from armlab.models.arm_5dof import load_arm_5dof
from armlab.protocols.stiffness_5dof_emg.config import Stiffness5dofConfig, trial_timing
from armlab.protocols.stiffness_5dof_emg.emg_map import MIN_EMG_CONDITIONS
from armlab.sim.arm5_force_task import PRELOAD_CONDITIONS, force_task_activations

__all__ = ["LAB_FS_HZ", "LAB_INTEGRATOR", "validate"]

#: Hz, the F/T channels' rate (paper Sec. 3: JR3 at 2 kHz): one sample per physics step
LAB_FS_HZ = 1.0 / ARM5_LAB_TIMESTEP_S
#: the lab's integrator (armlab.models.arm5_scene: the servos' velocity gains integrated implicitly)
LAB_INTEGRATOR = "implicitfast"


def validate(cfg: Stiffness5dofConfig) -> None:
    """Raise :class:`ConfigError` on a setting the stiffness stage cannot run."""
    check(
        abs(cfg.sim.timestep_s - ARM5_LAB_TIMESTEP_S) < 1e-12,
        f"sim.timestep_s={cfg.sim.timestep_s:g} s: the 5-DoF stiffness lab steps at "
        f"{ARM5_LAB_TIMESTEP_S:g} s (one step per 2 kHz F/T sample); valid: {ARM5_LAB_TIMESTEP_S:g}",
    )
    check(
        abs(cfg.sensors.fs_hz - LAB_FS_HZ) < 1e-9,
        f"sensors.fs_hz={cfg.sensors.fs_hz:g} Hz: the paper records its JR3s at 2 kHz (Sec. 3); "
        f"valid: {LAB_FS_HZ:g}",
    )
    check(
        cfg.sim.integrator == LAB_INTEGRATOR,
        f"sim.integrator={cfg.sim.integrator!r}: the lab's robot servos need {LAB_INTEGRATOR!r}; "
        f"valid: [{LAB_INTEGRATOR!r}]",
    )
    try:
        trial_timing(cfg)
    except ConfigError as exc:
        raise ConfigError(
            f"estimation.pre_interval_s / post_interval_s do not fit the record set by trials.pre_s, "
            f"rise_s, hold_s: {exc}"
        ) from None
    t = cfg.trials
    if "emg" in cfg.stages:
        start, end = cfg.estimation.emg_map_start_s, cfg.estimation.emg_map_start_s + MAP_SAMPLES / LAB_FS_HZ
        check(
            -t.pre_s - 1e-12 <= start and end <= t.rise_s + t.hold_s + 1e-12,
            f"estimation.emg_map_start_s={start:g} s: the EMG map's {MAP_SAMPLES} samples "
            f"[{start:g}, {end:g}] s must lie in the record [-trials.pre_s, trials.rise_s + trials.hold_s] "
            f"= [{-t.pre_s:g}, {t.rise_s + t.hold_s:g}] s",
        )
        check(
            len(t.conditions) >= MIN_EMG_CONDITIONS,
            f"the EMG stage's maps need at least {MIN_EMG_CONDITIONS} conditions (leave one condition out: "
            f"a test, a validation and two training conditions); trials.conditions={list(t.conditions)}",
        )
    arm = load_arm_5dof()
    for name in t.conditions:  # each pre-load must be holdable with activations in [a_min, 1]
        try:
            force_task_activations(arm, arm.q0, np.asarray(PRELOAD_CONDITIONS[name], float), t.a_min)
        except ConfigError as exc:
            raise ConfigError(f"trials.conditions {name!r} with trials.a_min={t.a_min:g}: {exc}") from None
