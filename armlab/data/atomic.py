"""Atomic, never-overwriting output files: written under a temporary name, renamed when complete.

Every output armlab writes (trial files, recordings, results, figures, tables, scenes) goes through
:func:`atomic_path`: the writer fills a hidden temporary file in the destination's folder
(``.<name>.<random>.tmp``) and only a complete file is given its final name, by a hard link that
fails if the name is taken (so nothing is ever clobbered, even by a file that appeared meanwhile).
A failed or interrupted writer (an exception, ``KeyboardInterrupt``, or SIGTERM turned into one by
the CLI) removes its temporary in a ``finally``; a process killed outright (SIGKILL) can leave one
behind, which :func:`armlab.data.rundir.clean_partial` removes when the run is resumed.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from armlab.errors import DataError

__all__ = ["TEMP_SUFFIX", "atomic_path", "is_temporary", "publish", "write_text_atomic"]

#: suffix of every temporary output (its name also starts with a dot: hidden)
TEMP_SUFFIX = ".tmp"


def is_temporary(path: Path) -> bool:
    """Whether ``path`` is the name of a temporary output made by :func:`atomic_path`."""
    name = Path(path).name
    return name.startswith(".") and name.endswith(TEMP_SUFFIX)


def _exists_error(path: Path) -> DataError:
    return DataError(f"{path} exists; armlab never overwrites results — use a new run directory")


def publish(tmp: Path, path: Path, overwrite: bool = False) -> None:
    """Give the complete temporary file ``tmp`` its final name ``path`` (atomic).

    Without ``overwrite`` an existing ``path`` is a DataError and is left untouched.
    """
    if overwrite:
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path)  # atomic and never clobbers
    except FileExistsError:
        raise _exists_error(path) from None
    except OSError:  # no hard links on this filesystem: check, then rename
        if path.exists():
            raise _exists_error(path) from None
        os.replace(tmp, path)


# the process umask, read once at import: reading it means setting it, which is not thread-safe
# (a thread creating a file between the two calls would get mode 0666), so never per write
_UMASK = os.umask(0)
os.umask(_UMASK)


@contextmanager
def atomic_path(path: str | os.PathLike[str], overwrite: bool = False) -> Iterator[Path]:
    """Yield a temporary path to write ``path``'s content to; publish it when the block succeeds.

    The temporary lives in the destination's folder (same filesystem: the rename is atomic) and
    has the permissions ``open()`` would give. It is removed whatever happens.

    Raises:
        DataError: ``path`` exists (and not ``overwrite``), or its folder does not exist.
    """
    path = Path(path)
    if not path.parent.is_dir():
        raise DataError(f"{path}: directory {path.parent} does not exist")
    if path.exists() and not overwrite:
        raise _exists_error(path)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=TEMP_SUFFIX)
    os.close(fd)
    tmp = Path(name)
    try:
        tmp.chmod(0o666 & ~_UMASK)  # mkstemp makes the file private; give it the permissions of open()
        yield tmp
        publish(tmp, path, overwrite)
    finally:
        tmp.unlink(missing_ok=True)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` to the new file ``path`` through :func:`atomic_path`."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)
