"""``armlab`` command line: run protocols (Hydra), re-estimate saved trials, view recordings.

    armlab run [protocol=<name>] [Hydra overrides ...]   simulate + estimate, outputs in the run dir
    armlab run --multirun seed=0,1,2 ...                 sweep through Hydra's launcher
    armlab estimate <run_dir> [<group>.<field>=<v>]      re-run estimation on saved trials.h5
                                                         (estimator | frf | vfs, by protocol)
    armlab view <run_dir>                                open the run's rerun recording
    armlab fit-joint <csv|folder> [frf.<f>=<v>] [out=<dir>]  FRF + Levy fits of real joint recordings

Bad input is reported on one line (``armlab: error: ...``, exit status 2), never as a traceback.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from armlab.errors import ArmlabError, ConfigError

__all__ = ["main"]

GROUPS = ("protocol", "arm", "robot", "sensors", "scenario", "estimator")
VERBS = ("run", "estimate", "view", "fit-joint", "diagnose", "effects", "diagnose-benchmark")


def _fail(msg: str) -> int:
    print(f"armlab: error: {msg}", file=sys.stderr)
    return 2


def _usage() -> str:
    from armlab.config.store import available_options

    protocols = ", ".join(available_options("protocol"))
    return (
        "usage: armlab <verb> [args]\n\n"
        "verbs:\n"
        "  run [--multirun] [protocol=<name>] [overrides]  simulate a protocol and estimate impedance\n"
        "  estimate <run_dir> [<group>.<field>=<value>]    re-run estimation on a run's trials.h5\n"
        "                                                  (estimator | frf | vfs, by protocol)\n"
        "  view <run_dir>                                  open the run's rerun recording (trials.rrd)\n"
        "  fit-joint <csv|folder> [frf.<field>=<value>] [out=<dir>]\n"
        "                                                  impedance/admittance fits of real 1-DoF joint\n"
        "                                                  recordings (t_s,position_rad,torque_Nm CSV)\n"
        "  diagnose data=<file|folder> protocol=<name> [diagnosis.<field>=<value>] [out=<dir>]\n"
        "  diagnose data=published protocol=conditioning_window|virtual_force_sensor [out=<dir>]\n"
        "                                                  where the sim-to-real gap lies, which effect\n"
        "                                                  explains it, how far it shrinks\n"
        "  effects [protocol=<name>]                       list the catalogue of unmodelled effects\n"
        "  diagnose-benchmark [referee.<f>=<v>] [diagnosis.<f>=<v>] [out=<dir>]\n"
        "                                                  blind referee of the diagnosis\n\n"
        f"protocols: {protocols}\n"
        "config groups: " + ", ".join(f"{g}=<{'|'.join(available_options(g))}>" for g in GROUPS) + "\n"
        "examples:\n"
        "  armlab run protocol=conditioning_window seed=3 arm=planar_linear reflex.enabled=false\n"
        "  armlab run --multirun seed=0,1,2 hydra/launcher=joblib\n"
        "  armlab run protocol=fractional_elbow elbow.impedance=fractional elbow.fractional_order=0.5\n"
        "  armlab run protocol=virtual_force_sensor capstan.cable=rigid capstan.drag=false\n"
    )


def compose(overrides: list[str]):
    """Compose and validate the experiment config (one-line errors for every bad override)."""
    from hydra import compose as hydra_compose
    from hydra import initialize_config_dir
    from hydra.errors import HydraException
    from omegaconf.errors import OmegaConfBaseException

    from armlab.config.store import CONFIG_DIR, available_options, register_configs, to_experiment

    for item in overrides:
        key, sep, value = item.partition("=")
        if sep and key.lstrip("+") == "effects":
            names = [n.strip() for n in value.strip().strip("[]").split(",") if n.strip()]
            unknown = [n for n in names if n not in available_options("effects")]
            if unknown:
                raise ConfigError(f"unknown effect(s) {unknown}; valid: {available_options('effects')}")
        elif sep and key in GROUPS and value not in available_options(key):
            raise ConfigError(f"unknown {key} {value!r}; valid: {available_options(key)}")
    selected = [
        n.strip()
        for o in overrides
        if o.lstrip("+").startswith("effects=")
        for n in o.partition("=")[2].strip("[] ").split(",")
    ]
    for item in overrides:
        parts = item.partition("=")[0].split(".")
        if parts[0] == "effects" and len(parts) > 2 and parts[1] not in selected:
            raise ConfigError(
                f"{item}: effect {parts[1]!r} is not switched on; add effects=[{parts[1]}] "
                f"(selected: {selected or 'none'})"
            )
    register_configs()
    try:
        with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
            cfg = hydra_compose(
                config_name="config", overrides=[o for o in overrides if not o.startswith("hydra")]
            )
    except (HydraException, OmegaConfBaseException) as exc:
        raise ConfigError(str(exc).strip().splitlines()[0]) from None
    return cfg, to_experiment(cfg)


def _hydra_task(cfg) -> None:
    from hydra.core.hydra_config import HydraConfig
    from omegaconf import OmegaConf

    from armlab.config.store import to_experiment
    from armlab.protocols.runner import format_table, run_protocol

    exp = to_experiment(cfg)
    out_dir = Path(HydraConfig.get().runtime.output_dir)
    results = run_protocol(exp, out_dir, OmegaConf.to_yaml(cfg))
    if exp.output.print_table:
        print(format_table(results))
    print(f"outputs: {out_dir}")


def _run(args: list[str]) -> int:
    import hydra

    from armlab.config.store import CONFIG_DIR, register_configs

    multirun = "--multirun" in args or "-m" in args
    overrides = [a for a in args if a not in ("--multirun", "-m")]
    bad = [a for a in overrides if a.startswith("-")]
    if bad:
        return _fail(f"unknown option(s) {bad}; valid: --multirun (or -m) and key=value overrides")
    if not multirun:
        compose(overrides)  # validates everything up front: one-line errors
    else:
        # validate the first value of each sweep (a,b,c); lists [a,b] are values, not sweeps
        compose([o if o.partition("=")[2].startswith(("[", "{")) else o.split(",")[0] for o in overrides])
    register_configs()

    def task(cfg) -> None:
        try:
            _hydra_task(cfg)
        except ArmlabError as exc:
            print(f"armlab: error: {exc}", file=sys.stderr)
            raise SystemExit(2) from None

    wrapped = hydra.main(config_path=str(CONFIG_DIR), config_name="config", version_base="1.3")(task)
    argv = sys.argv
    sys.argv = ["armlab"] + (["--multirun"] if multirun else []) + overrides
    try:
        wrapped()
    finally:
        sys.argv = argv
    return 0


def _estimate(args: list[str]) -> int:
    from armlab.protocols.runner import format_table, reestimate

    if not args:
        return _fail("estimate needs a run directory: armlab estimate <run_dir> [<group>.<field>=<value>]")
    out, results = reestimate(Path(args[0]), args[1:])
    print(format_table(results))
    print(f"outputs: {out}")
    return 0


def _view(args: list[str]) -> int:
    import shutil

    from armlab.viz import view_command

    if len(args) != 1:
        return _fail("view needs exactly one run directory: armlab view <run_dir>")
    rrd = Path(args[0]) / "trials.rrd"
    if not rrd.is_file():
        return _fail(f"{rrd} not found; give a run directory made by `armlab run` with output.recording=true")
    cmd = view_command(rrd)
    exe = shutil.which(cmd[0]) or str(Path(sys.executable).with_name(cmd[0]))
    if not Path(exe).exists():
        return _fail("the rerun viewer is not installed (pip install rerun-sdk)")
    return subprocess.call([exe, *cmd[1:]])


def _fit_joint(args: list[str]) -> int:
    from armlab.protocols.joint_report import (
        default_out_dir,
        fit_joint_recordings,
        format_joint_table,
        joint_frf_config,
    )

    if not args or "=" in args[0]:
        return _fail("fit-joint needs a CSV file or folder: armlab fit-joint <csv|folder> [frf.<f>=<v>]")
    out = default_out_dir()
    rest = []
    for item in args[1:]:
        if item.startswith("out="):
            out = Path(item.partition("=")[2])
        else:
            rest.append(item)
    results = fit_joint_recordings(Path(args[0]), joint_frf_config(rest), out)
    print(format_joint_table(results))
    print(f"outputs: {out}")
    return 0


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


def _diagnose(args: list[str]) -> int:
    from armlab.diagnosis.report import format_summary
    from armlab.protocols.diagnosis_run import default_diagnosis_dir, run_diagnosis

    named, rest = _keyed(args, ("data", "protocol", "out"), ("diagnosis",))
    missing = [k for k in ("data", "protocol") if not named.get(k)]
    if missing:
        return _fail(f"diagnose needs {missing}: armlab diagnose data=<file|folder> protocol=<name>")
    out = Path(named["out"]) if named.get("out") else default_diagnosis_dir()
    if named["data"] == "published":  # the source paper's published figures as the measurement
        return _diagnose_published(named["protocol"], rest, out)
    out, results = run_diagnosis(Path(named["data"]), named["protocol"], rest, out)
    print(format_summary(results))
    print(f"outputs: {out}")
    return 0


def _diagnose_published(protocol: str, overrides: list[str], out: Path) -> int:
    """``data=published``: the paper's thresholds (conditioning) or Table III pattern (VFS)."""
    valid = ("conditioning_window", "virtual_force_sensor")
    if protocol not in valid:
        return _fail(f"data=published is available for protocols {list(valid)}, not {protocol!r}")
    if overrides:
        return _fail(f"data=published takes no diagnosis.* settings; got {overrides}")
    cfg = compose([f"protocol={protocol}"])[1]
    if protocol == "conditioning_window":
        from armlab.diagnosis.published_conditioning import run_published_conditioning

        results = run_published_conditioning(cfg, out)
    else:
        from armlab.diagnosis.published_vfs import run_published_vfs

        results = run_published_vfs(cfg, out)
    verdict = results.get("verdict")
    print(verdict.get("text", verdict) if isinstance(verdict, dict) else verdict)
    print(f"outputs: {out}")
    return 0


