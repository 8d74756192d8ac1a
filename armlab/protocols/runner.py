"""Run a protocol end to end and write its outputs — the edge where files and figures happen.

Outputs in the run directory (never overwritten: a directory that already holds results is
refused): ``results.json`` (docs/results_schema.md), ``trials.h5`` (docs/trial_format.md),
``scene.xml`` (the composed MJCF), the protocol's figures and ``trials.rrd`` (rerun recording of
every trial).

- ``conditioning_window``: ``fig4_full.png``, ``fig5_reduced.png``, ``fig6_validation.png``,
  ``errors.png``.
- ``fractional_elbow``: ``fig4_bode_fits.png``, ``fig5_time_overlay.png``,
  ``fig6_bode_literature.png`` and ``table_I.txt``.
- ``virtual_force_sensor``: ``tables.txt`` (Tables III-VI beside the paper's),
  ``fig4_forces.png``, ``fig5_identified_vs_theory.png``, ``fig_arm.png``.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf

from armlab.config.effects import enabled_effects
from armlab.config.schema import EstimatorConfig, ExperimentConfig, FrfConfig, VfsConfig
from armlab.config.store import apply_overrides, to_experiment
from armlab.data.h5io import read_trials, write_trials
from armlab.data.trial import TrialSet
from armlab.errors import ConfigError, DataError
from armlab.models.direct_drive_scene import build_direct_drive_scene
from armlab.models.elbow_truth import elbow_truth
from armlab.perturbations.scenario import load_scenario
from armlab.protocols._files import write_json, write_new
from armlab.protocols.conditioning_window import (
    estimate_protocol,
    linearisation_bias,
    simulate_protocol,
    window_specs,
)
from armlab.protocols.fractional_elbow import estimate_fractional, simulate_fractional
from armlab.protocols.vfs_results import estimate_vfs
from armlab.protocols.virtual_force_sensor import simulate_vfs

__all__ = [
    "PROTOCOLS",
    "format_table",
    "reestimate",
    "run_protocol",
]

PROTOCOLS = ("conditioning_window", "fractional_elbow", "virtual_force_sensor")


def _save_trials(path: Path, trials: TrialSet, extra_attrs: dict) -> None:
    """Write the trial file; drawing aids (body points) stay out of it."""
    saved = {k: v for k, v in trials.channels.items() if not k.endswith("_points")}
    write_trials(
        path,
        TrialSet(
            fs_hz=trials.fs_hz,
            onset_index=trials.onset_index,
            channels=saved,
            units={k: trials.units[k] for k in saved},
            trial_meta=trials.trial_meta,
            attrs={**trials.attrs, **extra_attrs},
        ),
    )


@dataclass(frozen=True, eq=False)
class _Simulated:
    """What a protocol's simulation hands to the shared run: trials, the scene, how to estimate."""

    trials: TrialSet
    scene_xml: str
    attrs: dict  # extra attributes of the trial file (beside the config)
    estimate: Callable[[], tuple[dict, dict]]  # -> (results, series)


def _sim_conditioning(cfg: ExperimentConfig) -> _Simulated:
    rec, scenario = simulate_protocol(cfg)

    def estimate() -> tuple[dict, dict]:
        results, series = estimate_protocol(rec.trials, cfg.estimator, window_specs(scenario, cfg.estimator))
        results["linearisation_bias"] = linearisation_bias(cfg)
        return results, series

    return _Simulated(rec.trials, rec.scene.xml, {"scenario": scenario.name}, estimate)


def _out_conditioning(viz, out_dir: Path, trials: TrialSet, results: dict, series: dict, cfg) -> dict:
    written = {}
    if cfg.output.figures:
        written["fig4"] = viz.plot_window_sweep(results, out_dir / "fig4_full.png", model="full")
        written["fig5"] = viz.plot_window_sweep(results, out_dir / "fig5_reduced.png", model="reduced")
        written["fig6"] = viz.plot_validation(series, out_dir / "fig6_validation.png")
        written["errors"] = viz.plot_error_vs_window(results, out_dir / "errors.png")
    if cfg.output.recording:
        written["recording"] = viz.write_recording(out_dir / "trials.rrd", trials, results)
    return written


def _sim_fractional(cfg: ExperimentConfig) -> _Simulated:
    rec = simulate_fractional(cfg)
    return _Simulated(
        rec.trials,
        rec.scene.xml,
        {"scenario": rec.scenario.name},
        lambda: estimate_fractional(rec.trials, cfg.frf, rec.truth),
    )


