"""The typed experiment of ``conditioning_window`` (seeds/000): the groups it reads, nothing else.

The default lab is calibrated on the paper's full-model thresholds (section IV-D: K positive
definite beyond 320 ms, quasi-symmetric beyond 370 ms) and checked on the others (quasi-constant
beyond 400 ms, the reduced model reaching positive definiteness earlier, Fig. 5's behaviour); see
docs/reproduction/conditioning_window.md. The values below are the defaults of a directly built
:class:`ConditioningWindowConfig`; configs/protocol/conditioning_window.yaml repeats them for the
composed (CLI) config.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from armlab.config.integration import check_spring, check_steps_per_sample
from armlab.config.schema import (
    ArmConfig,
    CuffConfig,
    EstimatorConfig,
    ExperimentConfig,
    ReflexConfig,
    RobotConfig,
    ScenarioConfig,
)
from armlab.config.subject import PAPER000_SUBJECT, SubjectConfig

__all__ = [
    "CUFF_DAMPING_NS_PER_M",
    "CUFF_STIFFNESS_N_PER_M",
    "ConditioningWindowConfig",
    "CONSTANCY_TOL_PER_S",
    "SUBJECT",
    "SYMMETRY_TOL",
]

# N/m, forearm soft tissue + plastic cuff in series (the robot measures the cuff, not the bone).
# Measured interfaces of the upper arm in an exoskeleton cuff: 2.1-4.5 N/mm by direction
# (Schiebl et al. 2025, Sensors 25:4605). Calibrated inside that range on the paper's full-model
# K-positive-definite threshold (320 ms, Fig. 4): 3.0 kN/m gives 320-330 ms (seed 0).
CUFF_STIFFNESS_N_PER_M = 3000.0
# N s/m, 0.3 of critical damping with ~2 kg of hand + forearm behind the cuff (the rule the
# CuffConfig default states): 0.3 x 2 sqrt(3000 x 2) = 46 N s/m. Derived, not calibrated.
CUFF_DAMPING_NS_PER_M = 46.0
# The subject's activation fluctuation (armlab.config.subject carries the sources):
# fluctuation_cv calibrated on the quasi-symmetric threshold (370 ms, Fig. 4) inside the 2-10 %
# literature range (seed 0, cuff as above: 0.03 -> 310 ms, 0.035 and 0.0375 -> 350 ms, 0.04 ->
# never, the 500 ms extension window then staying skew; 0.035 is the closest to 370 ms);
# fluctuation_hz and trial_cv fixed from the literature, not calibrated.
SUBJECT = PAPER000_SUBJECT
# Criteria tolerances (section IV-D names the criteria but gives no tolerance):
# quasi-symmetric when |A - A^T|_F / |A + A^T|_F < 0.1 for K and D: a 10 % skew part, i.e. the
# off-diagonal pair differing by ~30 % of its mean for K ~ [[15, 6], [6, 16]] N m/rad; armlab's
# earlier default, kept (not calibrated).
SYMMETRY_TOL = 0.1
# quasi-constant when every parameter changes to the next window by less than 5 x its block's
# norm per second of T_obs: the earlier 5 % per 10 ms window step on the paper's grid, now per
# second so that the 30-50 ms extension steps are judged by the same rate (not calibrated).
CONSTANCY_TOL_PER_S = 5.0


@dataclass(kw_only=True)
class ConditioningWindowConfig(ExperimentConfig):
    """The LWR perturbing the planar arm through the cuff; joint-space least squares per window."""

    protocol_name: str = "conditioning_window"
    arm: ArmConfig = field(default_factory=ArmConfig)
    reflex: ReflexConfig = field(default_factory=ReflexConfig)
    cuff: CuffConfig = field(
        default_factory=lambda: CuffConfig(
            stiffness_N_per_m=CUFF_STIFFNESS_N_PER_M, damping_Ns_per_m=CUFF_DAMPING_NS_PER_M
        )
    )
    robot: RobotConfig = field(default_factory=RobotConfig)
    scenario: ScenarioConfig = field(default_factory=lambda: ScenarioConfig(name="conditioning_window"))
    estimator: EstimatorConfig = field(
        default_factory=lambda: EstimatorConfig(
            xi_source="full_fit", symmetry_tol=SYMMETRY_TOL, constancy_tol_per_s=CONSTANCY_TOL_PER_S
        )
    )
    subject: SubjectConfig = field(default_factory=lambda: SubjectConfig(**SUBJECT))

    def __post_init__(self) -> None:
        super().__post_init__()
        check_steps_per_sample(self.sim.timestep_s, self.sensors.fs_hz)
        if not self.cuff.rigid:
            # the cuff springs push the mount (0.02 kg, models/common/cuff.xml) that the connect
            # constraint ties to the shell (cuff.mass_kg) on the hand: the shell alone is a lower
            # bound of the mass they move (the arm adds to it). Necessary only: with the soft
            # constraint the lab diverges below it (measured, undamped at 0.5 ms: 5e6 N/m stable,
            # 8e6 N/m not; the trial's cuff-force bound catches that, armlab.sim.lab).
            check_spring(
                "cuff.stiffness_N_per_m",
                self.cuff.stiffness_N_per_m,
                self.cuff.mass_kg,
                "the cuff shell (cuff.mass_kg)",
                self.sim.timestep_s,
                self.sim.integrator,
                damping=self.cuff.damping_Ns_per_m,
                damping_name="cuff.damping_Ns_per_m",
            )
