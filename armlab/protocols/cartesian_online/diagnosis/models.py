"""Candidate models of ``cartesian_online``: the thesis's field (Eq. 3.4.1, D = δ√K) plus effects.

The nominal model is the thesis's (Eqs. 2.2.1-2.2.4, 3.4.1): per axis ``a``,

    F_a = K_a(q)·p_a + δ_a √K_a(q)·v_a,    K_a(q) = b(q)ᵀk_a,  b = [1, x, y, x², 2xy, y²],

fitted by the protocol's own 12 + 2 estimator (:func:`armlab.estimation.sqrt_damping_fit.
fit_sqrt_damping_field`) on the training sequences (:mod:`.data`). So that the effects can be
added by variable projection (:mod:`armlab.diagnosis.families`), the family refits it linearly:
the six ``k``'s of each axis on ``b(q)·p_a`` (the basis in positions scaled about the stops'
centroid, which spans the same quadratics and is well conditioned) and ``δ_a`` on ``√K̂₀_a(q)·v_a``,
the damping profile of the nominal fit. At the nominal fit this is the same model; with an effect
the stiffness and the damping's scale are re-calibrated, its shape held (its change is second
order: damping is ~5 % of the force on the thesis's triangles).

Each effect changes it in the thesis's own terms:

- ``payload_mass`` (hand inertia, which the thesis neglects, Ch. 3): ``+ m·a_a``, one mass ``m``
  (kg) for both axes, the measured acceleration;
- ``force_sensor_drift`` (F/T bias and drift): ``+ b_a + d_a·t`` per axis (N, N/s);
- ``non_quadratic_field``: the field to third order, ``+ c(q)ᵀh_a·p_a`` with ``c`` the four cubic
  monomials ``u³, u²v, uv², v³`` of the scaled position (8 parameters);
- ``cuff_compliance`` (intrinsic): the hand is the measured cuff position less the stretch of a
  series spring-damper, ``q - c·s``, ``s`` the nominal field's force at the measured states
  (:attr:`~.data.CartSet.u`) through ``1/(1 + τs)`` (``c`` m/N, ``τ`` = damping/stiffness s).
  The damping term keeps the measured (cuff) velocity: correcting it by the stretch's rate, whose
  basis steps at the triangle's corners, explained 0.3-0.4 of the gap of three tuning datasets
  (seed 7, 21-62 kN/m cuffs) where the position correction alone explains 0.83-1.05 and finds
  the cuff stiffness within 7 %;
- ``channel_delay`` (output): the force recorded ``d`` s after the position, every column
  delayed; a delay of the hand's reaction looks the same in these channels.

White force-sensor noise is not a candidate: it is the noise floor (:mod:`.data`).
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from armlab.diagnosis.families import ModelFamily, NLParam, Surrogate, shift_columns
from armlab.dsp import bilinear
from armlab.models.cartesian_field import quadratic_basis
from armlab.protocols.cartesian_online.diagnosis.data import AXES, CartSet

__all__ = [
    "CART_FAMILY",
    "CART_SURROGATES",
    "cart_columns",
    "cubic_basis",
]

_K_FLOOR = 1e-9  # N/m, √K at max(K, floor): a refit's profile stays finite where K̂₀ would cross 0
_ADDITIVE = ("payload_mass", "force_sensor_drift", "non_quadratic_field")  # fixed column order


def cubic_basis(w: np.ndarray) -> np.ndarray:
    """(..., 2) scaled positions -> (..., 4): ``u³, u²v, uv², v³``."""
    u, v = w[..., 0], w[..., 1]
    return np.stack([u**3, u * u * v, u * v * v, v**3], axis=-1)


def _per_axis(cols: np.ndarray, signal_: np.ndarray) -> np.ndarray:
    """(m, n, k) columns times (m, n, 2) signal -> (m, n, 2, 2k), axis a's rows in block a."""
    m, n, k = cols.shape
    out = np.zeros((m, n, 2, 2 * k))
    for j in range(2):
        out[:, :, j, j * k : (j + 1) * k] = cols * signal_[..., j, None]
    return out


def _stretch(cs: CartSet, tau_s: float) -> np.ndarray:
    """Stretch per unit compliance (N) of a spring with a damper in parallel."""
    s = cs.u
    if tau_s > 0:
        b, a = bilinear([1.0], [tau_s, 1.0], cs.fs_hz)
        zi = signal.lfilter_zi(b, a)[0] * s[:, :1, :]  # at rest on the first value
        s = signal.lfilter(b, a, s, axis=1, zi=zi)[0]
    return s


