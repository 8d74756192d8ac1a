"""The series-compliance surrogates of the 1-DoF joint diagnosis: a damped spring in series.

``cuff_compliance`` (the pedal's inertia rigid on the sensor's side) and
``transmission_compliance`` (everything beyond the spring) share the torque of a joint
``Z' = tau2·s² + tau1·s + 1`` (per unit K) behind a damped spring of stiffness ratio ``ratio``,
their nonlinear parameters and the start of ``tau2``, ``tau1`` from the nominal fit;
:mod:`.models` composes them with the other candidates.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from armlab.diagnosis.families import NLParam, padded_length
from armlab.protocols.joint_1dof.diagnosis.data import PreparedTrial

__all__ = ["COMPLIANCE_PARAMS", "compliance_torque", "start_compliance"]

#: s, the recorded angle's end values held on both sides before the compliance's spectral filter
#: (the interface mode rings for ~1/(ζ·ω) <= 0.1 s at ζ >= 0.003 and 500 Hz: it stays in the pad)
_PAD_S = 0.25


def compliance_torque(tr: PreparedTrial, tau2: float, tau1: float, ratio: float, zeta: float) -> np.ndarray:
    """Torque (per unit K) of a joint Z' = tau2·s² + tau1·s + 1 behind a damped series spring.

    The spring is ``S = ratio·(1 + tc·s)``: a real interface dissipates (soft tissue and a strap, a
    cable and its pulleys), sized by the damping ratio ``zeta`` of the mode it makes with what lies
    beyond it, ``tc = c/k = 2·zeta·sqrt(I/k) = 2·zeta·sqrt(tau2/ratio)``. The torque
    ``S·Z'/(Z' + S)`` is written ``Z' − Z'²/(Z' + S)``: the joint's own ``Z'`` from the trial's
    derivative columns (those of the nominal, so a stiff spring nests the nominal exactly) less the
    spring's correction, which is computed in the frequency domain at the recorded rate (exact at
    every frequency of the record), then band-limited and decimated like the torque.

    A time-domain discretisation misplaces that correction: the interface mode lies near or
    above the recorded rate's Nyquist frequency (a 90 kN·m/rad cable on a 0.03 kg·m² ankle rings
    at 275 Hz, recorded at 500-2000 Hz), where a bilinear map warps it by tens of percent; its
    error then matched the in-band correction itself, and a transmission fitted that way lost
    to the cuff (whose extra inertia column soaks up the error) on the ODE referee's datasets.
    """
    tc = 2.0 * zeta * np.sqrt(tau2 / ratio)
    pad, s, spectrum = _padded_angle_spectrum(tr)
    zp = (tau2 * s + tau1) * s + 1.0
    n = tr.x_raw.size
    correction = np.fft.irfft(zp * zp / (zp + ratio * (1.0 + tc * s)) * spectrum, padded_length(n, pad))
    return tau2 * tr.a + tau1 * tr.v + tr.x - tr.to_fit_rate(correction[pad : pad + n])


@lru_cache(maxsize=16)  # a fit's trials (6 in the REKLAB folder), each fit evaluates them ~10² times
def _padded_angle_spectrum(tr: PreparedTrial) -> tuple[int, np.ndarray, np.ndarray]:
    """(pad, s = 2πj·f, rfft) of the recorded angle padded with its end values: the same for every
    evaluation of a compliance on the trial (a third of its cost on 60 s at 1 kHz)."""
    x = tr.x_raw
    pad = int(_PAD_S * tr.raw_fs_hz) + 8
    z = np.concatenate([np.full(pad, x[0]), x, np.full(padded_length(x.size, pad) - x.size - pad, x[-1])])
    s = 2j * np.pi * np.fft.rfftfreq(z.size, 1.0 / tr.raw_fs_hz)
    spectrum = np.fft.rfft(z)
    s.flags.writeable = False
    spectrum.flags.writeable = False
    return pad, s, spectrum


def _ratio_grid() -> tuple[float, ...]:
    # factor 2 up to 512, then factor 4: above, the spring's share of the band's torque is small
    # and changes slowly with the ratio (the refinement takes it from there)
    return (1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 2048.0, 8192.0, 32768.0)


#: The nonlinear parameters both compliances fit (``tau2_s2`` and ``tau1_s`` started by
#: :func:`start_compliance`, ``ratio`` from its grid, ``damping_ratio`` refined from 0.05).
COMPLIANCE_PARAMS = (
    # I/K and B/K, s² and s, started from the nominal fit. Their upper bounds must hold a relaxed
    # elbow: K down to ~5 N·m/rad (Bennett et al. 1992) behind forearm, hand and handle of up to
    # ~0.1 kg·m² is I/K ~0.02 s² (a 1.1 Hz joint) and B/K up to ~0.2 s; the bounds leave 5x and
    # 2.5x (a 0.5 Hz joint). At 1e-2 s² and 0.2 s they cut such an elbow off: the transmission,
    # whose inertia is all beyond the spring, then fitted worse than the nominal it nests
    # (an ODE referee elbow at I/K = 0.0165 s²; the cuff's free pedal inertia had hidden it)
    NLParam("tau2_s2", 1e-6, 0.1, (), log=True),
    NLParam("tau1_s", 1e-4, 0.5, (), log=True),
    # interface or cable stiffness / K: cuffs 1.5-50 kN·m/rad and capstan cables 8-150 kN·m/rad
    # (the first referee's ranges) over ankle K of 50-200 N·m/rad reach a few thousand, over a
    # relaxed elbow's 5-40 N·m/rad (Bennett et al. 1992) 30 000
    NLParam("ratio", 0.2, 1.0e5, _ratio_grid(), log=True),
    # the interface mode's damping ratio: light structures (cables, couplings) ~0.02-0.1, soft
    # tissue under a cuff or strap ~0.1-0.3 (the grip's 178 N·s/m on 15 kN/m at ~1.5 kg of hand
    # and forearm, de Vlugt et al. 2003, is 0.6); started at 0.05 and refined
    NLParam("damping_ratio", 0.003, 1.0, (), log=True),
)


_START_ZETA = 0.05  # 1, the compliance's starting damping ratio (light structure; refined from there)


def start_compliance(theta, name, base_beta):
    """Start ``tau2``, ``tau1`` (I/K, B/K) from the nominal fit's mean parameters, the damping at
    :data:`_START_ZETA`; values already in ``theta`` are kept."""
    i, b, k = (np.mean([bb[j] for bb in base_beta]) for j in range(3))
    if k == 0 or not np.isfinite(k):
        k = 1.0
    theta.setdefault(f"{name}.tau2_s2", float(np.clip(abs(i / k), 2e-6, 0.05)))
    theta.setdefault(f"{name}.tau1_s", float(np.clip(abs(b / k), 2e-4, 0.25)))
    theta.setdefault(f"{name}.damping_ratio", _START_ZETA)
