"""Typed configuration of an armlab experiment (the single source of truth for Hydra).

Every group is a ``@dataclass(kw_only=True)`` whose ``__post_init__`` rejects invalid values with
a message naming the valid range or choices. A choice is a ``Literal`` type of
:mod:`armlab.config.choices`. YAML files under ``configs/`` only set values.
Units are in the field names (``_s``, ``_hz``, ``_N``, ...) and sources in the comments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, get_args

import numpy as np

from armlab.config import choices
from armlab.config.capstan import CapstanConfig, VfsConfig
from armlab.config.effects import EffectsConfig
from armlab.config.integration import TIMESTEP_MAX_S, TIMESTEP_MIN_S
from armlab.config.validate import check, check_tuple_lengths, choice
from armlab.errors import ConfigError

__all__ = [
    "ArmConfig",
    "CapstanConfig",
    "CuffConfig",
    "DirectDriveConfig",
    "EffectsConfig",
    "ElbowConfig",
    "FrfConfig",
    "EstimatorConfig",
    "ExperimentConfig",
    "OutputConfig",
    "ReflexConfig",
    "RobotConfig",
    "ScenarioConfig",
    "SensorsConfig",
    "SimConfig",
    "VfsConfig",
    "alpha_grid",
]

if TYPE_CHECKING:
    from armlab.config.choices import (
        ArmModel,
        ElbowImpedance,
        ElbowModel,
        EstimatorMethod,
        Integrator,
        MotorModel,
        MuscleModel,
        RobotModel,
        SensorPreset,
        XiSource,
    )
else:  # OmegaConf 2.3 rejects Literal field types: it reads these as str, __post_init__ checks them
    ArmModel = ElbowImpedance = ElbowModel = EstimatorMethod = Integrator = str
    MotorModel = MuscleModel = RobotModel = SensorPreset = XiSource = str

MUSCLE_VARIANTS = get_args(choices.MuscleModel)
SENSOR_PRESETS = get_args(choices.SensorPreset)
XI_SOURCES = get_args(choices.XiSource)
ELBOW_IMPEDANCES = get_args(choices.ElbowImpedance)


@dataclass(kw_only=True)
class ArmConfig:
    """The human arm model and the subject's posture and effort."""

    model: ArmModel = "arm_planar"
    muscle: MuscleModel = "hill"  # "hill" (MuJoCo FLV muscle) or "linear" (exact spring-damper)
    q0: tuple[float, float] = (0.08, 1.00)  # rad, initial configuration, conditioning paper IV-B
    cocontraction: float = 0.2  # activation of every muscle before the pre-load is added
    preload_N: float = 5.0  # N, distal force the subject exerts, conditioning paper IV-B
    shoulder_pos_m: tuple[float, float, float] = (0.0, 0.0, 0.9)  # m, shoulder in world (seated)

    def __post_init__(self) -> None:
        choice("arm.model", self.model, choices.ArmModel)
        choice("arm.muscle", self.muscle, choices.MuscleModel)
        check(
            0.0 < self.cocontraction < 1.0, f"arm.cocontraction must lie in (0, 1), got {self.cocontraction}"
        )
        check(0.0 <= self.preload_N <= 50.0, f"arm.preload_N must lie in [0, 50] N, got {self.preload_N}")
        check(len(self.q0) == 2, f"arm.q0 must be [shoulder, elbow] in rad (two angles), got {list(self.q0)}")
        check(0.0 < self.q0[1] < 2.6, f"arm.q0 elbow angle must lie in (0, 2.6) rad, got {self.q0[1]}")
        check(-0.7 < self.q0[0] < 2.3, f"arm.q0 shoulder angle must lie in (-0.7, 2.3) rad, got {self.q0[0]}")


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
            check(value > 0, f"reflex.{name} must be positive (s), got {value}")
        check(
            self.stretch_latency_s <= self.spinal_latency_s,
            f"reflex.stretch_latency_s ({self.stretch_latency_s}) must not exceed "
            f"reflex.spinal_latency_s ({self.spinal_latency_s})",
        )
        for name in ("stretch_gain", "velocity_gain", "spinal_gain"):
            value = getattr(self, name)
            check(value >= 0, f"reflex.{name} must be >= 0, got {value}")


