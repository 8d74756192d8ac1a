"""Frequency-response identification of a real 1-DoF joint recording, with position as the input.

The machinery of protocol ``fractional_elbow`` (Welch FRF, Levy fits of seeds/004) applied to a
joint driven by a stiff position-controlled actuator with a torque sensor (the REKLAB ankle
recordings, ``armlab.data.reklab``). Two orientations of the same measurement:

- **impedance** ``Z = -torque / position`` (N·m/rad; the minus makes ``I s² + B s + K`` positive,
  see the importer's docstring): the integer model ``I s² + B s + K`` and the fractional
  ``I s² + B s^alpha + K`` (a springpot in place of the damper), ``alpha`` swept over the paper's
  grid (steps of ``frf.alpha_step``) up to 1 — a springpot lies between a spring (0) and a damper
  (1); above 1 it trades places with the inertia — and chosen by the complex MSE (the phase is
  where a fractional order shows; the magnitude alone cannot tell a springpot from a damper) among
  the fits with positive I, B and K;
- **admittance** ``Y = position / -torque`` (rad/(N·m)), the orientation of the paper's
  ``G = theta / F``: Table I's structures (27), (28), (29), A and B, the fractional ones by the
  paper's alpha sweep; the best integer (alpha = 1) and the best fractional model by MSE.

Indices MSE, MAD, R² are Eqs. (24)-(26) of seeds/004 on magnitudes (as Table I), except where
named ``*_complex``. The FIR low-pass of ``frf`` is not applied: it exists for the elbow's angle
output, and here the band of the fits (``frf.band_hz``) already excludes what it would remove.
Pure computation: the CLI writes the files.
"""

from __future__ import annotations

import numpy as np

from armlab.config.schema import FrfConfig
from armlab.errors import ConfigError, DataError, EstimationError
from armlab.estimation.frf import estimate_frf
from armlab.estimation.levy import (
    PAPER_STRUCTURES,
    LevyFit,
    LevyStructure,
    alpha_grid,
    fit_indices,
    levy_fit,
    levy_sweep,
)

__all__ = ["JOINT_BAND_HZ", "fit_joint_frf"]

# Hz, default fitting band for the ankle: the REKLAB perturbations are broadband to ~50 Hz and the
# intrinsic I s² + B s + K description holds to ~40 Hz (Kearney & Hunter 1990, ankle IRF studies)
JOINT_BAND_HZ = (0.5, 40.0)


def _impedance(f: np.ndarray, Z: np.ndarray, step: float) -> tuple[dict, dict]:
    """Integer and fractional ``I s² + B s^alpha + K`` fits of an impedance (N·m/rad)."""
    integer = levy_fit(f, Z, LevyStructure(num_powers=(0, 1, 2), den_powers=(), name="I s² + B s + K"), 1.0)
    n_unit = round(1.0 / step)
    ks = list(range(1, n_unit + 1))  # springpot orders step .. 1: between spring (0) and damper (1)
    sweep = [
        levy_fit(f, Z, LevyStructure(num_powers=(0, k, 2 * n_unit), den_powers=()), alpha=1.0 / n_unit)
        for k in ks
    ]
    mse_c = np.array([fit_indices(Z, s.response(f), on="complex").mse for s in sweep])
    # physical fits only: I, B, K > 0
    physical = np.array(
        [bool(np.all(s.model.b[[0, k, 2 * n_unit]] > 0)) for s, k in zip(sweep, ks, strict=True)]
    )
    if not physical.any():
        raise EstimationError("no fractional impedance fit has positive I, B and K; check the sign and band")
    best = int(np.argmin(np.where(physical, mse_c, np.inf)))

    def params(fit: LevyFit, k: int) -> dict:
        b = fit.model.b
        ix = fit.indices
        return {
            "I": float(b[-1]),
            "B": float(b[k]),
            "K": float(b[0]),
            "mse": ix.mse,
            "mad": ix.mad,
            "r2": ix.r2,
        }

    out = {
        "integer": {**params(integer, 1), "mse_complex": fit_indices(Z, integer.response(f), "complex").mse},
        "fractional": {
            "alpha": round(ks[best] / n_unit, 12),
            **params(sweep[best], ks[best]),
            "mse_complex": mse_c[best],
        },
        "sweep": {"orders": [round(k / n_unit, 12) for k in ks], "mse_complex": mse_c, "physical": physical},
    }
    return out, {"integer": integer.response(f), "fractional": sweep[best].response(f)}


def fit_joint_frf(
    position: np.ndarray, torque: np.ndarray, fs_hz: float, frf: FrfConfig, name: str = ""
) -> tuple[dict, dict]:
    """Impedance and admittance fits of one joint recording.

    Args:
        position: (n,) rad, joint angle (the actuator's input).
        torque: (n,) N·m, joint torque as recorded (resisting the motion: ``-torque`` is the
            impedance's output).
        fs_hz: Hz, sample rate.
        frf: Welch window, overlap, fitting band and alpha step (the FIR fields are not used).
        name: the trial's name, for the report.

    Returns:
        (results dict, series for figures: ``f_hz``, ``Z``, ``coherence``, ``Z_fits``, ``Y``,
        ``Y_fits``).
    """
    position = np.asarray(position, dtype=float)
    torque = np.asarray(torque, dtype=float)
    if position.ndim != 1 or position.shape != torque.shape:
        raise DataError(f"position and torque must be equal 1-D arrays, got {position.shape}, {torque.shape}")
    frf.check_recording(fs_hz, position.size, "recording")
    lo, hi = frf.band_hz
    response = estimate_frf(position, -torque, fs_hz, window_len=frf.welch_window, overlap=frf.welch_overlap)
    band = response.band(lo, hi)
    f, Z = band.f_hz, band.G
    if f.size < 8:
        raise ConfigError(f"frf.band_hz {list(frf.band_hz)} holds only {f.size} frequency points; widen it")
    imp, z_fits = _impedance(f, Z, frf.alpha_step)
    Y = 1.0 / Z
    fits = {}
    for key, structure in PAPER_STRUCTURES.items():
        if structure.alpha is not None:
            fits[key] = levy_fit(f, Y, structure)
        else:
            fits[key] = levy_sweep(f, Y, structure, alphas=alpha_grid(frf.alpha_step)).best
    entries = {k: v.summary() for k, v in fits.items()}
    # integer: the structures of fixed order (27, A, B); fractional: those with an alpha sweep
    integer = [k for k, st in PAPER_STRUCTURES.items() if st.alpha is not None]
    fractional = [k for k, st in PAPER_STRUCTURES.items() if st.alpha is None]
    results = {
        "name": name,
        "fs_hz": fs_hz,
        "duration_s": position.size / fs_hz,
        "band_hz": [lo, hi],
        "n_freq": int(f.size),
        "mean_coherence": float(np.mean(band.coherence)),
        "impedance": imp,
        "admittance": {
            "models": entries,
            "best_integer": min(integer, key=lambda k: entries[k]["mse"]),
            "best_fractional": min(fractional, key=lambda k: entries[k]["mse"]),
        },
    }
    series = {
        "f_hz": f,
        "Z": Z,
        "coherence": band.coherence,
        "Z_fits": z_fits,
        "Y": Y,
        "Y_fits": {k: v.response(f) for k, v in fits.items()},
    }
    return results, series
