"""The one registry of protocols: a line per built-in protocol, and :func:`register` for others.

Everything that lists or dispatches on protocols (runner, CLI, docs, config composition) asks
this module; nothing else names a protocol. Registering a protocol with a schema also stores its
Hydra configs in the ConfigStore: ``<name>_schema`` (the typed experiment) and ``<name>`` (the
primary config: the schema, then the protocol's groups with their default options, then
``configs/protocol/<name>.yaml`` if it exists, then the shared Hydra settings of
``configs/config.yaml``).
"""

from __future__ import annotations

from hydra.core.config_store import ConfigStore

from armlab.config.effects import register_effect_configs
from armlab.config.store import CONFIG_DIR
from armlab.errors import ConfigError
from armlab.protocols import (
    cartesian_online,
    conditioning_window,
    fractional_elbow,
    joint_1dof,
    stiffness_5dof_emg,
    virtual_force_sensor,
)
from armlab.protocols.base import Protocol

__all__ = [
    "DEFAULT_PROTOCOL",
    "DEFAULT_REFEREE",
    "get",
    "names",
    "protocols",
    "register",
    "unregister",
]

_REGISTRY: dict[str, Protocol] = {}

#: what each capability needs of a protocol
_NEEDS = {
    "run": lambda p: p.runs,
    "estimate": lambda p: p.reestimate is not None,
    "diagnose": lambda p: p.diagnosis is not None,
    "referee": lambda p: p.diagnosis is not None and p.diagnosis.referee is not None,
}


def _store(protocol: Protocol) -> None:
    cs = ConfigStore.instance()
    cs.store(name=f"{protocol.name}_schema", node=protocol.schema)
    defaults: list = [f"{protocol.name}_schema"]
    defaults += [{group: option} for group, option in protocol.groups.items()]
    defaults.append({"effects": []})
    if (CONFIG_DIR / "protocol" / f"{protocol.name}.yaml").is_file():
        defaults.append({"protocol": protocol.name})
    defaults += ["config", "_self_"]
    cs.store(name=protocol.name, node={"defaults": defaults})


def register(protocol: Protocol) -> Protocol:
    """Add a protocol (and its Hydra configs). Registering the same object again is a no-op."""
    if not isinstance(protocol, Protocol):
        raise ConfigError(f"register() takes a Protocol, got {type(protocol).__name__}")
    known = _REGISTRY.get(protocol.name)
    if known is not None and known is not protocol:
        raise ConfigError(f"a protocol named {protocol.name!r} is already registered")
    _REGISTRY[protocol.name] = protocol
    if protocol.schema is not None:
        register_effect_configs()
        _store(protocol)
    return protocol


def unregister(name: str) -> None:
    """Remove a protocol (tests register toy protocols and take them away again)."""
    _REGISTRY.pop(name, None)


def names(need: str | None = None) -> list[str]:
    """Registered protocol names, in registration order; ``need``: only those that can
    ``run``, ``estimate``, ``diagnose`` or have a ``referee``."""
    if need is not None and need not in _NEEDS:
        raise ConfigError(f"unknown capability {need!r}; valid: {list(_NEEDS)}")
    return [n for n, p in _REGISTRY.items() if need is None or _NEEDS[need](p)]


def protocols() -> list[Protocol]:
    """Every registered protocol, in registration order."""
    return list(_REGISTRY.values())


def get(name: str, need: str | None = None) -> Protocol:
    """The protocol called ``name``; a ConfigError naming the valid choices otherwise.

    Args:
        name: the protocol's name.
        need: a capability it must have (``run``, ``estimate``, ``diagnose``, ``referee``).
    """
    valid = names(need)
    if name not in _REGISTRY:
        raise ConfigError(f"unknown protocol {name!r}; valid: {valid}")
    if name not in valid:
        can = {
            "run": "be run",
            "estimate": "re-estimate",
            "diagnose": "be diagnosed",
            "referee": "be refereed",
        }
        raise ConfigError(f"protocol {name!r} cannot {can[need]}; valid: {valid}")
    return _REGISTRY[name]


# --- the built-in protocols: one line each ------------------------------------------------------
register(conditioning_window.PROTOCOL)
register(fractional_elbow.PROTOCOL)
register(virtual_force_sensor.PROTOCOL)
register(joint_1dof.PROTOCOL)
register(cartesian_online.PROTOCOL)
register(stiffness_5dof_emg.PROTOCOL)

#: what ``armlab run`` runs when no protocol is given (and ``make run``)
DEFAULT_PROTOCOL = conditioning_window.PROTOCOL.name
#: whose referee ``armlab diagnose-benchmark`` runs when ``referee.protocol`` is not given
DEFAULT_REFEREE = joint_1dof.PROTOCOL.name
