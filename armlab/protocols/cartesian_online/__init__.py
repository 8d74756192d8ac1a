"""Protocol ``cartesian_online``: position-dependent Cartesian impedance by online LS (../shared/seeds/002).

The MSc thesis's Chapter 3: a hand whose diagonal stiffness is a quadratic of its position
(Tables 3.1/3.2) is perturbed by a robot stopping on a reference path; five experiments identify
it by least squares re-solved as data arrives, up to a polar model. Level B (default): the LWR
and a hand with inertia in MuJoCo, measured by JR3/encoder models, beside level A (the thesis's own
algebraic generator) on the same paths; level A alone is ``simulation=level_a``; level C
(``simulation=level_c``): the planar Hill arm as the truth, the diagonal quadratic against the
polar model.
"""

from armlab.protocols.base import Protocol
from armlab.protocols.cartesian_online import hooks, preflight
from armlab.protocols.cartesian_online.config import (
    CartesianOnlineConfig,
    IdentificationConfig,
    SimulationConfig,
)
from armlab.protocols.cartesian_online.diagnosis import HOOKS
from armlab.sim.cartesian_level_b import load_level_b_compiled

__all__ = [
    "PROTOCOL",
    "CartesianOnlineConfig",
    "IdentificationConfig",
    "SimulationConfig",
]

PROTOCOL = Protocol(
    name="cartesian_online",
    paper="seeds/002: position-dependent Cartesian impedance, online LS, polar model (MSc thesis Ch. 3)",
    summary="quadratic hand stiffness field perturbed on a path; per-sequence, cumulative and recursive LS",
    schema=CartesianOnlineConfig,
    groups={"sensors": "ideal", "simulation": "level_b"},
    simulate=hooks.simulate,
    preload=load_level_b_compiled,
    validate=preflight.validate,
    reestimate_group="identification",
    reestimate=hooks.reestimate,
    outputs=hooks.outputs,
    format_table=hooks.format_table,
    examples=(
        "run protocol=cartesian_online simulation=level_a simulation.force_noise_std_N=0.05",
        "run protocol=cartesian_online simulation.corner_s=0.02",
        "run protocol=cartesian_online simulation.hand_mass_kg=0.1",
        "run protocol=cartesian_online simulation.stiffness_scale=0.05 seed=3",
        "estimate outputs/cartesian_online/<run> identification.r2_adj_threshold=0.99",
        "diagnose data=outputs/cartesian_online/<run> protocol=cartesian_online",
        "diagnose-benchmark referee.protocol=cartesian_online referee.replicates=2",
    ),
    lab_effects={"force_sensor_noise": "simulation.force_noise_std_N"},
    catalogue=(
        "force_sensor_noise",
        "force_sensor_drift",
        "payload_mass",
        "cuff_compliance",
        "channel_delay",
        "non_quadratic_field",
    ),
    diagnosis=HOOKS,
)
