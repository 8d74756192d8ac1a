"""Level B of paper 002's Cartesian protocol: the LWR pushes a hand with inertia through a rigid cuff.

The thesis (Ch. 3) treats the robot as an ideal position source and the hand as massless. Here
MuJoCo steps the LWR-class robot (position servos, :mod:`armlab.models.cartesian_hand_scene`)
tracking the stopped reference plus the perturbation, a 0.966 kg hand (models/cartesian_hand)
joined to its cuff, and the human's force on the hand from the Table 3.1 field (Eqs. 2.2.1-2.2.4)
with its equilibrium at the stopped reference ``q_r``:

    F_human = -(K(q_h)·(q_h - q_r) + D(q_h)·q̇_h),    D = δ√K (Eq. 2.2.2).

**How the field is applied exactly.** ``F_human`` depends nonlinearly on the hand's state, which
no MuJoCo actuator can express (gains and biases are affine in one transmission's length and
velocity; a field linearised per chunk of steps is not exact). It is therefore the control of two
motors on the hand's slides, recomputed from every trial's state before **every physics step**.
That loop runs compiled (:mod:`armlab.sim._level_b_kernel`): each trial in its own ``MjData`` (reset
from a pool of :data:`DATA_POOL`), the field from its ``qpos``/``qvel`` written to its ``ctrl``,
then MuJoCo's ``mj_step``, the trials shared among threads. This is the discretisation MuJoCo uses
for its own explicit actuator forces (evaluated from the state at the start of the step), so
nothing is linearised or held over a chunk: the only error is the integrator's.

The thesis logs only during perturbations (§3.2.2) and each perturbation starts with the path
stopped, so every perturbation is simulated as one trial starting at rest in equilibrium at its
stop point (the path's motion between stops, 6.3 mm/s on the circle, is not simulated), with a
short settle (:data:`SETTLE_S`) before the perturbation begins.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import mujoco
import numpy as np

from armlab.cpus import usable_cpus
from armlab.errors import ConfigError, SimulationError
from armlab.models.cartesian_field import QuadraticImpedanceField
from armlab.models.cartesian_hand_scene import HAND_HEIGHT_M, HandScene
from armlab.models.robot_fk import RobotKinematics
from armlab.sim import _level_b_kernel as _kernel
from armlab.sim._mujoco_calls import mujoco_function_address
from armlab.sim.robot_ik import nominal_robot_posture, solve_ik
from armlab.sim.stability import warning_counts

__all__ = [
    "DATA_POOL",
    "SETTLE_S",
    "LevelBTrials",
    "load_level_b_compiled",
    "simulate_level_b",
    "stop_postures",
]

#: MjData reused for the trials (each trial is reset into one; a MjData holds ~0.46 MB, measured)
DATA_POOL = 64
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
        hand_acc: (n, s, 2) m/s², the hand's acceleration along x, y (its accelerometer; the
            site is world-aligned, so gravity is only in z).
        human_force: (n, s, 2) N, the field's force on the hand (``F_human`` above).
        fs_hz: Hz.
    """

    hand_pos: np.ndarray
    hand_vel: np.ndarray
    robot_q: np.ndarray
    ft_force: np.ndarray
    hand_acc: np.ndarray
    human_force: np.ndarray
    fs_hz: float


def _check(status: np.ndarray, rows: np.ndarray, ref: np.ndarray, warned: dict) -> None:
    """Raise on the stepped ``rows``' failures: a negative stiffness (the field's), a non-finite
    state or a MuJoCo warning (accumulated in each trial's ``MjData``, nothing clears them)."""
    bad = rows[status[rows] != 0]
    negative = bad[status[bad] == _kernel.NEGATIVE_STIFFNESS]
    if negative.size:
        i = negative[0]
        raise ConfigError(
            f"the stiffness field is negative on level-B trial {i} (stop {ref[i]} m): D = δ√K is undefined "
            "there; lower the perturbation or change the field"
        )
    if warned or bad.size:
        raise SimulationError(
            f"level-B simulation diverged or MuJoCo warned ({warned or 'non-finite state'}, trials "
            f"{bad.tolist() or rows[[0, -1]].tolist()}); lower sim.timestep_s or simulation.stiffness_scale"
        )


