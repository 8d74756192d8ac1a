"""``armlab`` command line: run protocols (Hydra), re-estimate saved trials, view recordings.

    armlab run [protocol=<name>] [out=<dir>] [Hydra overrides ...]  simulate + estimate into <dir>
    armlab run --multirun seed=0,1,2 [out=<sweep dir>] ...  sweep through Hydra's launcher
    armlab run resume=true out=<run_dir>                  finish an interrupted run (its overrides)
    armlab run --multirun resume=true out=<d> [sweep]     run a sweep's missing jobs only
    armlab estimate <run_dir> [<group>.<f>=<v>] [out=<dir>]  re-run estimation on saved trials.h5
                                                         (estimator | frf | vfs, by protocol)
    armlab view <run_dir>                                open the run's rerun recording
    armlab fit-joint <csv|folder> [frf.<f>=<v>] [out=<dir>]  FRF + Levy fits of real joint recordings

Every verb that writes names its output folder with ``out=<dir>`` (default: a new
``outputs/<protocol or verb>/<timestamp>``; armlab.data.outdir). Every verb takes
``progress=false``: no progress display (by default long work shows one on a terminal and log
lines elsewhere; :mod:`armlab.runner.progress`).

Bad input is reported on one line (``armlab: error: ...``, exit status 2), never as a traceback.
"""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path

from armlab.errors import ArmlabError, ArmlabWarning, ConfigError

__all__ = ["main"]


def _fail(msg: str) -> int:
    print(f"armlab: error: {msg}", file=sys.stderr)
    return 2


def _usage() -> str:
    from armlab.config.store import available_options
    from armlab.protocols import registry
    from armlab.protocols.compose import config_groups

    lines = [
        "usage: armlab <verb> [args]",
        "",
        "verbs:",
        "  run [--multirun] [protocol=<name>] [out=<dir>] [overrides]",
        "                                                  simulate a protocol and estimate impedance",
        "  run resume=true out=<run_dir>                   finish an interrupted run (same overrides, same",
        "                                                  results); a complete one is left untouched",
        "  run --multirun resume=true out=<sweep_dir> [sweep]",
        "                                                  run only a sweep's missing/incomplete jobs",
        "  estimate <run_dir> [<group>.<field>=<value>] [out=<dir>]",
        "                                                  re-run estimation on a run's trials.h5",
        "  view <run_dir>                                  open the run's rerun recording (trials.rrd)",
        "  diagnose data=<file|folder> protocol=<name> [diagnosis.<field>=<value>] [units=<u>] [out=<dir>]",
        "                                                  units= of joint CSV/.mat data when not rad and",
        "                                                  N·m: deg, Nmm or deg,Nmm (rad,Nm states SI; data",
        "                                                  outside human ranges are refused without it)",
        "  diagnose data=published protocol=<name> [out=<dir>]",
        "                                                  where the sim-to-real gap lies, which effect",
        "                                                  explains it, how far it shrinks",
        "  effects [protocol=<name>]                       list the catalogue of unmodelled effects",
        "  diagnose-benchmark [referee.<f>=<v>] [diagnosis.<f>=<v>] [out=<dir>]",
        "                                                  blind referee of the diagnosis",
        "  <verb> ... progress=false                       no progress display (default: live on a",
        "                                                  terminal, log lines on stderr otherwise)",
        "",
        "every verb that writes takes out=<dir> (default: a new outputs/<protocol or verb>/<timestamp>)",
    ]
    for p in registry.protocols():
        for c in p.commands:
            lines += [f"  {c.usage}", f"{'':50s}{c.help} ({p.name})"]
    lines += ["", f"protocols (default {registry.DEFAULT_PROTOCOL}):"]
    for p in registry.protocols():
        can = [v for v in ("run", "estimate", "diagnose", "referee") if p.name in registry.names(v)]
        lines.append(f"  {p.name}: {p.summary}")
        lines.append(f"      {p.paper}; can: {', '.join(can)}")
        if p.runs:
            groups = [
                "effects=[<name>,...]"
                if g == "effects"
                else f"{g}=<{'|'.join(available_options(g))}>"
                if available_options(g)
                else f"{g}.<field>"
                for g in config_groups(p)
            ]
            lines.append(f"      config groups: {' '.join(groups)}")
            if p.reestimate_group:
                lines.append(f"      armlab estimate takes {p.reestimate_group}.<field>=<value>")
    lines += ["", "examples:"] + [f"  armlab {e}" for p in registry.protocols() for e in p.examples]
    return "\n".join(lines) + "\n"


