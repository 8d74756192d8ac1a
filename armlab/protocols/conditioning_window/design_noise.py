"""The torque noise the Eq. (9) estimator sees, measured in the lab itself (issue 23's planning).

The realistic lab's noise is not only the F/T sensor's white noise: the subject's activation
fluctuates (3.5 % rms below ~2 Hz, armlab.config.subject), which moves the torque at the cuff by
about as much as a 0.05 rad perturbation does through K, slowly, so that over a short window it
looks like an offset or a ramp (a stiffness). Rather than model it, the designer records trials
of the configured lab with the robot holding still (zero amplitude) and processes them exactly as
the estimator does (low-pass, differentiation, pre-onset baseline); each trial's dtau after onset
is one realisation of the noise an estimate averages over.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from armlab.estimation.processing import ProcessingConfig, joint_signals
from armlab.perturbations.scenario import draw_trials, load_scenario
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.sim.lab import record_trials

__all__ = ["measure_noise"]


def measure_noise(
    cfg: ConditioningWindowConfig, n_trials: int, duration_s: float, rng: np.random.Generator
) -> np.ndarray:
    """(n_trials, round(duration_s fs), 2) N·m: processed dtau after onset with the robot still.

    Args:
        cfg: the lab (sensors, subject, cuff, reflex, estimator's processing) to measure.
        n_trials: noise realisations.
        duration_s: s, samples kept after onset (the longest window to be planned).
        rng: seeds the plan's waits, the sensors and the subject (three spawned children).
    """
    paper = load_scenario("conditioning_window").subset([26], n_trials)
    still = replace(
        paper,
        directions_rad=np.zeros((1, 2)),
        t_obs_s=np.array([duration_s]),
        extension_t_obs_s=(),
    )
    plan_rng, sensor_rng, subject_rng = rng.spawn(3)
    plan = draw_trials(still, plan_rng)
    rec = record_trials(cfg, still, plan, sensor_rng, cfg.subject, subject_rng)
    est = cfg.estimator
    proc = ProcessingConfig(
        lowpass_hz=est.lowpass_hz, filter_order=est.filter_order, baseline_s=est.baseline_s
    )
    sig = joint_signals(
        rec.channels["hand_pos"],
        rec.channels["hand_force"],
        rec.fs_hz,
        rec.onset_index,
        rec.scene.l1,
        rec.scene.l2,
        proc,
    )
    n = int(round(duration_s * rec.fs_hz))
    on = int(rec.onset_index[0])
    return np.array(sig.dtau[:, on : on + n])
