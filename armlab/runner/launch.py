"""The ``armlab run`` verb: every override (and every value of a sweep) validated up front, then
Hydra's launch, single run or multirun, with never-overwrite, ``resume=true`` and interrupts handled.

Nothing is written before the checks pass (one-line :class:`~armlab.errors.ConfigError`); each job
checks its folder (:mod:`armlab.runner.resume`) before Hydra's record is written; SIGTERM/SIGINT end
the run with the command that finishes it (:mod:`armlab.runner.interrupt`). The protocol comes
from the registry; nothing here names one.
"""

from __future__ import annotations

import os
import shlex
import sys
import warnings
from pathlib import Path

from armlab.errors import ArmlabError, ArmlabWarning, ConfigError

__all__ = ["internal_error", "launch", "sweep_values"]


def internal_error(exc: BaseException) -> str:
    """The one-line report of an exception no check foresaw (a safety net, not input handling)."""
    msg = " ".join(str(exc).split()) or "(no message)"
    return (
        f"internal error: {type(exc).__name__}: {msg} (please report it; rerun with ARMLAB_DEBUG=1 "
        "for the traceback)"
    )


def _hydra_task(cfg, resume: bool, progress: bool = True) -> None:
    """One Hydra job: check (or resume) its folder, run the protocol (its progress shown unless
    ``progress`` is false; as log lines naming the job in a multirun), print its table."""
    from hydra.core.hydra_config import HydraConfig
    from hydra.types import RunMode
    from omegaconf import OmegaConf

    from armlab.config.store import to_experiment
    from armlab.protocols import registry
    from armlab.runner.progress import display
    from armlab.runner.resume import prepare_run_dir
    from armlab.runner.run import format_table, run_protocol

    exp = to_experiment(cfg)
    protocol = registry.get(exp.protocol_name, need="run")
    if protocol.validate is not None:  # this job's combination of sweep values (checked one by one up front)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ArmlabWarning)  # shown once up front
            protocol.validate(exp)
    hydra_cfg = HydraConfig.instance().cfg
    out_dir = Path(hydra_cfg.hydra.runtime.output_dir)
    config_yaml = OmegaConf.to_yaml(cfg)
    meta = {
        "hydra_yaml": OmegaConf.to_yaml(hydra_cfg),
        "overrides_yaml": OmegaConf.to_yaml(hydra_cfg.hydra.overrides.task),
    }
    if not prepare_run_dir(out_dir, resume=resume, config_yaml=config_yaml, **meta):
        print(f"{out_dir} is complete (results.json); left untouched")
        return
    job = f"job {hydra_cfg.hydra.job.num}" if hydra_cfg.hydra.mode == RunMode.MULTIRUN else None
    with display(progress, job=job):
        results = run_protocol(exp, out_dir, config_yaml)
    if exp.output.print_table:
        print(format_table(results))
    print(f"outputs: {out_dir}")


def sweep_values(overrides: list[str]) -> list[list[str]]:
    """Per override, the ``key=value`` items of its sweep as Hydra reads it (``seed=0,1``,
    ``k=[1],[2]``, ``x=range(1,3)``); one item for a plain override."""
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.errors import HydraException

    out = []
    for item in overrides:
        try:
            (parsed,) = OverridesParser.create().parse_overrides([item])
        except HydraException as exc:
            raise ConfigError(f"{item}: {' '.join(str(exc).split())}") from None
        key = item.partition("=")[0]
        values = list(parsed.sweep_string_iterator()) if parsed.is_sweep_override() else None
        out.append([f"{key}={v}" for v in values] if values else [item])
    return out


