"""The checks of a ``conditioning_window`` config that need no simulation (``Protocol.validate``).

Run by :func:`armlab.protocols.compose.compose`, so ``armlab run`` refuses a setting that cannot
run before its run folder exists, instead of after minutes of simulation: the scenario's windows,
the sample rate against the physics step, the perturbation and the sensors, the estimator's
low-pass against Nyquist, the observation windows against the record. A reflex whose latencies
exceed every observation window runs but cannot act inside any: an ArmlabWarning.
"""

from __future__ import annotations

import warnings

from armlab.config.schema import EstimatorConfig
from armlab.errors import ArmlabWarning, ConfigError
from armlab.perturbations.scenario import load_scenario
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.experiment import check_window_lengths, window_specs
from armlab.sensors.channel import ChannelSpec
from armlab.sensors.presets import SensorSuite

__all__ = ["QUINTIC_BAND_PER_S", "check_estimator", "validate"]

# 1/s: 99.9 % of the energy of a quintic point-to-point move's acceleration (eq. (16), a cubic
# over T_k) lies below 5.6 / T_k Hz (computed from its spectrum, 5.56 / T_k). The estimator
# differentiates the joint angles twice, so the record's Nyquist frequency must lie above
# 5.6 / T_k for the shortest T_k (e.g. >= 224 Hz sampling for a 50 ms move).
QUINTIC_BAND_PER_S = 5.6


def check_estimator(estimator: EstimatorConfig, fs_hz: float, pre_onset_s: float) -> None:
    """ConfigError if the estimator's low-pass is not below Nyquist or its baseline is longer than
    the hold recorded before onset (checked before a run and before ``armlab estimate``)."""
    lowpass = estimator.lowpass_hz
    if lowpass is not None and not lowpass < fs_hz / 2:
        raise ConfigError(
            f"estimator.lowpass_hz={lowpass:g} Hz is at or above the Nyquist frequency {fs_hz / 2:g} Hz "
            f"(sensors.fs_hz={fs_hz:g}); valid: below {fs_hz / 2:g} Hz, or null for no low-pass"
        )
    if estimator.baseline_s > pre_onset_s + 1e-12:
        raise ConfigError(
            f"estimator.baseline_s={estimator.baseline_s:g} s is longer than the hold recorded before "
            f"onset ({pre_onset_s:g} s); valid: <= {pre_onset_s:g} s"
        )


def validate(cfg: ConditioningWindowConfig) -> None:
    """Raise :class:`ConfigError` on a setting the run cannot support; warn on a reflex that
    cannot act inside any observation window."""
    scenario = load_scenario(cfg.scenario.name).subset(cfg.scenario.k_values, cfg.scenario.n_trials)
    fs = cfg.sensors.fs_hz
    t_min = float(scenario.t_k_s.min())
    need_hz = 2 * QUINTIC_BAND_PER_S / t_min
    if fs < need_hz:
        raise ConfigError(
            f"sensors.fs_hz={fs:g} cannot resolve the shortest perturbation (T_k = {t_min * 1000:.0f} ms): "
            f"its acceleration reaches {QUINTIC_BAND_PER_S / t_min:.0f} Hz (5.6 / T_k), so the rate must be "
            f">= {need_hz:.0f} Hz (twice that, Nyquist); valid: sensors.fs_hz >= {need_hz:.0f}"
        )
    n_samples = int(round(scenario.record_s * fs))
    onset = int(round(scenario.pre_onset_record_s * fs))
    if cfg.sensors.preset == "realistic":
        SensorSuite.realistic().check_rate(fs, n_samples)
    bw, delay = cfg.effects.force_sensor_bandwidth, cfg.effects.channel_delay
    if bw is not None or delay is not None:  # the F/T channel's sensor-level effects (sim.lab)
        spec = ChannelSpec(
            bandwidth_hz=None if bw is None else bw.cutoff_hz, delay_s=0.0 if delay is None else delay.delay_s
        )
        try:
            spec.check_rate(
                fs, n_samples, "ft_force (effects.force_sensor_bandwidth / effects.channel_delay)"
            )
        except ConfigError as exc:
            raise ConfigError(f"sensors.fs_hz={fs:g}: {exc}") from None
    check_estimator(cfg.estimator, fs, scenario.pre_onset_record_s)
    specs = window_specs(scenario, cfg.estimator)
    check_window_lengths(specs, fs, n_samples - onset)
    if cfg.reflex.enabled:
        longest = max(s.t_obs_s for s in specs)
        first = min(cfg.reflex.stretch_latency_s, cfg.reflex.spinal_latency_s)
        if first >= longest:
            warnings.warn(
                f"reflex latencies (reflex.stretch_latency_s={cfg.reflex.stretch_latency_s:g} s, "
                f"reflex.spinal_latency_s={cfg.reflex.spinal_latency_s:g} s) exceed every observation window "
                f"(longest T_obs = {longest:g} s): the reflexes act only after the windows end and change no "
                f"estimate; shorten them below {longest:g} s or set reflex.enabled=false",
                ArmlabWarning,
                stacklevel=2,
            )
