"""The robot's limits on a scenario's commanded trajectory (issue 23: a designed excitation must
respect every limit of the LWR that performs it, checked after IK, not on the arm's joints).

Velocity and torque limits are the LBR4+ data-sheet values the robot model cites
(models/lwr/README.md, [LIM]). KUKA publishes no joint acceleration limit for the LWR (its torque
limit is the physical one); the bound used here is what the paper's own fastest perturbation
demanded of the real robot: the peak acceleration of each robot joint on the T_1 = 50 ms quintic
of the six paper directions (seeds/000, section IV-B), computed by the same IK.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from armlab.errors import ConfigError
from armlab.perturbations.scenario import Scenario, TrialPlan, load_scenario
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.sim.lab import robot_target_paths, settled_scene

__all__ = [
    "LWR_TORQUE_LIMIT_NM",
    "LWR_VELOCITY_LIMIT_RAD_S",
    "RobotLimits",
    "check_robot_torque",
    "robot_limits",
]

# rad/s, joint velocity limits A1..A7: 110, 110, 128, 128, 204, 184, 184 deg/s (LBR4+ specification,
# models/lwr/README.md [LIM]; MuJoCo does not model them, so they are checked here)
LWR_VELOCITY_LIMIT_RAD_S = np.deg2rad([110.0, 110.0, 128.0, 128.0, 204.0, 184.0, 184.0])
# N m, joint torque limits A1..A7 (LBR4+ specification, models/lwr/README.md [LIM]; the servos'
# forcerange in models/lwr/lwr.xml)
LWR_TORQUE_LIMIT_NM = np.array([176.0, 176.0, 100.0, 100.0, 100.0, 38.0, 38.0])


@dataclass(frozen=True, kw_only=True)
class RobotLimits:
    """Peaks of the commanded robot joint trajectory against the limits.

    Attributes:
        peak_vel: (7,) rad/s; vel_limit: (7,) rad/s, data sheet.
        peak_acc: (7,) rad/s²; acc_limit: (7,) rad/s², the paper's fastest quintic on the robot.
    """

    peak_vel: np.ndarray
    vel_limit: np.ndarray
    peak_acc: np.ndarray
    acc_limit: np.ndarray

    def check(self, what: str) -> None:
        """ConfigError naming each joint whose velocity or acceleration exceeds its limit."""
        bad = [
            f"A{j + 1} {kind} {peak[j]:.3g} > {limit[j]:.3g} {unit}"
            for kind, peak, limit, unit in (
                ("velocity", self.peak_vel, self.vel_limit, "rad/s"),
                ("acceleration", self.peak_acc, self.acc_limit, "rad/s^2"),
            )
            for j in np.flatnonzero(peak > limit)
        ]
        if bad:
            raise ConfigError(
                f"{what}: the commanded LWR trajectory exceeds its limits ({'; '.join(bad)}); valid: "
                "a slower waveform (longer T_k, smaller knot steps) or a smaller amplitude"
            )


def _peaks(cfg: ConditioningWindowConfig, scenario: Scenario, scene, hold) -> tuple[np.ndarray, np.ndarray]:
    """Peak |qd|, |qdd| (7,) of the robot targets, one path per (direction, T_k) of ``scenario``."""
    n_dir = scenario.directions_rad.shape[0]
    dirs = np.repeat(np.arange(n_dir), scenario.t_k_s.size)
    t_k = np.tile(scenario.t_k_s, n_dir)
    plan = TrialPlan(
        group=np.zeros(dirs.size, int),
        direction=dirs,
        amplitude_rad=scenario.directions_rad[dirs],
        t_k_s=t_k,
        wait_s=np.zeros(dirs.size),
        validate=np.zeros(dirs.size, bool),
    )
    dt = scene.model.opt.timestep
    t_rel = np.arange(-0.01, float(t_k.max()) + 0.01, dt)
    paths, _ = robot_target_paths(
        scene, hold, np.asarray(cfg.arm.q0, float), plan, scenario.directions_rad, t_rel, scenario.waveform
    )
    qd = np.gradient(paths, dt, axis=1)
    qdd = np.gradient(qd, dt, axis=1)
    return np.abs(qd).max(axis=(0, 1)), np.abs(qdd).max(axis=(0, 1))


def robot_limits(cfg: ConditioningWindowConfig, scenario: Scenario) -> RobotLimits:
    """The commanded robot trajectory of ``scenario`` in ``cfg``'s lab against the LWR's limits
    (central differences at the physics step of the IK'd targets the lab feeds its servos)."""
    scene, hold, _ = settled_scene(cfg)  # the lab's own (its model effects applied)
    vel, acc = _peaks(cfg, scenario, scene, hold)
    paper = load_scenario("conditioning_window")
    fastest = replace(paper, t_k_s=paper.t_k_s[:1], waveform=None)
    _, acc_limit = _peaks(cfg, fastest, scene, hold)
    return RobotLimits(peak_vel=vel, vel_limit=LWR_VELOCITY_LIMIT_RAD_S, peak_acc=acc, acc_limit=acc_limit)


def check_robot_torque(robot_tau: np.ndarray, what: str) -> np.ndarray:
    """Peak |torque| (7,) N·m of the simulated robot's joint torque sensors, (n_trials, n, 7);
    ConfigError naming each joint above its limit (:data:`LWR_TORQUE_LIMIT_NM`)."""
    peak = np.abs(np.asarray(robot_tau, float)).max(axis=(0, 1))
    over = np.flatnonzero(peak > LWR_TORQUE_LIMIT_NM)
    if over.size:
        bad = "; ".join(f"A{j + 1} {peak[j]:.1f} > {LWR_TORQUE_LIMIT_NM[j]:.0f} N m" for j in over)
        raise ConfigError(f"{what}: the simulated LWR exceeds its joint torque limits ({bad})")
    return peak
