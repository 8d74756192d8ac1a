"""Candidate models of the 1-DoF joint protocol: the nominal joint plus catalogue effects.

The nominal simulation of a position-imposed joint is its inverse dynamics, linear in the
parameters: ``torque = I·θ̈ + B·θ̇ + K·θ`` (the offset is removed by the scoring high-pass).
Each catalogue effect changes that model in one of three ways, written here in the same
linear-in-parameters form as the MuJoCo model of :mod:`armlab.sim.joint_rig` (checked against
it in the tests):

- **additive** columns (``reflex``, ``joint_friction``, ``cocontraction_variation``,
  ``voluntary_torque``; the last two also from leave-block-out local estimates of the nominal's
  residual, :mod:`.local`: a stiffness that drifts without the tonic torque showing it, a slow
  voluntary torque);
- **intrinsic** replacement of ``[θ̈, θ̇, θ]`` by a series-compliance response
  (``cuff_compliance``: the pedal's own inertia stays rigid on the sensor side;
  ``transmission_compliance``: everything beyond the spring; :mod:`.compliance`);
- **output** transforms of every column (``channel_delay``, ``force_sensor_bandwidth``);
- **position** errors: ``[θ̈, θ̇, θ]`` of the recorded angle through a Wiener smoother
  (``encoder_quantisation`` on a recording whose angle lies on a grid, ``position_sensor_noise``
  on one that does not; :mod:`.position_sensor`, which also gives the floor they leave).

``payload_mass`` changes nothing the nominal calibration does not already absorb (the joint's
inertia is calibrated): it is listed but cannot be identified from these trials.

Fitting is the core's variable projection (:func:`armlab.diagnosis.families.fit_model`) with
:data:`JOINT_FAMILY`.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from armlab.diagnosis.families import (
    ModelFamily,
    NLParam,
    Surrogate,
    lowpass2,
    sensor_response,
    shift_columns,
)
from armlab.protocols.joint_1dof.diagnosis.compliance import (
    COMPLIANCE_PARAMS,
    compliance_torque,
    start_compliance,
)
from armlab.protocols.joint_1dof.diagnosis.data import PreparedTrial
from armlab.protocols.joint_1dof.diagnosis.local import local_gains, local_level
from armlab.protocols.joint_1dof.diagnosis.position_sensor import (
    GRID_EFFECT,
    GRID_LEVELS,
    NOISE_EFFECT,
    denoised_columns,
)

__all__ = [
    "ANY_RATE_HZ",
    "JOINT_FAMILY",
    "JOINT_SURROGATES",
    "JOINT_TV_FAMILY",
    "OP_LINEAR_NAMES",
]


FRICTION_COULOMB = 0.0  # joint_friction.form: tanh(v / velocity), relaxing at rest (_friction)
FRICTION_DAHL = 1.0  # joint_friction.form: Dahl's presliding, held at rest (_dahl)
_COULOMB, _DAHL = ("form", FRICTION_COULOMB), ("form", FRICTION_DAHL)


def _friction(v: np.ndarray, velocity: float, release_s: float, fs: float) -> np.ndarray:
    """Coulomb friction, ``tanh(v / velocity)`` while sliding, relaxing with ``release_s`` at rest.

    The friction force follows the sliding direction while the joint moves and, once it stops,
    the static (pre-sliding) force left in the contact decays with time constant ``release_s``
    rather than vanishing at once: ``f[k] = s[k]`` if ``|s[k]| > decay·|f[k-1]|`` else
    ``decay·f[k-1]``, ``s = tanh(v / velocity)``. ``release_s`` → 0 is the plain smoothed
    Coulomb law.
    """
    s = np.tanh(v / velocity)
    # The recursion keeps, at sample k, the earlier s[j] with the largest |s[j]|·decay^(k-j):
    # a running argmax of log|s[j]| + j/(release_s·fs), then that sample decayed to k.
    rate = 1.0 / (release_s * fs)
    k = np.arange(s.size)
    with np.errstate(divide="ignore"):
        score = np.log(np.abs(s)) + k * rate
    best = np.maximum.accumulate(score)
    j = np.maximum.accumulate(np.where(score >= best, k, 0))
    out = s[j] * np.exp(-(k - j) * rate)
    out[~np.isfinite(best)] = 0.0  # nothing has moved yet
    return out


def _dahl(v: np.ndarray, presliding_rad: float, fs: float) -> np.ndarray:
    """Dahl's presliding friction, normalised to ±1: ``ds/dx = (sgn(dx) - s) / presliding_rad``.

    Rate-independent (Dahl 1968; Olsson et al. 1998, Eur. J. Control 4:176, Sec. 3.3): after each
    reversal the force builds over a few ``presliding_rad`` of travel towards the sliding level,
    and it is held while the joint rests (the bristles stay deflected), where the smoothed Coulomb
    law of :func:`_friction` follows the velocity. Exact for a direction constant within each
    sample: over a travel ``|dx|``, ``s`` moves towards ``sgn(dx)`` by ``1 - exp(-|dx| / x_p)``;
    ``v`` is read as the velocity at each sample's instant, so ``s`` at sample ``k`` has covered
    the path up to the middle of that sample's travel (``t_k``, not half a sample later).
    The recursion runs over the runs of one direction (one scalar step per reversal), then every
    sample is filled from its run's start at once.
    """
    dx = v / fs
    d = np.sign(dx)
    moving = np.flatnonzero(d)
    if moving.size == 0:
        return np.zeros_like(dx)
    # a rest keeps the last direction (nothing moves, so nothing changes there either)
    d = d[moving[np.maximum(np.searchsorted(moving, np.arange(d.size), side="right") - 1, 0)]]
    travel = np.r_[0.0, np.cumsum(np.abs(dx))]  # rad of path before each sample, then after it
    starts = np.r_[0, np.flatnonzero(np.diff(d)) + 1]
    decay = np.exp(-np.diff(travel[np.r_[starts, d.size]]) / presliding_rad).tolist()
    s0 = [0.0] * starts.size  # s at each run's start
    for k, (dk, ek) in enumerate(zip(d[starts[:-1]].tolist(), decay[:-1], strict=True)):
        s0[k + 1] = dk - (dk - s0[k]) * ek
    run = np.repeat(np.arange(starts.size), np.diff(np.r_[starts, d.size]))
    # the velocity v[k] is the sample's own (a central difference), its travel v[k]/fs spans
    # t_k ± 1/(2 fs): s(t_k) has covered half of it (the whole of it is s half a sample later)
    at_k = travel[1:] - 0.5 * np.abs(dx)
    return d - (d - np.asarray(s0)[run]) * np.exp(-(at_k - travel[starts][run]) / presliding_rad)


@lru_cache(maxsize=64)  # 6 trials x the delays in flight (the grid's 23, a few refinements)
def _delayed_velocity(tr: PreparedTrial, delay_s: float) -> np.ndarray:
    """The trial's velocity delayed by ``delay_s`` (a spectral shift), remembered (read-only): the
    reflex's grid repeats each delay for every cut-off, direction and damping (16 columns), and the
    shift was most of the search's time on the REKLAB folder."""
    out = shift_columns(tr.t_s, tr.v, delay_s)
    out.flags.writeable = False
    return out


