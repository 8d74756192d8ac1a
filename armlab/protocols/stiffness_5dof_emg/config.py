"""The typed experiment of ``stiffness_5dof_emg`` (seeds/001): the groups it reads, nothing else.

``stages`` picks the paper's protocol stages (Sec. 3): kinematic calibration, inertial trials,
stiffness trials, EMG maps; all four are built and the stiffness stage is always among them (its
trials are the run's trial file; the EMG is recorded alongside them). ``calibration`` and
``inertial`` set those stages' motion and holds, ``trials`` how the stiffness trials are drawn and
simulated, ``emg`` the electrodes' signal model, ``estimation`` how the trials are reduced to K_q
and the EMG maps (the group ``armlab estimate`` takes). Defaults are the paper's numbers or, where
it is silent, spec 001's assumptions (each named beside its field).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, get_args

from armlab.config.schema import ExperimentConfig, ReflexConfig
from armlab.config.validate import check, check_tuple_lengths, choice
from armlab.estimation.emg_features import MAP_SAMPLES, WINDOW_SAMPLES
from armlab.estimation.emg_stiffness import N_HIDDEN
from armlab.sensors.emg import EMG_BAND_HZ, EMG_CROSSTALK, EMG_FS_HZ, EMG_GAIN_MV
from armlab.sim.arm5_force_task import A_MIN, PRELOAD_CONDITIONS
from armlab.sim.arm5_trials import TrialTiming

__all__ = [
    "trial_timing",
    "BUILT_STAGES",
    "STAGES",
    "CalibrationConfig",
    "CuffConfig",
    "DEFAULT_STAGES",
    "EmgConfig",
    "EstimationConfig",
    "InertialConfig",
    "Stage",
    "Stiffness5dofConfig",
    "TrialsConfig",
]

#: The protocol's stages in the paper's order (Sec. 3).
Stage = Literal["calibration", "inertial", "stiffness", "emg"]
STAGES: tuple[str, ...] = get_args(Stage)
#: The stages this package simulates.
BUILT_STAGES: tuple[str, ...] = ("calibration", "inertial", "stiffness", "emg")
#: The stages a run has unless ``stages`` says otherwise.
DEFAULT_STAGES: tuple[str, ...] = ("calibration", "inertial", "stiffness")

if TYPE_CHECKING:
    StageName = Stage
else:  # OmegaConf 2.3 rejects Literal field types: it reads these as str, __post_init__ checks them
    StageName = str


@dataclass(kw_only=True)
class CalibrationConfig:
    """The kinematic calibration (paper Sec. 2.1, 3: random motion of every joint, Eqs. (7)-(10))."""

    # s of random motion recorded (the paper gives none; spec 001 assumption: 30 s at 500 Hz)
    duration_s: float = 30.0
    # rad, the largest excursion of each joint from the default posture (assumption: a sum of three
    # slow sines within q0 +- 0.5 rad, inside every joint range of models/arm_5dof)
    amplitude_rad: float = 0.5
    # the last part of the record kept out of the joint-centre fit, on which the IK of the
    # calibrated chain is checked (spec 001 check 2; the split is an assumption)
    holdout_fraction: float = 0.2

    def __post_init__(self) -> None:
        check(
            2.0 <= self.duration_s <= 600.0,
            f"calibration.duration_s must lie in [2, 600] s (the spec: 30), got {self.duration_s}",
        )
        check(
            0.05 <= self.amplitude_rad <= 0.6,
            f"calibration.amplitude_rad must lie in [0.05, 0.6] rad (q0 +- it stays inside every joint "
            f"range), got {self.amplitude_rad}",
        )
        check(
            0.05 <= self.holdout_fraction <= 0.5,
            f"calibration.holdout_fraction must lie in [0.05, 0.5], got {self.holdout_fraction}",
        )


@dataclass(kw_only=True)
class InertialConfig:
    """The inertial trials (paper Sec. 3, 4.1: predefined configurations held, Eq. (22))."""

    # configurations held for the regression (paper Sec. 3: "data (40 trials)")
    n_configurations: int = 40
    # configurations not simulated, on which the fitted G(q) is checked (spec 001 check 4: 10)
    n_held_out: int = 10
    # rad, each joint of a configuration drawn uniformly in q0 +- spread (the paper's predefined
    # configurations are not given; assumption: inside every joint range of models/arm_5dof)
    spread_rad: float = 0.7
    # s each configuration is held and averaged (spec 001 design: 1 s)
    hold_s: float = 1.0
    # s the servos settle at a configuration before its hold (assumption: the paper keeps samples
    # with velocity below a threshold; after 1 s the base wrench is still to 1e-5 N, measured)
    settle_s: float = 1.0

    def __post_init__(self) -> None:
        check(
            isinstance(self.n_configurations, int) and self.n_configurations >= 9,
            f"inertial.n_configurations must be an integer >= 9 (xi_red has 9 entries), got "
            f"{self.n_configurations!r}",
        )
        check(
            isinstance(self.n_held_out, int) and self.n_held_out >= 1,
            f"inertial.n_held_out must be an integer >= 1, got {self.n_held_out!r}",
        )
        check(
            0.05 <= self.spread_rad <= 0.7,
            f"inertial.spread_rad must lie in [0.05, 0.7] rad (q0 +- it stays inside every joint range), "
            f"got {self.spread_rad}",
        )
        for name in ("hold_s", "settle_s"):
            value = getattr(self, name)
            check(0.0 < value <= 10.0, f"inertial.{name} must lie in (0, 10] s, got {value}")


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
class EmgConfig:
    """The EMG electrodes' signal model (armlab.sensors.emg; spec 001's assumption
    emg = g u n + nu; the sensor noise nu follows ``sensors.preset``)."""

    # Hz, -3 dB band of the carrier (spec 001: the wireless sensor's 20-450 Hz)
    band_hz: tuple[float, float] = EMG_BAND_HZ
    # mV rms at full drive (assumption: surface EMG at maximal contraction is 0.1-1 mV)
    gain_mV: float = EMG_GAIN_MV
    # fraction of a neighbouring electrode's muscle picked up (spec 001: 10-20 %)
    crosstalk: float = EMG_CROSSTALK
    # A of the EMG-to-activation relation a = (e^(A u) - 1) / (e^A - 1) (Lloyd and Besier 2003,
    # -3 < A < 0): the electrodes see the drive u behind each activation (armlab.sensors.neural_drive);
    # 0 (spec 001's default): the EMG amplitude is proportional to the activation
    shape_factor: float = 0.0

    def __post_init__(self) -> None:
        check_tuple_lengths(self, "emg")
        lo, hi = self.band_hz
        check(
            0.0 < lo < hi < EMG_FS_HZ / 2,
            f"emg.band_hz must be (low, high) Hz with 0 < low < high < {EMG_FS_HZ / 2:g} (Nyquist of the "
            f"2 kHz electrodes), got {self.band_hz}",
        )
        check(self.gain_mV > 0, f"emg.gain_mV must be > 0 mV, got {self.gain_mV}")
        check(0.0 <= self.crosstalk < 0.5, f"emg.crosstalk must lie in [0, 0.5), got {self.crosstalk}")
        check(
            -3.0 < self.shape_factor <= 0.0,
            f"emg.shape_factor must lie in (-3, 0] (Lloyd and Besier 2003), got {self.shape_factor}",
        )


@dataclass(kw_only=True)
class EstimationConfig:
    """How the stiffness trials are reduced to K_q (Eqs. (10), (14)-(17); Fig. 3)."""

    # s from the onset: the working-point mean and the displaced mean (spec 001 assumption:
    # [-200, 0] ms and [rise + 100, rise + 300] ms; the paper gives no intervals)
    pre_interval_s: tuple[float, float] = (-0.2, 0.0)
    post_interval_s: tuple[float, float] = (0.2, 0.4)
    # m, the displacement sphere mapped to the force ellipsoid (paper Fig. 3: 5 mm)
    ellipsoid_radius_m: float = 0.005
    # s from the onset where each disturbance's EMG map stretch of 400 samples starts (paper Sec. 4.1:
    # "50 sets of 8x400"; where is not given; assumption: the 200 ms before the onset, the working
    # point K_q describes, like pre_interval_s)
    emg_map_start_s: float = -0.2
    # samples per window (paper Sec. 4.1: "time windows of length 70")
    emg_window_samples: int = WINDOW_SAMPLES
    # features of each sparse-filtering layer after the maxima (paper Sec. 4.1: "two layers of
    # unsupervised feature extraction" of Ngiam et al., sizes not given); empty: the maxima alone
    # (default: docs/stiffness_5dof_emg.md says why)
    emg_sparse_features: list[int] = field(default_factory=list)
    # softplus units of the hidden layer (paper Sec. 4.1: 100)
    emg_hidden: int = N_HIDDEN
    # hyper-parameter draws of each random search (paper: random search, count not given; assumption)
    emg_search_draws: int = 6
    # validation conditions of the leave-one-condition-out split's search (assumption; each one a
    # network fit per draw)
    emg_loco_validation: int = 3
    # shares of the windows held out as test and validation sets in the random-window split
    # (assumption: the paper names the sets, not their sizes)
    emg_test_fraction: float = 0.2
    emg_val_fraction: float = 0.2

    def __post_init__(self) -> None:
        check_tuple_lengths(self, "estimation")
        for name in ("pre_interval_s", "post_interval_s"):
            a, b = getattr(self, name)
            check(a < b, f"estimation.{name} must be (start, end) s with start < end, got {(a, b)}")
        check(
            self.ellipsoid_radius_m > 0,
            f"estimation.ellipsoid_radius_m must be > 0 m, got {self.ellipsoid_radius_m}",
        )
        check(
            isinstance(self.emg_window_samples, int) and 1 <= self.emg_window_samples <= MAP_SAMPLES,
            f"estimation.emg_window_samples must be an integer in [1, {MAP_SAMPLES}] (the map's stretch), "
            f"got {self.emg_window_samples!r}",
        )
        check(
            all(isinstance(k, int) and k >= 1 for k in self.emg_sparse_features),
            f"estimation.emg_sparse_features must list integers >= 1 (features per layer), got "
            f"{list(self.emg_sparse_features)}",
        )
        for name in ("emg_hidden", "emg_search_draws", "emg_loco_validation"):
            value = getattr(self, name)
            check(
                isinstance(value, int) and value >= 1,
                f"estimation.{name} must be an integer >= 1, got {value!r}",
            )
        for name in ("emg_test_fraction", "emg_val_fraction"):
            value = getattr(self, name)
            check(0.05 <= value <= 0.4, f"estimation.{name} must lie in [0.05, 0.4], got {value}")


@dataclass(kw_only=True)
class CuffConfig:
    """The 6-D cuff between the LWR's flange and the forearm (models/arm_5dof, a MuJoCo weld)."""

    # s, the weld's time constant (MuJoCo solref, critically damped; armlab.sim.arm5_lab_effects.
    # soften_cuff): 0 keeps the nominal rigid weld (2 timesteps); (2 timesteps, 0.1] makes the cuff
    # a compliance in series with the arm (the catalogue's cuff_compliance; referee 0.002-0.02 s)
    time_constant_s: float = 0.0

    def __post_init__(self) -> None:
        check(
            self.time_constant_s == 0.0 or 0.0 < self.time_constant_s <= 0.1,
            f"cuff.time_constant_s must be 0 (rigid) or lie in (0, 0.1] s, got {self.time_constant_s}",
        )


