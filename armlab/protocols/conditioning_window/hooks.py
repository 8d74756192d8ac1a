"""The run-side hooks of ``conditioning_window``: simulate, re-estimate, outputs, printed table."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from armlab import progress
from armlab.config.schema import EstimatorConfig
from armlab.config.store import apply_overrides, stored_group
from armlab.data.trial import TrialSet
from armlab.perturbations.scenario import load_scenario
from armlab.protocols.base import OutputContext, Simulated
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.experiment import (
    estimate_protocol,
    linearisation_bias,
    simulate_protocol,
    window_specs,
)
from armlab.protocols.conditioning_window.preflight import check_estimator
from armlab.protocols.conditioning_window.truths import effective_truth, score_truths

__all__ = ["format_table", "outputs", "reestimate", "simulate"]


def simulate(cfg: ConditioningWindowConfig) -> Simulated:
    """Simulate every window's trials; estimation runs when the runner asks for it."""
    rec, scenario = simulate_protocol(cfg)

    def estimate() -> tuple[dict, dict]:
        specs = window_specs(scenario, cfg.estimator)
        # The linearisation bias (its own exact-data run) is computed on a second thread while
        # this one estimates the windows and the effective truth: each spends part of its time in
        # Python (scene, robot paths, signal processing) while the other steps MuJoCo without the
        # GIL. It reports no progress (the thread does not carry the display's context).
        with ThreadPoolExecutor(max_workers=1) as beside:
            bias = beside.submit(linearisation_bias, cfg)
            results, series = estimate_protocol(rec.trials, cfg.estimator, specs)
            with progress.scope("effective truth"):  # the plan again, in the ideal lab
                score_truths(results, effective_truth(cfg, rec.trials, scenario, specs))
            results["linearisation_bias"] = bias.result()
        return results, series

    return Simulated(rec.trials, rec.scene.xml, {"scenario": scenario.name}, estimate)


def reestimate(trials: TrialSet, stored, overrides: list[str]) -> dict:
    """Estimation again with ``estimator.<field>=<value>`` overrides of the stored settings."""
    estimator = apply_overrides(stored_group(EstimatorConfig, stored, "estimator"), "estimator", overrides)
    check_estimator(estimator, trials.fs_hz, int(np.min(trials.onset_index)) / trials.fs_hz)
    scenario = load_scenario(str(trials.attrs.get("scenario", "conditioning_window")))
    groups = sorted(set(np.asarray(trials.trial_meta["group"]).tolist()))
    scenario = scenario.subset(k_values=groups, n_trials=None)
    results, _ = estimate_protocol(trials, estimator, window_specs(scenario, estimator))
    return results


def outputs(ctx: OutputContext) -> dict:
    """Figs. 4-6 of the paper, the error plot and the recording of every trial."""
    viz, out_dir, results, cfg = ctx.viz, ctx.out_dir, ctx.results, ctx.cfg
    written = {}
    if cfg.output.figures:
        written["fig4"] = viz.plot_window_sweep(results, out_dir / "fig4_full.png", model="full")
        written["fig5"] = viz.plot_window_sweep(results, out_dir / "fig5_reduced.png", model="reduced")
        written["fig6"] = viz.plot_validation(ctx.series, out_dir / "fig6_validation.png")
        written["errors"] = viz.plot_error_vs_window(results, out_dir / "errors.png")
    if cfg.output.recording:
        written["recording"] = viz.write_recording(out_dir / "trials.rrd", ctx.trials, results)
    return written


def _fmt(x) -> str:
    return "  -  " if x is None else f"{x * 1000:.0f} ms"


def _pct(entry: dict, key: str, width: int = 6) -> str:
    x = entry.get(key)
    return f"{'-':>{width}}" if x is None else f"{x * 100:{width - 1}.1f}%"


def format_table(results: dict, viz=None) -> str:
    """The window sweep as text: per window the conditioning, K eigenvalues, errors and VAF.

    Errors are relative (Frobenius) against two labelled truths: ``int`` the intrinsic truth
    (muscles linearised, activations frozen), ``eff`` the effective truth (the same plan in an
    ideal lab with the reflexes acting; see :mod:`~armlab.protocols.conditioning_window.truths`).
    """
    lines = [
        "T_obs  k  ext |   cond  |  eig(K_s)       | full: K err int  eff | D err int  eff | xi err | "
        "reduced: K err int  eff | D err eff | VAF1  VAF2",
    ]
    for w in results["windows"]:
        red = w.get("reduced", {})
        lines.append(
            f"{w['t_obs_s'] * 1000:4.0f}ms {w['k']:2d}  {'*' if w['extension'] else ' '}  | "
            f"{w.get('cond', float('nan')):7.0f} | "
            f"{w['eig_Ks'][0]:6.2f} {w['eig_Ks'][1]:6.2f}  |       "
            f"{_pct(w, 'K_rel_err', 8)} {_pct(w, 'K_err_effective')} | "
            f"{_pct(w, 'D_rel_err', 9)} {_pct(w, 'D_err_effective')} | {_pct(w, 'xi_rel_err')} |"
            f"          {_pct(red, 'K_rel_err', 8)} {_pct(red, 'K_err_effective')} | "
            f"{_pct(red, 'D_err_effective', 9)} | "
            f"{w['validation']['vaf_pct'][0]:4.0f}% {w['validation']['vaf_pct'][1]:4.0f}%"
        )
    if "truths" in results:
        lines.append(
            f"truths: int = intrinsic ({results['truths']['intrinsic']}); "
            f"eff = effective ({results['truths']['effective']})"
        )
    for model in ("full", "reduced"):
        c = results["criteria"][model]
        lines.append(
            f"{model:8s} criteria first met: K pos. def. {_fmt(c['K_pd_from_s'])}, quasi-symmetric "
            f"{_fmt(c['symmetric_from_s'])}, quasi-constant {_fmt(c['constant_from_s'])}"
        )
    if "tolerances" in results:
        t = results["tolerances"]
        lines.append(
            f"tolerances: quasi-symmetric |A-A^T|/|A+A^T| < {t['symmetry_tol']:g} (K and D); quasi-constant "
            + (
                f"change to the next window < {t['constancy_tol_per_s']:g} x block norm per s of T_obs"
                if t.get("constancy_tol_per_s") is not None
                else f"change to the next window < {t['constancy_tol']:g} x block norm per window step"
            )
        )
    p = results["paper"]
    lines.append(
        f"paper (seeds/000 IV-D): K pos. def. > {p['K_pd_after_s'] * 1000:.0f} ms, quasi-symmetric > "
        f"{p['symmetric_after_s'] * 1000:.0f} ms, quasi-constant > {p['constant_after_s'] * 1000:.0f} ms"
    )
    if "linearisation_bias" in results:
        b = results["linearisation_bias"]
        lines.append(
            f"linearisation bias ({b['muscle']} muscles, {b['conditions']}) at T_obs = "
            f"{b['t_obs_s'] * 1000:.0f} ms: K {b['K_rel_err'] * 100:.2f} %, D {b['D_rel_err'] * 100:.2f} %, "
            f"xi {b['xi_rel_err'] * 100:.2f} % (against the intrinsic truth)"
        )
    return "\n".join(lines)
