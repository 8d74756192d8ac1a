"""The checks of a ``fractional_elbow`` config that need no simulation (``Protocol.validate``).

Run by :func:`armlab.protocols.compose.compose`, so ``armlab run`` refuses before its run folder
exists: the scenario and its sample rate, the FRF settings against the trial (band below Nyquist,
Welch window within the record, the FIR's edges below Nyquist), the multisine below Nyquist and
the sensors' bandwidths and delays against the rate, the grasp spring against the physics step.
"""

from __future__ import annotations

from armlab.config.integration import check_spring
from armlab.errors import ConfigError
from armlab.models.direct_drive_scene import DirectDriveScene, build_direct_drive_scene
from armlab.perturbations.multisine import load_force_scenario
from armlab.protocols.fractional_elbow.config import FractionalElbowConfig
from armlab.sensors.presets import DD_ENCODER, JR3_FORCE

__all__ = ["check_grasp", "validate"]


def check_grasp(scene: DirectDriveScene, cfg: FractionalElbowConfig) -> None:
    """Refuse a grasp spring the step cannot integrate (before simulating).

    The grasp couples the handle (motor and link, ``link_inertia``) to the hand (forearm,
    ``elbow_inertia``): its mode moves their reduced inertia I_r = I1 I2 / (I1 + I2), i.e. a mass
    I_r / L² at the handle for the translational ``elbow.grasp_stiffness_N_per_m`` (0.26 kg with
    the default models: the bound is 1.0e8 N/m at 0.1 ms, the default 15 000 N/m has omega*dt 0.02).
    """
    i1, i2 = scene.link_inertia, scene.elbow_inertia
    check_spring(
        "elbow.grasp_stiffness_N_per_m",
        cfg.elbow.grasp_stiffness_N_per_m,
        i1 * i2 / (i1 + i2) / scene.link_length**2,
        "the handle and forearm's reduced inertia over L² (their grasp mode)",
        cfg.sim.timestep_s,
        cfg.sim.integrator,
        damping=cfg.elbow.grasp_damping_Ns_per_m,
        damping_name="elbow.grasp_damping_Ns_per_m",
    )


def validate(cfg: FractionalElbowConfig) -> None:
    """Raise :class:`ConfigError` on a setting the run cannot support."""
    scenario = load_force_scenario(cfg.scenario.name, cfg.scenario.n_trials)
    fs = scenario.fs_hz
    if abs(cfg.sensors.fs_hz - fs) > 1e-9:
        raise ConfigError(
            f"sensors.fs_hz = {cfg.sensors.fs_hz:g} Hz differs from the scenario's {fs:g} Hz; "
            f"valid: sensors.fs_hz={fs:g}"
        )
    if cfg.scenario.k_values is not None:
        raise ConfigError(
            f"scenario.k_values={cfg.scenario.k_values}: the fractional_elbow scenario has no windows to "
            "pick (it reads scenario.name and scenario.n_trials); leave scenario.k_values unset"
        )
    cfg.frf.check_recording(fs, scenario.n_samples, f"trial ({scenario.duration_s:g} s at {fs:g} Hz)")
    nyquist = fs / 2
    if not cfg.frf.fir_stop_hz < nyquist:
        raise ConfigError(
            f"frf.fir_stop_hz={cfg.frf.fir_stop_hz:g} Hz is at or above the Nyquist frequency {nyquist:g} Hz "
            f"of the {fs:g} Hz trials; valid: below {nyquist:g} Hz"
        )
    if cfg.sensors.preset == "realistic":
        for name, spec in (("force", JR3_FORCE), ("encoder", DD_ENCODER)):
            spec.check_rate(fs, scenario.n_samples, name)
    scene = build_direct_drive_scene(cfg.elbow, cfg.sim)
    check_grasp(scene, cfg)
    if cfg.subject.active and scene.muscle_act.size == 0:
        raise ConfigError(
            f"subject.enabled=true fluctuates muscle activations, but elbow.impedance="
            f"{cfg.elbow.impedance} has no muscles; valid: elbow.impedance=muscle, or subject.enabled=false"
        )
