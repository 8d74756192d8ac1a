"""Typed configuration of an armlab experiment (the single source of truth for Hydra).

Every group is a ``@dataclass(kw_only=True)`` whose ``__post_init__`` rejects invalid values with
a message naming the valid range or choices. YAML files under ``configs/`` only set values.
Units are in the field names (``_s``, ``_hz``, ``_N``, ...) and sources in the comments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from armlab.errors import ConfigError

__all__ = [
    "ArmConfig",
    "CuffConfig",
    "EstimatorConfig",
    "ExperimentConfig",
    "OutputConfig",
    "ReflexConfig",
    "RobotConfig",
    "ScenarioConfig",
    "SensorsConfig",
    "SimConfig",
]

MUSCLE_VARIANTS = ("hill", "linear")
SENSOR_PRESETS = ("realistic", "ideal")
XI_SOURCES = ("truth", "paper")


def _check(cond: bool, msg: str) -> None:
    if not cond:
        raise ConfigError(msg)


def _choice(name: str, value: str, valid: tuple[str, ...]) -> None:
    _check(value in valid, f"{name}={value!r} is not valid; choose one of {list(valid)}")


@dataclass(kw_only=True)
class ArmConfig:
    """The human arm model and the subject's posture and effort."""

    model: str = "arm_planar"
    muscle: str = "hill"  # "hill" (MuJoCo FLV muscle) or "linear" (exact spring-damper)
    q0: tuple[float, float] = (0.08, 1.00)  # rad, initial configuration, conditioning paper IV-B
    cocontraction: float = 0.2  # activation of every muscle before the pre-load is added
    preload_N: float = 5.0  # N, distal force the subject exerts, conditioning paper IV-B
    shoulder_pos_m: tuple[float, float, float] = (0.0, 0.0, 0.9)  # m, shoulder in world (seated)

    def __post_init__(self) -> None:
        _choice("arm.model", self.model, ("arm_planar",))
        _choice("arm.muscle", self.muscle, MUSCLE_VARIANTS)
        _check(
            0.0 < self.cocontraction < 1.0, f"arm.cocontraction must lie in (0, 1), got {self.cocontraction}"
        )
        _check(0.0 <= self.preload_N <= 50.0, f"arm.preload_N must lie in [0, 50] N, got {self.preload_N}")
        _check(0.0 < self.q0[1] < 2.6, f"arm.q0 elbow angle must lie in (0, 2.6) rad, got {self.q0[1]}")
        _check(
            -0.7 < self.q0[0] < 2.3, f"arm.q0 shoulder angle must lie in (-0.7, 2.3) rad, got {self.q0[0]}"
        )


@dataclass(kw_only=True)
class ReflexConfig:
    """Stretch-reflex pathways feeding muscle stretch back into activation (paper II-B, Fig. 1).

    Each muscle's control is ``cocontraction + sum over pathways of gain * [stretch]_+`` where
    stretch is the muscle-tendon lengthening relative to the pre-perturbation length, in units of
    the optimal fibre length 0.1 m, and its velocity in those units per second.
    """

    enabled: bool = True
    stretch_latency_s: float = 0.035  # s, short-latency stretch reflex 25-50 ms (paper II-B); mid
    # Gains (assumption): chosen so that the reflex torque becomes comparable to the intrinsic one
    # some 100 ms after onset, as in stretch-reflex studies of the arm (e.g. Perreault et al.
    # 2004), without destabilising the hold.
    stretch_gain: float = 0.5  # activation per unit normalised stretch
    velocity_gain: float = 0.02  # activation per (normalised length / s)
    spinal_latency_s: float = 0.090  # s, spinal reflex 70-110 ms (paper II-B); mid-range
    spinal_gain: float = 0.5  # activation per unit normalised stretch (assumption)

    def __post_init__(self) -> None:
        for name in ("stretch_latency_s", "spinal_latency_s"):
            value = getattr(self, name)
            _check(value > 0, f"reflex.{name} must be positive (s), got {value}")
        _check(
            self.stretch_latency_s <= self.spinal_latency_s,
            f"reflex.stretch_latency_s ({self.stretch_latency_s}) must not exceed "
            f"reflex.spinal_latency_s ({self.spinal_latency_s})",
        )
        for name in ("stretch_gain", "velocity_gain", "spinal_gain"):
            value = getattr(self, name)
            _check(value >= 0, f"reflex.{name} must be >= 0, got {value}")


@dataclass(kw_only=True)
class CuffConfig:
    """The cuff coupling hand and robot flange: explicit translational spring-damper."""

    rigid: bool = False
    # Soft tissue + strap compliance of an arm cuff (assumption: interface stiffness of order
    # 1e4 N/m, the range reported for forearm/hand orthoses and manipulandum handles).
    stiffness_N_per_m: float = 2.0e4
    damping_Ns_per_m: float = 100.0  # N s/m, ~0.3 of critical with ~2 kg endpoint mass (assumption)
    mass_kg: float = 0.6  # kg, plastic cuff + metal support beam (assumption, paper IV-A)

    def __post_init__(self) -> None:
        _check(
            self.stiffness_N_per_m > 0, f"cuff.stiffness_N_per_m must be > 0, got {self.stiffness_N_per_m}"
        )
        _check(self.damping_Ns_per_m >= 0, f"cuff.damping_Ns_per_m must be >= 0, got {self.damping_Ns_per_m}")
        _check(self.mass_kg > 0, f"cuff.mass_kg must be > 0, got {self.mass_kg}")


