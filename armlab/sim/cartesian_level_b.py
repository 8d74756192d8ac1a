"""Level B of paper 002's Cartesian protocol: the LWR pushes a hand with inertia through a rigid cuff.

The thesis (Ch. 3) treats the robot as an ideal position source and the hand as massless. Here
MuJoCo steps the LWR-class robot (position servos, :mod:`armlab.models.cartesian_hand_scene`)
tracking the stopped reference plus the perturbation, a 0.966 kg hand (models/cartesian_hand)
joined to its cuff, and the human's force on the hand from the Table 3.1 field (Eqs. 2.2.1-2.2.4)
with its equilibrium at the stopped reference ``q_r``:

    F_human = -(K(q_h)·(q_h - q_r) + D(q_h)·q̇_h),    D = δ√K (Eq. 2.2.2).

**How the field is applied exactly.** ``F_human`` depends nonlinearly on the hand's state, which
no MuJoCo actuator can express (gains and biases are affine in one transmission's length and
velocity). It is therefore the control of two motors on the hand's slides, recomputed from every
trial's state before **every physics step**: all trials advance together by one step per
``mujoco.rollout`` call (one call per step for the whole batch, not per trial), and between calls
the field is evaluated for the whole batch at once from the hand's ``qpos``/``qvel``, which are
entries of the state vector (no kinematics needed). This is the same discretisation MuJoCo uses
for its own explicit actuator forces (evaluated from the state at the start of the step), so
nothing is linearised or held over a chunk: the only error is the integrator's.

The thesis logs only during perturbations (§3.2.2) and each perturbation starts with the path
stopped, so every perturbation is simulated as one trial starting at rest in equilibrium at its
stop point (the path's motion between stops, 6.3 mm/s on the circle, is not simulated), with a
short settle (:data:`SETTLE_S`) before the perturbation begins.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from armlab.errors import SimulationError
from armlab.models.cartesian_field import QuadraticImpedanceField
from armlab.models.cartesian_hand_scene import HAND_HEIGHT_M, HandScene
from armlab.sim.robot_ik import nominal_robot_posture, solve_ik
from armlab.sim.stability import warning_counts

__all__ = [
    "SETTLE_S",
    "LevelBTrials",
    "simulate_level_b",
    "stop_postures",
]

#: s, settle at the stop before each perturbation: the cuff's 0.04 kg (not gravity compensated)
#: sags the servos by ~1e-5 m and the connect constraint takes up its 1 ms time constant
#: (assumption: 100 time constants; the field holds the hand in place meanwhile)
SETTLE_S = 0.05


@dataclass(frozen=True, kw_only=True, eq=False)
class LevelBTrials:
    """Clean level-B signals, one row per perturbation, sampled at ``fs_hz``.

    Attributes:
        hand_pos: (n, s, 2) m, hand position (thesis frame); hand_vel: (n, s, 2) m/s.
        robot_q: (n, s, 7) rad, robot joint angles (what the encoders measure).
        ft_force: (n, s, 3) N, the flange's force on the cuff and hand in the F/T site frame.
        human_force: (n, s, 2) N, the field's force on the hand (``F_human`` above).
        fs_hz: Hz.
    """

    hand_pos: np.ndarray
    hand_vel: np.ndarray
    robot_q: np.ndarray
    ft_force: np.ndarray
    human_force: np.ndarray
    fs_hz: float


def stop_postures(scene: HandScene, stops: np.ndarray) -> np.ndarray:
    """Robot joint angles placing the cuff at each stop, flange down (damped LS IK).

    Args:
        stops: (m, 2) m, stop positions in the thesis frame.

    Returns:
        (m, 7) rad.
    """
    targets = np.c_[stops, np.full(len(stops), HAND_HEIGHT_M)]
    order = np.lexsort((stops[:, 1], stops[:, 0]))  # neighbours after each other: warm starts
    q = np.empty((len(stops), 7))
    q[order] = solve_ik(scene, targets[order], nominal_robot_posture(scene, targets[order[0]]))
    return q


def _jacobians(scene: HandScene, q0: np.ndarray) -> np.ndarray:
    """(m, 7, 2): joint motion per metre of cuff motion along x, y at fixed height and flange
    orientation (pseudo-inverse of the 6 x 7 site Jacobian at each posture)."""
    model, data = scene.model, mujoco.MjData(scene.model)
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    out = np.empty((len(q0), 7, 2))
    for i, q in enumerate(q0):
        data.qpos[scene.robot_qpos] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        mujoco.mj_jacSite(model, data, jacp, None, scene.contact_site)
        mujoco.mj_jacSite(model, data, None, jacr, scene.flange_site)
        jac = np.vstack([jacp[:, scene.robot_dof], jacr[:, scene.robot_dof]])
        out[i] = np.linalg.pinv(jac)[:, :2]
    return out


def simulate_level_b(
    scene: HandScene,
    field: QuadraticImpedanceField,
    stops: np.ndarray,
    stop_of: np.ndarray,
    displacement: np.ndarray,
    *,
    fs_hz: float = 1000.0,
    sigma: float = 0.0,
    nthread: int | None = None,
) -> LevelBTrials:
    """Simulate every perturbation as one trial (module docstring).

    Args:
        scene: from :func:`~armlab.models.cartesian_hand_scene.build_hand_scene`.
        field: the human's impedance field (Table 3.1 times ``stiffness_scale``).
        stops: (m, 2) m, stop positions ``q_r``.
        stop_of: (n,) int, the stop of each perturbation.
        displacement: (n, s, 2) m, the commanded perturbation ``q_p`` at each sample (sample 0 is
            the perturbation's start).
        fs_hz: Hz, sample rate of ``displacement`` and of the output (a whole number of steps).
        sigma: co-contraction index of Eq. 2.2.4.
        nthread: rollout threads (default: all cores).

    Returns:
        The clean signals; sample ``j`` is the state at the start of the perturbation's step
        ``j·substeps`` and the F/T force during that step.

    Raises:
        SimulationError: a trial diverged or MuJoCo warned.
    """
    model = scene.model
    dt = model.opt.timestep
    substeps = int(round(1.0 / (fs_hz * dt)))
    if substeps < 1 or abs(substeps * dt * fs_hz - 1.0) > 1e-9:
        raise SimulationError(f"1/fs = {1 / fs_hz:g} s must be a whole number of {dt:g} s physics steps")
    n, n_s, _ = displacement.shape
    q_stop = stop_postures(scene, stops)
    jac = _jacobians(scene, q_stop)[stop_of]  # (n, 7, 2)
    q0 = q_stop[stop_of]
    ref = np.asarray(stops, float)[stop_of]
    # robot joint targets of each sample (first-order IK around the stop; the hand's position is
    # measured, so the small second-order error only changes the executed excursion)
    targets = q0[:, None, :] + np.einsum("nij,nsj->nsi", jac, displacement)

    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    nstate = mujoco.mj_stateSize(model, spec)
    data = mujoco.MjData(model)
    state = np.empty((n, nstate))
    for i in range(n):  # rest in equilibrium at the stop (n mj_forward calls, ~1 ms in all)
        mujoco.mj_resetData(model, data)
        data.qpos[scene.robot_qpos] = q0[i]
        data.qpos[scene.hand_qpos[:2]] = ref[i]
        data.ctrl[scene.robot_act] = q0[i]
        mujoco.mj_forward(model, data)
        mujoco.mj_getState(model, data, state[i], spec)
    pos_cols = 1 + scene.hand_qpos[:2]  # state = [time, qpos, qvel, act, ...]
    vel_cols = 1 + model.nq + scene.hand_dof[:2]
    robot_cols = 1 + scene.robot_qpos
    ft = scene.sensors["ft_force"]

    datas = [mujoco.MjData(model) for _ in range(nthread or os.cpu_count() or 1)]
    models = [model] * n
    ctrl = np.zeros((n, 1, model.nu))
    ctrl[:, 0, scene.robot_act] = q0
    out_state = np.empty((n, 1, nstate))
    out_sd = np.empty((n, 1, model.nsensordata))
    n_settle = int(round(SETTLE_S / dt))
    hand_pos, hand_vel = np.empty((n, n_s, 2)), np.empty((n, n_s, 2))
    robot_q, ft_force, human = np.empty((n, n_s, 7)), np.empty((n, n_s, 3)), np.empty((n, n_s, 2))
    with mj_rollout.Rollout(nthread=len(datas)) as runner:
        for step in range(n_settle + n_s * substeps):
            q_h, qd_h = state[:, pos_cols], state[:, vel_cols]
            f_h = -field.force(q_h, qd_h, q_h - ref, sigma)  # Eq. 2.2.1 (no inertia): the human's force
            ctrl[:, 0, scene.field_act] = f_h
            k = step - n_settle
            sample = k // substeps if k >= 0 and k % substeps == 0 else -1
            if k >= 0:  # servo target: the sample being moved to (held at the last one)
                ctrl[:, 0, scene.robot_act] = targets[:, min(k // substeps + 1, n_s - 1)]
            runner.rollout(
                models,
                datas,
                state,
                ctrl,
                control_spec=mujoco.mjtState.mjSTATE_CTRL,
                skip_checks=True,
                nstep=1,
                state=out_state,
                sensordata=out_sd,
            )
            # every rollout call clears MuJoCo's warning counters: read them after each step
            warned = warning_counts(datas)
            if warned or not np.all(np.isfinite(out_state[:, 0])):
                raise SimulationError(
                    f"level-B simulation diverged or MuJoCo warned at t = {(k if k >= 0 else 0) * dt:.4f} s "
                    f"of the perturbation ({warned or 'non-finite state'}); lower sim.timestep_s or "
                    "simulation.stiffness_scale"
                )
            if sample >= 0:
                hand_pos[:, sample], hand_vel[:, sample] = q_h, qd_h
                robot_q[:, sample] = state[:, robot_cols]
                ft_force[:, sample] = out_sd[:, 0, ft]
                human[:, sample] = f_h
            state = out_state[:, 0].copy()
    return LevelBTrials(
        hand_pos=hand_pos,
        hand_vel=hand_vel,
        robot_q=robot_q,
        ft_force=ft_force,
        human_force=human,
        fs_hz=fs_hz,
    )