@dataclass(kw_only=True)
class CuffConfig:
    """The cuff coupling hand and robot flange: explicit translational spring-damper."""

    rigid: bool = False
    # Soft tissue + strap compliance of an arm cuff (assumption: interface stiffness of order
    # 1e4 N/m, the range reported for forearm/hand orthoses and manipulandum handles). The
    # conditioning_window lab sets 3 kN/m (measured cuff interfaces, its config.py).
    stiffness_N_per_m: float = 2.0e4
    damping_Ns_per_m: float = 100.0  # N s/m, ~0.3 of critical with ~2 kg endpoint mass (assumption)
    mass_kg: float = 0.6  # kg, plastic cuff + metal support beam (assumption, paper IV-A)

    def __post_init__(self) -> None:
        check(self.stiffness_N_per_m > 0, f"cuff.stiffness_N_per_m must be > 0, got {self.stiffness_N_per_m}")
        check(self.damping_Ns_per_m >= 0, f"cuff.damping_Ns_per_m must be >= 0, got {self.damping_Ns_per_m}")
        check(self.mass_kg > 0, f"cuff.mass_kg must be > 0, got {self.mass_kg}")


@dataclass(kw_only=True)
class RobotConfig:
    """The perturbing robot."""

    model: RobotModel = "lwr"
    # m, robot base in the world, in front of and lateral to the subject (assumption: places the
    # hand at q0 well inside the LWR's workspace with the flange pointing down)
    base_pos_m: tuple[float, float, float] = (0.55, 0.75, 0.55)

    def __post_init__(self) -> None:
        choice("robot.model", self.model, choices.RobotModel)


@dataclass(kw_only=True)
class SimConfig:
    """Physics settings."""

    timestep_s: float = 0.0005  # s; 2 physics steps per 1 kHz sample
    # Semi-implicit Euler: the least biased of MuJoCo's integrators for the continuous-time models
    # the estimators fit, with the stiff cuff-hand connect constraint (measured on the rigid
    # linear arm: xi within 0.3 %; implicitfast 0.6 %; RK4 2.6 %, it handles the soft constraint
    # poorly). See the issue note for the timestep study.
    integrator: Integrator = "Euler"
    settle_s: float = 1.0  # s, settling of the pre-loaded hold before the trials start

    def __post_init__(self) -> None:
        choice("sim.integrator", self.integrator, choices.Integrator)
        check(
            TIMESTEP_MIN_S <= self.timestep_s <= TIMESTEP_MAX_S,
            f"sim.timestep_s must lie in [{TIMESTEP_MIN_S:g}, {TIMESTEP_MAX_S:g}] s (below, a run takes "
            f"hours; above, the step undersamples the recording), got {self.timestep_s}",
        )
        check(self.settle_s >= 0.2, f"sim.settle_s must be >= 0.2 s, got {self.settle_s}")


@dataclass(kw_only=True)
class SensorsConfig:
    """Sensor models applied to the clean simulated signals."""

    preset: SensorPreset = "realistic"  # "realistic" (JR3/LWR-class noise) or "ideal"
    fs_hz: float = 1000.0  # Hz, sampling rate of the recording system (paper IV-A)

    def __post_init__(self) -> None:
        choice("sensors.preset", self.preset, choices.SensorPreset)
        check(self.fs_hz > 0, f"sensors.fs_hz must be > 0, got {self.fs_hz}")


@dataclass(kw_only=True)
class ScenarioConfig:
    """Which perturbation timeline (``scenarios/<name>.yaml``) and optional subsetting."""

    name: str = ""  # scenarios/<name>.yaml; each protocol's schema and scenario group set it
    k_values: list[int] | None = None  # window indices to run; None = all in the scenario file
    n_trials: int | None = None  # trials per window; None = the scenario file's number

    def __post_init__(self) -> None:
        if self.k_values is not None:
            check(
                len(self.k_values) > 0,
                "scenario.k_values is empty; give window indices (e.g. [1,26]) or null for all",
            )
        if self.n_trials is not None:
            check(
                self.n_trials >= 2,
                f"scenario.n_trials must be >= 2 (identify + validate), got {self.n_trials}",
            )


