"""What a MuJoCo step can integrate: timestep bounds and the stability bound of a spring.

Refused up front (a :class:`~armlab.errors.ConfigError` naming the bound, before anything is
simulated or written), so that a setting that cannot be integrated never runs for minutes or
passes as a result (docs/reliability.md, "Instability"). Every laboratory also checks its trials
while simulating them (:mod:`armlab.sim.stability`): these bounds are necessary conditions, not
sufficient ones.
"""

from __future__ import annotations

import math

from armlab.config.validate import check, divisor_rates

__all__ = [
    "OMEGA_DT_LIMIT",
    "TIMESTEP_MAX_S",
    "TIMESTEP_MIN_S",
    "check_spring",
    "check_steps_per_sample",
]

# s, finest physics step a run may ask for. The finest any armlab laboratory needs is 0.1 ms
# (fractional_elbow's firm grasp; the joint rig picks its own, >= 0.1 ms at 1 kHz for ankle-sized
# subjects): 10 us leaves a 10x margin. Each 10x below multiplies the run time by 10 (a default
# conditioning run takes ~30 s at 0.5 ms, ~25 min at 10 us) inside MuJoCo's C loop, where Ctrl-C is
# not seen until a rollout chunk returns (sim.timestep_s=1e-7 ran ~10 min silently).
TIMESTEP_MIN_S = 1e-5
# s, coarsest step: the labs sample at >= 1 kHz and their cuff/grasp/cable modes lie at 10-200 Hz;
# a step beyond 1 ms undersamples the recording (the bound the schema has always had).
TIMESTEP_MAX_S = 1e-3
#: 1, largest omega*dt (omega = sqrt(k/m) of an undamped spring-mass) each MuJoCo integrator keeps
#: stable. "Euler" is semi-implicit (symplectic) Euler, stable for omega*dt < 2 on x'' = -omega^2 x;
#: "implicitfast" and "implicit" are implicit in velocity only (damping, actuator gains), so a
#: spring stays explicit with the same limit; RK4's stability region reaches 2*sqrt(2) on the
#: imaginary axis (and ~2.78 on the real axis, the bound used for its explicit damping).
OMEGA_DT_LIMIT = {"Euler": 2.0, "implicitfast": 2.0, "implicit": 2.0, "RK4": 2.78}


def check_steps_per_sample(timestep_s: float, fs_hz: float, what: str = "sample") -> None:
    """Refuse a physics step that does not divide the sample (or control) period 1/fs_hz.

    The message names both ways out: the rates that divide the physics rate, and the steps that
    divide the period.
    """
    for key, value in (("sensors.fs_hz", fs_hz), ("sim.timestep_s", timestep_s)):
        check(math.isfinite(value), f"{key}={value} is not a finite number; give a finite value")
        check(value > 0, f"{key}={value:g} must be positive")
    n = round(1.0 / (fs_hz * timestep_s))
    check(
        n >= 1 and abs(n * timestep_s * fs_hz - 1.0) < 1e-9,
        f"sensors.fs_hz={fs_hz:g} and sim.timestep_s={timestep_s:g} s: the {what} period "
        f"1/sensors.fs_hz = {1.0 / fs_hz:g} s must be a whole number of physics steps; valid: "
        f"sensors.fs_hz in {divisor_rates(1.0 / timestep_s)} Hz, ..., or sim.timestep_s = "
        f"{1.0 / fs_hz:g} / n (e.g. {1.0 / (fs_hz * max(n, 1)):g})",
    )


def check_spring(
    name: str,
    stiffness: float,
    mass: float,
    mass_what: str,
    timestep_s: float,
    integrator: str,
    *,
    unit: str = "N/m",
    mass_unit: str = "kg",
    damping: float = 0.0,
    damping_name: str = "",
) -> None:
    """Refuse a spring (and, under RK4, a damper) the step cannot integrate.

    Args:
        name: the stiffness's config path, e.g. ``"cuff.stiffness_N_per_m"``.
        stiffness: in ``unit``.
        mass: the lightest mass the spring moves, in ``mass_unit`` (kg; kg m² for a rotational
            spring in N m/rad).
        mass_what: what that mass is, named in the message (e.g. ``"the cuff shell (cuff.mass_kg)"``).
        timestep_s: s, physics step; integrator: MuJoCo's (:data:`OMEGA_DT_LIMIT`).
        damping, damping_name: the damper beside the spring; only RK4 integrates it explicitly
            (Euler and the implicit integrators take joint damping implicitly).
    """
    limit = OMEGA_DT_LIMIT[integrator]
    k_max = (limit / timestep_s) ** 2 * mass
    omega_dt = math.sqrt(stiffness / mass) * timestep_s
    check(
        stiffness < k_max,
        f"{name}={stiffness:g} {unit} cannot be integrated at sim.timestep_s={timestep_s:g} s: omega*dt = "
        f"{omega_dt:.2f} with {mass_what} = {mass:.3g} {mass_unit}, beyond the {integrator} integrator's "
        f"stability limit {limit:g}; valid: {name} < {k_max:.3g} {unit}, or a smaller sim.timestep_s",
    )
    if integrator == "RK4" and damping > 0:
        c_max = limit / timestep_s * mass
        check(
            damping < c_max,
            f"{damping_name}={damping:g} cannot be integrated explicitly by RK4 at sim.timestep_s="
            f"{timestep_s:g} s (rate*dt beyond {limit:g}); valid: {damping_name} < {c_max:.3g}, or "
            "sim.integrator=Euler (implicit in damping)",
        )
