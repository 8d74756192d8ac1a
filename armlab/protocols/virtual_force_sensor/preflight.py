"""The checks of a ``virtual_force_sensor`` config that need no simulation (``Protocol.validate``).

Run by :func:`armlab.protocols.compose.compose`, so ``armlab run`` refuses before its run folder
exists: the sample rate against the physics step, the excitation's band and the processing
low-pass against Nyquist, the Savitzky-Golay window against the trial, and the sensors' bandwidths
and delays against the rate.
"""

from __future__ import annotations

from armlab.config.integration import check_spring
from armlab.errors import ConfigError
from armlab.models.capstan_robot import CAPSTAN_RATIO, ROTOR_INERTIA_KGM2
from armlab.protocols.virtual_force_sensor.config import VirtualForceSensorConfig
from armlab.sensors.presets import CapstanSensorSuite

__all__ = ["check_cable", "validate"]


def check_cable(cfg: VirtualForceSensorConfig) -> None:
    """Refuse a compliant capstan cable the step cannot integrate (before simulating).

    The cable spring (link side, N m/rad) moves the rotor, whose inertia seen from the link is
    N² J_m = 10² x 1.34e-5 = 1.34e-3 kg m² (models/capstan_planar, armlab.models.capstan_robot); the
    link is far heavier. Default: 2000 N m/rad at 0.25 ms, omega*dt = 0.31 (bound 8.6e4 N m/rad).
    """
    if cfg.capstan.cable == "compliant":
        check_spring(
            "capstan.cable_stiffness_Nm_per_rad",
            cfg.capstan.cable_stiffness_Nm_per_rad,
            CAPSTAN_RATIO**2 * ROTOR_INERTIA_KGM2,
            "the rotor's inertia seen from the link (N² J_m)",
            cfg.sim.timestep_s,
            cfg.sim.integrator,
            unit="N m/rad",
            mass_unit="kg m²",
            damping=cfg.capstan.cable_damping_Nms_per_rad,
            damping_name="capstan.cable_damping_Nms_per_rad",
        )


def validate(cfg: VirtualForceSensorConfig) -> None:
    """Raise :class:`ConfigError` on a setting the run cannot support."""
    check_cable(cfg)
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