@lru_cache(maxsize=192)  # 6 trials x 3 effects x a few parameter sets in flight (~150 kB each)
def _effect_column(tr: PreparedTrial, name: str, values: tuple[float, ...]) -> np.ndarray:
    """One effect's regressor column(s) of one trial, remembered (read-only).

    A search moves one effect's parameters at a time (the grid of the newest effect, one finite
    difference per parameter): the other effects' columns repeat, and they are the costly part of
    an evaluation (a spectral shift, a raw-rate filter and decimation). ``tr`` is compared by
    identity (prepared trials are frozen).
    """
    if name == "reflex":
        d, s, cutoff, zeta = values
        stretch = np.maximum(s * _delayed_velocity(tr, d), 0.0)
        out = s * lowpass2(stretch, cutoff, zeta, tr.fs_hz)
    elif name == "joint_friction":
        form, velocity, release_s, presliding = values
        if form == FRICTION_DAHL:
            raw = _dahl(tr.v_raw, presliding, tr.raw_fs_hz)
        else:
            raw = _friction(tr.v_raw, velocity, release_s, tr.raw_fs_hz)
        out = tr.to_fit_rate(raw)
    elif name == "local":
        out = _local_columns(tr)
    else:  # a compliance: (tau2, tau1, ratio, zeta)
        out = compliance_torque(tr, *values)
    out.flags.writeable = False
    return out


