"""The one completeness rule of a run folder, and what resuming an unfinished one removes.

A run folder (made by ``armlab run``) is **complete** when it holds ``results.json``: the runner
writes it last, atomically (:mod:`armlab.data.atomic`), after every other output. A run folder
(one holding ``.hydra/config.yaml`` or ``scene.xml``) without ``results.json`` is **incomplete**:
its run was interrupted or failed. Every verb that reads a run folder asks
:func:`require_complete`, which names the command that finishes it. A non-empty folder that is
neither is **foreign** (the user's own files): armlab never writes into it nor removes anything
from it, resume included.
"""

from __future__ import annotations

import shlex
import shutil
from pathlib import Path
from typing import Literal

from armlab.data.atomic import is_temporary
from armlab.errors import DataError

__all__ = [
    "MARKER",
    "METADATA_DIR",
    "RunState",
    "clean_partial",
    "partial_files",
    "refusal",
    "require_complete",
    "resume_command",
    "run_state",
]

#: written last, atomically: its presence marks a complete run
MARKER = "results.json"
#: the run's configuration (config.yaml, hydra.yaml, overrides.yaml), kept when resuming
METADATA_DIR = ".hydra"
#: files a run folder holds from its start: metadata and Hydra's job log (kept when resuming)
_KEPT_SUFFIXES = (".log",)

RunState = Literal["new", "incomplete", "complete", "foreign"]


def run_state(folder: str | Path) -> RunState:
    """``"new"`` (absent or empty), ``"complete"`` (holds results.json), ``"incomplete"`` (a run
    folder without it) or ``"foreign"`` (anything else: not armlab's, never written into)."""
    folder = Path(folder)
    if (folder / MARKER).is_file():
        return "complete"
    if not folder.is_dir() or not any(p for p in folder.iterdir() if not _is_log(p)):
        return "new"  # Hydra opens the job log on entry: a folder with only that is new
    return "incomplete" if _is_run_folder(folder) else "foreign"


def refusal(folder: str | Path, state: RunState) -> DataError:
    """Why a run cannot go into ``folder`` in ``state`` (complete, incomplete or foreign): the one
    message per state that every verb and the Python API give."""
    if state == "complete":
        return DataError(
            f"{folder} already holds {MARKER}: a complete run is never touched, armlab never overwrites "
            "a run — choose a new out=<folder>, or add resume=true to leave "
            "complete runs untouched and finish incomplete ones"
        )
    if state == "incomplete":
        return DataError(
            f"{folder} is an incomplete run (no {MARKER}: it was interrupted or failed); finish it "
            f"with `{resume_command(folder)}`, or choose a new out=<folder>"
        )
    if state == "foreign":
        return DataError(
            f"{folder} is not empty and is not an armlab run folder (no .hydra/config.yaml, no "
            "scene.xml): armlab never writes into it nor removes anything from it — choose a new "
            "out=<folder>"
        )
    raise ValueError(f"a {state!r} folder needs no refusal")


def _is_log(p: Path) -> bool:
    return p.is_file() and p.suffix in _KEPT_SUFFIXES and not is_temporary(p)


def resume_command(folder: str | Path) -> str:
    """The command line that finishes the incomplete run in ``folder`` (its stored overrides)."""
    return f"armlab run resume=true {shlex.quote(f'out={Path(folder)}')}"  # a shell word, spaces and all


def _is_run_folder(folder: Path) -> bool:
    """Made by ``armlab run`` (its config record or composed scene): a trial file alone may be
    measured data converted to the trial format, which needs no results.json."""
    return (folder / METADATA_DIR / "config.yaml").is_file() or (folder / "scene.xml").is_file()


def require_complete(path: str | Path) -> None:
    """Refuse a run folder (or a file inside one) whose run did not finish.

    ``path`` that is not inside a run folder (a measured data file, a folder of CSVs) passes.

    Raises:
        DataError: naming the folder, what is missing and the command that finishes it.
    """
    path = Path(path)
    folder = path if path.is_dir() else path.parent
    if _is_run_folder(folder) and run_state(folder) == "incomplete":
        raise refusal(folder, "incomplete")


def partial_files(folder: str | Path) -> list[Path]:
    """What an interrupted run left in ``folder``: its outputs and temporaries, not its metadata.

    Everything except ``.hydra/`` and the job log; an incomplete run folder holds nothing else
    (``armlab estimate`` refuses it, so it has no ``reestimate_*`` folders).
    """
    folder = Path(folder)
    return sorted(p for p in folder.iterdir() if p.name != METADATA_DIR and not _is_log(p))


def clean_partial(folder: str | Path) -> list[Path]:
    """Remove :func:`partial_files` of an incomplete run folder (before it is run again).

    Raises:
        DataError: the folder is complete (a complete run is never touched) or not a run folder
            (the user's own files are never removed).
    """
    folder = Path(folder)
    state = run_state(folder)
    if state in ("complete", "foreign"):
        raise refusal(folder, state)
    removed = partial_files(folder)
    for p in removed:
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p)
        else:
            p.unlink()
    return removed
