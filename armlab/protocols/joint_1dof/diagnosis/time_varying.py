"""Impedance that varies with the joint's operating angle: the scan of a time-varying recording.

A time-varying recording (REKLAB's ``tv_pilot``: a position perturbation on a slow, large ankle
movement) carries the operating angle ``θ₀(t)`` about which the joint is perturbed. Two views of
whether the impedance changes with it, both in the scoring band of :mod:`.data`:

- **binned**: the samples (training and held-out) cut into :data:`N_BINS` bins of equal count by
  operating angle; in each, the nominal ``I θ̈ + B θ̇ + K θ`` fitted by least squares on the
  high-passed columns. Each parameter's constancy is tested with ``χ² = Σ (p_i − p̄)² / se_i²``
  (``p̄`` the inverse-variance mean, ``bins − 1`` degrees of freedom), the standard errors from
  the residual variance over the *effective* sample count ``n · band_share`` (the scoring band
  leaves that many independent samples, as in the core's BIC): a varying parameter is one whose
  ``χ²`` has a p-value below :data:`P_VARYING`;
- **parametric**: the time-varying nominal of :data:`~.models.JOINT_TV_FAMILY` (K and B
  quadratic in the operating angle), fitted and scored by the core's variable projection on the
  training / held-out split like every other model; its held-out gap against the stationary
  nominal's is how far the time-varying nominal shrinks the gap.

The impedance varies with the operating point when some parameter varies (binned) *and* the
time-varying nominal removes at least ``min_step_fraction`` of the stationary nominal's excess
over the noise floor (the rule every accepted effect of the diagnosis meets).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from armlab.dsp import zero_phase

__all__ = ["N_BINS", "P_VARYING", "OperatingPointScan", "scan_operating_point"]

N_BINS = 8  # bins of equal sample count over the operating angle: 8 leaves ~3000 samples each in
# REKLAB's 106 s tv_pilot at 250 Hz, enough for three parameters, while resolving a 0.6 rad range
# in steps of < 0.1 rad
P_VARYING = 1e-3  # p-value of the constancy test below which a parameter varies: three sigma,
# one-sided; eight bins and three parameters make 3 tests, so a constant joint is flagged ~0.3 %
_PARAMS = ("I", "B", "K")
_UNITS = {"I": "kg·m²", "B": "N·m·s/rad", "K": "N·m/rad"}


@dataclass(frozen=True, kw_only=True, eq=False)
class OperatingPointScan:
    """The binned view of a time-varying recording (see the module docstring).

    Attributes:
        centres_rad: (N_BINS,) rad, median operating angle of each bin.
        edges_rad: (N_BINS + 1,) rad, the bins' edges.
        values: name (``I``, ``B``, ``K``) -> (N_BINS,) fitted value per bin, torque sign folded
            so that a positive impedance is positive.
        se: name -> (N_BINS,) standard error of each value (effective sample count).
        p_constant: name -> p-value of the constancy test.
        relative_range: name -> (max − min) / |inverse-variance mean| over the bins.
    """

    centres_rad: np.ndarray
    edges_rad: np.ndarray
    values: dict[str, np.ndarray]
    se: dict[str, np.ndarray]
    p_constant: dict[str, float]
    relative_range: dict[str, float]

    @property
    def varying(self) -> list[str]:
        """The parameters whose constancy is rejected, most varying (relative range) first."""
        out = [k for k in _PARAMS if self.p_constant[k] < P_VARYING]
        return sorted(out, key=lambda k: -self.relative_range[k])

    def as_dict(self) -> dict:
        """JSON-ready form (lists of floats)."""
        return {
            "bins": N_BINS,
            "centres_rad": self.centres_rad.tolist(),
            "edges_rad": self.edges_rad.tolist(),
            "parameters": {
                k: {
                    "unit": _UNITS[k],
                    "values": self.values[k].tolist(),
                    "se": self.se[k].tolist(),
                    "p_constant": self.p_constant[k],
                    "relative_range": self.relative_range[k],
                }
                for k in _PARAMS
            },
            "varying": self.varying,
            "p_threshold": P_VARYING,
        }


def scan_operating_point(trials, y_band, hp, *, band_share: float, sign: float) -> OperatingPointScan:
    """The binned scan of time-varying trials (every trial's ``op`` set; see the module docstring).

    Args:
        trials: prepared trials with their operating angle (``op``, rad about ``op_ref``).
        y_band: their measured torque in the scoring band.
        hp: the scoring high-pass (second-order sections, applied zero-phase).
        band_share: (band width) / (Nyquist frequency) of the scoring band.
        sign: −1 where the torque is antiphase to the impedance (the diagnosis's torque sign).
    """
    cols, ys, ops = [], [], []
    for tr, y in zip(trials, y_band, strict=True):
        used = tr.train | tr.held
        cols.append(np.stack([zero_phase(hp, c) for c in (tr.a, tr.v, tr.x)], axis=1)[used])
        ys.append(y[used])
        ops.append(tr.op[used] + tr.op_ref)
    phi, y, op = np.concatenate(cols), np.concatenate(ys), np.concatenate(ops)
    edges = np.quantile(op, np.linspace(0.0, 1.0, N_BINS + 1))
    which = np.clip(np.searchsorted(edges, op, side="right") - 1, 0, N_BINS - 1)
    values = np.empty((N_BINS, 3))
    se = np.empty((N_BINS, 3))
    centres = np.empty(N_BINS)
    for i in range(N_BINS):
        m = which == i
        a, b = phi[m], y[m]
        beta, *_ = np.linalg.lstsq(a, b, rcond=None)
        n_eff = max(m.sum() * band_share, 4.0)
        # the residual's variance as if white over the effective samples (its band-limited power
        # over n_eff): with the band's columns, cov = sigma2 (a^T a)^-1 (a second factor
        # n / n_eff on the normal matrix counted the band twice: SEs 1/sqrt(band_share) too large)
        sigma2 = float(np.sum((b - a @ beta) ** 2)) / max(n_eff - 3.0, 1.0)
        cov = sigma2 * np.linalg.inv(a.T @ a)
        values[i], se[i] = sign * beta, np.sqrt(np.diag(cov))
        centres[i] = float(np.median(op[m]))
    p_const, rel = {}, {}
    for j, k in enumerate(_PARAMS):
        w = 1.0 / se[:, j] ** 2
        mean = float(np.sum(w * values[:, j]) / np.sum(w))
        chi2 = float(np.sum((values[:, j] - mean) ** 2 * w))
        p_const[k] = float(stats.chi2.sf(chi2, N_BINS - 1))
        rel[k] = float((values[:, j].max() - values[:, j].min()) / abs(mean)) if mean else float("inf")
    return OperatingPointScan(
        centres_rad=centres,
        edges_rad=edges,
        values={k: values[:, j] for j, k in enumerate(_PARAMS)},
        se={k: se[:, j] for j, k in enumerate(_PARAMS)},
        p_constant=p_const,
        relative_range=rel,
    )
