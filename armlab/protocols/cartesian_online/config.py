"""The typed experiment of ``cartesian_online`` (paper 002, thesis Ch. 3): the groups it reads.

``simulation`` says how the five experiments are generated (level B, the default: the LWR and a
hand with inertia in MuJoCo, its estimates tested against the field's truth in
tests/test_cartesian_level_b.py; level A: the thesis's own algebraic generator; level C: the
conditioning lab's planar Hill arm as the truth, where the diagonal quadratic and the polar model
are compared by held-out force VAF),
``identification`` how they are identified and scored (the group ``armlab estimate`` takes).
Defaults are the thesis's (Tables 3.1-3.3, §3.1-3.5) or, where it is silent, spec 002's and
docs/cartesian_online.md's documented choices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, get_args

from armlab.config.schema import ExperimentConfig, SensorsConfig
from armlab.config.validate import check, choice

__all__ = [
    "HAND_MASS_MIN_KG",
    "IDENTIFICATION_CHOICES",
    "CartesianOnlineConfig",
    "IdentificationConfig",
    "SimulationConfig",
    "SimulationLevel",
]

#: How the experiments are generated: (A) the thesis's algebraic generator; (B) the LWR pushing a
#: hand with inertia through its cuff in MuJoCo, the field as the human's force, measured through
#: the JR3 F/T and LWR encoder models; (C) the planar Hill arm as the truth (its full,
#: posture-dependent Cartesian impedance) on a circle within its reach.
SimulationLevel = Literal["A", "B", "C"]
#: Exp. 4 estimators: the thesis's Eq. 3.4.1 (constant damping columns) and the model's own D = δ√K.
Exp4Method = Literal["linear", "sqrt_damping"]
IDENTIFICATION_CHOICES: tuple[str, ...] = get_args(Exp4Method)

#: kg, the lightest level-B hand accepted. The field is an explicit force on the hand (evaluated
#: at the start of each step), and the cuff's connect constraint, whose stiffness MuJoCo scales by
#: the effective mass, holds a light hand less and less. Measured on Exp. 4 at the default 0.5 ms
#: step and Table 3.1's stiffness: at 10 g the hand's peak acceleration is 1.8 m/s² (as at 0.966 kg);
#: at 1 g the hand vibrates against the cuff (357 m/s²), which halving the step removes
#: (sqrt(K/m)·dt = 2.7 at 1 g, beyond the explicit limit of 2; 0.87 at 10 g).
HAND_MASS_MIN_KG = 0.01

if TYPE_CHECKING:
    Level = SimulationLevel
    Method = Exp4Method
else:  # OmegaConf 2.3 rejects Literal field types: it reads these as str, __post_init__ checks them
    Level = Method = str


@dataclass(kw_only=True)
class SimulationConfig:
    """How the thesis's five experiments are generated (thesis Ch. 3; spec 002)."""

    # B (default): the LWR + hand in MuJoCo (armlab.sim.cartesian_level_b), level A on the same paths
    # beside it; A: the thesis's q_h = q_r + q_p, F = D(q_h) q̇_h + K(q_h) q_p (thesis Ch. 3);
    # C: the planar Hill arm's force on the handle (armlab.sim.cartesian_level_c)
    level: Level = "B"
    # dimensionless factor on every stiffness coefficient of Table 3.1 (spec 002: its values are
    # 10-100x physiological hand stiffness; 1 is the thesis)
    stiffness_scale: float = 1.0
    # N, std of white force-sensor noise per axis on every experiment (0 = the thesis: noise-free)
    force_noise_std_N: float = 0.0
    # N, std of the force noise of the extra Exp. 4 run of spec 002's check 6 (0.05 N); 0 leaves
    # that run out
    noise_study_std_N: float = 0.05
    # kg, level B's hand (hand + the forearm's share at the wrist: Winter 2009, Table 4.1, 75 kg
    # subject; models/cartesian_hand/README.md); a test lowers it to show the inertia's effect
    hand_mass_kg: float = 0.966
    # co-contraction index σ of Eq. 2.2.4 (thesis: never stated; spec 002 assumption 0)
    sigma: float = 0.0
    n_stops: int = 20  # stops over the 100 s path (thesis §3.1-3.5: 20 perturbations/sequences)
    pause_s: float = 0.5  # s, pause between the perturbations of one sequence (thesis §3.2.1)
    corner_s: float = 0.0  # s, quintic corner blend of the waveforms (0: the thesis's sharp corners)
    # rad/s of Exp. 3's sinusoid; None: the golden-angle rate of the stop spacing (docs/cartesian_online.md)
    sinusoid_omega_rad_s: float | None = None
    spiral_end_fraction: float = 0.1  # Exp. 5's final radius, fraction of 0.1 m (thesis §3.5.1: 10 %)

    def __post_init__(self) -> None:
        choice("simulation.level", self.level, SimulationLevel)
        check(
            math.isfinite(self.stiffness_scale) and self.stiffness_scale > 0,
            "simulation.stiffness_scale must be a positive factor (1 = Table 3.1), "
            f"got {self.stiffness_scale}",
        )
        for name in ("force_noise_std_N", "noise_study_std_N"):
            value = getattr(self, name)
            check(value >= 0, f"simulation.{name} must be >= 0 N (0 = noise-free), got {value}")
        check(
            math.isfinite(self.hand_mass_kg) and self.hand_mass_kg >= HAND_MASS_MIN_KG,
            f"simulation.hand_mass_kg must be >= {HAND_MASS_MIN_KG:g} kg (default 0.966, Winter 2009), "
            f"got {self.hand_mass_kg}",
        )
        check(0.0 <= self.sigma <= 1.0, f"simulation.sigma must lie in [0, 1] (Eq. 2.2.4), got {self.sigma}")
        check(
            isinstance(self.n_stops, int) and 3 <= self.n_stops <= 200,
            f"simulation.n_stops must be an integer in [3, 200] (thesis: 20), got {self.n_stops}",
        )
        check(0.0 <= self.pause_s <= 5.0, f"simulation.pause_s must lie in [0, 5] s, got {self.pause_s}")
        check(
            0.0 <= self.corner_s <= 0.05,
            f"simulation.corner_s must lie in [0, 0.05] s (the trapezoid's shortest ramp is 0.05 s), "
            f"got {self.corner_s}",
        )
        if self.sinusoid_omega_rad_s is not None:
            check(
                self.sinusoid_omega_rad_s > 0,
                f"simulation.sinusoid_omega_rad_s must be > 0 rad/s or null (golden-angle rate), "
                f"got {self.sinusoid_omega_rad_s}",
            )
        check(
            0.0 < self.spiral_end_fraction <= 1.0,
            f"simulation.spiral_end_fraction must lie in (0, 1], got {self.spiral_end_fraction}",
        )