def compose(overrides: list[str]):
    """Compose and validate a protocol's experiment config (one-line errors for every bad override)."""
    from armlab.protocols.compose import compose as compose_protocol

    return compose_protocol(overrides)


def _run(args: list[str], show: bool) -> int:
    from armlab.runner.launch import launch

    return launch(args, progress=show)


def _estimate(args: list[str], show: bool) -> int:
    from armlab.data.outdir import take_out
    from armlab.runner.progress import display
    from armlab.runner.run import format_table, reestimate

    if not args or "=" in args[0]:
        return _fail(
            "estimate needs a run directory first: "
            "armlab estimate <run_dir> [<group>.<field>=<value>] [out=<dir>]"
        )
    out, rest = take_out(args[1:], "estimate")
    with display(show):
        out, results = reestimate(Path(args[0]), rest, out=out)
    print(format_table(results))
    print(f"outputs: {out}")
    return 0


def _view(args: list[str]) -> int:
    import shutil

    from armlab.data.rundir import require_complete
    from armlab.viz import view_command

    if len(args) != 1:
        return _fail("view needs exactly one run directory: armlab view <run_dir>")
    require_complete(Path(args[0]))
    rrd = Path(args[0]) / "trials.rrd"
    if not rrd.is_file():
        return _fail(f"{rrd} not found; give a run directory made by `armlab run` with output.recording=true")
    cmd = view_command(rrd)
    exe = shutil.which(cmd[0]) or str(Path(sys.executable).with_name(cmd[0]))
    if not Path(exe).exists():
        return _fail("the rerun viewer is not installed (pip install rerun-sdk)")
    return subprocess.call([exe, *cmd[1:]])


def _keyed(args: list[str], keys: tuple[str, ...], prefixes: tuple[str, ...]) -> tuple[dict, list[str]]:
    """Split ``key=value`` arguments into the named keys and the prefixed overrides."""
    named, rest = {}, []
    for item in args:
        key, sep, value = item.partition("=")
        if not sep:
            raise ConfigError(f"argument {item!r} must look like key=value")
        if key in keys:
            named[key] = value
        elif key.split(".", 1)[0] in prefixes and "." in key:
            rest.append(item)
        else:
            valid = [f"{k}=" for k in keys] + [f"{p}.<field>=" for p in prefixes]
            raise ConfigError(f"unknown argument {item!r}; valid: {valid}")
    return named, rest


def _diagnose(args: list[str], show: bool) -> int:
    from armlab.data.outdir import default_out, take_out
    from armlab.diagnosis.report_text import format_summary
    from armlab.protocols import registry
    from armlab.runner.diagnose import run_diagnosis
    from armlab.runner.progress import display

    out, args = take_out(args, "diagnose")
    named, rest = _keyed(args, ("data", "protocol", "out", "units"), ("diagnosis",))  # out= taken above
    missing = [k for k in ("data", "protocol") if not named.get(k)]
    if missing:
        return _fail(f"diagnose needs {missing}: armlab diagnose data=<file|folder> protocol=<name>")
    out = out or default_out("diagnose")
    if named["data"] == "published":  # the source paper's published figures as the measurement
        if named.get("units"):
            return _fail("data=published takes no units= (the published figures carry theirs)")
        with display(show):
            return _diagnose_published(named["protocol"], rest, out)
    registry.get(named["protocol"], need="diagnose")
    with display(show):
        out, results = run_diagnosis(
            Path(named["data"]), named["protocol"], rest, out, units=named.get("units") or None
        )
    print(format_summary(results))
    print(f"outputs: {out}")
    return 0


def _diagnose_published(protocol: str, overrides: list[str], out: Path) -> int:
    """``data=published``: the paper's published figures, diagnosed as measurements."""
    from armlab.reproduction import STUDIES

    if protocol not in STUDIES:
        return _fail(f"data=published is available for protocols {sorted(STUDIES)}, not {protocol!r}")
    if overrides:
        return _fail(f"data=published takes no diagnosis.* settings; got {overrides}")
    cfg = compose([f"protocol={protocol}"])[1]
    results = STUDIES[protocol](cfg, out)
    verdict = results.get("verdict")
    print(verdict.get("text", verdict) if isinstance(verdict, dict) else verdict)
    print(f"outputs: {out}")
    return 0


