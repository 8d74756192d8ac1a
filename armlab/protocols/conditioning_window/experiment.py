"""Protocol ``conditioning_window``: the observation-window study of the conditioning paper.

Glue from config to scenario to the simulated lab to estimation to results (../shared/seeds/000):
26 windows, each with its own 30 trials perturbed by a quintic of duration T_k; the full
11-parameter and the reduced 8-parameter least squares on T_obs = T_k + 70 ms of 29 trials; the
30th trial validates; the criteria of section III-C per window, and the first window from which
each criterion holds for good. Pure computation: files and figures are written by
:mod:`armlab.runner.run`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from armlab import progress
from armlab.config.schema import EstimatorConfig
from armlab.data.trial import TrialSet
from armlab.errors import ConfigError, DataError
from armlab.estimation import criteria
from armlab.estimation.joint_ls import LSEstimate, estimate_windows, validate
from armlab.estimation.processing import JointSignals, ProcessingConfig, joint_signals
from armlab.models.ground_truth import GroundTruth
from armlab.models.scene import MUSCLES, Scene
from armlab.perturbations.scenario import Scenario, draw_trials, load_scenario
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.sim.hold import HoldState
from armlab.sim.lab import record_trials

__all__ = [
    "check_window_lengths",
    "ConditioningRecording",
    "PAPER_THRESHOLDS_S",
    "PAPER_XI",
    "WindowSpec",
    "estimate_protocol",
    "linearisation_bias",
    "simulate_protocol",
    "window_specs",
]

# kg m^2, xi fixed in the paper's reduced model (section IV-D)
PAPER_XI = np.array([0.391, 0.155, 0.149])
# s, the paper's findings (section IV-D): K positive definite for T_obs > 320 ms, K and D
# quasi-symmetric for T_obs > 370 ms, all parameters quasi-constant for T_obs > 400 ms.
PAPER_THRESHOLDS_S = {"K_pd_after_s": 0.32, "symmetric_after_s": 0.37, "constant_after_s": 0.40}


@dataclass(frozen=True, kw_only=True)
class WindowSpec:
    """One estimation window: the trials of group ``k`` over ``t_obs_s`` after onset."""

    k: int
    t_k_s: float
    t_obs_s: float
    extension: bool  # a window longer than T_k + 70 ms on the same trials (see scenario file)


def window_specs(scenario: Scenario, estimator: EstimatorConfig) -> list[WindowSpec]:
    """The paper's windows (T_obs = T_k + 70 ms) plus the scenario's extension windows, in order
    of T_obs. Extension windows longer than the last paper window are kept; shorter ones only in a
    single-group scenario (a designed one, whose one T_k has no other group's windows below it).

    With ``estimator.t_obs_s`` set, those windows are used on the longest-T_k group instead.
    """
    if estimator.t_obs_s is not None:
        k = int(scenario.k_values[-1])
        return [
            WindowSpec(k=k, t_k_s=float(scenario.t_k_s[-1]), t_obs_s=float(t), extension=True)
            for t in sorted(estimator.t_obs_s)
        ]
    specs = [
        WindowSpec(k=int(k), t_k_s=float(tk), t_obs_s=float(to), extension=False)
        for k, tk, to in zip(scenario.k_values, scenario.t_k_s, scenario.t_obs_s, strict=True)
    ]
    last = specs[-1]
    single_group = len(specs) == 1
    specs += [
        WindowSpec(k=last.k, t_k_s=last.t_k_s, t_obs_s=float(t), extension=True)
        for t in scenario.extension_t_obs_s
        if t > last.t_obs_s or (single_group and t < last.t_obs_s)
    ]
    return sorted(specs, key=lambda s: s.t_obs_s)


@dataclass(frozen=True, kw_only=True, eq=False)
class ConditioningRecording:
    """What :func:`simulate_protocol` returns.

    Attributes:
        trials: the recorded trials (measured channels + ``true_*`` channels); ``trial_meta``
            holds the plan (``group``, ``direction``, ``T_k_s``, ``wait_s``, ``validate``).
        truth: ground truth at the operating point.
        scene: the compiled scene (its MJCF is saved with the run).
        hold: the settled pre-perturbation state.
    """

    trials: TrialSet
    truth: GroundTruth
    scene: Scene
    hold: HoldState


def simulate_protocol(cfg: ConditioningWindowConfig) -> tuple[ConditioningRecording, Scenario]:
    """Draw the seeded trial plan and record every trial in the simulated lab."""
    scenario = load_scenario(cfg.scenario.name).subset(cfg.scenario.k_values, cfg.scenario.n_trials)
    # the third child feeds the subject's fluctuation; the first two are those of a 2-way spawn,
    # so an ideal subject draws exactly the plan and sensor noise it always did
    plan_rng, sensor_rng, subject_rng = np.random.default_rng(cfg.seed).spawn(3)
    plan = draw_trials(scenario, plan_rng)
    rec = record_trials(cfg, scenario, plan, sensor_rng, cfg.subject, subject_rng)
    trials = TrialSet(
        fs_hz=rec.fs_hz,
        onset_index=rec.onset_index,
        channels=rec.channels,
        units=rec.units,
        trial_meta={
            "group": plan.group,
            "direction": plan.direction,
            "T_k_s": plan.t_k_s,
            "wait_s": plan.wait_s,
            "validate": plan.validate,
        },
        attrs={
            "protocol": cfg.protocol_name,
            "seed": cfg.seed,
            "arm_l1_m": rec.scene.l1,
            "arm_l2_m": rec.scene.l2,
            "muscles": list(MUSCLES),
            "ground_truth": rec.truth.as_dict(),
        },
    )
    return ConditioningRecording(trials=trials, truth=rec.truth, scene=rec.scene, hold=rec.hold), scenario


def check_window_lengths(specs: list[WindowSpec], fs_hz: float, available: int) -> np.ndarray:
    """The windows' lengths in samples at ``fs_hz``; ConfigError if one is longer than the
    ``available`` samples recorded after onset (checked before simulating and on the trials)."""
    samples = np.array([int(round(s.t_obs_s * fs_hz)) for s in specs])
    too_long = [s.t_obs_s for s, n in zip(specs, samples, strict=True) if n > available]
    if too_long:
        raise ConfigError(
            f"observation window(s) {too_long} s are longer than the recorded data after onset "
            f"({available / fs_hz:.3f} s); valid: T_obs <= {available / fs_hz:.3f} s"
            " (estimator.t_obs_s, or the scenario's windows)"
        )
    return samples


def _check_windows(trials: TrialSet, specs: list[WindowSpec]) -> np.ndarray:
    return check_window_lengths(specs, trials.fs_hz, trials.n_samples - int(np.max(trials.onset_index)))


def _entry(est: LSEstimate, truth: dict | None, fit, reduced: bool) -> dict:
    """One model's estimate in a window; errors against ground truth where it is known."""
    out = {
        "cond": float(est.cond),
        "K": est.K.tolist(),
        "D": est.D.tolist(),
        "eig_Ks": criteria.eig_symmetric_part(est.K).tolist(),
        "eig_Ds": criteria.eig_symmetric_part(est.D).tolist(),
        "asym_K": float(criteria.asymmetry(est.K)),
        "asym_D": float(criteria.asymmetry(est.D)),
        "std": dict(zip(est.names, est.std.tolist(), strict=True)),
        "rms_residual_Nm": float(est.rms_residual),
        "validation": {"vaf_pct": fit.vaf.tolist(), "rmse_Nm": fit.rmse.tolist()},
    }
    if not reduced:
        out["xi"] = est.xi.tolist()
    if truth is not None:
        out["K_rel_err"] = criteria.relative_error(est.K, np.asarray(truth["K"]))
        out["D_rel_err"] = criteria.relative_error(est.D, np.asarray(truth["D"]))
        if not reduced:
            out["xi_rel_err"] = criteria.relative_error(est.xi, np.asarray(truth["xi"]))
    return out


def criteria_flags(
    t_obs: np.ndarray,
    K: list[np.ndarray],
    D: list[np.ndarray],
    params: np.ndarray,
    *,
    symmetry_tol: float,
    constancy_tol: float,
    constancy_tol_per_s: float | None,
) -> dict[str, np.ndarray]:
    """Per window, whether each criterion of section IV-D holds: ``{"K_pd", "symmetric",
    "constant"}`` of (n_windows,) bool. ``K``, ``D``: the windows' estimates; ``params``:
    (n_windows, c) their parameter vectors in the estimator's order (Eq. 10 or 23). Used by the run
    and by CI's window sweep (:mod:`.window_sweep`), which judges jobs' results.json the same way."""
    sym = [
        criteria.asymmetry(k) < symmetry_tol and criteria.asymmetry(d) < symmetry_tol
        for k, d in zip(K, D, strict=True)
    ]
    if constancy_tol_per_s is None:  # per window step (the windows' spacing ignored)
        const = criteria.quasi_constant_flags(params, constancy_tol)
    else:  # per second of T_obs: 10 ms steps and 30-50 ms extension steps judged alike
        const = criteria.quasi_constant_flags(params, constancy_tol_per_s, t_obs=t_obs)
    return {
        "K_pd": np.array([criteria.is_positive_definite(k) for k in K]),
        "symmetric": np.array(sym),
        "constant": const,
    }


def first_met(t_obs: np.ndarray, flags: dict[str, np.ndarray]) -> dict[str, float | None]:
    """The window from which each criterion holds for it and every longer one (results.json's
    ``criteria``): ``{"K_pd_from_s", "symmetric_from_s", "constant_from_s"}``."""
    names = ("K_pd", "symmetric", "constant")
    return {f"{name}_from_s": criteria.first_satisfied(t_obs, flags[name]) for name in names}


def _criteria(t_obs: np.ndarray, ests: list[LSEstimate], cfg: EstimatorConfig) -> dict:
    flags = criteria_flags(
        t_obs,
        [e.K for e in ests],
        [e.D for e in ests],
        np.stack([e.zeta for e in ests]),
        symmetry_tol=cfg.symmetry_tol,
        constancy_tol=cfg.constancy_tol,
        constancy_tol_per_s=cfg.constancy_tol_per_s,
    )
    return first_met(t_obs, flags)


def estimate_protocol(
    trials: TrialSet, estimator: EstimatorConfig, specs: list[WindowSpec]
) -> tuple[dict, dict]:
    """Run both least-squares models on every window and score them against ground truth.

    Args:
        trials: recorded trials with ``hand_pos``, ``hand_force`` and trial_meta ``group``,
            ``validate``; attrs ``arm_l1_m``, ``arm_l2_m`` and (simulated data) ``ground_truth``.
        estimator: processing and criteria settings.
        specs: the windows to estimate.

    Returns:
        (results dict — see docs/results_schema.md — , validation series for Fig. 6 of the
        longest paper window).
    """
    for key in ("group", "validate"):
        if key not in trials.trial_meta:
            raise DataError(f"trials lack trial_meta[{key!r}]; have {sorted(trials.trial_meta)}")
    samples = _check_windows(trials, specs)
    progress.stage("estimate", len(specs), "windows")
    proc = ProcessingConfig(
        lowpass_hz=estimator.lowpass_hz, filter_order=estimator.filter_order, baseline_s=estimator.baseline_s
    )
    signals: JointSignals = joint_signals(
        trials.channel("hand_pos"),
        trials.channel("hand_force"),
        trials.fs_hz,
        trials.onset_index,
        float(trials.attrs["arm_l1_m"]),
        float(trials.attrs["arm_l2_m"]),
        proc,
    )
    group = np.asarray(trials.trial_meta["group"])
    held_out = np.asarray(trials.trial_meta["validate"], bool)
    masks = np.stack([(group == s.k) & ~held_out for s in specs])
    truth = trials.attrs.get("ground_truth")
    full = estimate_windows(signals, masks, samples)
    if estimator.xi_source == "full_fit":  # paper IV-D: xi from the full identification
        xi_known = np.asarray(full[int(np.argmax(samples))].xi, float)
    elif estimator.xi_source == "paper" or truth is None:
        xi_known = PAPER_XI
    else:
        xi_known = np.asarray(truth["xi"])
    reduced = estimate_windows(signals, masks, samples, xi_known=xi_known)

    windows = []
    series = {}
    for spec, n, e_full, e_red in zip(specs, samples, full, reduced, strict=True):
        val = np.flatnonzero((group == spec.k) & held_out)
        if val.size == 0:
            raise DataError(f"window k={spec.k} has no validation trial (trial_meta 'validate')")
        fit_f = validate(e_full, signals, int(val[0]), int(n))
        fit_r = validate(e_red, signals, int(val[0]), int(n))
        entry = {
            "k": spec.k,
            "T_k_s": spec.t_k_s,
            "t_obs_s": spec.t_obs_s,
            "extension": spec.extension,
            "n_trials_identify": int(masks[len(windows)].sum()),
        }
        entry.update(_entry(e_full, truth, fit_f, reduced=False))
        if truth:
            entry.update({"K_true": truth["K"], "D_true": truth["D"], "xi_true": truth["xi"]})
        entry["reduced"] = _entry(e_red, truth, fit_r, reduced=True)
        entry["reduced"]["xi_known"] = xi_known.tolist()
        windows.append(entry)
        progress.advance()
        if not spec.extension:
            series = {
                "t_s": fit_f.t,
                "dtau_measured": fit_f.dtau,
                "dtau_full": fit_f.dtau_hat,
                "dtau_reduced": fit_r.dtau_hat,
                "t_obs_s": spec.t_obs_s,
            }
    t_obs = np.array([s.t_obs_s for s in specs])
    results = {
        "protocol": trials.attrs.get("protocol", "conditioning_window"),
        "seed": trials.attrs.get("seed"),
        "ground_truth": truth,
        "paper": dict(PAPER_THRESHOLDS_S),
        "tolerances": {
            "symmetry_tol": estimator.symmetry_tol,
            "constancy_tol": estimator.constancy_tol,
            "constancy_tol_per_s": estimator.constancy_tol_per_s,
        },
        "xi_source": estimator.xi_source,
        "criteria": {
            "full": _criteria(t_obs, full, estimator),
            "reduced": _criteria(t_obs, reduced, estimator),
        },
        "windows": windows,
    }
    return results, series


def linearisation_bias(cfg: ConditioningWindowConfig) -> dict:
    """Error of the linear model of Eq. (9) on exact data from the configured muscle model.

    The run's arm (muscle variant, co-contraction, pre-load) and trial plan are simulated again
    with everything else that could bias the estimate removed: rigid cuff, ideal sensors, no
    reflex, a steady subject, no low-pass filter. What error remains in the longest paper window
    is the bias of linearising the muscles (plus MuJoCo's integration error, ~0.3 % on the linear variant):
    the Hill muscle's force-length-velocity curves are not linear over the 0.05 rad perturbation.

    Args:
        cfg: the run's configuration.

    Returns:
        A ``linearisation_bias`` entry of results.json (docs/results_schema.md).
    """
    scenario = load_scenario(cfg.scenario.name).subset(cfg.scenario.k_values, cfg.scenario.n_trials)
    exact = replace(
        cfg,
        cuff=replace(cfg.cuff, rigid=True),
        reflex=replace(cfg.reflex, enabled=False),
        sensors=replace(cfg.sensors, preset="ideal"),
        subject=replace(cfg.subject, enabled=False),
        estimator=replace(cfg.estimator, lowpass_hz=None, t_obs_s=None),
        scenario=replace(cfg.scenario, k_values=[int(scenario.k_values[-1])]),
    )
    with progress.scope("linearisation bias"):
        rec, scenario = simulate_protocol(exact)
        specs = [s for s in window_specs(scenario, exact.estimator) if not s.extension]
        results, _ = estimate_protocol(rec.trials, exact.estimator, specs)
    w = results["windows"][-1]
    return {
        "muscle": cfg.arm.muscle,
        "conditions": "rigid cuff, ideal sensors, reflex off, steady subject, no low-pass filter",
        "k": w["k"],
        "t_obs_s": w["t_obs_s"],
        "K": w["K"],
        "D": w["D"],
        "xi": w["xi"],
        "K_true": w["K_true"],
        "D_true": w["D_true"],
        "xi_true": w["xi_true"],
        "K_rel_err": w["K_rel_err"],
        "D_rel_err": w["D_rel_err"],
        "xi_rel_err": w["xi_rel_err"],
        "reduced": {"K_rel_err": w["reduced"]["K_rel_err"], "D_rel_err": w["reduced"]["D_rel_err"]},
    }
