"""The five experiments of paper 002 (thesis Ch. 3) at level A, as trials, and back to records.

:func:`simulate_cartesian` generates every *case* with the config's settings:

=====================  =====================================================================
case                   what (thesis §, spec 002)
=====================  =====================================================================
``exp1_triangular``    Exp. 1: Table 3.3 path, 20 alternating x / y triangles (§3.1)
``exp1_trapezoidal``   the same with the trapezoid (§3.1.1: "almost identical")
``exp2``               circle, 20 sequences (+x, −y, (+x, −y)), per-sequence LS (§3.2)
``exp3``               sinusoid in x, 20 x-triangles, cumulative LS (§3.3)
``exp4``               circle, 20 sequences, cumulative LS of the quadratic field (§3.4)
``exp4_noise``         Exp. 4 again with ``simulation.noise_study_std_N`` of force noise
                       (spec 002 check 6; left out when that is 0)
``exp5``               spiral 100 % → 10 %, 20 sequences, Cartesian and polar per sequence (§3.5)
=====================  =====================================================================

The thesis logs only during perturbations (§3.2.2), so **one trial is one perturbation**: its
logged samples (400 for the triangle at 1 kHz, 350 for the trapezoid, padded to the longest by
holding the last sample; ``trial_meta['n_logged']`` says how many are real). Channels (2 axes, x
and y of the thesis's frame of Tables 3.1/3.3, whose origin is also the polar origin):

- ``hand_pos`` m: ``q_h = q_r + q_p`` (Eq. 3.1.1); ``hand_vel`` m/s: ``q̇_h`` (ideal, §3.1.2);
- ``hand_force`` N: the robot's force on the hand, ``D(q_h) q̇_h + K(q_h) q_p`` plus noise;
- ``ref_pos`` m: the (stopped) reference ``q_r``; ``pert_pos`` m: the displacement ``q_p``;
- ``true_hand_force`` N: without noise; ``true_stiffness`` N/m: ``K_xx, K_yy`` at ``q_h``.

:func:`records_from_trials` turns the trials of one case back into the
:class:`~armlab.sim.cartesian_level_a.CartesianRecord` the pure identifications take (the same
arrays, bit for bit, as the generator's logged samples), so estimation reads the trial file only.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from armlab.data.trial import TrialSet
from armlab.errors import DataError
from armlab.models.cartesian_field import THESIS_FIELD, QuadraticImpedanceField
from armlab.perturbations.cartesian_timeline import StopTimeline, experiment_timeline
from armlab.perturbations.ramp_waveforms import ramp_waveform
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig
from armlab.sim.cartesian_level_a import CartesianRecord, simulate_level_a

__all__ = [
    "CASES",
    "CHANNEL_UNITS",
    "CartesianRecording",
    "case_trials",
    "field_from_attrs",
    "records_from_trials",
    "simulate_cartesian",
]

#: case -> (thesis experiment, waveform), in the order they are generated
CASES: dict[str, tuple[int, str]] = {
    "exp1_triangular": (1, "triangular"),
    "exp1_trapezoidal": (1, "trapezoidal"),
    "exp2": (2, "triangular"),
    "exp3": (3, "triangular"),
    "exp4": (4, "triangular"),
    "exp4_noise": (4, "triangular"),
    "exp5": (5, "triangular"),
}
CHANNEL_UNITS = {
    "hand_pos": "m",
    "hand_vel": "m/s",
    "hand_force": "N",
    "ref_pos": "m",
    "pert_pos": "m",
    "true_hand_force": "N",
    "true_stiffness": "N/m",
}


@dataclass(frozen=True, eq=False)
class CartesianRecording:
    """What :func:`simulate_cartesian` produced.

    Attributes:
        trials: one trial per perturbation of every case (module docstring).
        records: case -> the generator's full record (whole timeline, moving parts included).
        field: the true impedance field (Tables 3.1/3.2 times ``stiffness_scale``).
    """

    trials: TrialSet
    records: dict[str, CartesianRecord]
    field: QuadraticImpedanceField


def _timeline(cfg: CartesianOnlineConfig, experiment: int, shape: str) -> StopTimeline:
    s = cfg.simulation
    return experiment_timeline(
        experiment,
        shape=shape,
        corner_s=s.corner_s,
        n_stops=s.n_stops,
        pause_s=s.pause_s,
        fs=cfg.sensors.fs_hz,
        sinusoid_omega_rad_s=s.sinusoid_omega_rad_s,
        spiral_end_fraction=s.spiral_end_fraction,
    )


def case_trials(
    case: str, rec: CartesianRecord, n_max: int, kind: tuple[int, str] | None = None
) -> tuple[dict, dict]:
    """Per-perturbation arrays of one record: channels (m, n_max, k) and trial_meta (m,).

    ``kind``: the (experiment, waveform) of the case (default :data:`CASES`'s entry); any record
    with ``timeline``, ``force``, ``force_clean``, ``stiffness_true()`` and ``noise_std_n`` will do
    (level C's :class:`~armlab.sim.cartesian_level_c.LevelCRecord`).
    """
    tl = rec.timeline
    m = len(tl.directions)
    idx = np.flatnonzero(tl.perturbation >= 0)
    starts = idx[np.r_[True, np.diff(tl.perturbation[idx]) != 0]]
    n_logged = np.bincount(tl.perturbation[idx], minlength=m)
    # sample j of perturbation i: its start + min(j, n_i - 1) (the padding holds the last sample)
    take = starts[:, None] + np.minimum(np.arange(n_max)[None, :], n_logged[:, None] - 1)
    channels = {
        "hand_pos": tl.q_h[take],
        "hand_vel": tl.qd_h[take],
        "hand_force": rec.force[take],
        "ref_pos": tl.q_r[take],
        "pert_pos": tl.q_p[take],
        "true_hand_force": rec.force_clean[take],
        "true_stiffness": rec.stiffness_true()[take],
    }
    experiment, shape = kind or CASES[case]
    stop = tl.perturbation_stop
    meta = {
        "case": np.full(m, case),
        "experiment": np.full(m, experiment),
        "waveform": np.full(m, shape),
        "perturbation": np.arange(m),
        "stop": stop,
        "direction_x": tl.directions[:, 0],
        "direction_y": tl.directions[:, 1],
        "stop_x": tl.stop_position[stop, 0],
        "stop_y": tl.stop_position[stop, 1],
        "path_time_s": tl.s[starts],
        "t_start_s": tl.t[starts],
        "n_logged": n_logged,
        "noise_std_N": np.full(m, rec.noise_std_n),
    }
    return channels, meta


def _noise(cfg: CartesianOnlineConfig, case: str) -> float:
    return cfg.simulation.noise_study_std_N if case == "exp4_noise" else cfg.simulation.force_noise_std_N


def simulate_cartesian(cfg: CartesianOnlineConfig) -> CartesianRecording:
    """Generate every case (module docstring) at level A with the config's settings and seed.

    Noise is drawn from ``numpy.random.default_rng(cfg.seed)``, one spawned child per case, so a
    case's noise does not depend on which other cases carry noise.
    """
    s = cfg.simulation
    field = THESIS_FIELD.scaled(s.stiffness_scale)
    cases = [c for c in CASES if c != "exp4_noise" or s.noise_study_std_N > 0]
    rngs = dict(zip(CASES, np.random.default_rng(cfg.seed).spawn(len(CASES)), strict=True))
    records = {}
    for case in cases:
        experiment, shape = CASES[case]
        noise = _noise(cfg, case)
        records[case] = simulate_level_a(
            _timeline(cfg, experiment, shape),
            field,
            noise_std_n=noise,
            rng=rngs[case] if noise > 0 else None,
            sigma=s.sigma,
        )
    n_max = max(int(np.bincount(r.timeline.perturbation[r.logged]).max()) for r in records.values())
    parts = [case_trials(case, rec, n_max) for case, rec in records.items()]
    channels = {k: np.concatenate([p[0][k] for p in parts]) for k in CHANNEL_UNITS}
    meta = {k: np.concatenate([p[1][k] for p in parts]) for k in parts[0][1]}
    truth = {
        "coefficients": [list(map(float, row)) for row in field.coefficients],
        "k_sigma": list(map(float, field.k_sigma)),
        "delta": list(map(float, field.delta)),
        "stiffness_scale": float(field.stiffness_scale),
        "sigma": float(s.sigma),
    }
    trials = TrialSet(
        fs_hz=cfg.sensors.fs_hz,
        # the perturbation starts at the first logged sample (q_p = 0 there); sample 1 is the first
        # the hand has moved
        onset_index=np.ones(len(meta["case"]), dtype=int),
        channels=channels,
        units=dict(CHANNEL_UNITS),
        trial_meta=meta,
        attrs={
            "protocol": cfg.protocol_name,
            "seed": cfg.seed,
            "level": "A",  # this generator's trials; level B replaces them (level_b.py)
            "corner_s": s.corner_s,
            "truth_json": json.dumps(truth),
        },
    )
    return CartesianRecording(trials=trials, records=records, field=field)


def field_from_attrs(attrs) -> tuple[QuadraticImpedanceField, float]:
    """The true field and σ stored in a trial file's ``attrs['truth_json']``."""
    if "truth_json" not in attrs:
        raise DataError(
            "the trials lack attrs['truth_json']; they were not made by the cartesian_online protocol"
        )
    t = json.loads(str(attrs["truth_json"]))
    field = QuadraticImpedanceField(
        coefficients=tuple(tuple(r) for r in t["coefficients"]),
        k_sigma=tuple(t["k_sigma"]),
        delta=tuple(t["delta"]),
        stiffness_scale=t["stiffness_scale"],
    )
    return field, float(t["sigma"])


def records_from_trials(trials: TrialSet, force_channel: str = "hand_force") -> dict[str, CartesianRecord]:
    """Rebuild each case's logged record from the trials (module docstring), for the identifications.

    Args:
        trials: a trial set of this protocol (simulated, or read back from ``trials.h5``).
        force_channel: ``hand_force`` (measured) or ``true_hand_force`` (without noise).

    Returns:
        case -> a :class:`CartesianRecord` holding only the logged samples, in time order.

    Raises:
        DataError: if a channel or trial_meta key of this protocol is missing.
    """
    need = (
        "case",
        "waveform",
        "perturbation",
        "stop",
        "direction_x",
        "direction_y",
        "stop_x",
        "stop_y",
        "n_logged",
        "path_time_s",
    )
    missing = [k for k in need if k not in trials.trial_meta]
    missing += [k for k in ("hand_vel", "ref_pos", "pert_pos", force_channel) if k not in trials.channels]
    if missing:
        raise DataError(f"the trials lack {missing}; they were not made by the cartesian_online protocol")
    field, sigma = field_from_attrs(trials.attrs)
    meta = {k: np.asarray(v) for k, v in trials.trial_meta.items()}
    corner = float(trials.attrs.get("corner_s", 0.0))
    out = {}
    for case in dict.fromkeys(str(c) for c in meta["case"]):
        rows = np.flatnonzero(meta["case"] == case)
        rows = rows[np.argsort(meta["perturbation"][rows], kind="stable")]
        n = meta["n_logged"][rows]
        keep = np.arange(trials.n_samples)[None, :] < n[:, None]  # (m, n_samples) real samples

        def cat(name: str, rows=rows, keep=keep) -> np.ndarray:
            return np.asarray(trials.channels[name])[rows][keep]

        q_r, q_p, qd_h, force = cat("ref_pos"), cat("pert_pos"), cat("hand_vel"), cat(force_channel)
        pert = np.repeat(np.arange(len(rows)), n)
        stop_of = meta["stop"][rows]
        n_stops = int(stop_of.max()) + 1
        stop_position = np.full((n_stops, 2), np.nan)  # m; NaN at a stop without trials
        stop_position[stop_of] = np.stack([meta["stop_x"][rows], meta["stop_y"][rows]], axis=1)
        within = np.arange(trials.n_samples)[None, :].repeat(len(rows), 0)[keep]
        # wall time as the generator samples it: (sample index) / fs
        first = np.round(meta["t_start_s"][rows] * trials.fs_hz) if "t_start_s" in meta else 0.0
        t = (np.repeat(first, n) + within) / trials.fs_hz
        zeros = np.zeros_like(q_r)
        # the reference is stopped while logging (q̇_r = 0), so q̇_h = q̇_p exactly
        timeline = StopTimeline(
            fs=float(trials.fs_hz),
            t=t,
            s=np.repeat(meta["path_time_s"][rows], n),
            q_r=q_r,
            qd_r=zeros,
            q_p=q_p,
            qd_p=qd_h,
            perturbation=pert,
            stop=np.repeat(stop_of, n),
            directions=np.stack([meta["direction_x"][rows], meta["direction_y"][rows]], axis=1),
            perturbation_stop=stop_of,
            stop_position=stop_position,
            waveform=ramp_waveform(str(meta["waveform"][rows[0]]), corner),
        )
        out[case] = CartesianRecord(
            timeline=timeline,
            field=field,
            sigma=sigma,
            force_clean=cat("true_hand_force") if "true_hand_force" in trials.channels else force,
            force=force,
            noise_std_n=float(meta["noise_std_N"][rows[0]]) if "noise_std_N" in meta else 0.0,
        )
    return out