def _effects(args: list[str]) -> int:
    from armlab.config.effects import EFFECTS
    from armlab.protocols import registry

    named, _ = _keyed(args, ("protocol",), ())
    protocol = named.get("protocol")
    if protocol is not None and protocol not in registry.names():
        return _fail(f"no effects for protocol {protocol!r}; valid protocols: {sorted(registry.names())}")
    names = tuple(EFFECTS) if protocol is None else registry.get(protocol).catalogue
    scoring = [p for p in registry.protocols() if p.diagnosis is not None and protocol in (None, p.name)]
    for p in scoring:
        print(f"candidates of `armlab diagnose protocol={p.name}`: {', '.join(p.diagnosis.candidates)}")
    if scoring:
        print("(the others can be simulated but leave no gap these protocols can score)\n")
    for name in names:
        cls = EFFECTS[name]
        params = ", ".join(f"{k}={v:g}" for k, v in cls().params().items())
        print(f"{name}  [{cls.LEVEL}]  {params}")
        print(f"    {cls.PHYSICS}")
        print(f"    typical: {cls.SOURCE}")
        print(f"    protocols: {', '.join(p.name for p in registry.protocols() if name in p.catalogue)}")
        switches = [
            f"{p.name}: {p.lab_effects[name]}"
            for p in registry.protocols()
            if name in p.lab_effects and protocol in (None, p.name)
        ]
        if switches:
            print(f"    part of the lab, switched by: {'; '.join(switches)}")
        for other, trial in cls.CONFUSABLE.items():
            print(f"    confusable with {other}: separate with {trial}")
    return 0


def _benchmark(args: list[str], show: bool) -> int:
    from armlab.data.outdir import default_out, take_out
    from armlab.runner.diagnose import run_benchmark
    from armlab.runner.progress import display

    out, args = take_out(args, "diagnose-benchmark")
    _, rest = _keyed(args, ("out",), ("referee", "diagnosis"))  # out= taken above
    with display(show):
        out, summary = run_benchmark(rest, out or default_out("diagnose-benchmark"))
    print((out / "benchmark.md").read_text())
    print(f"outputs: {out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """The ``armlab`` command; returns the exit status (2 on bad input, with one ``armlab: error:``
    line). An exception no check foresaw is reported as an internal error on one line as well (the
    traceback with ``ARMLAB_DEBUG=1``): a safety net, not a way of handling bad input."""
    shown: set[str] = set()
    python_show = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None) -> None:
        """armlab's warnings on one line (``armlab: warning: ...``), each once per command (a sweep
        checks every value); others as Python prints them."""
        if not issubclass(category, ArmlabWarning):
            python_show(message, category, filename, lineno, file, line)
        elif str(message) not in shown:
            shown.add(str(message))
            print(f"armlab: warning: {message}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.simplefilter("always", ArmlabWarning)
        warnings.showwarning = show
        from armlab.runner.interrupt import Interrupted, handle_termination

        try:
            with handle_termination():  # SIGTERM like Ctrl-C: every writer removes its temporary
                return _main(argv)
        except ArmlabError as exc:
            return _fail(str(exc))
        except Interrupted as exc:
            print(
                f"armlab: interrupted ({exc}); its output may be incomplete (no half-written file is left)",
                file=sys.stderr,
            )
            return 128 + exc.signum
        except KeyboardInterrupt:
            print("armlab: interrupted", file=sys.stderr)
            return 130
        except Exception as exc:  # noqa: BLE001 - the last-resort guard of the command line
            if os.environ.get("ARMLAB_DEBUG"):
                raise
            from armlab.runner.launch import internal_error

            return _fail(internal_error(exc))


def _main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if not args or args[0] in ("-h", "--help", "help") or any(a in ("-h", "--help") for a in args[1:]):
        print(_usage())  # also `armlab <verb> --help`
        return 0
    verb, rest = args[0], args[1:]
    from armlab import viz
    from armlab.protocols import registry
    from armlab.runner.progress import display, split_flag

    show, rest = split_flag(rest)  # progress=true|false, taken by every verb
    handlers = {
        "run": lambda rest: _run(rest, show),
        "estimate": lambda rest: _estimate(rest, show),
        "view": _view,
        "diagnose": lambda rest: _diagnose(rest, show),
        "effects": _effects,
        "diagnose-benchmark": lambda rest: _benchmark(rest, show),
    }

    def command_handler(run):
        def handle(rest: list[str]) -> int:
            with display(show):  # a protocol's verb reports through armlab.progress like the others
                return run(rest, viz)

        return handle

    for protocol in registry.protocols():  # verbs that protocols bring (e.g. fit-joint)
        for command in protocol.commands:
            handlers[command.name] = command_handler(command.run)
    if verb not in handlers:
        return _fail(f"unknown verb {verb!r}; valid: {list(handlers)} (see armlab --help)")
    try:
        return handlers[verb](rest)
    except ArmlabError as exc:
        return _fail(str(exc))


if __name__ == "__main__":
    raise SystemExit(main())
