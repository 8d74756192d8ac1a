"""The direct-drive force controller's control periods, compiled (numba) and stepping MuJoCo in C.

:func:`control_periods` runs control periods ``k0 .. k1 - 1`` of one trial of
:mod:`armlab.sim.force_control`: each reads the encoder and the force sensor from MuJoCo's arrays,
computes the current of Eqs. (19)-(21) of seeds/004 (PID on the force error plus the dynamic
compensation), writes the controls and calls MuJoCo's own C ``mj_step`` ``substeps`` times. The
period's arithmetic is the same IEEE operations in the same order as the plain-Python loop it
replaced, so the trials are bit-identical to it (checked on the trials of ten configurations when
it replaced that loop). Compiled, a period's controller costs well under a microsecond against
~15 us of physics, and the kernel runs without Python's GIL, so the trials of a run step truly in
parallel on threads (:mod:`armlab.sim.threads`).

Why not ``mujoco.rollout``: the controller must read each period's measurement before the next
step and quantises, rounds and clamps what it reads and commands; no MuJoCo actuator holds that,
and a Python ``mj_step`` per 0.5 ms period held the protocol to ~11x real time (issue 21 asks 30x).

The caller (:mod:`armlab.sim.force_loop`) keeps what needs Python: the muscles' delayed reflex
commands, computed a latency's worth of periods at a time between calls (``mrows``), and the check
that MuJoCo did not reset a diverged state (its clock restarts), read from ``data.time``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import mujoco
import numpy as np
from numba import njit

from armlab.sim._mujoco_calls import call, mujoco_function_address

__all__ = [
    "CURRENT_DUTY",
    "CURRENT_RUN",
    "GRASP",
    "NONFINITE",
    "OK",
    "SAFETY",
    "ControlParams",
    "control_periods",
    "mj_pointers",
]

# what control_periods returns as its status, with the period it stopped at
OK, SAFETY, GRASP, CURRENT_RUN, CURRENT_DUTY, NONFINITE = range(6)


def mj_pointers(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[int, int, int]:
    """What the kernel calls MuJoCo with: the address of its C ``mj_step``
    (:func:`~armlab.sim._mujoco_calls.mujoco_function_address`) and of ``model`` and ``data``
    (the bindings' ``_address``). Passed as arguments, never compiled in, so numba's on-disk cache
    stays valid across processes."""
    return mujoco_function_address("mj_step"), int(model._address), int(data._address)


class ControlParams(NamedTuple):
    """The trial's constants, as the kernel reads them (units as in :mod:`.force_control`)."""

    substeps: int  # physics steps per control period
    qm: int  # qpos index of the motor angle
    qe: int  # qpos index of the elbow angle
    motor_act: int  # actuator index of the motor (current, A)
    el_act: int  # actuator index of the fractional element's torque, -1: none
    i_psi: int  # sensordata index of the grasp spring's angle (rad)
    i_psid: int  # ... and of its rate (rad/s)
    i_acc: int  # sensordata index of the handle accelerometer's tangential axis (m/s^2)
    n_saturate: int  # periods at the current limit without a break that fail the trial
    record_act: bool  # record data.act each period
    dt: float  # s, control period
    link: float  # m, link length L
    kt: float  # N·m/A, torque constant
    m_hat: float  # kg·m², C_hat N·m·s/rad, B_hat N·m: the compensation's model, Eq. (21)
    c_hat: float
    b_hat: float
    i_max: float  # A, current limit
    i_lsb: float  # A, the 16-bit reference's step
    lp_a: float  # the first-order bilinear low-pass of the differentiated signals
    lp_b: float
    grasp_k: float  # N·m/rad and N·m·s/rad, the grasp spring
    grasp_d: float
    grasp_bound: float  # N, largest valid grasp force
    safety: float  # rad, motor safety range
    sensed_mass: float  # kg, handle mass beyond the force sensor's plane
    deadband: float  # rad/s, of the Coulomb compensation's sign
    kp: float  # PID gains: 1, 1/s, s
    ki: float
    kd: float
    q_f: float  # N, force quantisation step (0: none)
    q_e: float  # rad, encoder quantisation step (0: none)
    f_bias: float  # N, force sensor bias; N/s its drift
    f_drift: float
    e_bias: float  # rad, encoder bias
    max_saturated: float  # periods at the current limit allowed over the trial
    el_coeff: float  # the fractional element: coefficient and feed-through D
    el_d: float


# indices into the controller's state vector ``st`` (float64, kept by the caller between calls)
THETA_PREV, E_PREV, V_F, V_RAW_PREV, INTEG, DE_F, DE_RAW_PREV, SATURATED, N_SATURATED, STOP_VALUE = range(10)
STATE_SIZE = 10


@njit(cache=True, inline="always")
def _round(x):
    # Python's round(x) (half to even) as the float it multiplies: + 0.0 turns rint's -0.0 into
    # the 0.0 that round()'s integer 0 gives
    return np.rint(x) + 0.0


@njit(nogil=True, cache=True)
def control_periods(
    step, mp, dp, k0, k1, p, st, ref, f_noise, e_noise, acc_noise,
    qpos, sd, ctrl, act, length, velocity,
    rec, act_rec, hist_len, hist_vel, mrows, mrow0, midx,
    el_a, el_b, el_c, el_x,
):  # fmt: skip
    """Run control periods ``k0 .. k1 - 1``; return ``(status, k)``: OK and ``k1``, or the failing
    check and its period (``st[STOP_VALUE]`` holds the value that failed it).

    ``step``, ``mp``, ``dp`` are :func:`mj_pointers` (``mj_step``, the model, the data);
    ``qpos``, ``sd`` (sensordata), ``ctrl``, ``act``, ``length``/``velocity`` (actuator) are views
    of the same MjData. Each period records into
    ``rec`` (7, total): f_measured, f_true, theta_measured, theta, phi, current, tau_dym;
    ``act_rec`` (total, na); ``hist_len``/``hist_vel`` (total, nu) the actuators' state the reflex
    reads ((total, 0): none). It writes ``mrows[k - mrow0]`` into the muscle controls ``midx``
    (none when ``midx`` is empty) and steps the fractional element (``el_x``, when
    ``p.el_act >= 0``).
    """
    dt, link = p.dt, p.link
    for k in range(k0, k1):
        t = k * dt
        theta = qpos[p.qm]
        if not abs(theta) <= p.safety:
            st[STOP_VALUE] = theta
            return SAFETY, k
        f_true = -(p.grasp_k * sd[p.i_psi] + p.grasp_d * sd[p.i_psid]) / link
        if not abs(f_true) <= p.grasp_bound:
            st[STOP_VALUE] = f_true
            return GRASP, k
        # the sensor also carries the handle mass beyond its measuring plane (tangential a_y)
        acc_y = sd[p.i_acc]
        f_meas = f_true + p.sensed_mass * acc_y + f_noise[k] + p.f_bias + p.f_drift * t
        if p.q_f > 0:
            f_meas = _round(f_meas / p.q_f) * p.q_f
        th_meas = theta + e_noise[k] + p.e_bias + 0.0 * t  # an encoder does not drift
        if p.q_e > 0:
            th_meas = _round(th_meas / p.q_e) * p.q_e
        if k == 0:
            st[THETA_PREV], st[E_PREV] = th_meas, ref[0] - f_meas
        # velocity: low-passed encoder differences (bilinear first order); acceleration: the JR3
        # accelerometer's tangential axis, a_y = L theta_dd (sensor data of the last step)
        v_raw = (th_meas - st[THETA_PREV]) / dt
        v_f = p.lp_a * st[V_F] + p.lp_b * (v_raw + st[V_RAW_PREV])
        st[V_F], st[V_RAW_PREV], st[THETA_PREV] = v_f, v_raw, th_meas
        a_f = acc_y / link + acc_noise[k]
        sgn = 0.0 if abs(v_f) < p.deadband else (1.0 if v_f > 0 else -1.0)
        tau_dym = p.m_hat * a_f + p.c_hat * v_f + p.b_hat * sgn
        r_k = ref[k]
        e = r_k - f_meas
        st[INTEG] += e * dt
        de_raw = (e - st[E_PREV]) / dt
        de_f = p.lp_a * st[DE_F] + p.lp_b * (de_raw + st[DE_RAW_PREV])
        st[DE_F], st[E_PREV], st[DE_RAW_PREV] = de_f, e, de_raw
        u_force = r_k + p.kp * e + p.ki * st[INTEG] + p.kd * de_f
        current = (tau_dym + link * u_force) / p.kt
        current = _round(current / p.i_lsb) * p.i_lsb
        if -p.i_max > current:  # Python's max(current, -i_max) then min(., i_max)
            current = -p.i_max
        if p.i_max < current:
            current = p.i_max
        if abs(current) >= p.i_max:
            st[SATURATED] += 1
            st[N_SATURATED] += 1
            if st[SATURATED] > p.n_saturate:
                return CURRENT_RUN, k
            if st[N_SATURATED] > p.max_saturated:
                return CURRENT_DUTY, k
        else:
            st[SATURATED] = 0
        ctrl[p.motor_act] = current
        for j in range(midx.size):
            ctrl[midx[j]] = mrows[k - mrow0, j]
        for j in range(hist_len.shape[1]):  # (none recorded when the array has no columns)
            hist_len[k, j] = length[j]
            hist_vel[k, j] = velocity[j]
        phi = qpos[p.qe]
        if p.el_act >= 0:
            ctrl[p.el_act] = -p.el_coeff * (np.dot(el_c, el_x) + p.el_d * phi)
            el_x[:] = np.dot(el_a, el_x) + el_b * phi
        rec[0, k], rec[1, k], rec[2, k], rec[3, k] = f_meas, f_true, th_meas, theta
        rec[4, k], rec[5, k], rec[6, k] = phi, current, tau_dym
        if p.record_act:
            for j in range(act.size):
                act_rec[k, j] = act[j]
        for _ in range(p.substeps):
            call(step, mp, dp)  # MuJoCo's C mj_step
        if not math.isfinite(qpos[p.qm]):
            return NONFINITE, k
    return OK, k1