@dataclass(kw_only=True)
class EstimatorConfig:
    """Processing and least-squares identification (paper IV-C, III-A, III-C)."""

    method: EstimatorMethod = "joint_ls"
    # Hz, phase-free low-pass of q and F before differentiation (paper IV-C gives no cutoff). The
    # same zero-phase filter on both sides keeps the linear fit consistent; 20 Hz keeps K within
    # ~5 % at T_obs >= 400 ms under the realistic sensor noise (40 Hz: ~20 %). None = off.
    lowpass_hz: float | None = 20.0
    filter_order: int = 4
    baseline_s: float = 0.2  # s, pre-onset span averaged for q0 and tau0 (paper IV-C)
    # known xi for the reduced model: model truth, the paper's values, or "full_fit": the full
    # model's xi in the longest window of the same data (paper IV-D: xi "obtained from the full
    # dynamic model identification")
    xi_source: XiSource = "truth"
    symmetry_tol: float = 0.1  # quasi-symmetric when ||A - A^T||_F / ||A + A^T||_F below this
    constancy_tol: float = 0.05  # quasi-constant when relative change to next window below this
    # 1/s; set: quasi-constant when the relative change to the next window, per second of T_obs,
    # is below this (replaces the per-step constancy_tol; windows need not be evenly spaced)
    constancy_tol_per_s: float | None = None
    t_obs_s: list[float] | None = None  # explicit windows; None = T_k + 70 ms per scenario window

    def __post_init__(self) -> None:
        choice("estimator.method", self.method, choices.EstimatorMethod)
        choice("estimator.xi_source", self.xi_source, choices.XiSource)
        if self.lowpass_hz is not None:
            check(self.lowpass_hz > 0, f"estimator.lowpass_hz must be > 0 Hz or null, got {self.lowpass_hz}")
        check(self.filter_order >= 1, f"estimator.filter_order must be >= 1, got {self.filter_order}")
        check(self.baseline_s > 0, f"estimator.baseline_s must be > 0 s, got {self.baseline_s}")
        check(
            0 < self.symmetry_tol < 1, f"estimator.symmetry_tol must lie in (0, 1), got {self.symmetry_tol}"
        )
        check(
            0 < self.constancy_tol < 1,
            f"estimator.constancy_tol must lie in (0, 1), got {self.constancy_tol}",
        )
        if self.constancy_tol_per_s is not None:
            check(
                0 < self.constancy_tol_per_s < 100,
                "estimator.constancy_tol_per_s must lie in (0, 100) 1/s or be null, got "
                f"{self.constancy_tol_per_s}",
            )
        if self.t_obs_s is not None:
            check(
                len(self.t_obs_s) > 0,
                "estimator.t_obs_s is empty; give observation windows in s (e.g. [0.3,0.4]) or null for "
                "the scenario's T_k + 70 ms",
            )
            bad = [t for t in self.t_obs_s if not (math.isfinite(t) and t > 0)]
            check(not bad, f"estimator.t_obs_s must hold positive times in s, got {bad}")


@dataclass(kw_only=True)
class ElbowConfig:
    """The 1-DoF elbow grasping the direct-drive handle (fractional-elbow paper, seeds/004).

    ``impedance`` picks the ground truth: ``muscle`` (Hill antagonist pair of
    models/elbow_1dof, co-contraction and the optional reflex of :class:`ReflexConfig`),
    ``five_element`` (linear arm spring/damper k2, d2 behind the grasp k1, d1, paper Sec. IV-B,
    Eqs. (31)-(37), with M the model's forearm inertia) or ``fractional`` (spring k2 in parallel
    with a fractional element ``c s^beta``, realised by an Oustaloup rational approximation).
    Grasp values are translational at the handle and enter the model as ``k L^2``.
    """

    model: ElbowModel = "elbow_1dof"
    impedance: ElbowImpedance = "muscle"
    cocontraction: float = 0.5  # activation of both muscles; the paper's subjects co-contract
    # Grasp of the hand on the handle (assumption, inside the range of the grasp elements of the
    # five-element models of seeds/004 Table II read by Eqs. (32)-(37): k1 770-15000 N/m,
    # d1 0.8-180 N s/m); puts the hand-on-grasp mode near 9 Hz, inside the 0.12-15 Hz band
    grasp_stiffness_N_per_m: float = 2000.0
    grasp_damping_Ns_per_m: float = 10.0
    # five_element / fractional: the arm behind the grasp (assumption: elbow stiffness and damping
    # under co-contraction, the range 20-100 N m/rad and 1-5 N m s/rad of elbow studies)
    arm_stiffness_Nm_per_rad: float = 60.0
    arm_damping_Nms_per_rad: float = 3.0
    # fractional: c s^beta with beta in (0, 1) (a "springpot" between spring and damper)
    fractional_order: float = 0.5
    fractional_coeff: float = 8.0  # N m s^beta / rad (assumption, near the integer damper's effect)
    oustaloup_band_hz: tuple[float, float] = (0.005, 200.0)  # Hz, approximation band (> 0.12-15 Hz)
    oustaloup_order: int = 6  # pole-zero pairs per side, 2N + 1 in all

    def __post_init__(self) -> None:
        check_tuple_lengths(self, "elbow")
        choice("elbow.model", self.model, choices.ElbowModel)
        choice("elbow.impedance", self.impedance, choices.ElbowImpedance)
        check(
            0.0 < self.cocontraction < 1.0,
            f"elbow.cocontraction must lie in (0, 1), got {self.cocontraction}",
        )
        for name in ("grasp_stiffness_N_per_m", "arm_stiffness_Nm_per_rad", "fractional_coeff"):
            value = getattr(self, name)
            check(value > 0, f"elbow.{name} must be > 0, got {value}")
        for name in ("grasp_damping_Ns_per_m", "arm_damping_Nms_per_rad"):
            value = getattr(self, name)
            check(value >= 0, f"elbow.{name} must be >= 0, got {value}")
        check(
            0.0 < self.fractional_order < 1.0,
            f"elbow.fractional_order must lie in (0, 1) (a springpot), got {self.fractional_order}",
        )
        lo, hi = self.oustaloup_band_hz
        check(0 < lo < hi, f"elbow.oustaloup_band_hz must be (low, high) with 0 < low < high, got {(lo, hi)}")
        check(self.oustaloup_order >= 1, f"elbow.oustaloup_order must be >= 1, got {self.oustaloup_order}")


