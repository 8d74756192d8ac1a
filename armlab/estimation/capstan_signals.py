"""From the capstan robot's recorded channels to the identification signals of Table II (seeds/003).

Sec. III-A/B: every recorded signal (encoders Θ, accelerometer, F/T force, command torque τ_r) is
smoothed by a Savitzky-Golay filter, which also gives the first derivatives, and the result is
passed through a zero-phase Butterworth low-pass (:mod:`armlab.estimation.smoothing`). Here the
Savitzky-Golay stage acts on the recorded channels, the nonlinear maps of the table below (forward
kinematics, the rotation of link-frame readings, Eqs. (7) and (2)) act on its outputs, and the
Butterworth stage acts on the signals that enter the least squares. For the linear parts this is
the paper's chain exactly; for the nonlinear ones it keeps the two sides of each regression
filtered alike (the 4.5 Hz cut-off would otherwise remove part of the 2-4 Hz products of the
0-2 Hz motion from one side only: measured 5 % on alpha2 of Table VI).

=======  ======================  ==========================  ============================
signal   Method 1 (virtual)      Method 2 (physical)         here
=======  ======================  ==========================  ============================
X        forward kinematics      forward kinematics          ``dyn.fk(theta)``
X_d      differentiation filter  differentiation filter      SG derivative of X
X_dd     accelerometer           accelerometer               R(theta2) acc_site
Θ_d      differentiation filter  —                           SG derivative of Θ
Θ_dd     Eq. (7)                 —                           ``dyn.joint_acceleration``
F_ext    Eq. (2)                 F/T sensor                  ``virtual_force`` / -R ft_site
=======  ======================  ==========================  ============================

The accelerometer and the F/T sensor read in link 2's frame, which is turned by θ2 from the base
frame (models/capstan_planar/README.md); they are rotated with the measured θ2. The F/T sensor
reads the force link 2 exerts on the handle subtree; the paper's F_ext (the hand, or fixture, on
the robot) is its negative.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from armlab.estimation.smoothing import (
    SmoothingSpec,
    differentiate,
    lowpass,
    smooth,
    smooth_and_differentiate,
)
from armlab.estimation.virtual_force import virtual_force
from armlab.models.capstan_robot import CapstanDynamics

__all__ = ["CapstanSignals", "capstan_signals", "rotate_by"]


def rotate_by(angle: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Turn planar vectors ``v`` (..., 2) by ``angle`` (...) rad (link 2's frame -> base frame)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


@dataclass(frozen=True, eq=False)
class CapstanSignals:
    """The processed signals of Table II, each ``(n_trials, n_samples, 2)`` (robot frame).

    Attributes:
        x m, x_dot m/s, x_ddot m/s²: end-effector position, velocity and acceleration.
        theta rad, theta_dot rad/s, theta_ddot rad/s²: joints (smoothed encoders, their
            derivative, Eq. (7)).
        sg: the same signals before the Butterworth stage (a regressor built from them is
            low-passed as a whole, Appendix).
        tau N·m: the smoothed command torques.
        f_virtual N: Eq. (2) with the given robot model (Method 1).
        f_sensor N: the F/T sensor, -R(theta2) ft_site (Method 2).
    """

    x: np.ndarray
    x_dot: np.ndarray
    x_ddot: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray
    theta_ddot: np.ndarray
    tau: np.ndarray
    f_virtual: np.ndarray
    f_sensor: np.ndarray
    sg: dict[str, np.ndarray]


def capstan_signals(
    channels: dict[str, np.ndarray], fs_hz: float, spec: SmoothingSpec, dyn: CapstanDynamics
) -> CapstanSignals:
    """Process measured channels ``theta``, ``tau``, ``acc_site``, ``ft_site`` (module docstring).

    Args:
        channels: name -> (n_trials, n_samples, 2) measured signal (units of
            :data:`armlab.sim.capstan_lab.CLEAN_UNITS`).
        fs_hz: sample rate, Hz.
        spec: the smoothing/differentiation filters (paper: SG N = 6, W = 151, 4.5 Hz).
        dyn: the robot model Method 1 uses (identified alphas, the robot's lengths).
    """
    sg = replace(spec, lowpass_hz=None)
    theta, theta_dot = smooth_and_differentiate(channels["theta"], fs_hz, sg, axis=-2)
    tau = smooth(channels["tau"], fs_hz, sg, axis=-2)
    x_ddot = rotate_by(theta[..., 1], smooth(channels["acc_site"], fs_hz, sg, axis=-2))
    f_sensor = -rotate_by(theta[..., 1], smooth(channels["ft_site"], fs_hz, sg, axis=-2))
    x = dyn.fk(theta)
    x_dot = differentiate(dyn.fk(channels["theta"]), fs_hz, sg, axis=-2)
    theta_ddot = dyn.joint_acceleration(theta, theta_dot, x_ddot)
    sg_stage = {
        "x": x,
        "x_dot": x_dot,
        "x_ddot": x_ddot,
        "theta": theta,
        "theta_dot": theta_dot,
        "theta_ddot": theta_ddot,
        "tau": tau,
        "f_virtual": virtual_force(dyn, theta, theta_dot, theta_ddot, tau),
        "f_sensor": f_sensor,
    }
    return CapstanSignals(**{k: lowpass(v, fs_hz, spec, axis=-2) for k, v in sg_stage.items()}, sg=sg_stage)
