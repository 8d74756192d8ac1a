"""Physical effects the 5-DoF stiffness lab can switch on beyond its nominal physics (seed paper
001's lab; the diagnosis referee's hidden effects, beside the reflex of :mod:`armlab.sim.arm5_reflex`).

- :func:`soften_cuff`: the 6-D cuff's weld made compliant: MuJoCo's ``solref`` time constant
  ``tc`` s (critically damped) instead of the rigid 2 timesteps, the impedance held at 0.99 so the
  spring is linear in the stretch (as the cartesian referee's cuff, armlab.sim.cartesian_level_b);
  a soft-tissue/strap interface of the paper's plastic cuff (Sec. 3).
- :func:`marker_soft_tissue`: the skin under the forearm cluster slides over the radius and ulna:
  the cluster turns about the forearm (pronation) axis by only ``1 - slip`` of the bone's
  pronation from the working posture (skin clusters under-read a long bone's axial rotation by
  tens of percent, the soft-tissue artefact: Cutti et al. 2005, Gait & Posture 21:341, for the
  humerus; *assumption* for the forearm and the size).
- :func:`base_sensor_drift`: the base JR3 drifts since its tare at a constant rate per axis over
  the session (thermal drift of an untempered gauge; the wrist JR3 preset assumes ~0.1 N/min).
"""

from __future__ import annotations

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from armlab.errors import ConfigError
from armlab.models.limb_kinematics import LimbKinematics

__all__ = [
    "base_sensor_drift",
    "marker_soft_tissue",
    "soften_cuff",
]

_RIGID_SOLIMP = 0.99  # the weld's impedance at zero violation, held: a linear spring (see above)


def soften_cuff(model: mujoco.MjModel, time_constant_s: float) -> None:
    """Make the cuff's weld(s) of ``model`` compliant in place: ``solref = (tc, 1)`` s (critically
    damped), impedance 0.99 over the whole stretch.

    Raises:
        ConfigError: ``tc`` not above two timesteps (MuJoCo's stable minimum) or above 0.1 s.
    """
    lo = 2.0 * model.opt.timestep
    if not lo < time_constant_s <= 0.1:
        raise ConfigError(f"cuff time constant must lie in ({lo:g}, 0.1] s, got {time_constant_s}")
    model.eq_solref[:] = (time_constant_s, 1.0)
    model.eq_solimp[:, :2] = _RIGID_SOLIMP


def marker_soft_tissue(
    pos: np.ndarray, quat: np.ndarray, q: np.ndarray, q0: np.ndarray, slip: float, kin: LimbKinematics
) -> tuple[np.ndarray, np.ndarray]:
    """The forearm cluster's pose with the skin lagging pronation (module docstring).

    Args:
        pos: (..., 3) m, quat: (..., 4) (w, x, y, z) the cluster on the bone; q: (..., 5) rad the
            arm's angles at the same samples; q0: (5,) rad the working posture; slip: the fraction
            of the pronation change the cluster misses (0 = none, < 1).
        kin: the arm's chain (the pronation axis passes through the elbow centre).

    Returns:
        (pos, quat) of the cluster on the skin.
    """
    if not 0.0 <= slip < 1.0:
        raise ConfigError(f"marker slip must lie in [0, 1), got {slip}")
    q = np.asarray(q, float)
    eps = 1e-6  # rad, the finite difference that finds the pronation axis in the world
    r0, _ = kin.forward(q)
    r1, _ = kin.forward(q + eps * np.eye(5)[4])
    axis = Rotation.from_matrix((r1 @ np.swapaxes(r0, -1, -2)).reshape(-1, 3, 3)).as_rotvec() / eps
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = -slip * (q[..., 4] - q0[4]).reshape(-1)
    turn = Rotation.from_rotvec(axis * angle[:, None])
    centre = kin.pose(q).elbow.reshape(-1, 3)
    p = np.asarray(pos, float).reshape(-1, 3)
    new_pos = centre + turn.apply(p - centre)
    qq = np.asarray(quat, float).reshape(-1, 4)
    rot = turn * Rotation.from_quat(qq[:, [1, 2, 3, 0]])
    xyzw = rot.as_quat()
    wxyz = xyzw[:, [3, 0, 1, 2]] * np.sign(np.sum(xyzw[:, [3, 0, 1, 2]] * qq, axis=1))[:, None]
    return new_pos.reshape(np.shape(pos)), wxyz.reshape(np.shape(quat))


def base_sensor_drift(
    force: np.ndarray, torque: np.ndarray, rate: np.ndarray, t_s: np.ndarray, t0_s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The base JR3's readings (n_trials, n, 3) N and N·m plus ``rate`` (6,) N/s, N·m/s times the
    time since its tare: ``t0_s`` (n_trials,) s at each record's start plus ``t_s`` (n,) s."""
    t = np.asarray(t0_s, float)[:, None, None] + np.asarray(t_s, float)[None, :, None]
    rate = np.asarray(rate, float)
    return force + rate[:3] * t, torque + rate[3:] * t
