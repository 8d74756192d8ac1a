"""The run-side hooks of ``cartesian_online``: simulate, re-estimate, outputs, printed table."""

from __future__ import annotations

import numpy as np

from armlab.config.store import apply_overrides, stored_group
from armlab.data.trial import TrialSet
from armlab.models.cartesian_field import quadratic_basis
from armlab.protocols._files import write_new
from armlab.protocols.base import OutputContext, Simulated
from armlab.protocols.cartesian_online.checks import NOISE_CHECK_LIMITS
from armlab.protocols.cartesian_online.config import CartesianOnlineConfig, IdentificationConfig
from armlab.protocols.cartesian_online.experiment import simulate_cartesian
from armlab.protocols.cartesian_online.level_b import (
    clean_trials,
    executed_path_trials,
    inertia_compensated_trials,
    simulate_level_b_trials,
)
from armlab.protocols.cartesian_online.level_c import (
    estimate_level_c,
    format_level_c_table,
    simulate_level_c_trials,
)
from armlab.protocols.cartesian_online.results import estimate_cartesian, estimate_headlines

__all__ = [
    "HEADLINES",
    "LEVEL_A_SCENE",
    "format_table",
    "level_comparison",
    "outputs",
    "reestimate",
    "simulate",
]

#: ``scene.xml`` of a level A run: the thesis's generator has no physics scene (an empty model
#: saying so; levels B and C write their composed MJCF instead)
LEVEL_A_SCENE = (
    '<mujoco model="cartesian_online_level_a">\n'
    "  <!-- level A (thesis Ch. 3): the algebraic generator q_h = q_r + q_p, "
    "F = D(q_h) q'_h + K(q_h) q_p (Eqs. 2.2.1-2.2.4, 3.1.1); no robot, arm or physics -->\n"
    "</mujoco>\n"
)
_PATH_HZ = 20.0  # Hz, the reference path drawn in the recording (the thesis's paths take 100 s)


def _viz_series(full: dict, results: dict, series: dict) -> dict:
    """Plain arrays for :mod:`armlab.viz.cartesian` and the recording (their docstrings)."""
    out: dict = {"convergence": {}, "convergence_limits": NOISE_CHECK_LIMITS, "recording": {}}
    for case in ("exp4", "exp4_noise"):
        for method, s in series.get(case, {}).items():
            noise = results[case]["noise_std_N"]
            out["convergence"][f"{method}, {noise:g} N"] = s["result"].field.max_pct
    grid, field = series["grid"], series["field"]
    exp4 = series.get("exp4", {})
    best = exp4.get("linear") or next(iter(exp4.values()), None)
    if best is not None:
        r = best["result"]
        rec = series["records"]["exp4"]
        label = f"Exp. 4 {r.method}, {rec.noise_std_n:g} N, after {len(r.coefficients)} sequences"
        out["k_map"] = {
            "grid": grid,
            "k_true": field.stiffness(grid, rec.sigma),
            "k_hat": quadratic_basis(grid) @ r.coefficients[-1].T,
            "stops": rec.timeline.stop_position,
            "label": label,
        }
        out["force"] = {
            "t": rec.timeline.t[rec.logged],
            "measured": rec.force[rec.logged],
            "predicted": r.prediction,
            "fs_hz": rec.timeline.fs,
            "label": label,
        }
    for case, rec in series["records"].items():
        tl = rec.timeline
        whole = full[case].timeline  # the generator's whole timeline: the path between the stops
        step = max(1, int(round(whole.fs / _PATH_HZ)))
        c = {
            "path": whole.q_r[::step],
            "stops": tl.stop_position,
            "t": tl.t,
            "hand": tl.q_h,
            "force": rec.force,
            "k_true": field.stiffness(tl.stop_position, rec.sigma),
        }
        if case in ("exp4", "exp4_noise") and series.get(case):
            r = (series[case].get("linear") or next(iter(series[case].values())))["result"]
            ends = tl.t[np.r_[np.diff(tl.stop) != 0, True]]  # each stop's last sample
            c["k_hat"] = np.einsum("sj,qaj->qsa", quadratic_basis(tl.stop_position), r.coefficients)
            c["t_after"] = ends
            c["field_error_pct"] = r.field.max_pct
        out["recording"][case] = c
    return out


#: per experiment, the headline error (% , Eq. 3.1.2) compared across levels: the path into the
#: results and what it measures
HEADLINES: dict[str, tuple[tuple[str, ...], str]] = {
    "exp1_triangular": (("exp1", "triangular", "k_error_pct_max"), "max per-perturbation K error"),
    "exp1_trapezoidal": (("exp1", "trapezoidal", "k_error_pct_max"), "max per-perturbation K error"),
    "exp2": (("exp2", "diagonal_error_pct_max"), "max per-sequence diagonal K error"),
    "exp3": (("exp3", "final_error_pct_max"), "k0, k1, k3 error after the last stop"),
    "exp4": (("exp4", "linear", "field_max_pct", -1), "field error after the last sequence (Eq. 3.4.1)"),
    "exp4_sqrt_damping": (("exp4", "sqrt_damping", "field_max_pct", -1), "field error, 12 + 2 fit"),
    "exp4_noise": (("exp4_noise", "linear", "field_max_pct", -1), "field error, noise study"),
}


def _headline(results: dict, path: tuple) -> float | None:
    v = results
    for key in path:
        try:
            v = v[key]
        except (KeyError, IndexError, TypeError):
            return None
    return float(v)