def _local_columns(tr: PreparedTrial) -> np.ndarray:
    """(n, 3) ``[ΔK(t)·θ, ΔB(t)·θ̇, slow level(t)]`` of the nominal's residual (:mod:`.local`).

    The residual is that of ``I·θ̈ + B·θ̇ + K·θ + c`` and the tonic level's terms ``m·θ``, ``m·θ̇``
    fitted on the trial's training part (so the local gains are the change ``m(t)`` does not
    reveal, and the candidate's slopes on ``m`` keep their meaning); every
    sample's local estimates come from the other fold's samples (training and held-out alike: the
    held-out sample itself never enters them), so the columns predict the held-out part from its
    neighbours, and their linear gains are fitted on the training part.
    """
    basis = np.stack([tr.a, tr.v, tr.x, np.ones_like(tr.x), tr.m * tr.x, tr.m * tr.v], axis=1)
    beta, *_ = np.linalg.lstsq(basis[tr.train], tr.y[tr.train], rcond=None)
    r = tr.y - basis @ beta
    dk, db = local_gains(r, tr.x, tr.v, tr.fs_hz)
    local = np.stack([dk * tr.x, db * tr.v, local_level(r, tr.fs_hz)], axis=1)
    # less their projection on that basis over the training part: the nominal's and m(t)'s
    # parameters then keep the values they take without these columns
    coef, *_ = np.linalg.lstsq(basis[tr.train], local[tr.train], rcond=None)
    return local - basis @ coef


def _columns(
    tr: PreparedTrial, model: tuple[Surrogate, ...], theta: dict[str, float], op: bool = False
) -> np.ndarray:
    """(n, k) regressor of one trial for the composed model; ``op``: with the time-varying
    nominal's columns (:data:`OP_LINEAR_NAMES`, the trial's operating angle ``tr.op``)."""
    names = [s.name for s in model]
    cols: list[np.ndarray]
    if "cuff_compliance" in names or "transmission_compliance" in names:
        key = "cuff_compliance" if "cuff_compliance" in names else "transmission_compliance"
        values = (
            theta[f"{key}.tau2_s2"],
            theta[f"{key}.tau1_s"],
            theta[f"{key}.ratio"],
            theta[f"{key}.damping_ratio"],
        )
        h = _effect_column(tr, "compliance", values)
        cols = [h, tr.a] if key == "cuff_compliance" else [h]
    elif GRID_EFFECT in names or NOISE_EFFECT in names:  # the de-noised angle's [θ̈, θ̇, θ]
        if GRID_EFFECT in names:
            d = denoised_columns(tr, GRID_EFFECT, theta[f"{GRID_EFFECT}.level"])
        else:
            d = denoised_columns(tr, NOISE_EFFECT)
        cols = [d[:, 0], d[:, 1], d[:, 2]]
    else:
        cols = [tr.a, tr.v, tr.x]
    if "reflex" in names:
        values = (
            theta["reflex.delay_s"],
            theta["reflex.direction"],
            theta["reflex.cutoff_hz"],
            theta["reflex.damping_ratio"],
        )
        cols.append(_effect_column(tr, "reflex", values))
    if "joint_friction" in names:
        values = tuple(
            theta[f"joint_friction.{k}"] for k in ("form", "velocity_rad_s", "release_s", "presliding_rad")
        )
        cols.append(_effect_column(tr, "joint_friction", values))
    if "cocontraction_variation" in names:
        local = _effect_column(tr, "local", ())
        cols += [tr.m * tr.x, tr.m * tr.v, local[:, 0], local[:, 1]]
    if "voluntary_torque" in names:
        cols.append(_effect_column(tr, "local", ())[:, 2])
    if op:  # K and B as quadratics of the operating angle, before the output transforms
        p = tr.op
        cols += [p * tr.x, p * tr.v, p * p * tr.x, p * p * tr.v]
    phi = np.stack(cols, axis=1)
    if "channel_delay" in names:
        phi = shift_columns(tr.t_s, phi, theta["channel_delay.delay_s"])
    if "force_sensor_bandwidth" in names:
        fsb = "force_sensor_bandwidth"
        phi = sensor_response(phi, theta[f"{fsb}.natural_hz"], theta[f"{fsb}.damping_ratio"], tr.fs_hz)
    return phi