@dataclass(kw_only=True)
class Stiffness5dofConfig(ExperimentConfig):
    """The seated 5-DoF arm perturbed by the LWR through a 6-D cuff (seeds/001)."""

    protocol_name: str = "stiffness_5dof_emg"
    # the stages to run (paper Sec. 3; run in the paper's order). Without calibration the stiffness
    # stage uses the true chain, without inertial the true xi_red; emg records the electrodes during
    # the stiffness trials and maps them to K_q (off by default: its training adds ~10 s)
    stages: list[str] = field(default_factory=lambda: list(DEFAULT_STAGES))
    calibration: CalibrationConfig = field(default_factory=CalibrationConfig)
    inertial: InertialConfig = field(default_factory=InertialConfig)
    trials: TrialsConfig = field(default_factory=TrialsConfig)
    emg: EmgConfig = field(default_factory=EmgConfig)
    estimation: EstimationConfig = field(default_factory=EstimationConfig)
    # the stretch reflex (armlab.sim.arm5_reflex): the conditioning lab's law, gains and latencies
    # (paper 000 Sec. II-B; armlab.config.schema.ReflexConfig), OFF by default: the paper's model
    # (Eq. (14)) freezes activation; on, spec 001's check 7 measures its bias
    reflex: ReflexConfig = field(default_factory=lambda: ReflexConfig(enabled=False))
    # the cuff's compliance (0: the rigid weld of the nominal lab); the diagnosis's cuff_compliance
    cuff: CuffConfig = field(default_factory=CuffConfig)

    def __post_init__(self) -> None:
        super().__post_init__()
        check(len(self.stages) > 0, f"stages is empty; choose from {list(BUILT_STAGES)}")
        for stage in self.stages:
            choice("stages", stage, Stage)
        check(len(set(self.stages)) == len(self.stages), f"stages repeats a stage: {list(self.stages)}")
        check(
            "stiffness" in self.stages,
            f"stages={list(self.stages)} lacks 'stiffness': the stiffness trials are the run's trial "
            f"file, the calibration and inertial stages feed them, the EMG is recorded during them; "
            f"valid: a subset of {list(BUILT_STAGES)} containing 'stiffness'",
        )


def trial_timing(cfg: Stiffness5dofConfig) -> TrialTiming:
    """The trials' record and averaging intervals from ``trials.*`` and ``estimation.*``
    (ConfigError where the intervals do not fit the record)."""
    t, e = cfg.trials, cfg.estimation
    return TrialTiming(
        pre_s=t.pre_s,
        rise_s=t.rise_s,
        hold_s=t.hold_s,
        pre_interval=tuple(e.pre_interval_s),
        post_interval=tuple(e.post_interval_s),
    )