def _delayed(cs: CartSet, z: np.ndarray, delay_s: float) -> np.ndarray:
    """z(t - delay) of (m, n, ...) trials along the sample axis (held before the start)."""
    t = np.arange(z.shape[1]) / cs.fs_hz
    moved = np.moveaxis(z, 1, 0).reshape(z.shape[1], -1)
    return np.moveaxis(shift_columns(t, moved, delay_s).reshape(z.shape[1], z.shape[0], *z.shape[2:]), 0, 1)


def cart_columns(cs: CartSet, model: tuple[Surrogate, ...], theta: dict[str, float]) -> np.ndarray:
    """(rows, k) band-limited regressor of the composed model on the scoring rows of ``cs``."""
    names = [s.name for s in model]
    q, p, v = cs.q, cs.p, cs.v
    if "cuff_compliance" in names:
        c = theta["cuff_compliance.compliance_m_per_N"]
        s = _stretch(cs, theta["cuff_compliance.time_constant_s"])
        q, p = q - c * s, p - c * s  # the damping stays on the cuff's velocity (module docstring)
    w = (q - cs.centre) / cs.radius
    root = np.sqrt(np.maximum(quadratic_basis(q) @ cs.k0.T, _K_FLOOR))  # (m, n, 2) √K̂₀(q)
    nominal = np.zeros((*q.shape[:2], 2, 14))
    b = quadratic_basis(w)
    for j in range(2):
        nominal[:, :, j, 7 * j : 7 * j + 6] = b * p[..., j, None]
        nominal[:, :, j, 7 * j + 6] = root[..., j] * v[..., j]
    blocks = [nominal]
    if "payload_mass" in names:
        blocks.append(cs.a[..., None])
    if "force_sensor_drift" in names:
        ones = np.ones((*q.shape[:2], 2, 1))
        t = cs.t[..., None, None] * ones
        drift = np.concatenate([ones, t], axis=-1)  # (m, n, 2, 2): per axis [1, t]
        blocks.append(
            np.concatenate([drift * (np.arange(2) == j)[None, None, :, None] for j in range(2)], axis=-1)
        )
    if "non_quadratic_field" in names:
        blocks.append(_per_axis(cubic_basis(w), p))
    phi = np.concatenate(blocks, axis=-1)
    if "channel_delay" in names:
        phi = _delayed(cs, phi, theta["channel_delay.delay_s"])
    return cs.rows(cs.band(phi))


def cart_linear_names(model: tuple[Surrogate, ...]) -> tuple[str, ...]:
    """Names of the linear parameters, in the column order of :func:`cart_columns`."""
    names = {s.name for s in model}
    out = [f"{a}.{k}" for a in AXES for k in ("k0", "k1", "k2", "k3", "k4", "k5", "delta")]
    if "payload_mass" in names:
        out.append("payload_mass.mass_kg")
    if "force_sensor_drift" in names:
        out += [f"force_sensor_drift.{a}_{k}" for a in AXES for k in ("bias_N", "drift_N_per_s")]
    if "non_quadratic_field" in names:
        out += [f"non_quadratic_field.{a}_h{i}" for a in AXES for i in range(4)]
    return tuple(out)


#: The cartesian_online candidates, by name (catalogue keys, and this protocol's own
#: ``non_quadratic_field``).
CART_SURROGATES: dict[str, Surrogate] = {
    s.name: s
    for s in (
        Surrogate("payload_mass", "additive", (), ("mass_kg",)),
        Surrogate(
            "force_sensor_drift",
            "additive",
            (),
            ("x_bias_N", "x_drift_N_per_s", "y_bias_N", "y_drift_N_per_s"),
        ),
        Surrogate("non_quadratic_field", "additive", (), tuple(f"h{i}" for i in range(8))),
        Surrogate(
            "cuff_compliance",
            "intrinsic",
            (
                # m/N, 1/(cuff stiffness): hand-handle interfaces 1-50 kN/m (catalogue CuffCompliance)
                # and stiffer mounts up to 1 MN/m
                NLParam("compliance_m_per_N", 1e-6, 1e-3, (1e-5, 3e-5, 1e-4, 3e-4), log=True),
                # s, damping / stiffness of the cuff (soft tissue: ~100 N·s/m over 2-50 kN/m)
                NLParam("time_constant_s", 1e-4, 0.1, (0.002, 0.01, 0.04), log=True),
            ),
        ),
        Surrogate(
            "channel_delay",
            "output",
            # s, F/T behind the encoders: 1-20 ms skew (catalogue ChannelDelay); negative: ahead
            (NLParam("delay_s", -0.01, 0.03, tuple(np.round(np.arange(-0.006, 0.0241, 0.003), 3))),),
        ),
    )
}

#: How the cartesian_online models are built from the surrogates.
CART_FAMILY = ModelFamily(columns=cart_columns, linear_names=cart_linear_names)
