"""Surrogate models of the ``stiffness_5dof_emg`` diagnosis: the nominal static model and the
candidate effects in this protocol's terms (rows of :mod:`.data`, all linear in their parameters).

Nominal (paper Eq. (14) with frozen activation, per pre-load condition): torque rows
``τ̃ = K_c Δq`` with ``K_c`` symmetric (15 entries per condition; the report adds the protocol's SPD
estimate of Eqs. (16)-(17) on the same training trials); displacement rows: the nominal lab's
commanded displacement less the robot servos' give (one scale); base rows: the seat's statics
(one scale).

Candidates (the catalogue keys where the catalogue has them):

- ``reflex``: a stretch reflex adds, per muscle ``i``, a torque ``−g_i r_i max(ℓ_i, 0)`` with
  ``ℓ_i = r_iᵀ Δq`` its lengthening along the nominal displacement (not the measured one: a basis
  built from a measured channel carries its noise and "explains" it) (``r_i`` the nominal arm's
  moment-arm row, m/rad, from
  :func:`armlab.sim.arm5_reflex.muscle_length_jacobian`): half-wave rectified, so the ± disturbances
  of one joint differ where a symmetric ``K_c`` cannot follow (its symmetric half ``K_c`` takes up).
  12 gains shared by the conditions (the lab's reflex law adds activation per stretch, independent
  of the pre-load);
- ``cuff_compliance``: a compliant cuff between the robot and the forearm: the limb lags the
  commanded displacement by ``J_limb⁺ [c_t Δf; c_r Δm]`` (m/N, rad/(N·m)), on the displacement rows
  (the markers are on the limb, so the torque-displacement relation is unchanged);
- ``marker_soft_tissue``: the skin under the forearm cluster slides, so the cluster (and the IK's
  pronation) turns by only ``1 - slip`` of the bone's pronation from the working posture (the lab's
  artefact, :func:`armlab.sim.arm5_lab_effects.marker_soft_tissue`). Correcting the measured
  pronation change by the gain ``g = slip / (1 - slip)`` changes every row computed from the markers
  (Δq, the wrist frame the wrist JR3 is turned by, J_limb, G(q), the base's lever arms): linear in
  ``g`` about the data (the probe rows of :func:`.data.prepare_stiff5`, a finite difference), the
  measured rows gain ``g·D_y`` and the nominal columns ``g·D_X``. So the model is
  ``y = (X + g D_X) β − c D_y`` with ``g`` (nonlinear, [0, 1]) and ``c`` (linear, ≈ g);
- ``base_sensor_drift``: the base JR3 drifts since its tare at a rate per axis (6 rates, N/s and
  N·m/s, the same over the session), on the base rows, ``rate·t`` from the pre-interval.

Torso motion and EMG cross-talk are not candidates yet (module docstring of :mod:`.diagnose`).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from armlab.diagnosis.families import ModelFamily, NLParam, Surrogate
from armlab.protocols.stiffness_5dof_emg.diagnosis.data import PROBE_GAIN, Stiff5Set

__all__ = [
    "STIFF5_SURROGATES",
    "linear_names_for",
    "moment_arms",
    "stiff5_columns",
    "stiff5_family",
]

_IU = np.triu_indices(5)


@lru_cache(maxsize=1)
def moment_arms() -> np.ndarray:
    """(12, 5) m/rad: dL/dq of the nominal arm's muscles at its working posture (models/arm_5dof)."""
    from armlab.models.arm_5dof import load_arm_5dof
    from armlab.sim.arm5_reflex import muscle_length_jacobian

    arm = load_arm_5dof()
    r = muscle_length_jacobian(arm.model, arm.muscle_act, arm.qpos, arm.q0)
    r.flags.writeable = False
    return r


def _nominal(cs: Stiff5Set) -> np.ndarray:
    """(m, nb, 16, 15 n_c + 2) columns of the nominal model."""
    m, nb, nch = cs.y.shape
    n_c = len(cs.condition_names)
    out = np.zeros((m, nb, nch, 15 * n_c + 2))
    for k, (i, j) in enumerate(zip(*_IU, strict=True)):
        col = np.zeros((m, nb, nch))
        col[:, :, i] = cs.dq[..., j]
        if i != j:
            col[:, :, j] = cs.dq[..., i]
        out[np.arange(m), :, :, 15 * cs.condition + k] = col
    out[:, :, 5:10, -2] = cs.nominal_disp
    out[:, :, 10:16, -1] = cs.nominal_base
    return out


