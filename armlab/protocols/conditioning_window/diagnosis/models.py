"""Candidate models of the conditioning-window protocol: Eq. (9) of the paper plus catalogue effects.

The nominal model is the paper's partially linearised arm, ``M(q, xi) qdd + (C + D) qd + K dq =
dtau_ext``, linear in ``zeta = [xi, D, K]`` (11 parameters, :func:`armlab.estimation.joint_ls.
regressor`), shared by every trial. Each effect changes it in the same three ways as the 1-DoF
joint models (:mod:`armlab.diagnosis.families`):

- **additive** columns: ``reflex`` (a delayed stretch feedback ``Kr dq(t-d) + Dr qd(t-d)``
  through a 2nd-order activation low-pass, Kr and Dr symmetric, the shape a muscle reflex
  through the moment arms takes), and
  ``joint_friction`` (Coulomb ``tanh(qd_i / v0_i)`` at each joint, band-limited like the
  measured torque);
- **intrinsic**: ``cuff_compliance`` — the arm follows the robot's hand position less the
  stretch of a series spring-damper (compliance ``c`` m/N, time constant ``b/k``) under the
  force, ``dq - c·J⁻¹ΔF/(1 + s·b/k)`` (the cuff shell's mass moves with the forearm and is
  part of the calibrated inertia);
- **output** transforms of every column: ``channel_delay`` (the force channel lags the position
  channel), ``force_sensor_bandwidth`` (2nd-order Butterworth low-pass of the force channel).

``payload_mass`` (a mass at the hand is exactly three changes of ``xi``) and ``plane_tilt``
(gravity leaking into the plane adds the symmetric gravity gradient to ``K`` at one posture)
are absorbed by the nominal calibration; they are listed and flagged, not fitted.
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from armlab.diagnosis.families import ModelFamily, NLParam, Surrogate, lowpass2, sensor_lowpass, shift_columns
from armlab.dsp import bilinear
from armlab.estimation.joint_ls import PARAM_NAMES, regressor
from armlab.estimation.processing import differentiate, lowpass_zero_phase
from armlab.protocols.conditioning_window.diagnosis.data import CHANNELS, CondSet

__all__ = [
    "COND_FAMILY",
    "COND_SURROGATES",
]


def _delayed(cs: CondSet, z: np.ndarray, delay_s: float) -> np.ndarray:
    """z(t - delay) of (m, n, ...) trials along the sample axis."""
    t = np.arange(z.shape[1]) / cs.fs_hz
    moved = np.moveaxis(z, 1, 0).reshape(z.shape[1], -1)
    return np.moveaxis(shift_columns(t, moved, delay_s).reshape(z.shape[1], z.shape[0], *z.shape[2:]), 0, 1)


def _sym_columns(a: np.ndarray) -> np.ndarray:
    """(m, n, 2) -> (m, n, 2, 3): the rows of ``S a`` for a symmetric S = [[s11, s12], [s12, s22]]."""
    out = np.zeros((*a.shape, 3))
    out[..., 0, 0] = a[..., 0]
    out[..., 0, 1] = a[..., 1]
    out[..., 1, 1] = a[..., 0]
    out[..., 1, 2] = a[..., 1]
    return out


def _spring_damper(cs: CondSet, tau_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stretch basis of a spring k in parallel with a damper b = k·tau_s: u / (1 + tau_s·s)."""
    if tau_s <= 0:
        return cs.u, cs.ud, cs.udd
    b, a = bilinear([1.0], [tau_s, 1.0], cs.fs_hz)
    u = signal.lfilter(b, a, cs.u, axis=1)
    ud, udd = differentiate(u, cs.fs_hz, axis=1)
    return u, ud, udd


