"""The floor that derivative estimation itself leaves under the joint_1dof nominal.

The nominal ``τ = I·θ̈ + B·θ̇ + K·θ`` is a statement about continuous signals; the diagnosis
evaluates it on velocity and acceleration estimated from the sampled angle by five-point central
differences (:func:`armlab.dsp.five_point_derivatives`). Whoever produced the torque (a simulator,
a lab's model, the physics itself) did not necessarily differentiate that way, so even a perfect
nominal leaves a residual of the order of the spread between derivative estimators. When the
sensor noise is very low (1e-4 of the torque's rms) that spread, not the noise, sets the
smallest gap a correct model can reach, and a clean recording would otherwise be called
``unknown``.

:func:`derivative_floor` measures it on each recording: the torque the nominal would predict
with the plainest common estimator, central differences applied twice (``numpy.gradient``, as
MATLAB's ``gradient``: truncation error ``h²/6·θ‴`` of the velocity, ``h²/3·θ⁗`` of the
acceleration), less the same nominal with the diagnosis' five-point derivatives, passed through
the diagnosis' own band-limiting, decimation and scoring high-pass; the nominal's columns are then
fitted to that difference on the training part (a perfect model absorbs what its own parameters
can), and what is left over the held-out part is the *spread*. The nominal's I and B are those of
a least-squares fit of the measured torque on the training part.

The floor is the spread only as far as the recording shows it: the held-out residual of the
nominal fitted with the five-point derivatives less that of the nominal fitted with an
alternative's, when positive (the torque was produced with a convention closer to the latter),
and never more than the spread. Every estimate shares the diagnosis' own end samples
(:func:`_own_ends`): only the interior conventions are compared. A recording whose torque follows
the continuous derivatives (a physical joint, an ODE) favours the five-point estimates over the
two-point ones; against the seven-point ones it shows only the five-point stencil's own
truncation (measured 13.5 % of a 1e-4 noise floor at 500 Hz, nothing at 1 kHz:
``tests/test_joint_none.py``), so the floor lowers no effect's detectability there beyond what
the diagnosis' own estimator leaves. A torque computed by a two-point convention gets the
spread, which no effect of the catalogue needs to explain.

It is a floor of the *model's evaluation*, not of the sensor, so it is reported beside the
noise floor (``gap.derivative_floor``) and added to it wherever the acceptance rules read the
floor. On recordings whose noise is above ~1e-3 of the torque's rms it is negligible (the REKLAB
ankle trials: below 1e-3 of the noise floor).
"""

from __future__ import annotations

import numpy as np

from armlab.dsp import five_point_derivatives, zero_phase
from armlab.protocols.joint_1dof.diagnosis.data import EDGE_SAMPLES, PreparedTrial, derivatives

__all__ = ["derivative_floor"]


def _two_point_difference(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """(velocity, acceleration) by central differences applied twice (``numpy.gradient``)."""
    v = np.gradient(x, 1.0 / fs, edge_order=2)
    return v, np.gradient(v, 1.0 / fs, edge_order=2)


# sixth-order central stencils (Fornberg 1988, Math. Comp. 51:699, Table 1), oldest sample first
_SEVEN_V = np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0
_SEVEN_A = np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0


def _seven_point(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """(velocity, acceleration) by seven-point central differences (truncation ``O(h⁶)``); the
    three samples at each end keep the five-point values."""
    v, a = five_point_derivatives(x, fs, axis=0)
    v[3:-3] = np.correlate(x, _SEVEN_V, mode="valid") * fs
    a[3:-3] = np.correlate(x, _SEVEN_A, mode="valid") * fs * fs
    return v, a


#: The other estimators a torque may have been computed with: the plainest common one and a
#: more accurate one than the diagnosis' own (the continuous derivative's closest neighbour).
_ALTERNATIVES = (_two_point_difference, _seven_point)


def _own_ends(
    v: np.ndarray, a: np.ndarray, v_own: np.ndarray, a_own: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(v, a)`` with the first and last :data:`~.data.EDGE_SAMPLES` samples of the diagnosis' own
    estimates: the floor compares the interior conventions, whose difference a torque's producer
    may carry throughout; the end samples' stencils are an artefact of the record's cut, amplified
    by fs² (one-sided coefficients up to 214/12), which the measured torque does not share and the
    filters' tails carry ~2 s into the scored part. Compared with stencils of their own there, the
    end samples of an angle on an encoder's grid ruled a floor 500 times the sensor noise's on
    one trial (ODE referee, tuning seed 7, encoder replicate 6) and hid the grid's error."""
    v, a = v.copy(), a.copy()
    e = EDGE_SAMPLES
    v[:e], a[:e], v[-e:], a[-e:] = v_own[:e], a_own[:e], v_own[-e:], a_own[-e:]
    return v, a


def derivative_floor(prepared: tuple[PreparedTrial, ...], hp: np.ndarray, y_band) -> float:
    """N·m² summed over every trial's held-out samples: the scoring-band residual that the
    choice of derivative estimator alone leaves under the nominal (module docstring).

    Divide by the held-out measured power (sum of squares) for the floor as a gap fraction.

    Args:
        prepared: the prepared trials (:func:`.data.prepare_trials`; their raw angle ``x_raw``).
        hp: second-order sections of the scoring high-pass at the fitting rate.
        y_band: per trial, the measured torque in the scoring band (``zero_phase(hp, tr.y)``).
    """
    total = 0.0
    for tr, y in zip(prepared, y_band, strict=True):
        fs, xr = tr.raw_fs_hz, tr.x_raw
        ones = np.ones_like(tr.x)
        phi = zero_phase(hp, np.stack([tr.a, tr.v, tr.x, ones], axis=1), axis=0)
        beta, left5 = _held_out_fit(phi, y, tr)
        floor = 0.0
        v_own, a_own = derivatives(xr, fs)
        for estimator in _ALTERNATIVES:
            v2, a2 = _own_ends(*estimator(xr, fs), v_own, a_own)
            phi2 = zero_phase(
                hp, np.stack([tr.to_fit_rate(a2), tr.to_fit_rate(v2), tr.x, ones], axis=1), axis=0
            )
            left2 = _held_out_fit(phi2, y, tr)[1]
            # the estimators' difference in the nominal's prediction, less what the nominal absorbs
            spread = _held_out_fit(phi, (phi2[:, :2] - phi[:, :2]) @ beta[:2], tr)[1]
            # a floor only where the data favour the other estimator, and never above the spread
            floor = max(floor, min(spread, max(left5 - left2, 0.0)))
        total += floor
    return total


def _held_out_fit(phi: np.ndarray, y: np.ndarray, tr: PreparedTrial) -> tuple[np.ndarray, float]:
    """(coefficients fitted on the training part, residual sum of squares on the held-out part)."""
    beta, *_ = np.linalg.lstsq(phi[tr.train], y[tr.train], rcond=None)
    return beta, float(np.sum((y - phi @ beta)[tr.held] ** 2))
