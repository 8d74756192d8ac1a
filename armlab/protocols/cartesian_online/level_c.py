"""Level C of ``cartesian_online``: is the thesis's diagonal quadratic or its polar model adequate
for a Hill arm?

:func:`simulate_level_c_trials` plays the thesis's Exp. 4 sequences (+x, −y, (+x, −y); 20 stops;
the triangle) on a circle of the thesis's radius 0.45 m ahead of the shoulder of the conditioning
lab's planar Hill arm (:mod:`armlab.models.hill_arm_field`, :mod:`armlab.sim.cartesian_level_c`),
one trial per perturbation with level A's channels plus ``true_stiffness`` = the arm's full
Cartesian K at the stop (``(xx, xy, yx, yy)``, N/m).

:func:`estimate_level_c` fits the thesis's diagonal quadratic (Eq. 3.4.1), its polar model
(§2.2.2 with §3.5.2's orders, polar origin at the shoulder) and a full quadratic for reference on
the sequences of the even stops and scores each by the force VAF on the odd stops
(:func:`~armlab.estimation.field_adequacy.fit_field_models`); it also scores the diagonal model's
K against the truth at the stops (Eq. 3.1.2) and reports how much coupling the truth has.
"""

from __future__ import annotations

import numpy as np

from armlab.config.schema import ArmConfig
from armlab.data.trial import TrialSet
from armlab.errors import DataError
from armlab.estimation.field_adequacy import ADEQUACY_MODELS, fit_field_models
from armlab.estimation.field_scoring import relative_error_pct
from armlab.models.cartesian_field import quadratic_basis
from armlab.models.hill_arm_field import LEVEL_C_CIRCLE_CENTRE_M, LEVEL_C_CIRCLE_RADIUS_M, build_hill_arm
from armlab.perturbations.cartesian_timeline import SEQUENCE_DIRECTIONS, stop_path_times, stop_timeline
from armlab.perturbations.ramp_waveforms import ramp_waveform
from armlab.perturbations.reference_paths import ReferencePath
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig, IdentificationConfig
from armlab.protocols.cartesian_online.experiment import CHANNEL_UNITS, case_trials
from armlab.sim.cartesian_level_c import simulate_level_c

__all__ = [
    "LEVEL_C_CASE",
    "estimate_level_c",
    "format_level_c_table",
    "simulate_level_c_trials",
]

LEVEL_C_CASE = "level_c"
#: the two models the thesis offers (the full quadratic is a reference, not a candidate)
_THESIS_MODELS = ("diagonal_quadratic", "polar")


def simulate_level_c_trials(cfg: CartesianOnlineConfig) -> tuple[TrialSet, str]:
    """The level-C trials of ``cfg`` (module docstring) and the arm's composed MJCF.

    Randomness: force noise (``simulation.force_noise_std_N``) from ``default_rng([seed, 3])``.
    """
    s = cfg.simulation
    arm = build_hill_arm(ArmConfig())
    path = ReferencePath(kind="circle", centre=LEVEL_C_CIRCLE_CENTRE_M, radius_m=LEVEL_C_CIRCLE_RADIUS_M)
    timeline = stop_timeline(
        path,
        ramp_waveform("triangular", s.corner_s),
        stop_path_times(s.n_stops, path.duration_s),
        [np.asarray(SEQUENCE_DIRECTIONS)] * s.n_stops,
        pause_s=s.pause_s,
        fs=cfg.sensors.fs_hz,
    )
    noise = s.force_noise_std_N
    rng = np.random.default_rng([cfg.seed, 3]) if noise > 0 else None
    rec = simulate_level_c(arm, timeline, noise_std_n=noise, rng=rng)
    n_max = int(np.bincount(timeline.perturbation[rec.logged]).max())
    channels, meta = case_trials(LEVEL_C_CASE, rec, n_max, kind=(4, "triangular"))
    trials = TrialSet(
        fs_hz=cfg.sensors.fs_hz,
        onset_index=np.ones(len(meta["case"]), dtype=int),
        channels=channels,
        units=dict(CHANNEL_UNITS),
        trial_meta=meta,
        attrs={
            "protocol": cfg.protocol_name,
            "seed": cfg.seed,
            "level": "C",
            "corner_s": s.corner_s,
            "arm": "arm_planar (hill), muscles held at arm.cocontraction",
            "activation": arm.activation,
            "circle_centre_m": list(LEVEL_C_CIRCLE_CENTRE_M),
            "circle_radius_m": LEVEL_C_CIRCLE_RADIUS_M,
        },
    )
    return trials, arm.scene.xml


def _logged(trials: TrialSet) -> dict[str, np.ndarray]:
    need = ("hand_pos", "hand_vel", "hand_force", "ref_pos", "true_stiffness")
    missing = [k for k in need if k not in trials.channels]
    missing += [k for k in ("stop", "n_logged") if k not in trials.trial_meta]
    if missing:
        raise DataError(f"the trials lack {missing}; they were not made by cartesian_online at level C")
    n = np.asarray(trials.trial_meta["n_logged"])
    keep = np.arange(trials.n_samples)[None, :] < n[:, None]
    out = {k: np.asarray(trials.channels[k])[keep] for k in need}
    out["stop"] = np.repeat(np.asarray(trials.trial_meta["stop"]), n)
    return out


