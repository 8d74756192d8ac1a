"""The progress display of the ``armlab`` verbs: what :mod:`armlab.progress` reports, shown.

On a terminal (stderr a TTY) a live ``rich`` display: one row per stage with its bar, items done /
total, elapsed and estimated remaining time. Elsewhere (CI logs, pipes) and in each job of a
multirun (joblib workers share one terminal), plain lines on stderr, at most one every
:data:`LINE_EVERY_S` per stage plus one when a stage ends and one when the command finishes:

    armlab: simulate 120/780 trials, 4.2 s elapsed, ~22 s left
    armlab: simulate 780/780 trials, done in 26.0 s
    armlab: finished in 41.3 s

``progress=false`` (an argument of every verb, see :func:`split_flag`) shows nothing. A display
only observes: results are the same with it, without it and with ``progress=false``.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TextIO

from armlab.errors import ConfigError
from armlab.progress import reporting

__all__ = [
    "LINE_EVERY_S",
    "LineSink",
    "LiveSink",
    "display",
    "split_flag",
]

# s, least time between two progress lines of one stage in a log: frequent enough that a CI log
# shows a long stage moving, rare enough that a 10-minute benchmark writes ~120 lines, not 10^4
LINE_EVERY_S = 5.0


def split_flag(args: list[str]) -> tuple[bool, list[str]]:
    """``progress=true|false`` taken out of a verb's arguments: (show progress, the others).

    Raises:
        ConfigError: a value other than true/false, or the argument given twice.
    """
    values = [a.partition("=")[2] for a in args if a.partition("=")[0] == "progress"]
    if len(values) > 1 or any(v not in ("true", "false") for v in values):
        given = values[0] if len(values) == 1 else values
        raise ConfigError(
            f"progress={given}: give it once, as progress=true (the default: a live display on a "
            "terminal, log lines otherwise) or progress=false (none)"
        )
    return values != ["false"], [a for a in args if a.partition("=")[0] != "progress"]


def _count(done: float, total: float | None, unit: str) -> str:
    """``120/780 trials``; ``12 cases`` of a stage of unknown size; empty where nothing is counted."""
    if total is None and done == 0:
        return ""
    # whole items done, never rounded up (lock-step rollouts report fractions of their trials);
    # 1e-6 absorbs the round-off of summing those fractions
    whole = math.floor(done + 1e-6)
    text = f"{whole}" if total is None else f"{whole}/{total:.0f}"
    return f"{text} {unit}".rstrip()


def _named(name: str, count: str) -> str:
    return f"{name} {count}" if count else name


class LineSink:
    """Progress as plain, throttled lines (see the module docstring)."""

    def __init__(
        self,
        stream: TextIO,
        *,
        prefix: str = "armlab",
        every_s: float = LINE_EVERY_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._stream, self._prefix, self._every, self._clock = stream, prefix, every_s, clock
        self._start = clock()
        self._name: str | None = None
        self._total: float | None = None
        self._unit = ""
        self._done = 0.0
        self._t0 = self._last = self._start

    def _line(self, text: str) -> None:
        print(f"{self._prefix}: {text}", file=self._stream, flush=True)

    def _end_stage(self) -> None:
        if self._name is not None:
            count = _count(self._done, self._total, self._unit)
            self._line(f"{_named(self._name, count)}, done in {self._clock() - self._t0:.1f} s")
        self._name = None

    def stage(self, name: str, total: float | None = None, unit: str = "") -> None:
        if name == self._name and self._done == 0:  # the same stage, its size now known
            self._total, self._unit = total, unit
            return
        self._end_stage()
        self._name, self._total, self._unit, self._done = name, total, unit, 0.0
        self._t0 = self._last = self._clock()

    def advance(self, n: float = 1) -> None:
        self._done += n
        now = self._clock()
        finished = self._total is not None and self._done >= self._total  # its end line follows
        if self._name is None or finished or now - self._last < self._every:
            return
        self._last = now
        elapsed = now - self._t0
        text = f"{_named(self._name, _count(self._done, self._total, self._unit))}, {elapsed:.1f} s elapsed"
        if self._total and 0 < self._done < self._total:
            text += f", ~{elapsed * (self._total - self._done) / self._done:.0f} s left"
        self._line(text)

    def close(self, ok: bool) -> None:
        """End the last stage and say how long the command took (``ok``: it did not fail)."""
        if ok:
            self._end_stage()
            self._line(f"finished in {self._clock() - self._start:.1f} s")


class LiveSink:
    """Progress as a live ``rich`` display on a terminal: one row per stage."""

    def __init__(self, stream: TextIO) -> None:
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            Progress,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        console = Console(file=stream, stderr=stream is sys.stderr)
        self._progress = Progress(
            SpinnerColumn(finished_text="[green]✓"),
            TextColumn("{task.description}"),
            BarColumn(),
            TextColumn("{task.fields[count]}"),
            TextColumn("elapsed"),
            TimeElapsedColumn(),
            TextColumn("left"),
            TimeRemainingColumn(),
            console=console,
            # printed lines (the results table, warnings) go above the display, not through it
            redirect_stdout=sys.stdout.isatty(),
            redirect_stderr=True,
        )
        self._task = None
        self._name: str | None = None
        self._unit = ""
        self._total: float | None = None
        self._done = 0.0
        self._progress.start()

    def _update(self, **kw) -> None:
        self._progress.update(self._task, count=_count(self._done, self._total, self._unit), **kw)

    def _end_stage(self) -> None:
        if self._task is not None:
            final = self._total if self._total is not None else max(self._done, 1.0)
            self._total = None if self._total is None else final
            self._update(total=final, completed=final)
        self._task = None

    def stage(self, name: str, total: float | None = None, unit: str = "") -> None:
        if name == self._name and self._done == 0 and self._task is not None:
            self._total, self._unit = total, unit
            self._update(total=total)
            return
        self._end_stage()
        self._name, self._total, self._unit, self._done = name, total, unit, 0.0
        self._task = self._progress.add_task(name, total=total, count=_count(0, total, unit))

    def advance(self, n: float = 1) -> None:
        if self._task is None:
            return
        self._done += n
        self._update(completed=self._done)

    def close(self, ok: bool) -> None:
        if ok:
            self._end_stage()
        self._progress.stop()


@contextmanager
def display(enabled: bool = True, *, job: str | None = None, stream: TextIO | None = None) -> Iterator[None]:
    """Show the progress of the block: live on a terminal, lines elsewhere or in a multirun job
    (``job`` names it in each line, ``armlab [job 3]: ...``), nothing when not ``enabled``."""
    if not enabled:
        yield
        return
    stream = sys.stderr if stream is None else stream
    sink: LineSink | LiveSink
    if job is None and stream.isatty():
        sink = LiveSink(stream)
    else:
        sink = LineSink(stream, prefix="armlab" if job is None else f"armlab [{job}]")
    ok = False
    try:
        with reporting(sink):
            yield
        ok = True
    finally:
        sink.close(ok)