#: The joint_1dof candidates, by catalogue name.
JOINT_SURROGATES: dict[str, Surrogate] = {
    s.name: s
    for s in (
        Surrogate(
            "reflex",
            "additive",
            (
                NLParam("delay_s", 0.005, 0.15, tuple(np.round(np.arange(0.01, 0.121, 0.005), 3))),
                NLParam("cutoff_hz", 0.5, 25.0, (1.5, 3.0, 6.0, 12.0), log=True),
                NLParam("direction", -1.0, 1.0, (1.0, -1.0), discrete=True),
                # the low-pass's damping, a choice of two shapes: 0.7 (the catalogue's and the MuJoCo
                # rig's reflex) or 1 (two equal first-order lags: activation then contraction,
                # Zajac 1989 Crit. Rev. Biomed. Eng. 17:359; the ODE referee's chain); decided on
                # that referee's reflex physics (tests/test_joint_models.py: with 0.7 alone, its
                # 45 ms latency came out at 33-35 ms), checked on the real ankle
                NLParam("damping_ratio", 0.7, 1.0, (0.7, 1.0), discrete=True),
            ),
            ("gain",),
        ),
        # the compliances replace I, B, K of each trial by a gain and I/K, B/K shared by the trials:
        # fewer free parameters than the nominal (with 4 trials: the cuff 1, the transmission 5), a
        # restriction of the nominal that is not the effect; counted as what they add: the spring's
        # ratio and damping, and for the cuff the split of the inertia between the pedal (rigid, on
        # the sensor's side) and the limb
        Surrogate("cuff_compliance", "intrinsic", COMPLIANCE_PARAMS, ("pedal_inertia",), counts_as=3),
        Surrogate("transmission_compliance", "intrinsic", COMPLIANCE_PARAMS, counts_as=2),
        Surrogate(
            "joint_friction",
            "additive",
            (
                # the law's form: 0 a Coulomb force smoothed in velocity, its held force relaxing at
                # rest (the MuJoCo rig's constraint friction); 1 Dahl's presliding, smoothed in
                # displacement and held at rest (a LuGre-type contact: the ODE referee's friction,
                # whose held force under smoothed steps the first form could not keep)
                NLParam("form", 0.0, 1.0, (FRICTION_COULOMB, FRICTION_DAHL), discrete=True),
                NLParam("velocity_rad_s", 1e-3, 0.5, (0.003, 0.01, 0.03), log=True, active_when=_COULOMB),
                NLParam("release_s", 0.002, 0.3, (0.004, 0.02, 0.05, 0.1), log=True, active_when=_COULOMB),
                # rad: a presliding travel of 0.03-3 mrad (an assumption, a decade either side of the
                # grid's middle; the ODE referee draws 0.2-1 mrad)
                NLParam("presliding_rad", 3e-5, 3e-3, (1e-4, 3e-4, 1e-3), log=True, active_when=_DAHL),
            ),
            ("coulomb",),
        ),
        # the torque sensor's own dynamics, a continuous 2nd-order response (not a digital filter at
        # the fitting rate, whose cut-off stops below its Nyquist frequency): strain-gauge sensors
        # and their electronics reach from tens of Hz to kHz, and their damping is not always a
        # Butterworth's 0.707 (a lightly damped load cell rings; an over-damped stage lags)
        Surrogate(
            "force_sensor_bandwidth",
            "output",
            (
                # Hz: up to 100 kHz, a lag 2ζ/w of a few µs (above a few hundred Hz only the lag
                # is seen in band: the response's f² gain term is an inertia the nominal takes up)
                NLParam("natural_hz", 2.0, 1e5, tuple(5.0 * 2.0**j for j in range(14)), log=True),
                NLParam("damping_ratio", 0.3, 1.5, (0.707,), log=True),
            ),
        ),
        Surrogate(
            "channel_delay",
            "output",
            (NLParam("delay_s", -0.03, 0.06, tuple(np.round(np.arange(-0.02, 0.0405, 0.002), 3))),),
        ),
        # the tonic torque's covariate m(t), and the local stiffness/damping change that m(t) does
        # not reveal (co-contraction: agonist and antagonist rise together, the net torque stays)
        Surrogate(
            "cocontraction_variation",
            "additive",
            (),
            ("stiffness_slope", "damping_slope", "local_stiffness_gain", "local_damping_gain"),
        ),
        # a slow torque the position does not predict, from its neighbours' level (:mod:`.local`)
        Surrogate("voluntary_torque", "additive", (), ("gain",)),
        # the recorded angle's own error, on a grid or white (:mod:`.position_sensor`)
        Surrogate(GRID_EFFECT, "position", (NLParam("level", *GRID_LEVELS, log=True),)),
        Surrogate(NOISE_EFFECT, "position"),
        # a torque-sensor bias drift: below the scoring band, scored there by :mod:`.low_band`
        # (a slow cosine basis of time), never by the in-band selection
        Surrogate("force_sensor_drift", "low_band"),
        Surrogate("payload_mass", "absorbed"),
    )
}


