"""The run-side hooks of ``stiffness_5dof_emg``: simulate, re-estimate, outputs, printed table."""

from __future__ import annotations

import numpy as np

from armlab.config.store import apply_overrides, stored_group
from armlab.data.trial import TrialSet
from armlab.models.arm_5dof import limb_kinematics, load_arm_5dof
from armlab.protocols._files import write_new
from armlab.protocols.base import OutputContext, Simulated
from armlab.protocols.stiffness_5dof_emg.config import EstimationConfig, Stiffness5dofConfig
from armlab.protocols.stiffness_5dof_emg.experiment import simulate_stages
from armlab.protocols.stiffness_5dof_emg.lab_effects import apply_recorded_effects, build_effect_lab
from armlab.protocols.stiffness_5dof_emg.results import estimate_stiffness

__all__ = ["RECORDING_HZ", "format_table", "outputs", "recording_series", "reestimate", "simulate"]

RECORDING_HZ = 100.0  # Hz, the rate the recording draws the skeleton and wrenches at (of 2 kHz)


def simulate(cfg: Stiffness5dofConfig) -> Simulated:
    """Simulate the chosen stages with the switched-on lab effects (:mod:`.lab_effects`);
    estimation runs when the runner asks for it."""
    lab = build_effect_lab(cfg)
    trials = apply_recorded_effects(cfg, simulate_stages(cfg, lab), lab)
    return Simulated(trials, lab.scene.xml, {}, lambda: estimate_stiffness(trials, cfg.estimation))


def reestimate(trials: TrialSet, stored, overrides: list[str]) -> dict:
    """Estimation again with ``estimation.<field>=<value>`` overrides of the stored settings."""
    est = apply_overrides(stored_group(EstimationConfig, stored, "estimation"), "estimation", overrides)
    results, _ = estimate_stiffness(trials, est)
    return results


def recording_series(trials: TrialSet, max_hz: float = RECORDING_HZ) -> dict:
    """Plain arrays for :func:`armlab.viz.write_stiffness5_recording`, decimated to ``max_hz``.

    Returns:
        ``t`` (n_trials, n) s from each onset; ``skeleton`` (n_trials, n, 3, 3) m shoulder, elbow,
        wrist (world) from the true joint angles; ``marker`` (n_trials, n, 3) m the measured forearm
        cluster; ``wrist_force`` (n_trials, n, 3) N the force on the limb (world, the JR3 turned by
        the true wrist frame); ``base_force`` (n_trials, n, 3) N the base JR3 (its frame is the
        world's); ``condition`` (n_trials,) and ``names``.
    """
    step = max(1, int(round(trials.fs_hz / max_hz)))
    ch = trials.channels
    idx = np.arange(0, ch["true_q"].shape[1], step)
    onset = int(np.asarray(trials.onset_index)[0])
    kin = limb_kinematics(load_arm_5dof())
    pose = kin.pose(ch["true_q"][:, idx])
    skeleton = np.stack([np.broadcast_to(pose.shoulder, pose.elbow.shape), pose.elbow, pose.wrist], axis=-2)
    r_s = pose.wrist_rot @ np.asarray(trials.attrs["wrist_ft_rot"], float)
    # the JR3 reads what the flange exerts on the tool; the limb feels it (tool weight aside)
    f_w = np.einsum("...ij,...j->...i", r_s, ch["wrist_force"][:, idx])
    return {
        "t": (idx - onset) / trials.fs_hz,
        "skeleton": skeleton,
        "marker": ch["forearm_marker_pos"][:, idx],
        "wrist_force": f_w,
        "base_force": ch["base_force"][:, idx],
        "condition": np.asarray(trials.trial_meta["condition"], int),
        "names": [str(n) for n in trials.attrs["condition_names"]],
    }


def outputs(ctx: OutputContext) -> dict:
    """The checks beside the spec (table.txt), the K_q and ellipsoid figures, the recording."""
    viz, out_dir, cfg = ctx.viz, ctx.out_dir, ctx.cfg
    written = {"table": write_new(out_dir / "table.txt", format_table(ctx.results, viz) + "\n")}
    if cfg.output.figures:
        written.update(viz.plot_stiffness5_figures(ctx.series, out_dir))
    if cfg.output.recording:
        written["recording"] = viz.write_stiffness5_recording(
            out_dir / "trials.rrd",
            recording_series(ctx.trials),
            ctx.series,
            ctx.results,
            application_id=f"armlab_{cfg.protocol_name}",
        )
    return written


def format_table(results: dict, viz) -> str:
    """Per condition K_q error, SPD, ellipsoid axes; spec 001's checks."""
    return viz.format_stiffness5_table(results)