def cond_columns(cs: CondSet, model: tuple[Surrogate, ...], theta: dict[str, float]) -> np.ndarray:
    """(rows, k) regressor of the composed model on the scoring rows of ``cs``."""
    names = [s.name for s in model]
    if "cuff_compliance" in names:
        c = theta["cuff_compliance.compliance_m_per_N"]
        u, ud, udd = _spring_damper(cs, theta["cuff_compliance.time_constant_s"])
        blocks = [regressor(cs.q - c * u, cs.qd - c * ud, cs.qdd - c * udd, cs.dq - c * u)]
    else:
        blocks = [cs.nominal_columns]
    if "reflex" in names:
        d = theta["reflex.delay_s"]
        fc = theta["reflex.cutoff_hz"]
        for z in (cs.dq, cs.qd):  # through a critically damped excitation-to-force low-pass
            blocks.append(_sym_columns(lowpass2(_delayed(cs, z, d), fc, 1.0, cs.fs_hz, axis=1)))
    if "joint_friction" in names:
        fr = np.zeros((*cs.qd.shape, 2))
        for j, joint in enumerate(CHANNELS):
            fr[..., j, j] = np.tanh(cs.qd[..., j] / theta[f"joint_friction.velocity_{joint}_rad_s"])
        # the measured torque is band-limited: so is the friction step it carries
        blocks.append(lowpass_zero_phase(fr, cs.fs_hz, cs.band_hz, 4, axis=1))
    phi = np.concatenate(blocks, axis=-1)  # (m, n, 2, k)
    if "channel_delay" in names:
        phi = _delayed(cs, phi, theta["channel_delay.delay_s"])
    if "force_sensor_bandwidth" in names:
        phi = sensor_lowpass(phi, theta["force_sensor_bandwidth.cutoff_hz"], cs.fs_hz, axis=1)
    return cs.rows(phi)


def cond_linear_names(model: tuple[Surrogate, ...]) -> tuple[str, ...]:
    """Names of the linear parameters, in the column order of :func:`cond_columns`."""
    names = {s.name: s for s in model}
    out = list(PARAM_NAMES)
    for key in ("reflex", "joint_friction"):  # the additive blocks' fixed order
        if key in names:
            out += [f"{key}.{n}" for n in names[key].linear]
    return tuple(out)


#: The conditioning-window candidates, by catalogue name.
COND_SURROGATES: dict[str, Surrogate] = {
    s.name: s
    for s in (
        Surrogate(
            "reflex",
            "additive",
            # s, loop latency: short-latency stretch reflex 25-50 ms, spinal 70-110 ms (paper II-B)
            (
                NLParam("delay_s", 0.01, 0.13, tuple(np.round(np.arange(0.015, 0.1201, 0.01), 3))),
                # Hz, muscle excitation-to-force low-pass (activation 10-40 ms: MuJoCo muscle defaults)
                NLParam("cutoff_hz", 1.0, 60.0, (3.0, 8.0, 20.0), log=True),
            ),
            ("Kr11", "Kr12", "Kr22", "Dr11", "Dr12", "Dr22"),
        ),
        Surrogate(
            "cuff_compliance",
            "intrinsic",
            (
                # m/N, 1/(cuff stiffness): hand-handle interfaces 1-50 kN/m (catalogue source)
                NLParam("compliance_m_per_N", 1e-6, 2e-3, (2e-5, 5e-5, 1e-4, 2e-4, 5e-4), log=True),
                # s, damping / stiffness of the cuff (soft tissue: 100 N·s/m over 2-50 kN/m)
                NLParam("time_constant_s", 1e-4, 0.05, (0.001, 0.005, 0.02), log=True),
            ),
        ),
        Surrogate(
            "joint_friction",
            "additive",
            # rad/s, the sliding velocity of each joint's Coulomb transition: a joint's own, since
            # a soft friction constraint's transition scales with the inertia the joint sees (a
            # shared one left twice the residual on the referee's friction datasets)
            tuple(
                NLParam(f"velocity_{joint}_rad_s", 1e-4, 0.3, (0.001, 0.003, 0.01, 0.03), log=True)
                for joint in CHANNELS
            ),
            ("coulomb_shoulder", "coulomb_elbow"),
        ),
        Surrogate(
            "force_sensor_bandwidth",
            "output",
            (NLParam("cutoff_hz", 5.0, 200.0, (10.0, 20.0, 40.0, 80.0, 150.0), log=True),),
        ),
        Surrogate(
            "channel_delay",
            "output",
            (NLParam("delay_s", -0.02, 0.03, tuple(np.round(np.arange(-0.01, 0.0205, 0.002), 3))),),
        ),
        Surrogate("payload_mass", "absorbed", absorbed_by="arm inertia"),
        Surrogate("plane_tilt", "absorbed", absorbed_by="arm stiffness"),
    )
}

#: How the conditioning-window models are built from the surrogates.
COND_FAMILY = ModelFamily(columns=cond_columns, linear_names=cond_linear_names)