#: Frequencies applied as an exact continuous frequency response, not by a digital filter at the
#: fitting rate: they may lie at or above its Nyquist frequency.
ANY_RATE_HZ = frozenset({"force_sensor_bandwidth.natural_hz"})


def _linear_names(model: tuple[Surrogate, ...], op: bool = False) -> tuple[str, ...]:
    names = [s.name for s in model]
    if "cuff_compliance" in names:
        base = ["compliance.gain", "cuff_compliance.pedal_inertia"]
    elif "transmission_compliance" in names:
        base = ["compliance.gain"]
    else:
        base = ["I", "B", "K"]
    for s in model:
        if s.kind == "additive":
            base += [f"{s.name}.{n}" for n in s.linear]
    if op:
        base += OP_LINEAR_NAMES
    return tuple(base)


#: The 1-DoF joint protocol's model family.
JOINT_FAMILY = ModelFamily(columns=_columns, linear_names=_linear_names, start=start_compliance)

#: The linear parameters a time-varying recording's nominal adds: K(p) = K + k1 p + k2 p² and
#: B(p) = B + b1 p + b2 p², p the operating angle less its mean (rad), in N·m/rad per rad^j and
#: N·m·s/rad per rad^j (the catalogue's ``operating_point_impedance``; torque sign as recorded).
OP_LINEAR_NAMES = (
    "operating_point.stiffness_slope",
    "operating_point.damping_slope",
    "operating_point.stiffness_curvature",
    "operating_point.damping_curvature",
)

#: The same family for time-varying recordings: every model, the nominal first, has stiffness and
#: damping that vary with the operating angle (:mod:`.time_varying`).
JOINT_TV_FAMILY = ModelFamily(
    columns=lambda tr, model, theta: _columns(tr, model, theta, op=True),
    linear_names=lambda model: _linear_names(model, op=True),
    start=start_compliance,
)