@dataclass(kw_only=True)
class DirectDriveConfig:
    """The direct-drive motor's force controller (fractional-elbow paper, Fig. 3, Eqs. (19)-(21)).

    The applied torque is ``tau = tau_Dym + L (F_ref + PID(F_ref - F_measured))`` with the
    dynamic compensation ``tau_Dym = M_hat theta_dd + C_hat theta_d + B_hat sign(theta_d)``
    (Eq. (21)); M_hat, C_hat, B_hat are the model's true values times ``1 + error``.
    """

    model: MotorModel = "direct_drive"
    safety_range_rad: float = 0.9  # rad, motor range each way around zero (paper III-A)
    # relative error of M_hat. The compensation reads the accelerometer one control period late,
    # a positive feedback that is unstable for M_hat >= the true inertia; -0.2 keeps a margin
    # (measured: tracking error 14 % at -0.2, divergence at 0).
    inertia_error: float = -0.2
    viscous_error: float = 0.0  # relative error of C_hat
    coulomb_error: float = 0.0  # relative error of B_hat
    # PID on the force error (assumption: tuned on the default elbow for a well-damped loop)
    kp: float = 1.0
    ki_per_s: float = 50.0
    kd_s: float = 0.0
    derivative_cutoff_hz: float = 40.0  # Hz, low-pass of the measured velocity/acceleration
    sign_deadband_rad_s: float = 0.002  # rad/s, below which sign(theta_d) is taken as 0
    current_bits: int = 16  # bits of the analog current reference (paper III-A: 16-bit input)
    # kg, part of the handle body that sits beyond the force sensor's measuring plane (grip and
    # the sensor's tool-side plate): the sensor then reads F_hand + m L theta_dd. 0 = the sensor
    # at the skin (the old lab); the fractional-elbow protocol sets its value in its YAML.
    sensed_mass_kg: float = 0.0

    def __post_init__(self) -> None:
        choice("motor.model", self.model, choices.MotorModel)
        check(
            0 < self.safety_range_rad <= 1.0,
            "motor.safety_range_rad must lie in (0, 1.0] rad (mechanical stops at 1.0), "
            f"got {self.safety_range_rad}",
        )
        for name in ("inertia_error", "viscous_error", "coulomb_error"):
            value = getattr(self, name)
            check(
                value >= -1.0,
                f"motor.{name} must be >= -1 (a relative error; -1 drops the term), got {value}",
            )
        for name in ("kp", "ki_per_s", "kd_s", "sign_deadband_rad_s"):
            value = getattr(self, name)
            check(value >= 0, f"motor.{name} must be >= 0, got {value}")
        check(
            self.derivative_cutoff_hz > 0,
            f"motor.derivative_cutoff_hz must be > 0, got {self.derivative_cutoff_hz}",
        )
        check(
            8 <= self.current_bits <= 24, f"motor.current_bits must lie in [8, 24], got {self.current_bits}"
        )
        check(self.sensed_mass_kg >= 0, f"motor.sensed_mass_kg must be >= 0 kg, got {self.sensed_mass_kg}")