def _reflex(cs: Stiff5Set) -> np.ndarray:
    r = moment_arms()  # (12, 5)
    stretch = np.maximum(cs.nominal_disp @ r.T, 0.0)  # (m, nb, 12), of the nominal displacement
    out = np.zeros((*cs.y.shape, r.shape[0]))
    out[:, :, :5, :] = r.T[None, None] * stretch[:, :, None, :]
    return out


def _cuff(cs: Stiff5Set) -> np.ndarray:
    pinv = np.linalg.pinv(cs.jac)  # (m, nb, 5, 6)
    out = np.zeros((*cs.y.shape, 2))
    out[:, :, 5:10, 0] = -np.einsum("...ij,...j->...i", pinv[..., :3], cs.dw[..., :3])
    out[:, :, 5:10, 1] = -np.einsum("...ij,...j->...i", pinv[..., 3:], cs.dw[..., 3:])
    return out


def _soft_tissue(cs: Stiff5Set) -> np.ndarray:
    """(m, nb, 16, 1): minus the rows' change per unit of pronation gain (probe's finite difference)."""
    return (-(cs.probe.y - cs.y) / PROBE_GAIN)[..., None]


def _drift(cs: Stiff5Set) -> np.ndarray:
    out = np.zeros((*cs.y.shape, 6))
    for k in range(6):
        out[:, :, 10 + k, k] = cs.t_rel[None, :]
    return out


_BLOCKS = {
    "reflex": _reflex,
    "cuff_compliance": _cuff,
    "marker_soft_tissue": _soft_tissue,
    "base_sensor_drift": _drift,
}


def stiff5_columns(cs: Stiff5Set, model: tuple[Surrogate, ...], theta: dict[str, float]) -> np.ndarray:
    """(rows, k) whitened regressor of the composed model on the rows of ``cs``; ``theta`` holds
    the one nonlinear parameter, ``marker_soft_tissue.pronation_gain``."""
    nominal = _nominal(cs)
    if any(s.name == "marker_soft_tissue" for s in model):  # the K columns of the corrected Δq
        gain = theta["marker_soft_tissue.pronation_gain"]
        nominal = nominal + (gain / PROBE_GAIN) * (_nominal(cs.probe) - nominal)
    blocks = [nominal] + [_BLOCKS[s.name](cs) for s in model]
    return cs.rows(np.concatenate(blocks, axis=-1))


def linear_names_for(cs: Stiff5Set, model: tuple[Surrogate, ...]) -> tuple[str, ...]:
    """Names of the linear parameters of ``model`` on ``cs`` (column order of :func:`stiff5_columns`)."""
    out = [f"K[{name}].{i + 1}{j + 1}" for name in cs.condition_names for i, j in zip(*_IU, strict=True)]
    out += ["displacement.nominal_scale", "base.nominal_scale"]
    for s in model:
        out += [f"{s.name}.{p}" for p in s.linear]
    return tuple(out)


#: The candidates, by name (``reflex``, ``cuff_compliance`` are catalogue keys; the others are this
#: protocol's own).
STIFF5_SURROGATES: dict[str, Surrogate] = {
    s.name: s
    for s in (
        Surrogate("reflex", "additive", (), tuple(f"gain_{i}" for i in range(12))),
        Surrogate("cuff_compliance", "additive", (), ("translational_m_per_N", "rotational_rad_per_Nm")),
        Surrogate(
            "marker_soft_tissue",
            "additive",
            (NLParam("pronation_gain", 0.0, 1.0, (0.02, 0.1, 0.4)),),
            ("rows_gain",),
        ),
        Surrogate(
            "base_sensor_drift",
            "additive",
            (),
            ("fx_N_per_s", "fy_N_per_s", "fz_N_per_s", "mx_Nm_per_s", "my_Nm_per_s", "mz_Nm_per_s"),
        ),
    )
}


def stiff5_family(cs: Stiff5Set) -> ModelFamily:
    """How the models are built from the surrogates on ``cs`` (the names depend on its conditions)."""
    return ModelFamily(columns=stiff5_columns, linear_names=lambda model: linear_names_for(cs, model))
