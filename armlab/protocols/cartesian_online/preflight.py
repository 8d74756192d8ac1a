"""The checks of a ``cartesian_online`` config that need no simulation (``Protocol.validate``).

Run by :func:`armlab.protocols.compose.compose`, so ``armlab run`` refuses before its run folder
exists: level B has its own sensor models and settle; level A has ideal sensors (its one sensor
effect is ``simulation.force_noise_std_N``) and no physics step (``sim.*`` is read by levels B and
C only); the waveforms need at least 10 samples per ramp at ``sensors.fs_hz``.
"""

from __future__ import annotations

from armlab.config.schema import SimConfig
from armlab.errors import ConfigError
from armlab.perturbations.ramp_waveforms import MIN_SAMPLES_PER_SEGMENT, TRAPEZOIDAL, TRIANGULAR
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig, SimulationConfig

__all__ = [
    "LEVEL_C_READS",
    "LEVEL_C_UNREAD",
    "validate",
]

#: the ``simulation`` fields level C reads, and those it does not (refused when changed)
LEVEL_C_READS = ("force_noise_std_N", "n_stops", "pause_s", "corner_s")
LEVEL_C_UNREAD = (
    "stiffness_scale",
    "noise_study_std_N",
    "hand_mass_kg",
    "sigma",
    "sinusoid_omega_rad_s",
    "spiral_end_fraction",
)


def validate(cfg: CartesianOnlineConfig) -> None:
    """Raise :class:`ConfigError` on a setting the chosen level cannot honour (never ignore it)."""
    s = cfg.simulation
    if s.level == "B":
        if cfg.sensors.preset != "ideal":
            raise ConfigError(
                f"sensors.preset={cfg.sensors.preset!r}: level B always records through its own JR3 F/T and "
                "LWR encoder models and keeps the clean channels beside them (valid: ideal, the default)"
            )
        if cfg.sim.settle_s != SimConfig().settle_s:
            raise ConfigError(
                "sim.settle_s is not read at simulation.level=B (each perturbation starts at rest at its "
                "stop, armlab.sim.cartesian_level_b.SETTLE_S); valid: sim.timestep_s, sim.integrator"
            )
    if s.level == "A":
        if cfg.sensors.preset != "ideal":
            raise ConfigError(
                f"sensors.preset={cfg.sensors.preset!r}: level A's sensors are the thesis's ideal ones "
                "(valid: ideal); set force noise with simulation.force_noise_std_N"
            )
        if cfg.sim != SimConfig():
            raise ConfigError(
                "sim.* is not read at simulation.level=A (the thesis's algebraic generator has no physics "
                "step); valid: leave sim at its defaults"
            )
        if s.hand_mass_kg != SimulationConfig().hand_mass_kg:
            raise ConfigError(
                "simulation.hand_mass_kg is not read at simulation.level=A (the thesis's model has no "
                "inertia); valid: simulation=level_b"
            )
    if s.level == "C":
        if cfg.sensors.preset != "ideal" or cfg.sim != SimConfig():
            raise ConfigError(
                "sensors.* presets and sim.* are not read at simulation.level=C (the Hill arm's force is "
                "quasi-static, the robot an ideal position source); valid: simulation.force_noise_std_N"
            )
        defaults = SimulationConfig()
        unread = [f for f in LEVEL_C_UNREAD if getattr(s, f) != getattr(defaults, f)]
        if unread:
            raise ConfigError(
                f"simulation.{unread[0]} is not read at simulation.level=C (the Hill arm is the truth, on "
                f"its own circle); valid there: {', '.join(LEVEL_C_READS)}"
            )
    # the rule of RampWaveform.sample; the trapezoid's 50 ms ramp is the shortest segment (§3.1.1)
    need = max(w.min_fs_hz for w in (TRIANGULAR, TRAPEZOIDAL))
    if cfg.sensors.fs_hz < need:
        raise ConfigError(
            f"sensors.fs_hz={cfg.sensors.fs_hz:g} Hz gives fewer than {MIN_SAMPLES_PER_SEGMENT} samples on "
            f"the waveforms' shortest ramp; valid: >= {need:g} Hz (thesis: 1000 Hz)"
        )
