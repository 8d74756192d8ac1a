"""The one validation helper set of the typed configs: a failed check raises ConfigError.

Every ``__post_init__`` of :mod:`armlab.config` checks through :func:`check` and :func:`choice`,
so a rejected value always surfaces as :class:`~armlab.errors.ConfigError` with a message that
says what was wrong and what is valid.
"""

from __future__ import annotations

from typing import Any, Literal, get_args, get_origin

from armlab.errors import ConfigError

__all__ = [
    "check",
    "choice",
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
