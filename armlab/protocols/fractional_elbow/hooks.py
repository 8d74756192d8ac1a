"""The run-side hooks of ``fractional_elbow``: simulate, re-estimate, outputs, printed table."""

from __future__ import annotations

from dataclasses import fields

from omegaconf import OmegaConf

from armlab.config.schema import FrfConfig
from armlab.config.store import apply_overrides, stored_group
from armlab.data.trial import TrialSet
from armlab.models.direct_drive_scene import build_direct_drive_scene
from armlab.models.elbow_truth import elbow_truth
from armlab.protocols._files import write_new
from armlab.protocols.base import OutputContext, Simulated
from armlab.protocols.fractional_elbow.config import FractionalElbowConfig
from armlab.protocols.fractional_elbow.experiment import estimate_fractional, simulate_fractional

__all__ = ["format_table", "outputs", "reestimate", "simulate"]


def simulate(cfg: FractionalElbowConfig) -> Simulated:
    """Simulate the multisine trials; estimation runs when the runner asks for it."""
    rec = simulate_fractional(cfg)
    return Simulated(
        rec.trials,
        rec.scene.xml,
        {"scenario": rec.scenario.name},
        lambda: estimate_fractional(rec.trials, cfg.frf, rec.truth),
    )


def reestimate(trials: TrialSet, stored, overrides: list[str]) -> dict:
    """Estimation again with ``frf.<field>=<value>`` overrides; the truth is rebuilt from the stored
    model settings (no simulation)."""
    frf = apply_overrides(stored_group(FrfConfig, stored, "frf"), "frf", overrides)
    truth = None
    if "elbow" in stored:
        # the groups this protocol reads (runs made before the per-protocol configs stored them all)
        own = {f.name: stored[f.name] for f in fields(FractionalElbowConfig) if f.name in stored}
        exp = OmegaConf.to_object(OmegaConf.merge(OmegaConf.structured(FractionalElbowConfig), own))
        scene = build_direct_drive_scene(exp.elbow, exp.sim)
        truth = elbow_truth(scene, exp.elbow, trials.fs_hz, exp.motor.sensed_mass_kg)
    results, _ = estimate_fractional(trials, frf, truth)
    return results


def outputs(ctx: OutputContext) -> dict:
    """Figs. 4-6 of the paper, Table I beside the paper's and the recording of every trial."""
    viz, out_dir, results, cfg = ctx.viz, ctx.out_dir, ctx.results, ctx.cfg
    written = {}
    if cfg.output.figures:
        written["fig4"] = viz.plot_bode_fits(ctx.series, results, out_dir / "fig4_bode_fits.png")
        written["fig5"] = viz.plot_time_overlay(ctx.series, out_dir / "fig5_time_overlay.png")
        written["fig6"] = viz.plot_bode_literature(ctx.series, out_dir / "fig6_bode_literature.png", results)
    written["table"] = write_new(out_dir / "table_I.txt", viz.format_fractional_table(results) + "\n")
    if cfg.output.recording:
        written["recording"] = viz.write_fractional_recording(out_dir / "trials.rrd", ctx.trials, results)
    return written


def format_table(results: dict, viz) -> str:
    """Table I of the paper beside armlab's fits."""
    return viz.format_fractional_table(results)
