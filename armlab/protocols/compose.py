"""Composing a protocol's typed experiment with Hydra, with one-line errors for every bad override.

Each protocol composes only its own groups (its schema's fields): an override of a group it does
not read is a :class:`~armlab.errors.ConfigError` naming the groups it does read.
"""

from __future__ import annotations

from dataclasses import fields, is_dataclass

from armlab.config.effects import EFFECTS, enabled_effects
from armlab.config.schema import ExperimentConfig
from armlab.config.store import CONFIG_DIR, available_options, to_experiment
from armlab.config.validate import check_finite
from armlab.errors import ConfigError
from armlab.protocols import registry
from armlab.protocols.base import Protocol

__all__ = [
    "check_effects",
    "compose",
    "config_groups",
    "split_protocol",
]


def split_protocol(overrides: list[str]) -> tuple[Protocol, list[str]]:
    """(the protocol chosen by ``protocol=<name>`` or the default, the other overrides)."""
    chosen = [o for o in overrides if o.partition("=")[0].lstrip("+") == "protocol"]
    rest = [o for o in overrides if o not in chosen]
    runnable = registry.names("run")
    if len(chosen) > 1:
        raise ConfigError(f"protocol given {len(chosen)} times ({chosen}); give one of {runnable}")
    name = chosen[0].partition("=")[2] if chosen else registry.DEFAULT_PROTOCOL
    if "," in name:
        raise ConfigError(
            f"protocol={name}: a sweep over protocols is not supported (each composes its own groups); "
            f"run one protocol per sweep, one of {runnable}"
        )
    return registry.get(name, need="run"), rest


def config_groups(protocol: Protocol) -> list[str]:
    """The config groups a protocol reads (its schema's dataclass fields)."""
    default = protocol.schema()
    return [f.name for f in fields(default) if is_dataclass(getattr(default, f.name))]


def _check(protocol: Protocol, overrides: list[str]) -> None:
    groups = config_groups(protocol)
    keys = [f.name for f in fields(protocol.schema) if f.name not in groups and f.name != "protocol_name"]
    seen: dict[str, str] = {}
    selected: list[str] = []  # the effects switched on by effects=[...]
    for item in overrides:
        key, sep, value = item.partition("=")
        if not sep:
            raise ConfigError(f"argument {item!r} must look like key=value (e.g. seed=3, arm=planar_linear)")
        bare = key.lstrip("+~")
        if not bare:
            raise ConfigError(f"argument {item!r} has no key before '='; give key=value (e.g. seed=3)")
        top = bare.split(".", 1)[0]
        if key.startswith("+") and (top == "hydra" or top.startswith("hydra/")):
            raise ConfigError(
                f"{item}: armlab sets Hydra's existing settings and groups (e.g. hydra/launcher=joblib, "
                f"hydra.launcher.n_jobs=2) but adds none; drop the '+'"
            )
        if bare in seen:
            raise ConfigError(f"{bare} is given twice ({seen[bare]!r} and {item!r}); give it once")
        seen[bare] = item
        if top == "hydra" or top.startswith("hydra/"):  # Hydra's own settings and groups (launcher, ...)
            continue
        if top not in groups and top not in keys:
            raise ConfigError(
                f"{item}: {top!r} is not read by protocol {protocol.name!r}; its groups: {groups}"
                f" (and {', '.join(keys)})"
            )
        if "." in bare and top in groups:
            _check_key_path(protocol, bare, item)
        if bare == "effects":
            names = [n.strip() for n in value.strip().strip("[]").split(",") if n.strip()]
            selected += names
            unknown = [n for n in names if n not in available_options("effects")]
            if unknown:
                raise ConfigError(f"unknown effect(s) {unknown}; valid: {available_options('effects')}")
        elif bare in groups and "." not in bare and not available_options(bare):
            names = [f.name for f in fields(getattr(protocol.schema(), bare))]
            raise ConfigError(
                f"{item}: {bare!r} has no options to choose; set its fields as {bare}.<field>=<value>, "
                f"its fields: {names}"
            )
        elif bare in groups and "." not in bare and value not in available_options(bare):
            raise ConfigError(f"unknown {bare} {value!r}; valid: {available_options(bare)}")
    for item in overrides:
        parts = item.partition("=")[0].lstrip("+~").split(".")
        if parts[0] == "effects" and len(parts) > 2 and parts[1] not in selected:
            raise ConfigError(
                f"{item}: effect {parts[1]!r} is not switched on; add effects=[{parts[1]}] "
                f"(selected: {selected or 'none'})"
            )
        if parts[0] == "effects" and len(parts) > 2:
            effect_keys = [f.name for f in fields(EFFECTS[parts[1]])]
            if parts[2] not in effect_keys or len(parts) > 3:
                raise ConfigError(
                    f"{item}: effect {parts[1]!r} has no key {'.'.join(parts[2:])!r}; its keys: {effect_keys}"
                )


