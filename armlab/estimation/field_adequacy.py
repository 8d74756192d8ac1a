"""Is a diagonal quadratic or a polar impedance model adequate for a musculoskeletal arm? (paper 002)

Level C of ``cartesian_online`` records the thesis's perturbation sequences on a Hill arm whose
Cartesian impedance is full and posture dependent. Three global models of the field are fitted by
least squares (:func:`~armlab.estimation.online_ls.ls_fit`) to the sequences of a training set and
judged by the variance of the force they account for on held-out sequences:

- ``diagonal_quadratic``: the thesis's Eq. 3.4.1 per axis, ``F_a = K_aa(q_h)·a_p + D_ax ẋ + D_ay ẏ``
  with ``K_aa`` quadratic in the hand's position (8 parameters per axis);
- ``polar``: the thesis's polar model (§2.2.2, Eqs. 2.2.12-2.2.15) made global: the radial force
  and the moment about the polar origin, ``(F_ρ, M) = K_pol(ρ, θ)·(ρ_p, θ_p) + D_pol(ρ, θ)·(ρ̇,
  θ̇)``, each of the eight entries a separable polynomial in ``(ρ, θ)`` of the orders the thesis
  reports (§3.5.2: diagonal (1, 1), anti-diagonal (1, 2); 28 parameters), mapped back to a
  Cartesian force ``F = F_ρ e_ρ + (M/ρ) e_θ`` for the score;
- ``full_quadratic``: a reference with every Cartesian entry quadratic
  (:func:`~armlab.estimation.cartesian_regressors.full_quadratic_regressor`, 14 per axis): it
  tells whether a diagonal model's deficit is the missing coupling or the quadratic form.

VAF (variance accounted for) ``= 100·(1 − var(F − F̂)/var(F))`` per axis, %
(:func:`~armlab.estimation.virtual_force.vaf`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.errors import DataError
from armlab.estimation.cartesian_regressors import full_quadratic_regressor, quadratic_field_regressor
from armlab.estimation.online_ls import ls_fit
from armlab.estimation.polar import polar_signals, to_polar
from armlab.estimation.virtual_force import vaf

__all__ = [
    "ADEQUACY_MODELS",
    "POLAR_ORDERS",
    "ModelFit",
    "fit_field_models",
    "polar_field_regressor",
]

#: the models compared (module docstring)
ADEQUACY_MODELS = ("diagonal_quadratic", "polar", "full_quadratic")
#: §3.5.2's orders of the polar model's entries in (ρ, θ): rows (F_ρ, M), columns (ρ_p, θ_p) for
#: K and (ρ̇, θ̇) for D; "at least second order in θ" for the anti-diagonal is taken as 2
POLAR_ORDERS = {"11": (1, 1), "12": (1, 2), "21": (1, 2), "22": (1, 1)}


def _monomials(u: np.ndarray, v: np.ndarray, order: tuple[int, int]) -> np.ndarray:
    """(n, 1 + a + b): ``1, u…u^a, v…v^b`` (separable, no cross terms: §3.5.2's counting)."""
    cols = [np.ones_like(u)] + [u**i for i in range(1, order[0] + 1)] + [v**j for j in range(1, order[1] + 1)]
    return np.stack(cols, axis=1)


def polar_field_regressor(
    q_pol: np.ndarray, q_p: np.ndarray, qd: np.ndarray, row: int, centre: np.ndarray
) -> np.ndarray:
    """Rows of the global polar model for the output ``row`` (0: F_ρ, 1: M).

    Args:
        q_pol: (n, 2) hand ``(ρ m, θ rad)``; q_p: (n, 2) ``(ρ_p, θ_p)``; qd: (n, 2) ``(ρ̇, θ̇)``
            (:func:`~armlab.estimation.polar.polar_signals`).
        row: 0 or 1.
        centre: (2,) the ``(ρ, θ)`` the polynomials are centred on (conditioning only).

    Returns:
        (n, p): ``K_r1(ρ, θ)·ρ_p, K_r2(ρ, θ)·θ_p, D_r1(ρ, θ)·ρ̇, D_r2(ρ, θ)·θ̇`` with each entry's
        monomials of :data:`POLAR_ORDERS`.
    """
    u, v = q_pol[:, 0] - centre[0], q_pol[:, 1] - centre[1]
    cols = []
    for signal in (q_p, qd):
        for col in (0, 1):
            basis = _monomials(u, v, POLAR_ORDERS[f"{row + 1}{col + 1}"])
            cols.append(basis * signal[:, col : col + 1])
    return np.concatenate(cols, axis=1)


@dataclass(frozen=True, kw_only=True, eq=False)
class ModelFit:
    """One model fitted on the training samples and scored on the held-out ones.

    Attributes:
        model: one of :data:`ADEQUACY_MODELS`.
        n_parameters: parameters over both outputs.
        vaf_train_pct, vaf_held_out_pct: (2,) %, per Cartesian axis (x, y).
        predicted: (n_held_out, 2) N, the held-out Cartesian force predicted.
        theta: the two outputs' parameter vectors.
    """

    model: str
    n_parameters: int
    vaf_train_pct: np.ndarray
    vaf_held_out_pct: np.ndarray
    predicted: np.ndarray
    theta: tuple[np.ndarray, np.ndarray]


def _cartesian(model: str, q_h, q_p, qd_h) -> tuple[np.ndarray, np.ndarray]:
    regressor = quadratic_field_regressor if model == "diagonal_quadratic" else full_quadratic_regressor
    return regressor(q_h, q_p, qd_h, 0)[0], regressor(q_h, q_p, qd_h, 1)[0]


def fit_field_models(
    q_h: np.ndarray,
    q_r: np.ndarray,
    qd_h: np.ndarray,
    force: np.ndarray,
    train: np.ndarray,
    *,
    origin: tuple[float, float] = (0.0, 0.0),
) -> dict[str, ModelFit]:
    """Fit each of :data:`ADEQUACY_MODELS` on ``train`` and score it on the other samples.

    Args:
        q_h, q_r: (n, 2) m, hand and (stopped) reference positions; qd_h: (n, 2) m/s; force:
            (n, 2) N, the robot's force on the hand (logged samples only).
        train: (n,) bool, the training samples (whole sequences: the rest is held out).
        origin: (2,) m, the polar model's origin.

    Returns:
        model -> :class:`ModelFit`.

    Raises:
        DataError: mismatched shapes, or an empty training or held-out set.
    """
    q_h, q_r, qd_h, force = (np.asarray(a, float) for a in (q_h, q_r, qd_h, force))
    train = np.asarray(train, bool)
    if not (q_h.shape == q_r.shape == qd_h.shape == force.shape == (len(train), 2)):
        raise DataError("q_h, q_r, qd_h and force must be (n, 2) and train (n,)")
    test = ~train
    if not train.any() or not test.any():
        raise DataError("fit_field_models needs training and held-out samples")
    out = {}
    for model in ADEQUACY_MODELS:
        if model == "polar":
            sig = polar_signals(q_h, q_r, qd_h, force, origin)
            centre = sig.q_pol[train].mean(axis=0)
            phis = [polar_field_regressor(sig.q_pol, sig.q_p, sig.qd, r, centre) for r in (0, 1)]
            fits = [ls_fit(phi[train], sig.force[train, r]) for r, phi in enumerate(phis)]
            pol = np.stack([phi @ f.theta for phi, f in zip(phis, fits, strict=True)], axis=1)
            theta = to_polar(q_h, origin)[:, 1]
            e_rho = np.stack([np.cos(theta), np.sin(theta)], axis=1)
            e_theta = np.stack([-np.sin(theta), np.cos(theta)], axis=1)
            pred = pol[:, :1] * e_rho + (pol[:, 1:] / sig.q_pol[:, :1]) * e_theta  # Eqs. 2.2.14-15 inverted
        else:
            phis = _cartesian(model, q_h, q_h - q_r, qd_h)
            fits = [ls_fit(phi[train], force[train, a]) for a, phi in enumerate(phis)]
            pred = np.stack([phi @ f.theta for phi, f in zip(phis, fits, strict=True)], axis=1)
        out[model] = ModelFit(
            model=model,
            n_parameters=sum(len(f.theta) for f in fits),
            vaf_train_pct=vaf(force[train], pred[train]),
            vaf_held_out_pct=vaf(force[test], pred[test]),
            predicted=pred[test],
            theta=(fits[0].theta, fits[1].theta),
        )
    return out