def estimate_level_c(trials: TrialSet, ident: IdentificationConfig) -> tuple[dict, dict]:
    """Fit and score the field models on level-C trials (module docstring).

    Returns:
        ``(results, series)``: per model its parameters and the train / held-out VAF per axis,
        ``better_model`` (the thesis's model with the higher held-out VAF, mean over the axes), the
        truth's stiffness range and coupling, and the diagonal model's K error at the stops.
    """
    d = _logged(trials)
    train = d["stop"] % 2 == 0  # whole sequences: even stops fit, odd stops held out
    fits = fit_field_models(
        d["hand_pos"], d["ref_pos"], d["hand_vel"], d["hand_force"], train, origin=tuple(ident.polar_origin_m)
    )
    models = {
        m: {
            "n_parameters": f.n_parameters,
            "vaf_train_pct": f.vaf_train_pct.tolist(),
            "vaf_held_out_pct": f.vaf_held_out_pct.tolist(),
            "vaf_held_out_mean_pct": float(f.vaf_held_out_pct.mean()),
        }
        for m, f in fits.items()
    }
    better = max(_THESIS_MODELS, key=lambda m: models[m]["vaf_held_out_mean_pct"])
    # the truth at each stop and what the diagonal model says there (its K_aa polynomials)
    stops, first = np.unique(d["stop"], return_index=True)
    k_true = d["true_stiffness"][first].reshape(-1, 2, 2)
    pos = d["ref_pos"][first]
    diag_theta = fits["diagonal_quadratic"].theta
    k_diag = quadratic_basis(pos) @ np.stack([diag_theta[a][:6] for a in (0, 1)], axis=1)  # K_aa(pos)
    truth_diag = np.stack([k_true[:, 0, 0], k_true[:, 1, 1]], axis=1)
    coupling = np.abs(k_true[:, 0, 1]) / np.sqrt(k_true[:, 0, 0] * k_true[:, 1, 1])
    results = {
        "protocol": "cartesian_online",
        "level": "C",
        "n_stops": int(len(stops)),
        "noise_std_N": float(np.asarray(trials.trial_meta.get("noise_std_N", [0.0]))[0]),
        "circle_centre_m": list(trials.attrs.get("circle_centre_m", LEVEL_C_CIRCLE_CENTRE_M)),
        "circle_radius_m": float(trials.attrs.get("circle_radius_m", LEVEL_C_CIRCLE_RADIUS_M)),
        "polar_origin_m": list(ident.polar_origin_m),
        "split": "sequences at even stops fit, odd stops held out",
        "models": models,
        "better_model": better,
        "truth": {
            "k_xx_N_per_m": [float(truth_diag[:, 0].min()), float(truth_diag[:, 0].max())],
            "k_yy_N_per_m": [float(truth_diag[:, 1].min()), float(truth_diag[:, 1].max())],
            "coupling_pct_max": float(100 * coupling.max()),
        },
        "diagonal_quadratic_k_error_pct_max": float(relative_error_pct(truth_diag, k_diag).max()),
        "checks": [],
    }  # fmt: skip
    return results, {"fits": fits, "k_true": k_true, "stops": pos}


def format_level_c_table(results: dict) -> str:
    """The level-C comparison as text (``table.txt`` and the printed table)."""
    t = results["truth"]
    lines = [
        f"cartesian_online (paper 002), level C: the planar Hill arm as the truth, circle R "
        f"{results['circle_radius_m']:g} m at {tuple(results['circle_centre_m'])} m from the shoulder, "
        f"{results['n_stops']} stops ({results['split']})",
        f"truth: K_xx {t['k_xx_N_per_m'][0]:.0f}-{t['k_xx_N_per_m'][1]:.0f} N/m, "
        f"K_yy {t['k_yy_N_per_m'][0]:.0f}-{t['k_yy_N_per_m'][1]:.0f} N/m, "
        f"coupling |K_xy|/sqrt(K_xx K_yy) up to {t['coupling_pct_max']:.1f} %",
    ]
    for m in ADEQUACY_MODELS:
        r = results["models"][m]
        vt, vh = r["vaf_train_pct"], r["vaf_held_out_pct"]
        lines.append(
            f"  {m:18s} {r['n_parameters']:3d} parameters  VAF train x {vt[0]:6.2f} y {vt[1]:6.2f} %  "
            f"held out x {vh[0]:6.2f} y {vh[1]:6.2f} %"
        )
    lines.append(
        f"better of the thesis's models (held-out VAF): {results['better_model']}; the diagonal "
        f"quadratic's K_xx, K_yy at the stops are up to "
        f"{results['diagonal_quadratic_k_error_pct_max']:.1f} % off the truth"
    )
    return "\n".join(lines)
