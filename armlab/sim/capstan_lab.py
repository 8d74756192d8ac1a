"""Batched trials of the capstan robot under joint PD control (virtual-force-sensor paper, seeds/003).

The PD servos of :mod:`armlab.models.capstan_scene` make the closed loop open-loop in ``ctrl``
(the reference and its derivative), so every trial of a batch is stepped by one threaded
``mujoco.rollout`` call per chunk of steps. Each trial starts at rest at ``theta0`` and its
reference fades in over ``settle_s`` (simulated, not recorded); samples are taken every
``fs``-th of a second from the sensors MuJoCo computes in the forward pass of a step (the state at
the start of that step), so every channel of a sample belongs to the same instant.

Clean channels (robot frame unless said, ``(n_trials, n_samples, 2)``):

- ``theta`` rad: motor encoders in link-side units (ρ/N), the paper's Θ;
- ``tau`` N·m: the controller's joint torques τ_r (actuator force, clamped at ±25 N·m);
- ``acc_site`` m/s²: accelerometer x, y in the ee site frame (link 2's axes, turned by θ2);
- ``ft_site`` N: F/T force x, y in the ft site frame (link 2 on the handle subtree, same axes);
- ``true_theta`` rad, ``true_x`` m, ``true_psi`` rad: link angles, end-effector position and
  cable stretch behind the encoders (truth);
- ``true_hand`` m: the hand's position (arm scenes only);
- ``reference`` rad: the joint references θ0 + r(t).
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from armlab import progress
from armlab.cpus import usable_cpus
from armlab.errors import SimulationError
from armlab.models.capstan_scene import CapstanScene
from armlab.perturbations.sum_of_sines import SumOfSines
from armlab.sim.stability import TrialLabels, check_bound, check_rollout

__all__ = [
    "CAPSTAN_HINT",
    "CLEAN_UNITS",
    "HANDLE_FORCE_BOUND_N",
    "simulate_capstan",
]

# N, largest clean F/T force at the handle of a valid trial: the PD servos are clamped at
# ±25 N m per joint (capstan_planar.xml), which over the >= 0.3 m arms pushes ~100-170 N at
# most statically; the paper's fixtures (<= ~900 N/m over a few cm) and a relaxed arm load the
# handle with tens of N. The default runs peak at 13 N (38x margin).
HANDLE_FORCE_BOUND_N = 500.0
#: What to change when a capstan trial is unstable.
CAPSTAN_HINT = "lower sim.timestep_s or capstan.cable_stiffness_Nm_per_rad (docs/reliability.md, Instability)"

CLEAN_UNITS = {
    "theta": "rad",
    "tau": "N*m",
    "acc_site": "m/s^2",
    "ft_site": "N",
    "true_theta": "rad",
    "true_x": "m",
    "true_psi": "rad",
    "true_hand": "m",
    "reference": "rad",
}
_CHUNK_STEPS = 5000  # physics steps per rollout call (bounds memory: trials x chunk x state)


def _pairs(scene: CapstanScene, sd: np.ndarray) -> dict[str, np.ndarray]:
    def two(a: str, b: str) -> np.ndarray:
        return np.concatenate([scene.sensor(sd, a), scene.sensor(sd, b)], axis=-1)

    out = {
        "theta": two("theta1", "theta2"),
        "tau": two("tau1", "tau2"),
        "acc_site": scene.sensor(sd, "ee_acc")[..., :2],
        "ft_site": scene.sensor(sd, "ft_force")[..., :2],
        "true_theta": two("link_theta1", "link_theta2"),
        "true_x": scene.sensor(sd, "p_ee")[..., :2],
        "true_psi": two("psi1", "psi2"),
    }
    if scene.load == "arm":
        out["true_hand"] = scene.sensor(sd, "p_hand")[..., :2]
    return out


def simulate_capstan(
    scene: CapstanScene,
    initial_state: np.ndarray,
    theta0: np.ndarray,
    references: Sequence[SumOfSines],
    *,
    kp: float,
    kd: float,
    fs_hz: float,
    duration_s: float,
    settle_s: float,
    muscle_ctrl: np.ndarray | None = None,
    nthread: int | None = None,
    who: TrialLabels | None = None,
) -> dict[str, np.ndarray]:
    """Run one trial per reference from the same initial state.

    Args:
        scene: the composed lab (its timestep must divide the sample period).
        initial_state: full-physics state at rest at ``theta0``.
        theta0: (2,) rad, the joints' operating point (the references are added to it).
        references: one joint reference per trial (fade-in ``settle_s`` before t = 0).
        kp, kd: the servo gains in the scene (N·m/rad, N·m·s/rad), for the derivative feed-forward
            ``ctrl = theta_ref + (kd / kp) theta_ref_dot``.
        fs_hz: sample rate of the record, Hz; duration_s: recorded length, s; settle_s: s before.
        muscle_ctrl: muscle excitations (arm scenes): (6,) held constant, or
            (n_trials, n_steps, 6) per trial and physics step (settle steps included, e.g. a
            subject whose activation fluctuates, :mod:`armlab.sim.subject`).
        nthread: rollout threads (default: the CPU count).
        who: the trials, named in a :class:`SimulationError` (default: "reference <i>").

    Returns:
        Clean channels (module docstring), ``(n_trials, n_samples, k)`` float64.

    Raises:
        SimulationError: the timestep does not divide the sample period; a trial diverged (MuJoCo
            warned or reset its state) or its handle force passed :data:`HANDLE_FORCE_BOUND_N`.
            Times are from the recorded start (negative while settling).
    """
    model = scene.model
    dt = float(model.opt.timestep)
    sub = round(1.0 / (fs_hz * dt))
    if sub < 1 or abs(sub * dt * fs_hz - 1.0) > 1e-9:
        raise SimulationError(f"the physics step {dt} s must divide the sample period 1/{fs_hz} s")
    n_settle = round(settle_s * fs_hz) * sub
    n_samples = round(duration_s * fs_hz)
    n_steps = n_settle + n_samples * sub
    n_trials = len(references)
    if who is None:
        who = TrialLabels(
            protocol="capstan lab", labels=tuple(f"reference {k}" for k in range(n_trials)), hint=CAPSTAN_HINT
        )
    per_step = muscle_ctrl is not None and np.ndim(muscle_ctrl) == 3
    if per_step and np.shape(muscle_ctrl)[:2] != (n_trials, n_steps):
        raise SimulationError(
            f"per-step muscle commands must have shape ({n_trials}, {n_steps}, n_muscles), "
            f"got {np.shape(muscle_ctrl)}"
        )
    nthread = nthread or usable_cpus()
    data = [mujoco.MjData(model) for _ in range(min(nthread, n_trials))]
    state = np.tile(np.asarray(initial_state, float), (n_trials, 1))
    sd_out = np.empty((n_trials, n_samples, model.nsensordata))
    progress.stage("simulate", n_trials, "trials")  # lock-step: n_trials * c1 / n_steps after a chunk
    with mj_rollout.Rollout(nthread=len(data)) as runner:
        for c0 in range(0, n_steps, _CHUNK_STEPS):
            steps = np.arange(c0, min(n_steps, c0 + _CHUNK_STEPS)) - n_settle  # 0 at the first sample
            t = steps * dt
            ctrl = np.zeros((n_trials, len(steps), model.nu))
            for k, ref in enumerate(references):
                r, dr = ref.value_and_derivative(t)
                ctrl[k][:, scene.motor_act] = theta0 + r + (kd / kp) * dr
            if per_step:
                ctrl[:, :, scene.muscle_act] = muscle_ctrl[:, c0 : c0 + len(steps)]
            elif muscle_ctrl is not None:
                ctrl[:, :, scene.muscle_act] = muscle_ctrl
            states, sd = runner.rollout(model, data, state, ctrl, nstep=len(steps))
            check_rollout(who, state, states, data, dt, (steps + 1) * dt)
            state = states[:, -1]
            keep = (steps >= 0) & (steps % sub == 0)
            sd_out[:, steps[keep] // sub] = sd[:, keep]
            c1 = c0 + len(steps)
            progress.advance(n_trials * c1 / n_steps - n_trials * c0 / n_steps)
    out = _pairs(scene, sd_out)
    t_samples = np.arange(n_samples) / fs_hz
    check_bound(
        who,
        out["ft_site"],
        t_samples,
        HANDLE_FORCE_BOUND_N,
        "handle force",
        "N",
        "beyond the servos' ±25 N m; valid runs stay below 15 N",
    )
    out["reference"] = np.stack([theta0 + ref.value(t_samples) for ref in references])
    return out