def load_level_b_compiled() -> None:
    """Load the compiled stepping (:mod:`armlab.sim._level_b_kernel`) and the robot's forward
    kinematics (:mod:`armlab.models._fk_kernel`) from numba's cache (compiled there on a first use);
    a protocol declares it as its ``preload``."""
    _kernel.load()
    RobotKinematics.load_compiled()


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
        nthread: threads stepping the trials (default: all cores).

    Returns:
        The clean signals; sample ``j`` is the state at the start of the perturbation's step
        ``j·substeps`` and the F/T force during that step.

    Raises:
        SimulationError: a trial diverged or MuJoCo warned.
        ConfigError: the field's stiffness turned negative on a trial (D = δ√K undefined).
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
    ref = np.ascontiguousarray(np.asarray(stops, float)[stop_of])
    # robot joint targets of each sample (first-order IK around the stop; the hand's position is
    # measured, so the small second-order error only changes the executed excursion)
    targets = q0[:, None, :] + np.einsum("nij,nsj->nsi", jac, displacement)

    ft, acc = scene.sensors["ft_force"], scene.sensors["hand_acc"]
    cols = np.r_[np.arange(ft.start, ft.stop), np.arange(acc.start, acc.stop)].astype(np.int64)
    idx = np.array(
        [
            *scene.hand_qpos[:2],
            *scene.hand_dof[:2],
            *scene.field_act,
            model.nq,
            model.nv,
            model.nu,
            model.nsensordata,
        ],
        dtype=np.int64,
    )
    coef = field.coefficients_at(0.0)
    k_sigma = np.asarray(field.k_sigma, float) * field.stiffness_scale
    hand_pos, hand_vel = np.empty((n, n_s, 2)), np.empty((n, n_s, 2))
    robot_q, sensor, human = np.empty((n, n_s, 7)), np.empty((n, n_s, cols.size)), np.empty((n, n_s, 2))
    status = np.zeros(n, dtype=np.int64)
    rest = (
        idx,
        cols,
        scene.robot_qpos.astype(np.int64),
        scene.robot_act.astype(np.int64),
        ref,
        coef,
        k_sigma,
        float(sigma),
        np.asarray(field.delta, float),
        np.ascontiguousarray(q0),
        np.ascontiguousarray(targets),
        int(round(SETTLE_S / dt)),
        substeps,
        hand_pos,
        hand_vel,
        robot_q,
        sensor,
        human,
        status,
    )
    step_fn = mujoco_function_address("mj_step")
    n_threads = max(1, min(n, nthread or usable_cpus()))
    pool = [mujoco.MjData(model) for _ in range(min(n, DATA_POOL))]
    data_addr, addr = np.zeros(n, dtype=np.int64), np.zeros((n, 4), dtype=np.int64)
    with ThreadPoolExecutor(n_threads) as threads:
        for first in range(0, n, len(pool)):
            rows = np.arange(first, min(n, first + len(pool)), dtype=np.int64)
            for i, data in zip(rows, pool, strict=False):  # rest in equilibrium at the stop
                mujoco.mj_resetData(model, data)
                data.qpos[scene.robot_qpos] = q0[i]
                data.qpos[scene.hand_qpos[:2]] = ref[i]
                data.ctrl[scene.robot_act] = q0[i]
                mujoco.mj_forward(model, data)
                data_addr[i] = data._address
                addr[i] = [a.ctypes.data for a in (data.qpos, data.qvel, data.ctrl, data.sensordata)]
            # the kernel releases the GIL: one contiguous share of the rows per thread
            shares = np.array_split(rows, n_threads)
            list(
                threads.map(
                    lambda r: _kernel.step_trials(step_fn, model._address, data_addr, addr, r, *rest), shares
                )
            )
            _check(status, rows, ref, warning_counts(pool[: len(rows)]))
    return LevelBTrials(
        hand_pos=hand_pos,
        hand_vel=hand_vel,
        robot_q=robot_q,
        ft_force=sensor[..., :3],
        hand_acc=sensor[..., 3:5],
        human_force=human,
        fs_hz=fs_hz,
    )
