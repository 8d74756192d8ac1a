"""The one validation helper set of the typed configs: a failed check raises ConfigError.

Every ``__post_init__`` of :mod:`armlab.config` checks through :func:`check` and :func:`choice`,
so a rejected value always surfaces as :class:`~armlab.errors.ConfigError` with a message that
says what was wrong and what is valid.
"""

from __future__ import annotations

import math
from dataclasses import fields, is_dataclass
from typing import Any, Literal, get_args, get_origin, get_type_hints

from armlab.errors import ConfigError

__all__ = [
    "check",
    "check_finite",
    "check_tuple_lengths",
    "choice",
    "divisor_rates",
    "options",
]


def check(cond: bool, msg: str) -> None:
    """Raise :class:`ConfigError` with ``msg`` unless ``cond`` holds."""
    if not cond:
        raise ConfigError(msg)


def options(valid: Any) -> tuple[str, ...]:
    """The values of a ``Literal[...]`` type (see :mod:`armlab.config.choices`), or the tuple itself."""
    if get_origin(valid) is Literal:
        return get_args(valid)
    if not isinstance(valid, tuple):
        raise TypeError(f"options must be a Literal[...] type or a tuple, got {valid!r}")
    return valid


def choice(name: str, value: str, valid: Any) -> None:
    """Raise :class:`ConfigError` unless ``value`` is one of ``valid`` (a ``Literal`` or a tuple).

    Args:
        name: the dotted config path named in the message, e.g. ``"arm.muscle"``.
        value: the configured value.
        valid: the choice set, a ``Literal[...]`` type or a tuple of its values.
    """
    valid = options(valid)
    check(value in valid, f"{name}={value!r} is not valid; choose one of {list(valid)}")


def check_finite(cfg: Any, prefix: str = "") -> None:
    """Raise :class:`ConfigError` naming the first NaN or infinite number in a config tree.

    Every number of armlab's configs is a physical quantity, a rate, a gain or a count; none
    means anything as NaN or inf, and range checks written ``x > 0`` let ``inf`` (and
    comparisons with NaN) through, so the whole tree is checked once after composing.

    Args:
        cfg: a config dataclass (nested dataclasses, lists, tuples and dicts are walked).
        prefix: the dotted path of ``cfg`` in messages (``""`` for the experiment's root).
    """
    if is_dataclass(cfg):
        items = [(f.name, getattr(cfg, f.name)) for f in fields(cfg)]
    elif isinstance(cfg, dict):
        items = [(str(k), v) for k, v in cfg.items()]
    elif isinstance(cfg, (list, tuple)):
        for i, v in enumerate(cfg):
            if isinstance(v, float) and not math.isfinite(v):
                raise ConfigError(f"{prefix}={list(cfg)}: element {i} is {v}; give finite numbers")
            check_finite(v, f"{prefix}[{i}]")
        return
    else:
        return
    for name, value in items:
        path = f"{prefix}.{name}" if prefix else name
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{path}={value} is not a finite number; give a finite value")
        check_finite(value, path)


def divisor_rates(physics_hz: float, count: int = 6) -> list[float]:
    """The first ``count`` sample rates that divide ``physics_hz`` into whole physics steps
    (``physics_hz / n`` for n = 1, 2, ... that are whole numbers of Hz), for error messages."""
    rates = [physics_hz / n for n in range(1, 1000) if abs(physics_hz / n - round(physics_hz / n)) < 1e-9]
    return [float(f"{r:g}") for r in rates[:count]]


def check_tuple_lengths(cfg: Any, prefix: str) -> None:
    """Raise :class:`ConfigError` when a fixed-length tuple field (``tuple[float, float]``) of the
    config dataclass ``cfg`` holds another number of values (``frf.band_hz=[1]``), naming it.

    Called first in a ``__post_init__``, before the checks that unpack those tuples.
    """
    for name, hint in get_type_hints(type(cfg)).items():
        args = get_args(hint)
        if get_origin(hint) is not tuple or not args or Ellipsis in args:
            continue
        value = getattr(cfg, name, None)
        if value is not None and len(value) != len(args):
            raise ConfigError(f"{prefix}.{name} must hold {len(args)} values, got {list(value)}")
