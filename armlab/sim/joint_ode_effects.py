"""The parameters of the ODE joint generator (:mod:`armlab.sim.joint_ode`), in its own physical forms.

These are not the catalogue's forms (:mod:`armlab.config.effects`, which the MuJoCo rig and the
diagnosis' surrogates follow) but another physics for the same catalogue effects, so that a
diagnosis tuned on one is tested on another:

- :class:`OdeReflex`: delayed half-wave rectified stretch velocity → excitation; activation with
  asymmetric time constants (fast rise, slow decay: Zajac 1989, Crit. Rev. Biomed. Eng. 17:359,
  Eq. 2: τ_act ≈ 10-20 ms, τ_deact ≈ 30-60 ms) → a first-order contraction lag (the ankle's
  reflex low-pass near 3 Hz, Kearney, Stein & Parameswaran 1997, IEEE TBME 44:493: τ_c ≈ 40-70 ms);
- :class:`LuGre`: the LuGre friction model (Canudas de Wit et al. 1995, IEEE TAC 40:419, Eqs. 2-4)
  with the bristle stiffness set by a presliding deflection and no micro-damping or viscous term
  (viscous friction is the nominal's B);
- :class:`SeriesSpring`: a spring-damper between two bodies (transmission or cuff);
- :class:`SensorDynamics`: a second-order torque sensor (its mechanical element and electronics),
  of any damping ratio (not a Butterworth);
- :class:`StiffnessModulation`: K(t) = K·exp(depth·n(t)), B(t) = B·exp(depth·n(t)/2) (damping
  ratio kept, B ∝ √K), and the tonic torque that goes with the stiffness change, (K(t) − K)/slope;
- :class:`VoluntaryTorque`: a torque rms·n(t) on the limb, band-limited below ``fmax_hz``;
- :class:`TorqueDrift`: a smooth bias of the torque channel: ramp + first-order thermal settling +
  a slow wander below 0.02 Hz.

n(t) is a :class:`SlowSignal`: a sum of sinusoids at random frequencies in a band with Gaussian
coefficients, defined at every t (so the ODE solver reads it exactly), with unit expected rms.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from armlab.errors import ConfigError

__all__ = [
    "LuGre",
    "OdeEffects",
    "OdeReflex",
    "SensorDynamics",
    "SeriesSpring",
    "SlowSignal",
    "StiffnessModulation",
    "TorqueDrift",
    "VoluntaryTorque",
    "drift_signal",
    "slow_signal",
]


class _Positive:
    """Checks that every float field is finite and > 0 (``direction`` may be ±1)."""

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "direction":
                if v not in (-1.0, 1.0):
                    raise ConfigError(f"{type(self).__name__}.direction must be +1 or -1, got {v!r}")
            elif not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise ConfigError(f"{type(self).__name__}.{f.name} must be finite and > 0, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class OdeReflex(_Positive):
    gain_Nms_per_rad: float  # N·m·s/rad, excitation per rad/s of stretch velocity
    delay_s: float  # s, loop latency (40-50 ms at the ankle, Kearney 1997)
    tau_act_s: float = 0.015  # s, activation rise (Zajac 1989)
    tau_deact_s: float = 0.045  # s, activation decay (Zajac 1989)
    tau_contraction_s: float = 0.05  # s, contraction lag (~3 Hz, Kearney 1997)
    direction: float = 1.0  # +1: stretch is positive joint velocity


@dataclass(frozen=True, kw_only=True)
class LuGre(_Positive):
    coulomb_Nm: float  # N·m, Fc
    static_Nm: float  # N·m, Fs >= Fc (Stribeck peak)
    stribeck_rad_s: float = 0.02  # rad/s, vs
    presliding_rad: float = 5e-4  # rad, Fc/σ0: bristle deflection at sliding

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.static_Nm < self.coulomb_Nm:
            raise ConfigError(f"LuGre.static_Nm ({self.static_Nm}) must be >= coulomb_Nm ({self.coulomb_Nm})")


@dataclass(frozen=True, kw_only=True)
class SeriesSpring(_Positive):
    stiffness_Nm_per_rad: float  # N·m/rad
    damping_Nms_per_rad: float  # N·m·s/rad


@dataclass(frozen=True, kw_only=True)
class SensorDynamics(_Positive):
    natural_hz: float  # Hz
    damping_ratio: float  # 1


@dataclass(frozen=True, kw_only=True)
class StiffnessModulation(_Positive):
    depth: float  # 1, rms of log K(t)/K
    fmax_hz: float = 0.2  # Hz, top of the modulation band (from 0.02 Hz)
    torque_slope_per_rad: float = 10.0  # 1/rad, dK/dT: stiffness change per N·m of tonic torque


@dataclass(frozen=True, kw_only=True)
class VoluntaryTorque(_Positive):
    rms_Nm: float  # N·m
    fmax_hz: float = 1.0  # Hz, top of its band (from 0.05 Hz)


@dataclass(frozen=True, kw_only=True)
class TorqueDrift(_Positive):
    rate_Nm_per_s: float  # N·m/s, linear thermal drift (signed by a draw)
    thermal_Nm: float  # N·m, amplitude of the first-order thermal settling
    thermal_tau_s: float = 60.0  # s, its time constant
    wander_Nm: float = 0.1  # N·m, rms of the slow wander (below 0.02 Hz)


@dataclass(frozen=True, kw_only=True)
class OdeEffects:
    """The hidden effects of one batch of trials; None: off."""

    reflex: OdeReflex | None = None
    friction: LuGre | None = None
    transmission: SeriesSpring | None = None
    cuff: SeriesSpring | None = None
    sensor: SensorDynamics | None = None
    channel_delay_s: float = 0.0  # s, torque sampled this much before the position (fractional)
    modulation: StiffnessModulation | None = None
    voluntary: VoluntaryTorque | None = None
    drift: TorqueDrift | None = None
    quant_step_rad: float = 0.0  # rad, encoder resolution (0: none)

    def __post_init__(self) -> None:
        for name in ("channel_delay_s", "quant_step_rad"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ConfigError(f"OdeEffects.{name} must be finite and >= 0, got {v!r}")


@dataclass(frozen=True, kw_only=True, eq=False)
class SlowSignal:
    """n(t) = Σ_j c_j cos(2π f_j t) + s_j sin(2π f_j t) per row; unit expected rms.

    Attributes:
        freq_hz: (rows, m) Hz.
        cos, sin: (rows, m) 1, coefficients (Gaussian, scaled by sqrt(1/m)).
    """

    freq_hz: np.ndarray
    cos: np.ndarray
    sin: np.ndarray

    def __call__(self, t: np.ndarray | float) -> np.ndarray:
        """n at times ``t`` (scalar or (nt,)): (rows,) or (rows, nt)."""
        t = np.asarray(t, float)
        ph = 2 * np.pi * self.freq_hz[..., None] * t.reshape(1, 1, -1)  # (rows, m, nt)
        out = np.einsum("rm,rmt->rt", self.cos, np.cos(ph)) + np.einsum("rm,rmt->rt", self.sin, np.sin(ph))
        return out[:, 0] if t.ndim == 0 else out


def slow_signal(rng: np.random.Generator, rows: int, lo_hz: float, hi_hz: float, m: int = 24) -> SlowSignal:
    """Draw a :class:`SlowSignal` band-limited to [lo_hz, hi_hz]: frequencies uniform in the band,
    coefficients N(0, 1/m) (so E[n²] = 1). Draw order: frequencies, cos, sin coefficients."""
    if not 0 < lo_hz < hi_hz:
        raise ConfigError(f"slow_signal band must satisfy 0 < lo_hz < hi_hz, got [{lo_hz}, {hi_hz}]")
    f = rng.uniform(lo_hz, hi_hz, (rows, m))
    c = rng.standard_normal((rows, m)) / np.sqrt(m)
    s = rng.standard_normal((rows, m)) / np.sqrt(m)
    return SlowSignal(freq_hz=f, cos=c, sin=s)


def drift_signal(t_s: np.ndarray, drift: TorqueDrift, rows: int, rng: np.random.Generator) -> np.ndarray:
    """The drift of :class:`TorqueDrift` at times ``t_s`` (n,) s: (rows, n) N·m.

    ``sign·(rate·t + thermal·(1 − exp(−t/τ)))`` + wander·n(t), n a :class:`SlowSignal` in
    0.002-0.02 Hz; draw order: the signs (one per row), then the wander.
    """
    sign = rng.choice([-1.0, 1.0], (rows, 1))
    wander = slow_signal(rng, rows, 0.002, 0.02)(t_s)
    ramp = drift.rate_Nm_per_s * t_s + drift.thermal_Nm * (1.0 - np.exp(-t_s / drift.thermal_tau_s))
    return sign * ramp + drift.wander_Nm * wander
