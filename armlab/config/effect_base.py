"""The base of every catalogue effect (:mod:`armlab.config.effects`): its class attributes and checks.

An effect is a ``@dataclass(kw_only=True)`` whose fields are its parameters (unit in the name,
typical magnitude and its source in the comment) and whose class attributes say where it acts
(``LEVEL``: model, controller or sensor), what physics it adds (``PHYSICS``), where its typical
magnitude comes from (``SOURCE``) and which other effects it cannot be told apart from with a
protocol's trials (``CONFUSABLE``: name -> the extra trial that separates them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import ClassVar, get_args

from armlab.config.choices import EffectLevel
from armlab.errors import ConfigError

__all__ = ["LEVELS", "Effect"]

LEVELS = get_args(EffectLevel)


@dataclass(kw_only=True)
class Effect:
    """Base of every catalogue entry: positive, finite parameters unless a field says otherwise."""

    NAME: ClassVar[str] = ""
    LEVEL: ClassVar[EffectLevel] = "model"  # a ClassVar, not an OmegaConf field: the Literal stays
    PHYSICS: ClassVar[str] = ""
    SOURCE: ClassVar[str] = ""
    CONFUSABLE: ClassVar[dict[str, str]] = {}
    SIGNED: ClassVar[tuple[str, ...]] = ()  # fields that may be negative

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                continue
            ok = math.isfinite(v) and (f.name in self.SIGNED or v >= 0)
            if not ok:
                sign = "finite" if f.name in self.SIGNED else "finite and >= 0"
                raise ConfigError(f"effects.{self.NAME}.{f.name} must be {sign}, got {v!r}")

    def params(self) -> dict[str, float]:
        """The parameters as a name -> value dict (units in the names)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}
