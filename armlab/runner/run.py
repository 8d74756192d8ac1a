"""Run a protocol end to end and write its outputs — the edge where files and figures happen.

Outputs in the run directory (never overwritten: a directory that already holds results is
refused; each file is written under a temporary name and renamed when complete, and
``results.json`` is written last: it marks the run complete, see :mod:`armlab.data.rundir`):
``results.json`` (docs/results_schema.md), ``trials.h5`` (docs/trial_format.md),
``scene.xml`` (the composed MJCF), and what the protocol's ``outputs`` hook writes (its figures,
tables and ``trials.rrd``, the rerun recording of every trial). The protocol comes from the
registry; nothing here names one.
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from datetime import datetime
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf

from armlab import progress
from armlab.config.schema import ExperimentConfig
from armlab.data.h5io import read_trials, write_trials
from armlab.data.rundir import (
    MARKER,
    partial_files,
    refusal,
    require_complete,
    resume_command,
    run_state,
)
from armlab.data.trial import TrialSet
from armlab.errors import ConfigError, DataError
from armlab.protocols import registry
from armlab.protocols._files import check_new_dir, new_dir, write_json, write_new
from armlab.protocols.base import OutputContext
from armlab.protocols.compose import check_effects
from armlab.runner.memory import small_pages

__all__ = [
    "format_table",
    "reestimate",
    "run_protocol",
]


def _saved_trials(trials: TrialSet, extra_attrs: dict) -> TrialSet:
    """What the trial file holds: drawing aids (body points) stay out of it. Its own dicts, taken
    before the file is written in the background (the arrays are shared: :func:`_run` makes them
    read-only until the file is written)."""
    saved = {k: v for k, v in trials.channels.items() if not k.endswith("_points")}
    return TrialSet(
        fs_hz=trials.fs_hz,
        onset_index=trials.onset_index,
        channels=saved,
        units={k: trials.units[k] for k in saved},
        trial_meta=dict(trials.trial_meta),
        attrs={**trials.attrs, **extra_attrs},
    )


def _freeze(arrays) -> list[np.ndarray]:
    """Make the writeable ones of ``arrays`` read-only; returns them (to be made writeable again)."""
    frozen = [a for a in arrays if isinstance(a, np.ndarray) and a.flags.writeable]
    for a in frozen:
        a.flags.writeable = False
    return frozen


def _thaw(frozen: list[np.ndarray]) -> None:
    """Make :func:`_freeze`'s arrays writeable again: the ones that own their memory first (NumPy
    refuses a view while its base is read-only, whichever order they were frozen in)."""
    for arr in sorted(frozen, key=lambda a: a.base is not None):
        arr.flags.writeable = True


def _run(cfg: ExperimentConfig, out_dir: Path, config_yaml: str, timing: dict) -> dict:
    protocol = registry.get(cfg.protocol_name, need="run")
    check_effects(protocol, cfg)
    # One background thread: rerun is imported once the protocol has simulated (when the run
    # records; not during the simulation, whose rollout keeps both cores busy), then the trial file
    # is compressed (HDF5's deflate runs without the GIL) from the end of the
    # simulation on, while the protocol estimates and then draws its figures and recording;
    # leaving the block waits for it, so the file is complete (or its error raised) before
    # results.json can mark the run complete; a failed estimation still leaves the complete trial
    # file (the folder is then an unfinished run, which `resume=true` finishes). The arrays saved
    # are read-only while the file is written: an in-place write by the estimation or the outputs
    # raises instead of changing the file.
    frozen: list[np.ndarray] = []
    try:
        with ThreadPoolExecutor(max_workers=1) as background:
            # what the simulation can load beforehand (Protocol.preload) loads while viz is imported
            # and the simulation prepares, on the core that is idle then
            preloading = background.submit(protocol.preload) if protocol.preload is not None else None
            from armlab import viz  # the only place figures and recordings are made

            t0 = time.perf_counter()
            progress.stage("simulate")  # each stage's size, where known, comes from the computation
            sim = protocol.simulate(cfg)
            timing["simulate_s"] = time.perf_counter() - t0
            if preloading is not None:
                preloading.result()  # done by now; raises what it raised
            if cfg.output.recording:
                background.submit(viz.preload_rerun)
            trials = sim.trials
            saving = None
            if cfg.output.trials:
                saved = _saved_trials(trials, {"config_yaml": config_yaml, **sim.attrs})
                frozen += _freeze([saved.onset_index, *saved.channels.values(), *saved.trial_meta.values()])
                saving = background.submit(write_trials, out_dir / "trials.h5", saved)
            t1 = time.perf_counter()
            progress.stage("estimate")
            results, series = sim.estimate()
            timing["estimate_s"] = time.perf_counter() - t1
            results["simulated_s"] = trials.n_trials * trials.n_samples / trials.fs_hz
            t2 = time.perf_counter()
            progress.stage("outputs")
            write_new(out_dir / "scene.xml", sim.scene_xml)
            ctx = OutputContext(
                viz=viz, out_dir=out_dir, trials=trials, results=results, series=series, cfg=cfg
            )
            written = protocol.outputs(ctx) if protocol.outputs is not None else {}
            if saving is not None:
                saving.result()
    finally:  # the writer has finished (leaving the pool waits for it)
        _thaw(frozen)
    results["files"] = {k: str(v) for k, v in written.items()}
    timing["outputs_s"] = time.perf_counter() - t2
    return results


def run_protocol(cfg: ExperimentConfig, out_dir: Path, config_yaml: str = "") -> dict:
    """Simulate, estimate and write every output of one protocol run.

    Args:
        cfg: the validated experiment configuration (an instance of the protocol's schema).
        out_dir: the run directory (Hydra's); must not already contain results.
        config_yaml: the composed config, stored with the trials for re-estimation.

    Returns:
        The results dict (also written to ``results.json``).
    """
    registry.get(cfg.protocol_name, need="run")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    state = run_state(out_dir)
    if state in ("complete", "foreign"):
        raise refusal(out_dir, state)
    left = partial_files(out_dir)
    if left:  # refused before simulating, not after
        raise DataError(
            f"{out_dir} holds outputs of an unfinished run ({', '.join(p.name for p in left)}); "
            f"finish it with `{resume_command(out_dir)}`, or choose a new run directory"
        )
    timing: dict = {}
    t0 = time.perf_counter()
    with small_pages():  # no page-fault stalls in the run's large arrays (armlab.runner.memory)
        results = _run(cfg, out_dir, config_yaml, timing)
    timing["total_s"] = time.perf_counter() - t0
    results["timing"] = timing
    write_json(out_dir / MARKER, results)  # last: it marks the run complete (armlab.data.rundir)
    return results


@small_pages()  # no page-fault stalls in its large arrays (armlab.runner.memory)
def reestimate(
    run_dir: Path, overrides: list[str] | None = None, out: Path | None = None
) -> tuple[Path, dict]:
    """Re-run the estimation on a run's saved ``trials.h5`` without simulating again.

    The settings come from the run's stored config, updated by overrides of the protocol's
    re-estimation group (``<group>.<field>=<value>``; the group is the protocol's
    ``reestimate_group``). Results go to ``out`` (new or empty; ``out=`` of ``armlab estimate``) or
    by default to a new ``reestimate_<timestamp>/`` directory inside the run directory, with
    ``overrides.yaml`` (the overrides given) and ``config.yaml`` (the stored config they were applied
    to); ``results.json`` (written last) repeats both under ``"reestimate"``.
    """
    run_dir = Path(run_dir)
    path = run_dir / "trials.h5"
    require_complete(run_dir)
    if not path.is_file():
        raise DataError(f"{run_dir} has no trials.h5; give a run directory made by `armlab run`")
    if out is not None:
        check_new_dir(out)  # before reading the trials: a refused folder costs nothing
    trials = read_trials(path)
    stored = OmegaConf.create(trials.attrs.get("config_yaml") or "{}")
    name = str(trials.attrs.get("protocol", registry.DEFAULT_PROTOCOL))
    try:
        protocol = registry.get(name, need="estimate")
    except ConfigError as exc:
        raise DataError(f"{path} holds trials of protocol {name!r}: {exc}") from None
    overrides = list(overrides or [])
    progress.stage("estimate")
    results = protocol.reestimate(trials, stored, overrides)
    out = new_dir(out if out is not None else run_dir / f"reestimate_{datetime.now():%Y-%m-%d_%H-%M-%S-%f}")
    write_new(out / "overrides.yaml", OmegaConf.to_yaml(overrides))
    write_new(out / "config.yaml", OmegaConf.to_yaml(stored))
    results["reestimate"] = {"run": str(run_dir), "trials": str(path), "overrides": overrides}
    write_json(out / MARKER, results)
    return out, results


def format_table(results: dict) -> str:
    """The run's results as text (printed at the end of ``armlab run`` and ``armlab estimate``)."""
    from armlab import viz

    name = results.get("protocol", registry.DEFAULT_PROTOCOL)
    return registry.get(name, need="run").format_table(results, viz) + _timing_line(results)


def _timing_line(results: dict) -> str:
    if "timing" not in results:
        return ""
    t = results["timing"]
    return (
        f"\nsimulated {results['simulated_s']:.0f} s in {t['simulate_s']:.1f} s "
        f"({results['simulated_s'] / t['simulate_s']:.0f}x real time); estimation {t['estimate_s']:.2f} s; "
        f"outputs {t['outputs_s']:.1f} s; total {t['total_s']:.1f} s"
    )