def _effects(args: list[str]) -> int:
    from armlab.config.effects import EFFECTS, effect_names

    named, _ = _keyed(args, ("protocol",), ())
    protocol = named.get("protocol")
    names = effect_names(protocol)
    if protocol is not None and not names:
        protocols = sorted({p for c in EFFECTS.values() for p in c.PROTOCOLS})
        return _fail(f"no effects for protocol {protocol!r}; valid protocols: {protocols}")
    if protocol is None or protocol == "joint_1dof":
        from armlab.diagnosis.joint_models import JOINT_SURROGATES

        print(f"candidates of `armlab diagnose protocol=joint_1dof`: {', '.join(JOINT_SURROGATES)}")
    if protocol is None or protocol == "conditioning_window":
        from armlab.diagnosis.cond_models import COND_SURROGATES

        print(f"candidates of `armlab diagnose protocol=conditioning_window`: {', '.join(COND_SURROGATES)}")
    if protocol in (None, "joint_1dof", "conditioning_window"):
        print("(the others can be simulated but leave no gap these protocols can score)\n")
    for name in names:
        cls = EFFECTS[name]
        params = ", ".join(f"{k}={v:g}" for k, v in cls().params().items())
        print(f"{name}  [{cls.LEVEL}]  {params}")
        print(f"    {cls.PHYSICS}")
        print(f"    typical: {cls.SOURCE}")
        print(f"    protocols: {', '.join(cls.PROTOCOLS)}")
        for other, trial in cls.CONFUSABLE.items():
            print(f"    confusable with {other}: separate with {trial}")
    return 0


def _benchmark(args: list[str]) -> int:
    from armlab.protocols.diagnosis_run import default_diagnosis_dir, run_benchmark

    named, rest = _keyed(args, ("out",), ("referee", "diagnosis"))
    out = Path(named["out"]) if named.get("out") else default_diagnosis_dir("diagnose-benchmark")
    out, summary = run_benchmark(rest, out)
    print((out / "benchmark.md").read_text())
    print(f"outputs: {out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if not args or args[0] in ("-h", "--help", "help"):
        print(_usage())
        return 0
    verb, rest = args[0], args[1:]
    handlers = {
        "run": _run,
        "estimate": _estimate,
        "view": _view,
        "fit-joint": _fit_joint,
        "diagnose": _diagnose,
        "effects": _effects,
        "diagnose-benchmark": _benchmark,
    }
    if verb not in handlers:
        return _fail(f"unknown verb {verb!r}; valid: {list(VERBS)} (see armlab --help)")
    try:
        return handlers[verb](rest)
    except ArmlabError as exc:
        return _fail(str(exc))


if __name__ == "__main__":
    raise SystemExit(main())