def _check_key_path(protocol: Protocol, path: str, item: str) -> None:
    """Refuse ``group.key[.subkey]`` when a key is not a field of the group's dataclass, naming the
    fields it has (Hydra alone says only "Key 'x' not in 'ArmConfig'"). Stops at the first level
    that is not a dataclass (dicts, lists and values hold free keys)."""
    obj = protocol.schema()
    walked: list[str] = []
    for name in path.split("."):
        if not is_dataclass(obj):
            return
        names = [f.name for f in fields(obj)]
        if name not in names:
            where = ".".join(walked)
            raise ConfigError(f"{item}: {where!r} has no key {name!r}; its keys: {names}")
        walked.append(name)
        obj = getattr(obj, name)


def check_effects(protocol: Protocol, cfg: ExperimentConfig) -> None:
    """Refuse a switched-on effect the protocol's simulation does not apply (never ignore it), and
    one that is part of its lab (switched by the lab's own field: one switch per effect)."""
    on = [n for n in enabled_effects(cfg.effects) if n not in protocol.effects]
    lab = {n: protocol.lab_effects[n] for n in on if n in protocol.lab_effects}
    if lab:  # one switch per physical effect: this lab models it in its own terms
        raise ConfigError(
            f"effects {list(lab)} are part of the lab of protocol {protocol.name!r}; switch them with "
            + ", ".join(f"{path} (and {path.split('.')[0]}.*)" for path in lab.values())
            + " instead of effects=[...]"
        )
    if on:  # never silently ignore a switched-on effect
        simulating = [p.name for p in registry.protocols() if set(on) <= set(p.effects)]
        raise ConfigError(
            f"effects {on} are not simulated by protocol {protocol.name!r} yet; it applies "
            f"{list(protocol.effects)}"
            + (f"; protocols that simulate them: {simulating}" if simulating else "")
            + "; the referees of `armlab diagnose-benchmark` simulate the diagnosis candidates"
        )


def compose(overrides: list[str]):
    """Compose and validate one protocol's experiment.

    Args:
        overrides: ``protocol=<name>`` (default: the registry's default protocol) and Hydra
            overrides of that protocol's groups (``seed=3``, ``arm=planar_linear``,
            ``estimator.lowpass_hz=30``, ``effects=[joint_friction]``).

    Returns:
        (the composed DictConfig, the typed experiment: an instance of the protocol's schema).
        Whether its simulation applies the switched-on effects is :func:`check_effects`'s to say
        (``armlab run`` checks before anything is written).

    Raises:
        ConfigError: a bad override, naming the valid choices.
    """
    from hydra import compose as hydra_compose
    from hydra import initialize_config_dir
    from hydra.errors import HydraException
    from omegaconf.errors import OmegaConfBaseException

    protocol, rest = split_protocol(overrides)
    _check(protocol, rest)
    hydra_items = [o for o in rest if o.lstrip("+~").startswith("hydra")]
    try:
        with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
            cfg = hydra_compose(
                config_name=protocol.name, overrides=[o for o in rest if o not in hydra_items]
            )
            if hydra_items:  # Hydra's own settings and groups (hydra/launcher=joblib, the run folder)
                hydra_compose(config_name=protocol.name, overrides=hydra_items, return_hydra_config=True)
    except (HydraException, OmegaConfBaseException) as exc:
        raise ConfigError(_hydra_message(exc, rest)) from None
    exp = to_experiment(cfg)
    if not isinstance(exp, protocol.schema) or not isinstance(exp, ExperimentConfig):
        raise ConfigError(f"composed config is a {type(exp).__name__}, not {protocol.schema.__name__}")
    check_finite(exp)
    if protocol.validate is not None:
        protocol.validate(exp)
    return cfg, exp


def _hydra_message(exc: BaseException, overrides: list[str]) -> str:
    """Hydra's whole message and its cause's, on one line (``armlab: error:`` prints one line):
    "Error merging override seed=abc" alone does not say what was wrong; its cause does ("Value
    'abc' ... could not be converted to Integer"), and a missing option's message lists the
    available ones. Names the override when Hydra's parser does not ("no viable alternative at
    input '[0.1'")."""
    parts: list[str] = []
    for e in (exc, exc.__cause__ or exc.__context__):
        if e is None:
            continue
        for line in str(e).splitlines():
            line = line.strip().rstrip(".")
            if line and line not in parts and not any(line in p for p in parts):
                parts.append(line)
    msg = "; ".join(parts).replace(":;", ":")
    named = [o for o in overrides if o in msg or o.partition("=")[0] in msg]
    if not named:
        bad = [o for o in overrides if o.partition("=")[2] and o.partition("=")[2] in msg]
        if bad:
            msg = f"{bad[0]}: {msg}"
    return msg
