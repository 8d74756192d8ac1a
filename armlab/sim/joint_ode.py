"""A second, independent generator of 1-DoF joint recordings: an ODE plant integrated by SciPy.

Not MuJoCo, not the diagnosis' surrogates: the plant is written here from its physics and
integrated by :func:`scipy.integrate.solve_ivp` (explicit Runge-Kutta 4(5), Dormand-Prince,
``rtol`` 1e-8: the nonlinear effects make no part of it worth an exact discretisation).

**Bodies.** A motor (inertia Jm, where the encoder is), a pedal (Ip) and the limb (I), in a
chain: motor -[transmission]- torque sensor - pedal -[cuff]- limb. A connection is rigid unless
its :class:`~armlab.sim.joint_ode_effects.SeriesSpring` is given (then that body has its own
degree of freedom). Forces: the servo torque on the motor; the LuGre friction of the pedal's
bearing (sensor side); on the limb −B(t)·θ̇ − K(t)·θ − T(t) + reflex + voluntary torque.

**Actuator.** A PD position servo with velocity feed-forward and a torque limit:
``τm = clip(kp·(r − θm) + kd·(ṙ − θ̇m), ±limit)``, kp = J·ω², kd = 2ζ·J·ω with J = Jm + Ip (what
the controller knows) at the servo's bandwidth; r is the reference's cubic spline.

**Recorded torque** (sign: in phase with the angle, the torque the transmission applies to the
pedal; the first referee records the opposite): the transmission spring's torque, or with a rigid
transmission τm − Jm·θ̈m. With no effects it is exactly (Ip + I)·θ̈ + B·θ̇ + K·θ of the encoder
angle: the nominal of the diagnosis holds on clean data to the integration tolerance. A second-
order sensor (``SensorDynamics``) filters it: it feeds nothing back, so its input is sampled
from the dense output at 4x the recorded rate and filtered exactly between samples (first-order
hold); the channel delay samples it ``channel_delay_s`` before the position (dense output: any
fraction of a sample).

**Reflex** (closed loop through the servo's finite stiffness and any compliance): the excitation
G·max(dir·θ̇_limb(t − d), 0) drives the activation a (rise τ_act, decay τ_deact) and the force f
(lag τ_c); the limb receives −dir·f. The delayed velocity comes from the previous chunk's dense
output: with a reflex the integration proceeds in chunks of exactly d (the method of steps for
delay equations), else of 1 s.

**Sensor level** (after sampling): the drift, then white noise on the torque; the encoder
rounds the angle to its grid (with a random offset of the grid).

**Random draws** from ``rng``, in order: the stiffness modulation's n(t) (one per trial), the
voluntary torque's n(t), the drift's sign and wander, the encoder grid offsets, the torque noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import integrate, interpolate, signal

from armlab.errors import ConfigError, DataError
from armlab.sim.joint_ode_effects import OdeEffects, drift_signal, slow_signal

__all__ = [
    "OdeJoint",
    "OdeRecording",
    "OdeServo",
    "simulate_joint_ode",
]

_RTOL = 1e-8  # 1, relative tolerance (clean torque vs the nominal of the sampled angle: < 1e-4, tests)
_ATOL = 1e-11  # absolute tolerance (rad, rad/s, N·m: every state)
_CHUNK_S = 1.0  # s, integration chunk without a reflex (bounds the dense outputs kept)
# the sensor's input is sampled this many times per recorded sample and filtered exactly between
# them (first-order hold): a linear sensor acts on nothing else, and as two ODE states its
# natural frequency (up to kHz: a fast sensor is a few µs of delay in the band) made RK45's steps
# shrink to its period (over 15 min a dataset). The hold's error, measured against 32x (5 s
# trials): 5e-6 of the torque's rms (multisine, 2 kHz, 150 Hz sensor), 2.7e-4 (steps, 500 Hz,
# 100 Hz sensor), 4e-4 (PRBS, 500 Hz, 1 kHz sensor: 5 % of that sensor's own effect); the
# referee's quietest noise is 1e-3 of the rms. (Not :func:`armlab.dsp.second_order_lowpass`:
# its bilinear map holds only for natural frequencies well below Nyquist.)
_SENSOR_OVERSAMPLING = 4


@dataclass(frozen=True, kw_only=True)
class OdeJoint:
    """The subject's joint and the rig's pedal (I, B, K of the nominal: I = inertia + pedal)."""

    inertia_kgm2: float  # kg·m², limb
    damping_Nms_per_rad: float  # N·m·s/rad
    stiffness_Nm_per_rad: float  # N·m/rad
    pedal_inertia_kgm2: float = 0.004  # kg·m²

    def __post_init__(self) -> None:
        for k in ("inertia_kgm2", "damping_Nms_per_rad", "stiffness_Nm_per_rad", "pedal_inertia_kgm2"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(f"OdeJoint.{k} must be finite and > 0, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class OdeServo:
    """The position servo (its own dynamics: PD with velocity feed-forward and a torque limit)."""

    motor_inertia_kgm2: float = 0.01  # kg·m², reflected motor inertia
    bandwidth_hz: float = 50.0  # Hz, ω/2π of the PD loop on the known inertia
    damping_ratio: float = 0.8  # 1
    torque_limit_Nm: float = 400.0  # N·m

    def __post_init__(self) -> None:
        for k in ("motor_inertia_kgm2", "bandwidth_hz", "damping_ratio", "torque_limit_Nm"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(f"OdeServo.{k} must be finite and > 0, got {v!r}")


@dataclass(frozen=True, kw_only=True, eq=False)
class OdeRecording:
    """A batch of trials at the reference's rate; arrays (n_trials, n).

    Attributes:
        t_s: (n,) s.
        position: rad, the recorded encoder angle (quantised if set).
        torque: N·m, the recorded torque (drift and noise included).
        clean_torque: N·m, the torque before the sensor-level effects (drift, noise), sampled
            like ``torque`` (delayed, filtered by the sensor dynamics).
        motor_angle, motor_velocity, motor_acceleration: rad, rad/s, rad/s², the encoder's
            true angle and its derivatives (from the ODE's right-hand side).
        limb_angle: rad.
        drift: N·m, the drift added to the torque.
        noise_std_Nm: N·m, std of the white torque noise.
    """

    t_s: np.ndarray
    position: np.ndarray
    torque: np.ndarray
    clean_torque: np.ndarray
    motor_angle: np.ndarray
    motor_velocity: np.ndarray
    motor_acceleration: np.ndarray
    limb_angle: np.ndarray
    drift: np.ndarray
    noise_std_Nm: float


class _Plant:
    """The ODE's right-hand side over a batch of rows (trials), states (rows, n_states)."""

    def __init__(self, ref, fs_hz, joint: OdeJoint, servo: OdeServo, fx: OdeEffects, rng):
        rows, n = ref.shape
        self.rows, self.fx, self.joint = rows, fx, joint
        # the reference's cubic spline as (4, rows, n - 1) coefficients, evaluated directly
        self.coef = np.ascontiguousarray(
            interpolate.CubicSpline(np.arange(n) / fs_hz, ref, axis=1).c.transpose(0, 2, 1)
        )
        self.fs, self.n = fs_hz, n
        self.dm = 0
        self.dp = self.dm + (fx.transmission is not None)
        self.dl = self.dp + (fx.cuff is not None)
        self.ndof = self.dl + 1
        self.J = np.zeros(self.ndof)
        for d, j in ((self.dm, servo.motor_inertia_kgm2), (self.dp, joint.pedal_inertia_kgm2)):
            self.J[d] += j
        self.J[self.dl] += joint.inertia_kgm2
        w = 2 * np.pi * servo.bandwidth_hz
        jk = servo.motor_inertia_kgm2 + joint.pedal_inertia_kgm2
        self.kp, self.kd, self.limit = jk * w**2, 2 * servo.damping_ratio * jk * w, servo.torque_limit_Nm
        self.jm = servo.motor_inertia_kgm2
        names = [f"q{d}" for d in range(self.ndof)] + [f"w{d}" for d in range(self.ndof)]
        names += ["z"] * (fx.friction is not None) + ["a", "f"] * (fx.reflex is not None)
        self.idx = {k: i for i, k in enumerate(names)}
        self.n_states = len(names)
        m, v = fx.modulation, fx.voluntary
        self.mod = slow_signal(rng, rows, 0.02, m.fmax_hz) if m is not None else None
        self.vol = slow_signal(rng, rows, 0.05, v.fmax_hz) if v is not None else None
        self.history = None  # (t0, t1, OdeSolution) of the previous chunk (reflex)

    def reference(self, t) -> tuple[np.ndarray, np.ndarray]:
        """r and ṙ at t (scalar: (rows,); (nt,): (rows, nt)), rad and rad/s."""
        if np.ndim(t) == 0:  # the solver's calls: plain arithmetic is ~10x faster than arrays here
            k = min(max(int(t * self.fs), 0), self.n - 2)
        else:
            k = np.clip(np.floor(np.asarray(t) * self.fs).astype(int), 0, self.n - 2)
        h = t - k / self.fs
        c0, c1, c2, c3 = self.coef[:, :, k]
        return ((c0 * h + c1) * h + c2) * h + c3, (3 * c0 * h + 2 * c1) * h + c2

    def forces(self, t, x):
        """(accelerations (..., ndof), sensor-input torque (...,)) at states x (..., n_states)."""
        fx, j, i = self.fx, self.joint, self.idx
        q, w = x[..., : self.ndof], x[..., self.ndof : 2 * self.ndof]
        F = np.zeros(q.shape)
        r, dr = self.reference(t)
        tau_m = self.kp * (r - q[..., self.dm]) + self.kd * (dr - w[..., self.dm])
        tau_m = np.minimum(np.maximum(tau_m, -self.limit), self.limit)
        F[..., self.dm] += tau_m
        if fx.transmission is not None:
            s = fx.transmission
            tau_t = s.stiffness_Nm_per_rad * (q[..., self.dm] - q[..., self.dp])
            tau_t = tau_t + s.damping_Nms_per_rad * (w[..., self.dm] - w[..., self.dp])
            F[..., self.dm] -= tau_t
            F[..., self.dp] += tau_t
        if fx.friction is not None:
            F[..., self.dp] -= (fx.friction.coulomb_Nm / fx.friction.presliding_rad) * x[..., i["z"]]
        if fx.cuff is not None:
            c = fx.cuff
            tau_c = c.stiffness_Nm_per_rad * (q[..., self.dp] - q[..., self.dl])
            tau_c = tau_c + c.damping_Nms_per_rad * (w[..., self.dp] - w[..., self.dl])
            F[..., self.dp] -= tau_c
            F[..., self.dl] += tau_c
        k, b = j.stiffness_Nm_per_rad, j.damping_Nms_per_rad
        limb = np.zeros(q.shape[:-1])
        if self.mod is not None:
            g = np.exp(fx.modulation.depth * self.mod(t))
            limb -= (k * (g - 1.0)) / fx.modulation.torque_slope_per_rad  # tonic torque with K(t)
            k, b = k * g, b * np.sqrt(g)
        if self.vol is not None:
            limb += fx.voluntary.rms_Nm * self.vol(t)
        if fx.reflex is not None:
            limb -= fx.reflex.direction * x[..., i["f"]]
        F[..., self.dl] += limb - b * w[..., self.dl] - k * q[..., self.dl]
        acc = F / self.J
        sensor_in = tau_t if fx.transmission is not None else tau_m - self.jm * acc[..., self.dm]
        return acc, sensor_in

    def delayed_velocity(self, t: float) -> np.ndarray:
        """(rows,) rad/s, the limb velocity at t − delay (0 before the record)."""
        td = t - self.fx.reflex.delay_s
        if self.history is None or td <= self.history[0]:
            return np.zeros(self.rows)
        t0, t1, sol = self.history
        y = sol(min(td, t1)).reshape(self.rows, self.n_states)
        return y[:, self.ndof + self.dl]

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        x = y.reshape(self.rows, self.n_states)
        fx, i = self.fx, self.idx
        acc, sensor_in = self.forces(t, x)
        dx = np.zeros_like(x)
        dx[:, : self.ndof] = x[:, self.ndof : 2 * self.ndof]
        dx[:, self.ndof : 2 * self.ndof] = acc
        if fx.friction is not None:  # LuGre, Canudas de Wit 1995 Eq. (2)-(3)
            fr, v = fx.friction, x[:, self.ndof + self.dp]
            g = fr.coulomb_Nm + (fr.static_Nm - fr.coulomb_Nm) * np.exp(-((v / fr.stribeck_rad_s) ** 2))
            sigma0 = fr.coulomb_Nm / fr.presliding_rad
            dx[:, i["z"]] = v - sigma0 * np.abs(v) * x[:, i["z"]] / g
        if fx.reflex is not None:
            r = fx.reflex
            e = r.gain_Nms_per_rad * np.maximum(r.direction * self.delayed_velocity(t), 0.0)
            a = x[:, i["a"]]
            dx[:, i["a"]] = (e - a) / np.where(e > a, r.tau_act_s, r.tau_deact_s)
            dx[:, i["f"]] = (a - x[:, i["f"]]) / r.tau_contraction_s
        return dx.ravel()

    def rest(self) -> np.ndarray:
        """(rows, n_states): static equilibrium at t = 0 (every force is affine in the angles at rest)."""
        x0 = np.zeros((self.rows, self.n_states))
        f0 = self.forces(0.0, x0)[0] * self.J
        jac = np.zeros((self.rows, self.ndof, self.ndof))
        for d in range(self.ndof):
            e = x0.copy()
            e[:, d] = 1e-3  # rad; exact: the forces are affine in q at rest
            jac[:, :, d] = (self.forces(0.0, e)[0] * self.J - f0) / 1e-3
        x0[:, : self.ndof] = np.linalg.solve(jac, -f0[..., None])[..., 0]
        return x0


def _integrate(plant: _Plant, t_pos: np.ndarray, t_tq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States at the position and torque sample times: (rows, n_pos, n_states), (rows, n_tq, n_states)."""
    times = np.union1d(t_pos, t_tq)
    chunk = plant.fx.reflex.delay_s if plant.fx.reflex is not None else _CHUNK_S
    end = float(t_pos[-1])
    y = plant.rest().ravel()
    out = np.empty((times.size, y.size))
    before = times <= 0.0
    out[before] = y  # at rest before and at the start
    t0 = 0.0
    while t0 < end:
        t1 = min(end, t0 + chunk)
        sel = (times > t0) & (times <= t1)
        sol = integrate.solve_ivp(
            plant.rhs, (t0, t1), y, method="RK45", rtol=_RTOL, atol=_ATOL, dense_output=True
        )
        if not sol.success:
            raise DataError(f"the ODE joint generator failed at t = {t0:g} s: {sol.message}")
        out[sel] = sol.sol(times[sel]).T
        y = sol.y[:, -1]
        plant.history = (t0, t1, sol.sol)
        t0 = t1
    rows = plant.rows
    states = out.reshape(times.size, rows, plant.n_states).transpose(1, 0, 2)
    pick = lambda ts: states[:, np.searchsorted(times, ts)]  # noqa: E731
    return pick(t_pos), pick(t_tq)


def _sensor_output(u: np.ndarray, sensor, fs: float) -> np.ndarray:
    """(rows, m) the 2nd-order sensor's output for its input ``u`` sampled at ``fs``, at rest on
    ``u``'s first value: the exact response to the input interpolated linearly between samples
    (first-order hold; :func:`scipy.signal.cont2discrete`)."""
    wn = 2 * np.pi * sensor.natural_hz
    num, den, _ = signal.cont2discrete(
        ([wn**2], [1.0, 2 * sensor.damping_ratio * wn, wn**2]), 1.0 / fs, "foh"
    )
    u0 = u[:, :1]
    return signal.lfilter(np.ravel(num), den, u - u0, axis=1) + u0


def simulate_joint_ode(
    reference: np.ndarray,
    fs_hz: float,
    joint: OdeJoint,
    servo: OdeServo,
    effects: OdeEffects,
    *,
    noise_std_Nm: float,
    rng: np.random.Generator,
) -> OdeRecording:
    """Simulate position-perturbation trials of the ODE plant (module docstring).

    Args:
        reference: (n_trials, n) rad, smooth servo references sampled at ``fs_hz``, at rest at 0
            at the start (e.g. :func:`armlab.perturbations.joint_families.perturbation_signal`).
        fs_hz: Hz, the recorded rate.
        joint, servo: the subject and the actuator.
        effects: the hidden effects (:class:`~armlab.sim.joint_ode_effects.OdeEffects`).
        noise_std_Nm: N·m, std of the white torque noise (>= 0).
        rng: the only source of randomness (draw order: module docstring).

    Returns:
        The recording.

    Raises:
        ConfigError: a bad rate or noise level; DataError: a bad reference or a failed integration.
    """
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ConfigError(f"fs_hz must be finite and > 0 Hz, got {fs_hz!r}")
    if not (np.isfinite(noise_std_Nm) and noise_std_Nm >= 0):
        raise ConfigError(f"noise_std_Nm must be finite and >= 0 N·m, got {noise_std_Nm!r}")
    ref = np.asarray(reference, float)
    if ref.ndim != 2 or ref.shape[1] < 4 or not np.all(np.isfinite(ref)):
        raise DataError(f"reference must be finite with shape (n_trials, n >= 4) rad, got {ref.shape}")
    rows, n = ref.shape
    t = np.arange(n) / fs_hz
    plant = _Plant(ref, fs_hz, joint, servo, effects, rng)
    over = _SENSOR_OVERSAMPLING if effects.sensor is not None else 1
    t_in = np.arange(n * over) / (over * fs_hz) - effects.channel_delay_s  # the sensor's input times
    x_pos, x_in = _integrate(plant, t, t_in)
    _, sensor_in = plant.forces(np.maximum(t_in, 0.0), x_in)
    clean = (
        sensor_in
        if effects.sensor is None
        else _sensor_output(sensor_in, effects.sensor, over * fs_hz)[:, ::over]
    )
    acc_pos = plant.forces(t, x_pos)[0][..., plant.dm]
    drift = np.zeros((rows, n))
    if effects.drift is not None:
        drift = drift_signal(t, effects.drift, rows, rng)
    motor = x_pos[..., plant.dm]
    position = motor
    if effects.quant_step_rad > 0:
        q = effects.quant_step_rad
        offset = rng.uniform(0.0, q, (rows, 1))
        position = np.round((motor - offset) / q) * q + offset
    torque = clean + drift + noise_std_Nm * rng.standard_normal((rows, n))
    return OdeRecording(
        t_s=t,
        position=position,
        torque=torque,
        clean_torque=clean,
        motor_angle=motor,
        motor_velocity=x_pos[..., plant.ndof + plant.dm],
        motor_acceleration=acc_pos,
        limb_angle=x_pos[..., plant.dl],
        drift=drift,
        noise_std_Nm=float(noise_std_Nm),
    )
