"""The checks of a ``conditioning_window`` config that need no simulation (``Protocol.validate``).

Run by :func:`armlab.protocols.compose.compose`, so ``armlab run`` refuses a setting that cannot
run before its run folder exists, instead of after minutes of simulation: the scenario's windows,
the sample rate against the physics step, the perturbation and the sensors, the estimator's
low-pass against Nyquist, the observation windows against the record. Two settings run but bias
what they measure, an ArmlabWarning each: a rate whose Nyquist frequency resolves the
perturbation's velocity but not its acceleration, and a reflex whose latencies exceed every
observation window.
"""

from __future__ import annotations

import warnings

import numpy as np

from armlab.config.schema import EstimatorConfig
from armlab.errors import ArmlabWarning, ConfigError
from armlab.perturbations.scenario import load_scenario
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.design_limits import robot_limits
from armlab.protocols.conditioning_window.experiment import check_window_lengths, window_specs
from armlab.sensors.channel import ChannelSpec
from armlab.sensors.presets import SensorSuite

__all__ = [
    "QUINTIC_ACCEL_BAND_PER_S",
    "QUINTIC_VELOCITY_BAND_PER_S",
    "check_estimator",
    "check_rate",
    "quintic_band",
    "validate",
]

# 1 (band x T_k): the quintic point-to-point move of eq. (16), s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5
# over tau = t / T_k in [0, 1], has 99.9 % of the energy of its velocity (a quartic) below
# c_v / T_k Hz and of its acceleration (a cubic) below c_a / T_k Hz, with c_v = 2.155 and
# c_a = 5.560 (quintic_band(1) and quintic_band(2), computed from the spectrum; 99 %: 1.337 and
# 2.532), each rounded up to 3 digits. For T_k = 50 ms: velocity to 43.2 Hz, acceleration to
# 111.2 Hz, so a rate below 86.4 Hz cannot resolve the move at all and one below 222.4 Hz aliases
# its acceleration.
#: 1, the velocity band x T_k: a Nyquist frequency below it is refused (velocity/damping unresolved)
QUINTIC_VELOCITY_BAND_PER_S = 2.16
#: 1, the acceleration band x T_k: a Nyquist frequency below it is warned (inertia biased: the
#: estimator differentiates the joint angles twice)
QUINTIC_ACCEL_BAND_PER_S = 5.56


def quintic_band(order: int, fraction: float = 0.999) -> float:
    """c such that ``fraction`` of the energy of the ``order``-th derivative (1: velocity, 2:
    acceleration) of the quintic move over [0, T_k] lies below c / T_k Hz.

    Parseval: the energy below c is 2 * int_0^c |X(nu)|^2 dnu over the total int_0^1 x(tau)^2 dtau,
    with X the Fourier transform of x on [0, 1] (x is zero outside); both integrals by
    Gauss-Legendre quadrature, exact for the polynomial and accurate to ~1e-6 for nu <= 20.
    Gives 2.155 (order 1) and 5.560 (order 2) at 99.9 % (the constants above).
    """
    from numpy.polynomial import Polynomial
    from numpy.polynomial.legendre import leggauss
    from scipy.optimize import brentq

    tau, w = leggauss(96)
    tau, w = (tau + 1) / 2, w / 2
    x = Polynomial([0, 0, 0, 10, -15, 6]).deriv(order)(tau)
    total = float(np.sum(w * x**2))
    nodes, weights = leggauss(160)

    def excess(c: float) -> float:
        nu, wn = (nodes + 1) * c / 2, weights * c / 2
        spectrum = np.exp(-2j * np.pi * np.outer(nu, tau)) @ (w * x)
        return 2 * float(np.sum(wn * np.abs(spectrum) ** 2)) / total - fraction

    return float(brentq(excess, 0.2, 20.0, xtol=1e-5))


def check_rate(fs_hz: float, t_min_s: float) -> None:
    """ConfigError if the Nyquist frequency of ``fs_hz`` lies below the velocity band of the
    shortest perturbation (T_k = ``t_min_s``); an :class:`ArmlabWarning` if it lies below its
    acceleration band (the run goes on: a sample-rate sweep shows the loss)."""
    ms = f"T_k = {t_min_s * 1000:.0f} ms"
    refuse = 2 * QUINTIC_VELOCITY_BAND_PER_S / t_min_s
    warn = 2 * QUINTIC_ACCEL_BAND_PER_S / t_min_s
    if fs_hz < refuse:
        raise ConfigError(
            f"sensors.fs_hz={fs_hz:g} cannot resolve the shortest perturbation ({ms}): its velocity reaches "
            f"{refuse / 2:.1f} Hz ({QUINTIC_VELOCITY_BAND_PER_S:g} / T_k, 99.9 % of its energy), so the rate "
            f"must be >= {refuse:.1f} Hz (twice that, Nyquist); valid: sensors.fs_hz >= {refuse:.1f} "
            f"(>= {warn:.1f} to resolve its acceleration too)"
        )
    if fs_hz < warn:
        warnings.warn(
            f"sensors.fs_hz={fs_hz:g} aliases the acceleration of the shortest perturbation ({ms}), which "
            f"reaches {warn / 2:.1f} Hz ({QUINTIC_ACCEL_BAND_PER_S:g} / T_k, 99.9 % of its energy): the "
            f"inertia estimates are biased; sensors.fs_hz >= {warn:.1f} resolves it",
            ArmlabWarning,
            stacklevel=3,
        )


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
    """Raise :class:`ConfigError` on a setting the run cannot support; warn on a rate that aliases
    the perturbation's acceleration and on a reflex that cannot act inside any observation window."""
    scenario = load_scenario(cfg.scenario.name).subset(cfg.scenario.k_values, cfg.scenario.n_trials)
    fs = cfg.sensors.fs_hz
    # the shortest quintic: T_k itself, or one segment of a designed multi-segment waveform
    w = scenario.waveform
    check_rate(fs, float(scenario.t_k_s.min()) * (1.0 if w is None else w.fraction / len(w.knots)))
    if scenario.waveform is not None:  # a designed waveform: the LWR's limits after IK (issue 23)
        robot_limits(cfg, scenario).check(f"scenario {scenario.name!r}")
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
