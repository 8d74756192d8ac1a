"""Closed-loop force perturbation of the elbow by the direct-drive motor (seeds/004, Fig. 3).

Each 1/fs control period the controller reads the encoder and the handle force sensor, computes

    tau = tau_Dym + L (F_ref + kp e + ki int(e) + kd de/dt),     e = F_ref - F_measured,
    tau_Dym = M_hat theta_dd + C_hat theta_d + B_hat sign(theta_d)           (Eqs. (20), (21))

with theta_d from low-passed differences of the encoder and theta_dd from the JR3's accelerometer
(tangential axis, read one control period late), and commands the current
``I_C = tau / K_torque`` (Eq. (19)) through a 16-bit reference. The elbow's muscles receive their
co-contraction (fluctuating, when a subject's commands are given) plus the delayed stretch reflex,
or the fractional element its torque. A trial whose motor angle leaves the safety range fails
with :class:`SimulationError`.

The controller needs each sample's measurement before the next step and quantises, rounds and
clamps what it reads and commands (no MuJoCo actuator can hold it), so MuJoCo is stepped from
Python once per control period (``mujoco.rollout`` cannot close a Python feedback loop). The
period's Python is kept to plain float arithmetic (about 7 us against about 15 us of physics for
the 5 steps), the muscles' delayed reflex is computed a latency's worth of periods at a time, and
the trials of a run step concurrently on threads (:mod:`armlab.sim.threads`: MuJoCo releases the
GIL while stepping), bit-identical to one trial after the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.config.schema import DirectDriveConfig, ElbowConfig, ReflexConfig
from armlab.errors import ConfigError
from armlab.models.direct_drive_scene import DirectDriveScene
from armlab.models.oustaloup import FractionalElement
from armlab.sensors.channel import ChannelSpec
from armlab.sim.rollout import reflex_command
from armlab.sim.stability import TrialLabels, warning_counts

__all__ = [
    "FORCE_LOOP_HINT",
    "GRASP_FORCE_BOUND_N",
    "SATURATION_DUTY_MAX",
    "ForceTrial",
    "simulate_force_trial",
]

# N, largest grasp force between hand and handle of a valid trial: the reference never exceeds
# 5 N (seeds/004 Sec. III-A) and the motor's peak torque (12.34 A x K_t over L = 0.35 m) pushes
# at most ~48 N statically; the default runs peak at 4.7 N (20x margin).
GRASP_FORCE_BOUND_N = 100.0
# 1, largest fraction of a trial's control periods with the current at its limit: a force loop
# whose amplifier saturates no longer applies its reference (the paper's <= 5 N multisine needs
# ~1.6 A of the 12.34 A); the default runs never saturate (0 %), an unstable loop sits there most
# of the time (motor.inertia_error=0.5: 88 %).
SATURATION_DUTY_MAX = 0.05
_SATURATION_RUN_S = 0.1  # s at the limit without a break: the loop is lost (a failure at once)
#: What to change when the force loop is unstable.
FORCE_LOOP_HINT = (
    "lower motor.inertia_error (M_hat must stay below the true inertia), motor.kp or motor.ki_per_s, "
    "or the force peak (docs/reliability.md, Instability)"
)


@dataclass(frozen=True, kw_only=True, eq=False)
class ForceTrial:
    """One recorded force-perturbation trial, all (n,) at ``fs_hz``.

    Attributes:
        f_ref: N, reference force at the handle.
        f_measured: N, the force sensor's reading (what the controller used).
        f_true: N, the grasp force on the hand along the link normal (the sensor reads it plus
            ``motor.sensed_mass_kg`` times the handle's tangential acceleration).
        theta_measured: rad, the encoder reading; ``theta_true`` rad the motor angle.
        phi_true: rad, the elbow angle from the hold posture.
        current: A, commanded motor current; ``tau_motor`` N·m = K_torque · current.
        tau_dym: N·m, the dynamic compensation of Eq. (21).
        activation: (n, 2) muscle activations (zeros unless the muscle option).
        fs_hz: Hz.
    """

    f_ref: np.ndarray
    f_measured: np.ndarray
    f_true: np.ndarray
    theta_measured: np.ndarray
    theta_true: np.ndarray
    phi_true: np.ndarray
    current: np.ndarray
    tau_motor: np.ndarray
    tau_dym: np.ndarray
    activation: np.ndarray
    fs_hz: float

    @property
    def tracking_error(self) -> float:
        """RMS of ``f_measured - f_ref`` relative to the RMS of ``f_ref``."""
        return float(np.sqrt(np.mean((self.f_measured - self.f_ref) ** 2) / np.mean(self.f_ref**2)))


class _MuscleCommands:
    """The elbow muscles' commands, one control period at a time: the base (co-contraction or a
    subject's fluctuating commands) plus the delayed stretch reflex.

    The reflex of period ``k`` reads the muscle lengths and velocities of period
    ``k - lag >= k - lag_stretch`` (the shorter latency, at least one period), all recorded by
    then, so the commands of ``lag_stretch`` periods are computed at once by one vectorised
    :func:`reflex_command` call (the same element-wise operations as one call per period, so the
    same numbers); each period only records the state and writes its row.
    """

    def __init__(
        self,
        data: mujoco.MjData,
        muscles: np.ndarray,
        elbow: ElbowConfig,
        reflex: ReflexConfig,
        muscle_base: np.ndarray | None,
        total: int,
        fs_hz: float,
    ) -> None:
        self.ctrl, self.muscles = data.ctrl, muscles
        first = int(muscles[0])
        if np.array_equal(muscles, np.arange(first, first + muscles.size)):
            self.ctrl, self.muscles = data.ctrl[first : first + muscles.size], slice(None)  # a view
        self.base = elbow.cocontraction if muscle_base is None else np.asarray(muscle_base, float)
        self.rows = self.base  # without reflex: the base, row by row
        self.reflex = reflex if reflex.enabled else None
        if self.reflex is not None:
            self.lag1 = max(1, int(round(reflex.stretch_latency_s * fs_hz)))
            self.lag2 = max(1, int(round(reflex.spinal_latency_s * fs_hz)))
            self.all_muscles = muscles
            self.len_ref = data.actuator_length[muscles].copy()
            self.length, self.velocity = data.actuator_length, data.actuator_velocity  # views
            self.hist_len = np.empty((total, data.actuator_length.size))
            self.hist_vel = np.empty((total, data.actuator_velocity.size))
            self.total, self.k0 = total, 0

    def apply(self, k: int) -> None:
        """Record period ``k``'s muscle state and write its commands into ``data.ctrl``."""
        if self.reflex is not None:
            self.hist_len[k] = self.length
            self.hist_vel[k] = self.velocity
            if k % self.lag1 == 0:  # the next lag1 periods' commands, from periods <= k
                self.k0 = k
                ks = np.arange(k, min(k + self.lag1, self.total))
                lagged = np.stack([np.maximum(ks - self.lag1, 0), np.maximum(ks - self.lag2, 0)])
                cols = self.all_muscles
                base = self.base if np.ndim(self.base) == 0 else self.base[ks]
                self.rows = reflex_command(
                    base,
                    self.hist_len[lagged][..., cols],
                    self.hist_vel[lagged][..., cols],
                    self.len_ref,
                    self.reflex,
                )
            self.ctrl[self.muscles] = self.rows[k - self.k0]
        else:
            self.ctrl[self.muscles] = self.rows[k]


def simulate_force_trial(
    scene: DirectDriveScene,
    f_ref: np.ndarray,
    fs_hz: float,
    settle_s: float,
    elbow: ElbowConfig,
    reflex: ReflexConfig,
    motor: DirectDriveConfig,
    force_spec: ChannelSpec,
    encoder_spec: ChannelSpec,
    rng: np.random.Generator,
    accel_noise_rad_s2: float = 0.0,
    muscle_base: np.ndarray | None = None,
    who: TrialLabels | None = None,
    trial: int = 0,
) -> ForceTrial:
    """Simulate one trial: ``settle_s`` of hold at zero force, then ``f_ref`` (recorded).

    Args:
        scene: the composed direct-drive + elbow scene.
        f_ref: (n,) N, reference force at 1/fs_hz spacing.
        fs_hz: Hz, control and sample rate; a whole number of physics steps per period.
        settle_s: s, unrecorded hold before the reference starts.
        elbow, reflex, motor: the subject and the controller.
        force_spec, encoder_spec: sensor imperfections used online: noise, bias and quantisation,
            plus drift for the force sensor (an encoder counts position and does not drift, so
            ``encoder_spec.drift_per_s`` is not used); the sensors' filters and delays are not
            modelled in the loop.
        rng: source of the sensor noise.
        accel_noise_rad_s2: rad/s², rms noise of the accelerometer read by the compensation.
        muscle_base: (n_settle + n, n_muscles) the muscles' commands before the reflex at every
            control period, settle included (a subject whose activation fluctuates, see
            :mod:`armlab.sim.subject`); None: ``elbow.cocontraction`` throughout.
        who, trial: the trials of the run and this one's index, named in a SimulationError.

    Returns:
        The recorded :class:`ForceTrial`.

    Raises:
        SimulationError: the motor angle left ``motor.safety_range_rad``; the state diverged
            (MuJoCo warned or reset it); the grasp force passed :data:`GRASP_FORCE_BOUND_N`; the
            current stayed at its limit for 0.1 s, or for more than :data:`SATURATION_DUTY_MAX` of
            the trial. Times are from the reference's start (negative while settling).
    """
    m = scene.model
    dt = 1.0 / fs_hz
    if who is None:
        who = TrialLabels(protocol="force control", labels=("the trial",), hint=FORCE_LOOP_HINT)
    substeps = int(round(dt / m.opt.timestep))
    if substeps < 1 or abs(substeps * m.opt.timestep - dt) > 1e-9:
        raise ConfigError(
            f"the control period 1/{fs_hz:g} s must be a whole number of physics steps "
            f"({m.opt.timestep} s); valid: sim.timestep_s = {dt:g} / n"
        )
    n_settle = int(round(settle_s * fs_hz))
    n = int(np.size(f_ref))
    total = n_settle + n
    ref = np.concatenate([np.zeros(n_settle), np.asarray(f_ref, float)])

    f_noise = rng.standard_normal(total) * force_spec.noise_std
    f_bias = float(rng.standard_normal() * force_spec.bias_std)
    f_drift = float(rng.standard_normal() * force_spec.drift_per_s)
    e_noise = rng.standard_normal(total) * encoder_spec.noise_std
    e_bias = float(rng.standard_normal() * encoder_spec.bias_std)
    acc_noise = rng.standard_normal(total) * accel_noise_rad_s2

    L, kt = scene.link_length, scene.torque_constant
    m_hat = scene.link_inertia * (1 + motor.inertia_error)
    c_hat = scene.viscous * (1 + motor.viscous_error)
    b_hat = scene.coulomb * (1 + motor.coulomb_error)
    i_max = float(m.actuator_ctrlrange[scene.motor_act, 1])
    i_lsb = 2 * i_max / 2**motor.current_bits
    # first-order low-pass (bilinear) of the differentiated encoder signal
    wc = np.tan(np.pi * motor.derivative_cutoff_hz * dt)
    lp_a, lp_b = (1 - wc) / (1 + wc), wc / (1 + wc)

    data = mujoco.MjData(m)
    muscles = scene.muscle_act
    if muscle_base is not None and np.shape(muscle_base) != (total, muscles.size):
        raise ConfigError(
            f"muscle_base has shape {np.shape(muscle_base)}; need (settle + record samples, muscles) = "
            f"{(total, muscles.size)}"
        )
    act_idx = m.actuator_actadr[muscles] if muscles.size else muscles
    if muscles.size:
        data.act[act_idx] = elbow.cocontraction
        data.ctrl[muscles] = elbow.cocontraction
    element = None
    if scene.element_act >= 0:
        element = FractionalElement.build(
            elbow.fractional_order, elbow.fractional_coeff, elbow.oustaloup_band_hz, elbow.oustaloup_order, dt
        )
        x_el = element.initial_state(0.0)
    mujoco.mj_forward(m, data)
    muscle_ctrl = None  # without reflex or a subject's commands the co-contraction written above holds
    if muscles.size and (reflex.enabled or muscle_base is not None):
        muscle_ctrl = _MuscleCommands(data, muscles, elbow, reflex, muscle_base, total, fs_hz)

    # the loop below is the controller of one control period, in plain Python floats (the same
    # IEEE operations, in the same order, as Eqs. (19)-(21) above; no NumPy call per period): it
    # runs once per 0.5 ms, so each operation counts. MuJoCo's arrays are read through views.
    qpos, sd, ctrl, act = data.qpos, data.sensordata, data.ctrl, data.act
    i_psi, i_psid = scene.sensors["grasp_psi"].start, scene.sensors["grasp_psi_dot"].start
    i_acc = scene.sensors["handle_acc"].start + 1  # the tangential axis a_y
    kg, dg = scene.grasp_k, scene.grasp_d
    qm, qe, motor_act, el_act = scene.motor_qpos, scene.elbow_qpos, scene.motor_act, scene.element_act
    safety, sensed_mass, deadband = motor.safety_range_rad, motor.sensed_mass_kg, motor.sign_deadband_rad_s
    kp, ki, kd = motor.kp, motor.ki_per_s, motor.kd_s
    q_f, q_e = force_spec.quant_step, encoder_spec.quant_step
    ref_l, f_noise_l, e_noise_l = ref.tolist(), f_noise.tolist(), e_noise.tolist()
    acc_noise_l = acc_noise.tolist()
    # the recorded samples, one Python list per channel (stacked after the loop)
    rec_f_meas, rec_f_true, rec_th_meas, rec_theta = ([0.0] * total for _ in range(4))
    rec_phi, rec_current, rec_tau_dym = ([0.0] * total for _ in range(3))
    act_hist = np.zeros((total, m.na))
    n_saturate = int(round(_SATURATION_RUN_S * fs_hz))
    max_saturated = SATURATION_DUTY_MAX * total
    saturated = n_saturated = 0
    h = m.opt.timestep
    theta_prev = e_prev = v_f = v_raw_prev = integ = de_f = de_raw_prev = 0.0
    step = mujoco.mj_step
    for k in range(total):
        t = k * dt
        q, s = qpos.tolist(), sd.tolist()  # one read each: Python floats
        theta = q[qm]
        if not abs(theta) <= safety:
            raise who.error(
                trial,
                (k - n_settle) * dt,
                f"the motor angle reached {theta:+.3f} rad, outside the safety range "
                f"±{safety} rad; the trial is aborted (lower the force peak, raise the "
                "co-contraction or the arm stiffness)",
                state="aborted",
            )
        f_true = -(kg * s[i_psi] + dg * s[i_psid]) / L
        if not abs(f_true) <= GRASP_FORCE_BOUND_N:
            raise who.error(
                trial,
                (k - n_settle) * dt,
                f"grasp force |{f_true:.4g}| N beyond its {GRASP_FORCE_BOUND_N:g} N bound (the reference "
                "stays within 5 N, the motor pushes at most ~48 N)",
            )
        # the sensor also carries the handle mass beyond its measuring plane (tangential a_y)
        acc_y = s[i_acc]
        f_meas = f_true + sensed_mass * acc_y + f_noise_l[k] + f_bias + f_drift * t
        if q_f > 0:
            f_meas = round(f_meas / q_f) * q_f
        th_meas = theta + e_noise_l[k] + e_bias + 0.0 * t  # an encoder does not drift
        if q_e > 0:
            th_meas = round(th_meas / q_e) * q_e
        if k == 0:
            theta_prev, e_prev = th_meas, ref_l[0] - f_meas
        # velocity: low-passed encoder differences (bilinear first order); acceleration: the JR3
        # accelerometer's tangential axis, a_y = L theta_dd (sensor data of the last step)
        v_raw = (th_meas - theta_prev) / dt
        v_f = lp_a * v_f + lp_b * (v_raw + v_raw_prev)
        v_raw_prev, theta_prev = v_raw, th_meas
        a_f = acc_y / L + acc_noise_l[k]
        sgn = 0.0 if abs(v_f) < deadband else (1.0 if v_f > 0 else -1.0)
        tau_dym = m_hat * a_f + c_hat * v_f + b_hat * sgn
        r_k = ref_l[k]
        e = r_k - f_meas
        integ += e * dt
        de_raw = (e - e_prev) / dt
        de_f = lp_a * de_f + lp_b * (de_raw + de_raw_prev)
        e_prev, de_raw_prev = e, de_raw
        u_force = r_k + kp * e + ki * integ + kd * de_f
        current = (tau_dym + L * u_force) / kt
        current = min(max(round(current / i_lsb) * i_lsb, -i_max), i_max)
        if abs(current) >= i_max:
            saturated += 1
            n_saturated += 1
            if saturated > n_saturate:
                raise who.error(
                    trial,
                    (k - n_settle) * dt,
                    f"the motor current stayed at its ±{i_max:.2f} A limit for {_SATURATION_RUN_S:g} s "
                    "without a break (the force loop is unstable or the force exceeds the motor's peak "
                    "torque)",
                )
            if n_saturated > max_saturated:
                raise who.error(
                    trial,
                    (k - n_settle) * dt,
                    f"the motor current was at its ±{i_max:.2f} A limit for {n_saturated / fs_hz:.2f} s, "
                    f"more than the {SATURATION_DUTY_MAX:.0%} saturation duty allowed over the "
                    f"{total / fs_hz:g} s trial (the force loop oscillates against the current limit)",
                )
        else:
            saturated = 0
        ctrl[motor_act] = current
        if muscle_ctrl is not None:
            muscle_ctrl.apply(k)
        phi = q[qe]
        if element is not None:
            ctrl[el_act] = -element.coeff * (element.C @ x_el + element.D * phi)
            x_el = element.A @ x_el + element.B * phi

        rec_f_meas[k], rec_f_true[k], rec_th_meas[k], rec_theta[k] = f_meas, f_true, th_meas, theta
        rec_phi[k], rec_current[k], rec_tau_dym[k] = phi, current, tau_dym
        if muscles.size:
            act_hist[k] = act
        step(m, data, substeps)  # (nstep positional: a keyword costs ~0.3 us a call)
        # MuJoCo resets a diverged state (its clock restarts at 0) and warns
        if not abs(data.time - (k + 1) * substeps * h) < 0.5 * h or not math.isfinite(qpos[qm]):
            raise who.error(
                trial,
                (k - n_settle) * dt + dt,
                "the state became non-finite or MuJoCo reset it (its acceleration diverged); "
                f"MuJoCo warned {warning_counts([data])}",
            )
    warned = warning_counts([data])
    if warned:
        raise who.error(trial, (total - n_settle) * dt, f"MuJoCo warned {warned} during the trial")

    out = np.array([ref_l, rec_f_meas, rec_f_true, rec_th_meas, rec_theta, rec_phi, rec_current, rec_tau_dym])
    act_out = act_hist[:, act_idx] if muscles.size else np.zeros((total, 2))
    rec = out[:, n_settle:]
    return ForceTrial(
        f_ref=rec[0],
        f_measured=rec[1],
        f_true=rec[2],
        theta_measured=rec[3],
        theta_true=rec[4],
        phi_true=rec[5],
        current=rec[6],
        tau_motor=rec[6] * kt,
        tau_dym=rec[7],
        activation=act_out[n_settle:],
        fs_hz=float(fs_hz),
    )