def _out_fractional(viz, out_dir: Path, trials: TrialSet, results: dict, series: dict, cfg) -> dict:
    written = {}
    if cfg.output.figures:
        written["fig4"] = viz.plot_bode_fits(series, results, out_dir / "fig4_bode_fits.png")
        written["fig5"] = viz.plot_time_overlay(series, out_dir / "fig5_time_overlay.png")
        written["fig6"] = viz.plot_bode_literature(series, out_dir / "fig6_bode_literature.png", results)
    written["table"] = write_new(out_dir / "table_I.txt", viz.format_fractional_table(results) + "\n")
    if cfg.output.recording:
        written["recording"] = viz.write_fractional_recording(out_dir / "trials.rrd", trials, results)
    return written


def _sim_vfs(cfg: ExperimentConfig) -> _Simulated:
    rec = simulate_vfs(cfg)
    scene = rec.scenes.get("arm") or rec.scenes.get("fixture") or rec.scenes["robot_id"]
    return _Simulated(
        rec.trials,
        scene,
        {"truth_json": json.dumps(rec.truth)},
        lambda: estimate_vfs(rec.trials, cfg.vfs, rec.truth),
    )


def _out_vfs(viz, out_dir: Path, trials: TrialSet, results: dict, series: dict, cfg) -> dict:
    written = {"tables": write_new(out_dir / "tables.txt", viz.format_vfs_tables(results) + "\n")}
    if cfg.output.figures:
        written.update(viz.plot_vfs_figures(results, series, out_dir))
    if cfg.output.recording:
        written["recording"] = viz.write_vfs_recording(out_dir / "trials.rrd", trials, results)
    return written


# protocol -> (simulate, write its figures/tables/recording); the run itself is shared
_RUNS = {
    "conditioning_window": (_sim_conditioning, _out_conditioning),
    "fractional_elbow": (_sim_fractional, _out_fractional),
    "virtual_force_sensor": (_sim_vfs, _out_vfs),
}