def level_comparison(results: dict[str, dict], summary: dict) -> dict:
    """How far level B's physics and sensors move each experiment's headline error
    (:data:`HEADLINES`) from level A on the same commanded paths, split into three effects that
    add up to the whole difference:

    - ``path_effect_points``: level A's generator on the path level B executed minus level A (the
      servos' compliance shortens the excursions; no inertia, ideal sensors);
    - ``inertia_effect_points``: level B with ideal sensors minus that (the inertial force of the
      hand and cuff in the F/T reading, which the thesis's massless model does not have);
    - ``sensor_effect_points``: level B as measured minus level B with ideal sensors;

    and ``level_b_inertia_compensated_pct``: ideal sensors with ``m·a`` taken out by the handle's
    accelerometer (close to the executed path's when the compensation is right).

    Args:
        results: the results of ``a``, ``executed_path``, ``b_ideal``, ``b_compensated`` and
            ``b`` (the estimates on each version of the trials).
        summary: per case, the simulation's peak inertial force, peak force and saturated share.

    Returns:
        experiment -> ``{"what", "level_a_pct", "level_a_executed_path_pct",
        "level_b_ideal_sensors_pct", "level_b_inertia_compensated_pct", "level_b_pct", and the
        three effects}`` plus ``summary``'s entries of its case.
    """
    out = {}
    for name, (path, what) in HEADLINES.items():
        v = {k: _headline(r, path) for k, r in results.items()}
        if any(x is None for x in v.values()):
            continue
        case = name if name in summary else name.split("_sqrt")[0]
        out[name] = {
            "what": what,
            "level_a_pct": v["a"],
            "level_a_executed_path_pct": v["executed_path"],
            "level_b_ideal_sensors_pct": v["b_ideal"],
            "level_b_inertia_compensated_pct": v["b_compensated"],
            "level_b_pct": v["b"],
            "path_effect_points": v["executed_path"] - v["a"],
            "inertia_effect_points": v["b_ideal"] - v["executed_path"],
            "sensor_effect_points": v["b"] - v["b_ideal"],
            **summary.get(case, {}),
        }
    return out


def simulate(cfg: CartesianOnlineConfig) -> Simulated:
    """Generate the five experiments (level A, and at level B the LWR's on the same paths), or
    level C's Hill-arm circle; estimation runs when the runner asks for it."""
    if cfg.simulation.level == "C":
        trials_c, scene_c = simulate_level_c_trials(cfg)
        return Simulated(trials_c, scene_c, {}, lambda: estimate_level_c(trials_c, cfg.identification))
    rec = simulate_cartesian(cfg)
    if cfg.simulation.level == "A":

        def estimate() -> tuple[dict, dict]:
            results, series = estimate_cartesian(rec.trials, cfg.identification)
            return results, _viz_series(rec.records, results, series)

        return Simulated(rec.trials, LEVEL_A_SCENE, {}, estimate)

    trials_b, scene_xml, summary = simulate_level_b_trials(cfg, rec.trials, rec.field)

    def estimate_b() -> tuple[dict, dict]:
        results, series = estimate_cartesian(trials_b, cfg.identification)
        versions = {
            "a": rec.trials,
            "executed_path": executed_path_trials(trials_b),
            "b_ideal": clean_trials(trials_b),
            "b_compensated": inertia_compensated_trials(trials_b),
        }
        compared = {k: estimate_headlines(t, cfg.identification) for k, t in versions.items()}
        results["level_b_vs_a"] = level_comparison({**compared, "b": results}, summary)
        for row in results["checks"]:  # spec 002's checks are defined on the thesis's level A
            row["applies"] = False
            row["note"] = (row.get("note", "") + " (level B: see level_b_vs_a)").strip()
        return results, _viz_series(rec.records, results, series)

    return Simulated(trials_b, scene_xml, {}, estimate_b)


def reestimate(trials: TrialSet, stored, overrides: list[str]) -> dict:
    """Estimation again with ``identification.<field>=<value>`` overrides of the stored settings."""
    ident = apply_overrides(
        stored_group(IdentificationConfig, stored, "identification"), "identification", overrides
    )
    if str(trials.attrs.get("level", "A")) == "C":
        return estimate_level_c(trials, ident)[0]
    results, _ = estimate_cartesian(trials, ident)
    return results


def outputs(ctx: OutputContext) -> dict:
    """The checks beside the thesis (table.txt), the figures and the recording."""
    viz, out_dir, cfg = ctx.viz, ctx.out_dir, ctx.cfg
    written = {"table": write_new(out_dir / "table.txt", format_table(ctx.results, viz) + "\n")}
    if ctx.results.get("level") == "C":  # the comparison is the table; the figures are Exps. 1-5's
        return written
    if cfg.output.figures:
        written.update(viz.plot_cartesian_figures(ctx.series, ctx.results, out_dir))
    if cfg.output.recording:
        written["recording"] = viz.write_cartesian_recording(
            out_dir / "trials.rrd", ctx.series, ctx.results, application_id=f"armlab_{cfg.protocol_name}"
        )
    return written


def format_table(results: dict, viz) -> str:
    """Spec 002's checks beside the thesis's claims (level C: its model comparison)."""
    if results.get("level") == "C":
        return format_level_c_table(results)
    return viz.format_cartesian_table(results)
