"""A diagnosed joint model scored the way the REKLAB lab scores its own (the peer's figures).

The source lab's parallel-cascade identification (``shared/data/README.md``) is fitted on 0-40 s
of a trial and scored on 40-60 s, with the signals decimated to 100 Hz, over the whole band that
rate carries (no high-pass). :func:`peer_vaf` scores one of the diagnosis' fitted models the same
way: the model's structure and nonlinear parameters (delays, cut-offs) are kept, its linear
parameters and a constant offset are refitted by least squares on the first ``fit_s`` seconds of
its unfiltered columns at 100 Hz, and the variance accounted for is computed over the rest.

Remaining pre-processing differences from the peer (stated, not corrected):

- the signals are band-limited by the diagnosis' own zero-phase 4th-order Butterworth at
  ``band_hz`` (40 Hz) and decimated 1 kHz -> 250 Hz -> 100 Hz (:func:`scipy.signal.resample_poly`),
  where the lab decimates 1 kHz -> 100 Hz with its own anti-alias filter (MATLAB ``decimate``:
  an 8th-order Chebyshev at 0.8 of the new Nyquist, i.e. 40 Hz as well);
- velocity and acceleration are five-point differences at 1 kHz (the lab's intrinsic IRF needs
  none: it is a ±40 ms two-sided filter of the position);
- the columns that the diagnosis builds from the measured torque (the tonic level ``m(t)`` and the
  leave-block-out local estimates of :mod:`.local`) are kept: a model with them predicts part of
  the torque from the torque's own neighbouring samples, which the lab's input-output model does
  not; :func:`peer_vaf` with ``position_only=True`` drops them, for the like-for-like figure.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy import signal

from armlab.diagnosis.families import FittedModel
from armlab.errors import DataError
from armlab.protocols.joint_1dof.diagnosis.data import PreparedTrial
from armlab.protocols.joint_1dof.diagnosis.models import JOINT_FAMILY, JOINT_SURROGATES

__all__ = ["PEER_FIT_S", "PEER_FS_HZ", "TORQUE_COVARIATE_EFFECTS", "peer_vaf"]

PEER_FS_HZ = 100.0  # Hz, the lab's scoring rate (shared/data/README.md)
PEER_FIT_S = 40.0  # s, the lab's fitting part (0-40 s; scored on the rest, 40-60 s)
#: Effects whose columns are built from the measured torque, not the position (dropped with
#: ``position_only``).
TORQUE_COVARIATE_EFFECTS = ("cocontraction_variation", "voluntary_torque")


def peer_vaf(
    trial: PreparedTrial, model: FittedModel, *, fit_s: float = PEER_FIT_S, position_only: bool = False
) -> float:
    """Held-out VAF (%) of ``model`` on ``trial`` scored as the peer is (module docstring).

    Args:
        trial: the prepared trial the model was diagnosed on (a stationary one).
        model: one of its fitted stages (nominal or with effects).
        fit_s: s, the fitting part from the start; the rest is scored.
        position_only: drop the effects of :data:`TORQUE_COVARIATE_EFFECTS` first.

    Raises:
        DataError: a trial too short to leave both parts, or one with an operating angle.
    """
    if trial.op is not None:
        raise DataError(
            f"trial {trial.name!r} has an operating angle; the peer's figures are for stationary trials"
        )
    effects = [e for e in model.effects if not (position_only and e in TORQUE_COVARIATE_EFFECTS)]
    surrogates = tuple(JOINT_SURROGATES[e] for e in effects)
    phi = JOINT_FAMILY.columns(trial, surrogates, model.theta)
    ratio = Fraction(PEER_FS_HZ / trial.fs_hz).limit_denominator(1000)
    z = signal.resample_poly(np.column_stack([trial.y, phi]), ratio.numerator, ratio.denominator, axis=0)
    y, phi = z[:, 0], np.column_stack([z[:, 1:], np.ones(z.shape[0])])
    t = np.arange(y.size) / PEER_FS_HZ
    fit = t < fit_s
    if fit.sum() < 10 * phi.shape[1] or (~fit).sum() < 10:
        raise DataError(
            f"trial {trial.name!r} lasts {t[-1]:.1f} s: scoring as the peer needs {fit_s:g} s to fit and "
            "some seconds after them to score"
        )
    beta, *_ = np.linalg.lstsq(phi[fit], y[fit], rcond=None)
    e = y[~fit] - phi[~fit] @ beta
    return float(100.0 * (1.0 - np.var(e) / np.var(y[~fit])))