def _run(cfg: ExperimentConfig, out_dir: Path, config_yaml: str, timing: dict) -> dict:
    from armlab import viz  # the only place figures and recordings are made

    simulate, outputs = _RUNS[cfg.protocol_name]
    from armlab.sim.lab import LAB_EFFECTS

    applied = LAB_EFFECTS if cfg.protocol_name == "conditioning_window" else ()
    on = [n for n in enabled_effects(cfg.effects) if n not in applied]
    if on:  # never silently ignore a switched-on effect
        raise ConfigError(
            f"effects {on} are not simulated by protocol {cfg.protocol_name!r} yet; it applies "
            f"{list(applied)}; the joint_1dof simulation (armlab.sim.joint_1dof, used by "
            "`armlab diagnose-benchmark`) applies the catalogue"
        )
    t0 = time.perf_counter()
    sim = simulate(cfg)
    timing["simulate_s"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    results, series = sim.estimate()
    timing["estimate_s"] = time.perf_counter() - t1
    trials = sim.trials
    results["simulated_s"] = trials.n_trials * trials.n_samples / trials.fs_hz
    t2 = time.perf_counter()
    if cfg.output.trials:
        _save_trials(out_dir / "trials.h5", trials, {"config_yaml": config_yaml, **sim.attrs})
    write_new(out_dir / "scene.xml", sim.scene_xml)
    results["files"] = {k: str(v) for k, v in outputs(viz, out_dir, trials, results, series, cfg).items()}
    timing["outputs_s"] = time.perf_counter() - t2
    return results


def run_protocol(cfg: ExperimentConfig, out_dir: Path, config_yaml: str = "") -> dict:
    """Simulate, estimate and write every output of one protocol run.

    Args:
        cfg: the validated experiment configuration.
        out_dir: the run directory (Hydra's); must not already contain results.
        config_yaml: the composed config, stored with the trials for re-estimation.

    Returns:
        The results dict (also written to ``results.json``).
    """
    if cfg.protocol_name not in _RUNS:
        raise ConfigError(f"unknown protocol {cfg.protocol_name!r}; valid: {list(PROTOCOLS)}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if (out_dir / "results.json").exists():
        raise DataError(f"{out_dir} already holds results.json; armlab never overwrites a run")
    timing: dict = {}
    t0 = time.perf_counter()
    results = _run(cfg, out_dir, config_yaml, timing)
    timing["total_s"] = time.perf_counter() - t0
    results["timing"] = timing
    write_json(out_dir / "results.json", results)
    return results


def _group(schema, stored, name: str):
    """The stored config group ``name`` on its schema (defaults for fields it lacks)."""
    return OmegaConf.merge(OmegaConf.structured(schema), stored.get(name, {}))


def reestimate(run_dir: Path, overrides: list[str] | None = None) -> tuple[Path, dict]:
    """Re-run the estimation on a run's saved ``trials.h5`` without simulating again.

    The settings come from the run's stored config, updated by overrides of the form
    ``estimator.<field>=<value>`` (conditioning_window), ``frf.<field>=<value>``
    (fractional_elbow) or ``vfs.<field>=<value>`` (virtual_force_sensor). Results go to a new ``reestimate_<timestamp>/`` directory inside the run
    directory.
    """
    run_dir = Path(run_dir)
    path = run_dir / "trials.h5"
    if not path.is_file():
        raise DataError(f"{run_dir} has no trials.h5; give a run directory made by `armlab run`")
    trials = read_trials(path)
    stored = OmegaConf.create(trials.attrs.get("config_yaml") or "{}")
    protocol = str(trials.attrs.get("protocol", "conditioning_window"))
    if protocol == "fractional_elbow":
        frf = apply_overrides(_group(FrfConfig, stored, "frf"), "frf", overrides)
        truth = None
        if "elbow" in stored:  # the truth is rebuilt from the stored model settings (no simulation)
            exp = to_experiment(OmegaConf.merge(OmegaConf.structured(ExperimentConfig), stored))
            truth = elbow_truth(build_direct_drive_scene(exp.elbow, exp.sim), exp.elbow, trials.fs_hz)
        results, _ = estimate_fractional(trials, frf, truth)
    elif protocol == "conditioning_window":
        estimator = apply_overrides(_group(EstimatorConfig, stored, "estimator"), "estimator", overrides)
        scenario = load_scenario(str(trials.attrs.get("scenario", "conditioning_window")))
        groups = sorted(set(np.asarray(trials.trial_meta["group"]).tolist()))
        scenario = scenario.subset(k_values=groups, n_trials=None)
        results, _ = estimate_protocol(trials, estimator, window_specs(scenario, estimator))
    elif protocol == "virtual_force_sensor":
        vfs = apply_overrides(_group(VfsConfig, stored, "vfs"), "vfs", overrides)
        results, _ = estimate_vfs(trials, vfs, json.loads(str(trials.attrs.get("truth_json", "{}"))))
    else:
        raise DataError(f"{path} holds trials of protocol {protocol!r}; valid: {list(PROTOCOLS)}")
    out = run_dir / f"reestimate_{datetime.now():%Y-%m-%d_%H-%M-%S-%f}"
    out.mkdir()
    write_json(out / "results.json", results)
    return out, results


def _fmt(x) -> str:
    return "  -  " if x is None else f"{x * 1000:.0f} ms"


def format_table(results: dict) -> str:
    """The run's results as a text table (printed at the end of ``armlab run``)."""
    if results.get("protocol") == "virtual_force_sensor":
        from armlab.viz import format_vfs_tables

        return format_vfs_tables(results) + _timing_line(results)
    if results.get("protocol") == "fractional_elbow":
        from armlab.viz import format_fractional_table

        return format_fractional_table(results) + _timing_line(results)
    return _conditioning_table(results) + _timing_line(results)


def _timing_line(results: dict) -> str:
    if "timing" not in results:
        return ""
    t = results["timing"]
    return (
        f"\nsimulated {results['simulated_s']:.0f} s in {t['simulate_s']:.1f} s "
        f"({results['simulated_s'] / t['simulate_s']:.0f}x real time); estimation {t['estimate_s']:.2f} s; "
        f"outputs {t['outputs_s']:.1f} s; total {t['total_s']:.1f} s"
    )


def _conditioning_table(results: dict) -> str:
    lines = [
        "T_obs  k  ext |   cond  |  eig(K_s)       | K err  D err  xi err | reduced K err  D err | VAF1  VAF2",
    ]
    for w in results["windows"]:
        red = w.get("reduced", {})
        lines.append(
            f"{w['t_obs_s'] * 1000:4.0f}ms {w['k']:2d}  {'*' if w['extension'] else ' '}  | {w.get('cond', float('nan')):7.0f} | "
            f"{w['eig_Ks'][0]:6.2f} {w['eig_Ks'][1]:6.2f}  | {w.get('K_rel_err', float('nan')) * 100:5.1f}% "
            f"{w.get('D_rel_err', float('nan')) * 100:5.1f}% {w.get('xi_rel_err', float('nan')) * 100:5.1f}% | "
            f"{red.get('K_rel_err', float('nan')) * 100:11.1f}%  {red.get('D_rel_err', float('nan')) * 100:5.1f}% | "
            f"{w['validation']['vaf_pct'][0]:4.0f}% {w['validation']['vaf_pct'][1]:4.0f}%"
        )
    for model in ("full", "reduced"):
        c = results["criteria"][model]
        lines.append(
            f"{model:8s} criteria first met: K pos. def. {_fmt(c['K_pd_from_s'])}, quasi-symmetric "
            f"{_fmt(c['symmetric_from_s'])}, quasi-constant {_fmt(c['constant_from_s'])}"
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
            f"xi {b['xi_rel_err'] * 100:.2f} %"
        )
    return "\n".join(lines)