def launch(args: list[str], *, progress: bool = True) -> int:
    """``armlab run [--multirun] [resume=true] [out=<dir>] <overrides>``; returns the exit status.

    ``progress``: show each job's progress (``progress=false`` of the command line: not). Like
    ``resume=``, it is armlab's argument, not a config key: it changes no result, so it is not
    stored with the run and a run resumes the same with or without it.

    Raises:
        ConfigError: a bad option or override (before Hydra makes any folder).
    """
    import hydra

    from armlab.config.store import CONFIG_DIR
    from armlab.data.outdir import hydra_out, take_out
    from armlab.data.rundir import resume_command
    from armlab.protocols.compose import check_effects, split_protocol
    from armlab.protocols.compose import compose as compose_protocol
    from armlab.runner import interrupt
    from armlab.runner.resume import given_folder, keep_file, plan_launch, restore_file

    multirun = "--multirun" in args or "-m" in args
    overrides = [a for a in args if a not in ("--multirun", "-m")]
    bad = [a for a in overrides if a.startswith("-")]
    if bad:
        raise ConfigError(f"unknown option(s) {bad}; valid: --multirun (or -m) and key=value overrides")
    # resume=<true|false> is armlab's, not Hydra's: finish an interrupted run or sweep folder
    flags = [a.partition("=")[2] for a in overrides if a.partition("=")[0] == "resume"]
    if any(v not in ("true", "false") for v in flags) or len(flags) > 1:
        raise ConfigError(
            f"resume={flags[-1] if len(flags) == 1 else flags}: give it once, as resume=true or resume=false"
        )
    resume = flags == ["true"]
    overrides = [a for a in overrides if a.partition("=")[0] != "resume"]
    out, overrides = take_out(overrides, "run")  # one convention: out=<dir> (the sweep folder of a multirun)
    if out is not None:
        overrides.append(hydra_out(out, multirun=multirun))
    overrides, note = plan_launch(overrides, multirun=multirun, resume=resume)
    if note is not None:
        print(note)
        return 0
    # validate everything up front (one-line errors, nothing written); of a sweep (a,b,c) its first
    # value (lists [a,b] are values, not sweeps)
    sweeps = sweep_values(overrides) if multirun else [[o] for o in overrides]
    first = [values[0] for values in sweeps]
    _, exp = compose_protocol(first)
    for i, values in enumerate(sweeps):  # each value of each sweep, the others at their first value
        for item in values[1:]:
            compose_protocol(first[:i] + [item] + first[i + 1 :])
    protocol, overrides = split_protocol(overrides)
    check_effects(protocol, exp)

    parent = os.getpid()
    started: list[str] = []  # the job folders this process entered (not those of joblib workers)

    def task(cfg) -> None:
        from hydra.core.hydra_config import HydraConfig

        interrupt.stop_with_parent(parent)  # in a joblib worker: stop when the parent is gone
        started.append(HydraConfig.get().runtime.output_dir)
        try:
            with interrupt.handle_termination():  # a joblib worker's main thread runs the task
                _hydra_task(cfg, resume, progress)
        except ArmlabError as exc:
            print(f"armlab: error: {exc}", file=sys.stderr)
            raise SystemExit(2) from None
        except Exception as exc:  # noqa: BLE001 - Hydra would print a traceback hint instead
            if os.environ.get("ARMLAB_DEBUG"):
                raise
            print(f"armlab: error: {internal_error(exc)}", file=sys.stderr)
            raise SystemExit(2) from None

    wrapped = hydra.main(config_path=str(CONFIG_DIR), config_name=protocol.name, version_base="1.3")(task)
    argv = sys.argv
    sys.argv = ["armlab"] + (["--multirun"] if multirun else []) + overrides
    sweep = given_folder(overrides, "hydra.sweep.dir") if multirun else None
    sweep_yaml = sweep / "multirun.yaml" if sweep is not None and resume else None
    kept = keep_file(sweep_yaml) if sweep_yaml else None
    try:
        with interrupt.handle_termination():
            wrapped()
    except interrupt.Interrupted as exc:
        if multirun:
            # the folder given, else Hydra's default one: the parent of a started job's folder
            where = sweep or (Path(started[-1]).parent if started else None)
            out = shlex.quote(f"out={where}") if where is not None else "out=<sweep folder>"
            fix = f"armlab run --multirun resume=true {out} <same sweep>"
        else:
            fix = resume_command(started[-1] if started else "<run folder>")
        print(
            f"armlab: interrupted ({exc}); the unfinished run is incomplete: finish it with `{fix}`",
            file=sys.stderr,
        )
        return 128 + exc.signum
    finally:
        sys.argv = argv
        if sweep_yaml:
            restore_file(sweep_yaml, kept)
    return 0