@dataclass(kw_only=True)
class IdentificationConfig:
    """How the experiments are identified and scored (thesis §3.1.2-3.5.2; spec 002)."""

    # Exp. 4 estimators run on the configured record: the thesis's "linear" Eq. 3.4.1 and
    # "sqrt_damping" (the model's own D = δ√K, 12 + 2 parameters; exact without noise)
    exp4_methods: list[str] = field(default_factory=lambda: ["linear", "sqrt_damping"])
    polar_origin_m: tuple[float, float] = (0.0, 0.0)  # m, origin of the polar model (not stated: the frame's)
    r2_adj_threshold: float = 0.999  # R²_adj an order must reach (not stated; spec 002's level)
    max_order: int = 3  # highest polynomial order tried per coordinate in Exp. 5's selection
    grid_points_per_axis: int = 41  # field score grid over the circle's disc (41 x 41 -> 1257 points)

    def __post_init__(self) -> None:
        check(
            len(self.exp4_methods) > 0 and len(set(self.exp4_methods)) == len(self.exp4_methods),
            f"identification.exp4_methods must name each method once, got {list(self.exp4_methods)}; "
            f"valid: {list(IDENTIFICATION_CHOICES)}",
        )
        for m in self.exp4_methods:
            choice("identification.exp4_methods", m, Exp4Method)
        check(
            len(self.polar_origin_m) == 2,
            f"identification.polar_origin_m must be (x, y) in m, got {list(self.polar_origin_m)}",
        )
        check(
            0.0 < self.r2_adj_threshold < 1.0,
            f"identification.r2_adj_threshold must lie in (0, 1), got {self.r2_adj_threshold}",
        )
        check(
            isinstance(self.max_order, int) and 1 <= self.max_order <= 5,
            f"identification.max_order must be an integer in [1, 5], got {self.max_order}",
        )
        check(
            isinstance(self.grid_points_per_axis, int) and 5 <= self.grid_points_per_axis <= 201,
            "identification.grid_points_per_axis must be an integer in [5, 201], "
            f"got {self.grid_points_per_axis}",
        )


@dataclass(kw_only=True)
class CartesianOnlineConfig(ExperimentConfig):
    """The thesis's five Cartesian experiments and their online least-squares identification."""

    protocol_name: str = "cartesian_online"
    # ideal sensors: level A's only sensor effect is simulation.force_noise_std_N (thesis §3.2.2)
    sensors: SensorsConfig = field(default_factory=lambda: SensorsConfig(preset="ideal"))
    simulation: SimulationConfig = field(default_factory=SimulationConfig)
    identification: IdentificationConfig = field(default_factory=IdentificationConfig)
