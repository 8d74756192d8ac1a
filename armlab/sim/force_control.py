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
clamps what it reads and commands (no MuJoCo actuator can hold it), so ``mujoco.rollout`` cannot
close the loop: the control periods run in a compiled kernel that calls MuJoCo's C ``mj_step``
(:mod:`armlab.sim.force_kernel`; bit-identical to the plain-Python loop it replaced), without
Python's GIL, so the trials of a run step in parallel on threads (:mod:`armlab.sim.threads`).
Between kernel calls this module computes the muscles' delayed reflex a latency's worth of periods
at a time and checks MuJoCo's clock (a diverged state is reset by MuJoCo; a trial that reset is
replayed period by period to name the period).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.config.schema import DirectDriveConfig, ElbowConfig, ReflexConfig
from armlab.errors import ConfigError
from armlab.models.direct_drive_scene import DirectDriveScene
from armlab.models.oustaloup import FractionalElement
from armlab.sensors.channel import ChannelSpec
from armlab.sim.force_kernel import ControlParams
from armlab.sim.force_loop import GRASP_FORCE_BOUND_N, SATURATION_DUTY_MAX, SATURATION_RUN_S, run_periods
from armlab.sim.stability import TrialLabels, warning_counts

__all__ = [
    "FORCE_LOOP_HINT",
    "GRASP_FORCE_BOUND_N",
    "SATURATION_DUTY_MAX",
    "ForceTrial",
    "simulate_force_trial",
]

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

    muscles = scene.muscle_act
    if muscle_base is not None and np.shape(muscle_base) != (total, muscles.size):
        raise ConfigError(
            f"muscle_base has shape {np.shape(muscle_base)}; need (settle + record samples, muscles) = "
            f"{(total, muscles.size)}"
        )
    element = None
    if scene.element_act >= 0:
        element = FractionalElement.build(
            elbow.fractional_order, elbow.fractional_coeff, elbow.oustaloup_band_hz, elbow.oustaloup_order, dt
        )
    params = ControlParams(
        substeps=substeps,
        qm=int(scene.motor_qpos),
        qe=int(scene.elbow_qpos),
        motor_act=int(scene.motor_act),
        el_act=int(scene.element_act),
        i_psi=int(scene.sensors["grasp_psi"].start),
        i_psid=int(scene.sensors["grasp_psi_dot"].start),
        i_acc=int(scene.sensors["handle_acc"].start) + 1,  # the tangential axis a_y
        n_saturate=int(round(SATURATION_RUN_S * fs_hz)),
        record_act=bool(muscles.size),
        dt=float(dt),
        link=float(L),
        kt=float(kt),
        m_hat=float(m_hat),
        c_hat=float(c_hat),
        b_hat=float(b_hat),
        i_max=i_max,
        i_lsb=float(i_lsb),
        lp_a=float(lp_a),
        lp_b=float(lp_b),
        grasp_k=float(scene.grasp_k),
        grasp_d=float(scene.grasp_d),
        grasp_bound=GRASP_FORCE_BOUND_N,
        safety=float(motor.safety_range_rad),
        sensed_mass=float(motor.sensed_mass_kg),
        deadband=float(motor.sign_deadband_rad_s),
        kp=float(motor.kp),
        ki=float(motor.ki_per_s),
        kd=float(motor.kd_s),
        q_f=float(force_spec.quant_step),
        q_e=float(encoder_spec.quant_step),
        f_bias=f_bias,
        f_drift=f_drift,
        e_bias=e_bias,
        max_saturated=SATURATION_DUTY_MAX * total,
        el_coeff=float(element.coeff) if element is not None else 0.0,
        el_d=float(element.D) if element is not None else 0.0,
    )
    noise = (f_noise, e_noise, acc_noise)
    rec, act_rec, data = run_periods(
        scene, params, ref, noise, elbow, reflex, muscle_base, element, fs_hz, who, trial, n_settle
    )
    warned = warning_counts([data])
    if warned:
        raise who.error(trial, (total - n_settle) * dt, f"MuJoCo warned {warned} during the trial")

    act_idx = m.actuator_actadr[muscles] if muscles.size else muscles
    act_out = act_rec[:, act_idx] if muscles.size else np.zeros((total, 2))
    rec = rec[:, n_settle:]
    return ForceTrial(
        f_ref=ref[n_settle:],
        f_measured=rec[0],
        f_true=rec[1],
        theta_measured=rec[2],
        theta_true=rec[3],
        phi_true=rec[4],
        current=rec[5],
        tau_motor=rec[5] * kt,
        tau_dym=rec[6],
        activation=act_out[n_settle:],
        fs_hz=float(fs_hz),
    )
