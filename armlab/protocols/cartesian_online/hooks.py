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
from armlab.protocols.cartesian_online.results import estimate_cartesian

__all__ = ["LEVEL_A_SCENE", "format_table", "outputs", "reestimate", "simulate"]

#: ``scene.xml`` of a level A run: the thesis's generator has no physics scene (an empty model
#: saying so; levels B and C will write their composed MJCF here)
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


def simulate(cfg: CartesianOnlineConfig) -> Simulated:
    """Generate the five experiments (level A); estimation runs when the runner asks for it."""
    rec = simulate_cartesian(cfg)

    def estimate() -> tuple[dict, dict]:
        results, series = estimate_cartesian(rec.trials, cfg.identification)
        return results, _viz_series(rec.records, results, series)

    return Simulated(rec.trials, LEVEL_A_SCENE, {}, estimate)


def reestimate(trials: TrialSet, stored, overrides: list[str]) -> dict:
    """Estimation again with ``identification.<field>=<value>`` overrides of the stored settings."""
    ident = apply_overrides(
        stored_group(IdentificationConfig, stored, "identification"), "identification", overrides
    )
    results, _ = estimate_cartesian(trials, ident)
    return results


def outputs(ctx: OutputContext) -> dict:
    """The checks beside the thesis (table.txt), the figures and the recording."""
    viz, out_dir, cfg = ctx.viz, ctx.out_dir, ctx.cfg
    written = {"table": write_new(out_dir / "table.txt", format_table(ctx.results, viz) + "\n")}
    if cfg.output.figures:
        written.update(viz.plot_cartesian_figures(ctx.series, ctx.results, out_dir))
    if cfg.output.recording:
        written["recording"] = viz.write_cartesian_recording(
            out_dir / "trials.rrd", ctx.series, ctx.results, application_id=f"armlab_{cfg.protocol_name}"
        )
    return written


def format_table(results: dict, viz) -> str:
    """Spec 002's checks beside the thesis's claims."""
    return viz.format_cartesian_table(results)
