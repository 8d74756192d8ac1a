"""The checks of a ``virtual_force_sensor`` config that need no simulation (``Protocol.validate``).

Run by :func:`armlab.protocols.compose.compose`, so ``armlab run`` refuses before its run folder
exists: the sample rate against the physics step, the excitation's band and the processing
low-pass against Nyquist, the Savitzky-Golay window against the trial, and the sensors' bandwidths
and delays against the rate.
"""

from __future__ import annotations

from armlab.errors import ConfigError
from armlab.protocols.virtual_force_sensor.config import VirtualForceSensorConfig
from armlab.sensors.presets import CapstanSensorSuite

__all__ = ["validate"]


def validate(cfg: VirtualForceSensorConfig) -> None:
    """Raise :class:`ConfigError` on a setting the run cannot support."""
    fs, v = cfg.sensors.fs_hz, cfg.vfs
    nyquist = fs / 2
    # the sum-of-sines excitation's highest component must lie below Nyquist to be recorded at all
    for name in ("band_hz", "id_band_hz"):
        hi = getattr(v, name)[1]
        if not hi < nyquist:
            raise ConfigError(
                f"vfs.{name} upper edge {hi:g} Hz is at or above the Nyquist frequency {nyquist:g} Hz "
                f"(sensors.fs_hz={fs:g}): the excitation cannot be recorded; valid: below {nyquist:g} Hz"
            )
    if not v.lowpass_hz < nyquist:
        raise ConfigError(
            f"vfs.lowpass_hz={v.lowpass_hz:g} Hz is at or above the Nyquist frequency {nyquist:g} Hz "
            f"(sensors.fs_hz={fs:g}); valid: below {nyquist:g} Hz"
        )
    n_samples = int(round(v.trial_s * fs))
    if v.sg_window > n_samples:
        raise ConfigError(
            f"vfs.sg_window={v.sg_window} samples is longer than a trial ({n_samples} samples: vfs.trial_s="
            f"{v.trial_s:g} s at {fs:g} Hz); valid: <= {n_samples}"
        )
    if cfg.sensors.preset == "realistic":
        CapstanSensorSuite.realistic().check_rate(fs, n_samples)
