"""The typed experiment of ``stiffness_5dof_emg`` (seeds/001): the groups it reads, nothing else.

``stages`` picks the paper's protocol stages (Sec. 3): kinematic calibration, inertial trials,
stiffness trials, EMG maps. Only the stiffness stage is built; asking for another is refused with
the list of what exists. ``trials`` sets how the stiffness trials are drawn and simulated,
``estimation`` how they are reduced to K_q (the group ``armlab estimate`` takes). Defaults are the
paper's numbers or, where it is silent, spec 001's assumptions (each named beside its field).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, get_args

from armlab.config.schema import ExperimentConfig, ReflexConfig
from armlab.config.validate import check, check_tuple_lengths, choice
from armlab.sim.arm5_force_task import A_MIN, PRELOAD_CONDITIONS

__all__ = [
    "BUILT_STAGES",
    "STAGES",
    "EstimationConfig",
    "Stage",
    "Stiffness5dofConfig",
    "TrialsConfig",
]

#: The protocol's stages in the paper's order (Sec. 3).
Stage = Literal["calibration", "inertial", "stiffness", "emg"]
STAGES: tuple[str, ...] = get_args(Stage)
#: The stages this package simulates today (the others come with later slices of issue 19).
BUILT_STAGES: tuple[str, ...] = ("stiffness",)

if TYPE_CHECKING:
    StageName = Stage
else:  # OmegaConf 2.3 rejects Literal field types: it reads these as str, __post_init__ checks them
    StageName = str


@dataclass(kw_only=True)
class TrialsConfig:
    """The stiffness trials (paper Sec. 3; spec 001, Protocol item 3)."""

    # disturbances per pre-load condition: paper Sec. 3, "50 disturbances" per stiffness estimate
    n_per_condition: int = 50
    # the pre-load conditions, names of armlab.sim.arm5_force_task.PRELOAD_CONDITIONS (spec 001
    # assumption: 4 levels in X and 4 in Z, +-5 and +-10 N; the paper gives no values)
    conditions: list[str] = field(default_factory=lambda: list(PRELOAD_CONDITIONS))
    # rad, the joint-space displacement (paper Sec. 3: "approximately 0.08 rad")
    amplitude_rad: float = 0.08
    # s, the random hold before each onset (paper Sec. 3: 1.5-2.5 s)
    wait_s: tuple[float, float] = (1.5, 2.5)
    # s, the quintic's rise and the hold at the displacement (spec 001 assumption: 100 / 300 ms)
    rise_s: float = 0.1
    hold_s: float = 0.3
    # s recorded before the onset (covers the pre-interval, spec 001 assumption [-200, 0] ms)
    pre_s: float = 0.25
    # resting co-contraction, the lower bound of every activation of the force task
    # (armlab.sim.arm5_force_task.A_MIN: intrinsic K_q eigenvalues ~1-13 N m/rad)
    a_min: float = A_MIN

    def __post_init__(self) -> None:
        check_tuple_lengths(self, "trials")
        check(
            isinstance(self.n_per_condition, int) and self.n_per_condition >= 10,
            f"trials.n_per_condition must be an integer >= 10 (one disturbance per direction of the "
            f"10), got {self.n_per_condition!r}",
        )
        valid = list(PRELOAD_CONDITIONS)
        check(len(self.conditions) > 0, f"trials.conditions is empty; choose from {valid}")
        for name in self.conditions:
            choice("trials.conditions", name, tuple(valid))
        check(
            len(set(self.conditions)) == len(self.conditions),
            f"trials.conditions repeats a condition: {list(self.conditions)}",
        )
        check(
            0.0 < self.amplitude_rad <= 0.2,
            f"trials.amplitude_rad must lie in (0, 0.2] rad (the paper: ~0.08), got {self.amplitude_rad}",
        )
        lo, hi = self.wait_s
        check(
            0.0 <= lo <= hi, f"trials.wait_s must be (low, high) s with 0 <= low <= high, got {self.wait_s}"
        )
        for name in ("rise_s", "hold_s", "pre_s"):
            value = getattr(self, name)
            check(value > 0, f"trials.{name} must be a positive number of seconds, got {value}")
        check(0.0 <= self.a_min < 1.0, f"trials.a_min must lie in [0, 1), got {self.a_min}")


@dataclass(kw_only=True)
class EstimationConfig:
    """How the stiffness trials are reduced to K_q (Eqs. (10), (14)-(17); Fig. 3)."""

    # s from the onset: the working-point mean and the displaced mean (spec 001 assumption:
    # [-200, 0] ms and [rise + 100, rise + 300] ms; the paper gives no intervals)
    pre_interval_s: tuple[float, float] = (-0.2, 0.0)
    post_interval_s: tuple[float, float] = (0.2, 0.4)
    # m, the displacement sphere mapped to the force ellipsoid (paper Fig. 3: 5 mm)
    ellipsoid_radius_m: float = 0.005

    def __post_init__(self) -> None:
        check_tuple_lengths(self, "estimation")
        for name in ("pre_interval_s", "post_interval_s"):
            a, b = getattr(self, name)
            check(a < b, f"estimation.{name} must be (start, end) s with start < end, got {(a, b)}")
        check(
            self.ellipsoid_radius_m > 0,
            f"estimation.ellipsoid_radius_m must be > 0 m, got {self.ellipsoid_radius_m}",
        )


@dataclass(kw_only=True)
class Stiffness5dofConfig(ExperimentConfig):
    """The seated 5-DoF arm perturbed by the LWR through a 6-D cuff (seeds/001)."""

    protocol_name: str = "stiffness_5dof_emg"
    # the stages to run, in the paper's order (Sec. 3); only BUILT_STAGES exist today
    stages: list[str] = field(default_factory=lambda: ["stiffness"])
    trials: TrialsConfig = field(default_factory=TrialsConfig)
    estimation: EstimationConfig = field(default_factory=EstimationConfig)
    # the stretch reflex (armlab.sim.arm5_reflex): the conditioning lab's law, gains and latencies
    # (paper 000 Sec. II-B; armlab.config.schema.ReflexConfig), OFF by default: the paper's model
    # (Eq. (14)) freezes activation; on, spec 001's check 7 measures its bias
    reflex: ReflexConfig = field(default_factory=lambda: ReflexConfig(enabled=False))

    def __post_init__(self) -> None:
        super().__post_init__()
        check(len(self.stages) > 0, f"stages is empty; choose from {list(BUILT_STAGES)}")
        for stage in self.stages:
            choice("stages", stage, Stage)
            check(
                stage in BUILT_STAGES,
                f"stage {stage!r} of the paper's protocol is not built yet; the stages that exist: "
                f"{list(BUILT_STAGES)} (of the paper's {list(STAGES)})",
            )
