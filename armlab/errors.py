"""armlab's exception hierarchy.

Every error raised on bad input is an :class:`ArmlabError`; its message says what was wrong and
what would have been valid, so the CLI can print it on one line instead of a traceback.
"""

from __future__ import annotations

__all__ = [
    "ArmlabError",
    "ArmlabWarning",
    "ConfigError",
    "DataError",
    "ModelError",
    "EstimationError",
    "SimulationError",
]


class ArmlabError(Exception):
    """Base class of every error armlab raises deliberately."""


class ConfigError(ArmlabError, ValueError):
    """A configuration value is invalid (unknown choice, out of range, inconsistent)."""


class DataError(ArmlabError, ValueError):
    """A trial file or data array is malformed (missing channel, wrong shape, NaN, ...)."""


class ModelError(ArmlabError, ValueError):
    """An MJCF model is missing, does not compile, or lacks a required element."""


class EstimationError(ArmlabError, ValueError):
    """An estimation problem is ill-posed (too few samples, singular regressor, ...)."""


class SimulationError(ArmlabError, RuntimeError):
    """A simulated trial failed (safety range hit, instability); the message says when and why."""


class ArmlabWarning(UserWarning):
    """A setting that runs but cannot do what it is set for (e.g. a reflex latency longer than
    every observation window); the CLI prints it once, as ``armlab: warning: ...``."""
