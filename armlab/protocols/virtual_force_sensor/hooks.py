"""The run-side hooks of ``virtual_force_sensor``: simulate, re-estimate, outputs, printed tables."""

from __future__ import annotations

import json

from armlab.config.schema import VfsConfig
from armlab.config.store import apply_overrides, stored_group
from armlab.data.trial import TrialSet
from armlab.protocols._files import write_new
from armlab.protocols.base import OutputContext, Simulated
from armlab.protocols.virtual_force_sensor.config import VirtualForceSensorConfig
from armlab.protocols.virtual_force_sensor.experiment import simulate_vfs
from armlab.protocols.virtual_force_sensor.results import estimate_vfs

__all__ = ["format_table", "outputs", "reestimate", "simulate"]


def simulate(cfg: VirtualForceSensorConfig) -> Simulated:
    """Simulate the robot identification, fixture and arm stages; estimation runs when asked."""
    rec = simulate_vfs(cfg)
    scene = rec.scenes.get("arm") or rec.scenes.get("fixture") or rec.scenes["robot_id"]
    return Simulated(
        rec.trials,
        scene,
        {"truth_json": json.dumps(rec.truth)},
        lambda: estimate_vfs(rec.trials, cfg.vfs, rec.truth),
    )


def reestimate(trials: TrialSet, stored, overrides: list[str]) -> dict:
    """Estimation again with ``vfs.<field>=<value>`` overrides of the stored settings."""
    vfs = apply_overrides(stored_group(VfsConfig, stored, "vfs"), "vfs", overrides)
    results, _ = estimate_vfs(trials, vfs, json.loads(str(trials.attrs.get("truth_json", "{}"))))
    return results


def outputs(ctx: OutputContext) -> dict:
    """Tables III-VI beside the paper's, Figs. 4-5 and the recording of every trial."""
    viz, out_dir, cfg = ctx.viz, ctx.out_dir, ctx.cfg
    written = {"tables": write_new(out_dir / "tables.txt", viz.format_vfs_tables(ctx.results) + "\n")}
    if cfg.output.figures:
        written.update(viz.plot_vfs_figures(ctx.results, ctx.series, out_dir))
    if cfg.output.recording:
        written["recording"] = viz.write_vfs_recording(
            out_dir / "trials.rrd", ctx.trials, ctx.results, application_id=f"armlab_{cfg.protocol_name}"
        )
    return written


def format_table(results: dict, viz) -> str:
    """Tables III-VI as text."""
    return viz.format_vfs_tables(results)
