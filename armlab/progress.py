"""Progress reports from long computations, without knowing who (if anyone) displays them.

Computation (simulation, estimation, diagnosis) announces what it does through two calls:

    progress.stage("simulate", total=780, unit="trials")   # a new stage of known size
    progress.advance(35)                                    # so much of it is done

Both go to the :class:`ProgressSink` of the current context, a :class:`contextvars.ContextVar`
that only the edge sets (:mod:`armlab.runner.progress` renders it on a terminal or as log lines);
its default, :data:`NULL_SINK`, does nothing, so computation called from Python, from tests or
in a worker process stays silent and pure. Nothing here prints, imports a renderer or changes a
result: a sink only observes.

``scope(label)`` prefixes the stage names reported inside it (``linearisation bias: simulate``),
for a computation that runs again as part of a larger one.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Protocol, runtime_checkable

__all__ = [
    "NULL_SINK",
    "NullSink",
    "ProgressSink",
    "advance",
    "reporting",
    "scope",
    "stage",
]


@runtime_checkable
class ProgressSink(Protocol):
    """What receives progress: a stage begins (``total`` None: size unknown), then advances."""

    def stage(self, name: str, total: float | None = None, unit: str = "") -> None: ...

    def advance(self, n: float = 1) -> None: ...


class NullSink:
    """The sink of a context no edge set: it ignores everything."""

    def stage(self, name: str, total: float | None = None, unit: str = "") -> None:
        pass

    def advance(self, n: float = 1) -> None:
        pass


NULL_SINK = NullSink()
_SINK: ContextVar[ProgressSink] = ContextVar("armlab_progress_sink", default=NULL_SINK)
_SCOPE: ContextVar[str] = ContextVar("armlab_progress_scope", default="")


def stage(name: str, total: float | None = None, unit: str = "") -> None:
    """Begin a stage of the current computation: ``total`` items of ``unit`` (None: unknown)."""
    prefix = _SCOPE.get()
    _SINK.get().stage(f"{prefix}{name}", total, unit)


def advance(n: float = 1) -> None:
    """Report ``n`` more items of the current stage done."""
    _SINK.get().advance(n)


@contextmanager
def reporting(sink: ProgressSink) -> Iterator[ProgressSink]:
    """Send the progress of everything run inside the block to ``sink`` (the edge's call)."""
    token = _SINK.set(sink)
    try:
        yield sink
    finally:
        _SINK.reset(token)


@contextmanager
def scope(label: str) -> Iterator[None]:
    """Name the stages reported inside the block ``<label>: <stage>`` (an empty label: as they are)."""
    if not label:
        yield
        return
    token = _SCOPE.set(f"{_SCOPE.get()}{label}: ")
    try:
        yield
    finally:
        _SCOPE.reset(token)