@dataclass(kw_only=True)
class RobotConfig:
    """The perturbing robot."""

    model: str = "lwr"
    # m, robot base in the world, in front of and lateral to the subject (assumption: places the
    # hand at q0 well inside the LWR's workspace with the flange pointing down)
    base_pos_m: tuple[float, float, float] = (0.55, 0.75, 0.55)

    def __post_init__(self) -> None:
        _choice("robot.model", self.model, ("lwr",))


@dataclass(kw_only=True)
class SimConfig:
    """Physics settings."""

    timestep_s: float = 0.0005  # s; 2 physics steps per 1 kHz sample
    # Semi-implicit Euler: the least biased of MuJoCo's integrators for the continuous-time models
    # the estimators fit, with the stiff cuff-hand connect constraint (measured on the rigid
    # linear arm: xi within 0.3 %; implicitfast 0.6 %; RK4 2.6 %, it handles the soft constraint
    # poorly). See the issue note for the timestep study.
    integrator: str = "Euler"
    settle_s: float = 1.0  # s, settling of the pre-loaded hold before the trials start

    def __post_init__(self) -> None:
        _choice("sim.integrator", self.integrator, ("RK4", "implicitfast", "Euler", "implicit"))
        _check(
            0 < self.timestep_s <= 0.001, f"sim.timestep_s must lie in (0, 0.001] s, got {self.timestep_s}"
        )
        _check(self.settle_s >= 0.2, f"sim.settle_s must be >= 0.2 s, got {self.settle_s}")


@dataclass(kw_only=True)
class SensorsConfig:
    """Sensor models applied to the clean simulated signals."""

    preset: str = "realistic"  # "realistic" (JR3/LWR-class noise) or "ideal"
    fs_hz: float = 1000.0  # Hz, sampling rate of the recording system (paper IV-A)

    def __post_init__(self) -> None:
        _choice("sensors.preset", self.preset, SENSOR_PRESETS)
        _check(self.fs_hz > 0, f"sensors.fs_hz must be > 0, got {self.fs_hz}")


@dataclass(kw_only=True)
class ScenarioConfig:
    """Which perturbation timeline (``scenarios/<name>.yaml``) and optional subsetting."""

    name: str = "conditioning_window"
    k_values: list[int] | None = None  # window indices to run; None = all in the scenario file
    n_trials: int | None = None  # trials per window; None = the scenario file's number

    def __post_init__(self) -> None:
        if self.n_trials is not None:
            _check(
                self.n_trials >= 2,
                f"scenario.n_trials must be >= 2 (identify + validate), got {self.n_trials}",
            )


@dataclass(kw_only=True)
class EstimatorConfig:
    """Processing and least-squares identification (paper IV-C, III-A, III-C)."""

    method: str = "joint_ls"
    # Hz, phase-free low-pass of q and F before differentiation (paper IV-C gives no cutoff). The
    # same zero-phase filter on both sides keeps the linear fit consistent; 20 Hz keeps K within
    # ~5 % at T_obs >= 400 ms under the realistic sensor noise (40 Hz: ~20 %). None = off.
    lowpass_hz: float | None = 20.0
    filter_order: int = 4
    baseline_s: float = 0.2  # s, pre-onset span averaged for q0 and tau0 (paper IV-C)
    xi_source: str = "truth"  # known xi for the reduced model: model truth or the paper's values
    symmetry_tol: float = 0.1  # quasi-symmetric when ||A - A^T||_F / ||A + A^T||_F below this
    constancy_tol: float = 0.05  # quasi-constant when relative change to next window below this
    t_obs_s: list[float] | None = None  # explicit windows; None = T_k + 70 ms per scenario window

    def __post_init__(self) -> None:
        _choice("estimator.method", self.method, ("joint_ls",))
        _choice("estimator.xi_source", self.xi_source, XI_SOURCES)
        if self.lowpass_hz is not None:
            _check(self.lowpass_hz > 0, f"estimator.lowpass_hz must be > 0 Hz or null, got {self.lowpass_hz}")
        _check(self.filter_order >= 1, f"estimator.filter_order must be >= 1, got {self.filter_order}")
        _check(self.baseline_s > 0, f"estimator.baseline_s must be > 0 s, got {self.baseline_s}")
        _check(
            0 < self.symmetry_tol < 1, f"estimator.symmetry_tol must lie in (0, 1), got {self.symmetry_tol}"
        )
        _check(
            0 < self.constancy_tol < 1,
            f"estimator.constancy_tol must lie in (0, 1), got {self.constancy_tol}",
        )
        if self.t_obs_s is not None:
            bad = [t for t in self.t_obs_s if not (math.isfinite(t) and t > 0)]
            _check(not bad, f"estimator.t_obs_s must hold positive times in s, got {bad}")


@dataclass(kw_only=True)
class OutputConfig:
    """What a run writes besides results.json."""

    trials: bool = True  # trials.h5
    figures: bool = True  # PNG figures
    recording: bool = True  # rerun .rrd of every trial
    print_table: bool = True


@dataclass(kw_only=True)
class ExperimentConfig:
    """A whole experiment: one protocol applied to one simulated subject."""

    protocol_name: str = "conditioning_window"  # set by configs/protocol/<name>.yaml
    seed: int = 0
    arm: ArmConfig = field(default_factory=ArmConfig)
    reflex: ReflexConfig = field(default_factory=ReflexConfig)
    cuff: CuffConfig = field(default_factory=CuffConfig)
    robot: RobotConfig = field(default_factory=RobotConfig)
    sim: SimConfig = field(default_factory=SimConfig)
    sensors: SensorsConfig = field(default_factory=SensorsConfig)
    scenario: ScenarioConfig = field(default_factory=ScenarioConfig)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    output: OutputConfig = field(default_factory=OutputConfig)

    def __post_init__(self) -> None:
        _check(self.seed >= 0, f"seed must be a non-negative integer, got {self.seed}")
