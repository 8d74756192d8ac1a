"""Stopping a run cleanly: SIGTERM handled like Ctrl-C, and sweep workers that stop with their parent.

Python's default SIGTERM ends the process at once: no ``finally`` runs, so temporaries stay and
nothing says what was left unfinished. Within :func:`handle_termination` SIGTERM (and SIGINT) raise
:class:`Interrupted` in the main thread, so every writer removes its temporary file
(:mod:`armlab.data.atomic`) and the CLI names the unfinished folder.

A joblib (loky) worker is a separate process: when its parent is killed it keeps running its job to
the end unless told otherwise (loky notices a dead parent only when it asks for the next job).
:func:`stop_with_parent` starts a watcher thread in the worker that sends the worker SIGTERM once
its parent has gone (its job stops and cleans up) and then ends the process. When the parent
itself is interrupted, joblib aborts the sweep and kills its workers (SIGKILL: they cannot clean
up; resuming removes what they left, see :func:`armlab.data.rundir.clean_partial`).
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["Interrupted", "handle_termination", "stop_with_parent"]

#: how often a worker checks that its parent is alive, s (a job outlives its parent by at most this)
_PARENT_POLL_S = 0.5
#: time an orphaned worker's job gets to run its ``finally`` blocks (remove its temporaries, close
#: files: milliseconds in practice) before the process exits, s
_CLEANUP_GRACE_S = 2.0
_WATCHER_NAME = "armlab-parent-watcher"
_SIGNALS = (signal.SIGTERM, signal.SIGINT)


class Interrupted(KeyboardInterrupt):
    """A run stopped by a signal (SIGTERM or SIGINT); ``signum`` names which."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _raise(signum, frame) -> None:
    raise Interrupted(signum)


@contextmanager
def handle_termination() -> Iterator[None]:
    """Within the block, SIGTERM and SIGINT raise :class:`Interrupted` in the main thread.

    The previous handlers are restored after it; outside the main thread (where no handler can be
    set) it does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = {sig: signal.getsignal(sig) for sig in _SIGNALS}
    for sig in _SIGNALS:
        signal.signal(sig, _raise)
    try:
        yield
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)


def _watch(parent_pid: int) -> None:
    while os.getppid() == parent_pid:
        time.sleep(_PARENT_POLL_S)
    os.kill(os.getpid(), signal.SIGTERM)  # the parent is gone: stop this job like a SIGTERM would
    time.sleep(_CLEANUP_GRACE_S)
    os._exit(128 + signal.SIGTERM)  # and the worker itself (loky would keep it idle for minutes)


def stop_with_parent(parent_pid: int) -> None:
    """In a worker process of ``parent_pid``: stop as soon as the parent dies (SIGTERM to itself,
    then exit once its job has cleaned up).

    Does nothing in the parent itself or in a process that is not its child; starts one watcher per
    process (workers are reused across jobs).
    """
    if os.getpid() == parent_pid or os.getppid() != parent_pid:
        return
    if any(t.name == _WATCHER_NAME for t in threading.enumerate()):
        return
    threading.Thread(target=_watch, args=(parent_pid,), name=_WATCHER_NAME, daemon=True).start()