def alpha_grid(step: float = 0.1) -> np.ndarray:
    """The orders ``step, 2 step, ...`` below 2 (Sec. IV-A's grid); ``step`` must divide 1."""
    n_unit = round(1.0 / step) if 0 < step < 1 else 0
    if n_unit < 2 or abs(n_unit * step - 1.0) > 1e-9:
        raise ConfigError(f"the alpha step must divide 1 (e.g. 0.1, 0.05, 0.25, 0.5), got {step}")
    return np.round(np.arange(1, 2 * n_unit) / n_unit, 12)


@dataclass(kw_only=True)
class FrfConfig:
    """Frequency-response estimation and Levy fits (fractional-elbow paper, Sec. II and III-B)."""

    # zero-phase equiripple FIR on the angle: pass 15 Hz, stop 18 Hz, 1 dB ripple, 80 dB
    fir_pass_hz: float = 15.0
    fir_stop_hz: float = 18.0
    fir_ripple_db: float = 1.0
    fir_attenuation_db: float = 80.0
    welch_window: int = 5000  # samples, Blackman-Harris windows
    welch_overlap: float = 0.25
    band_hz: tuple[float, float] = (0.12, 15.0)  # Hz, band of the fits
    alpha_step: float = 0.1  # sweep of the commensurate order over (0, 2)
    # The paper filters the angle only; its 1 dB equiripple pass band then ripples G by up to
    # ~2 x 0.8 dB (forward + backward). True filters the force too, which cancels the ripple.
    filter_force: bool = False

    def __post_init__(self) -> None:
        check_tuple_lengths(self, "frf")
        check(
            0 < self.fir_pass_hz < self.fir_stop_hz,
            "frf.fir_pass_hz must be > 0 and below frf.fir_stop_hz, "
            f"got {self.fir_pass_hz}, {self.fir_stop_hz}",
        )
        check(self.welch_window >= 16, f"frf.welch_window must be >= 16 samples, got {self.welch_window}")
        check(0 <= self.welch_overlap < 1, f"frf.welch_overlap must lie in [0, 1), got {self.welch_overlap}")
        lo, hi = self.band_hz
        check(0 <= lo < hi, f"frf.band_hz must be (low, high) with 0 <= low < high, got {(lo, hi)}")
        try:
            alpha_grid(self.alpha_step)
        except ConfigError:
            raise ConfigError(
                "frf.alpha_step must divide 1 so that alpha = 1 is on the grid (e.g. 0.1, 0.05, 0.25, 0.5), "
                f"got {self.alpha_step}"
            ) from None

    def check_recording(self, fs_hz: float, n_samples: int, what: str = "trial") -> None:
        """Reject settings the recording cannot support: a band at or beyond Nyquist, a Welch
        window longer than the record."""
        lo, hi = self.band_hz
        check(
            hi < fs_hz / 2,
            f"frf.band_hz upper edge {hi:g} Hz is at or beyond Nyquist ({fs_hz / 2:.6g} Hz); "
            f"valid: < {fs_hz / 2:.6g}",
        )
        check(
            self.welch_window <= n_samples,
            f"frf.welch_window = {self.welch_window} samples is longer than the {what} "
            f"({n_samples} samples); valid: <= {n_samples}",
        )


@dataclass(kw_only=True)
class OutputConfig:
    """What a run writes besides results.json."""

    trials: bool = True  # trials.h5
    figures: bool = True  # PNG figures
    recording: bool = True  # rerun .rrd of every trial
    print_table: bool = True


@dataclass(kw_only=True)
class ExperimentConfig:
    """What every protocol's experiment has; each protocol's schema adds the groups it reads.

    The protocol schemas (``armlab/protocols/<name>/config.py``) subclass this one, so an
    override of a group the chosen protocol does not read is refused, never silently ignored.
    """

    protocol_name: str = ""  # set by each protocol's schema
    seed: int = 0
    sim: SimConfig = field(default_factory=SimConfig)
    sensors: SensorsConfig = field(default_factory=SensorsConfig)
    output: OutputConfig = field(default_factory=OutputConfig)
    effects: EffectsConfig = field(default_factory=EffectsConfig)  # the catalogue, all off by default

    def __post_init__(self) -> None:
        # trials.h5 stores the seed as a 64-bit integer attribute
        check(0 <= self.seed < 2**63, f"seed must be an integer in [0, 2**63), got {self.seed}")
