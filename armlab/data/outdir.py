"""The one output convention of every verb: ``out=<dir>`` names the folder a command writes.

``armlab run``, ``estimate``, ``diagnose``, ``diagnose-benchmark`` and ``fit-joint`` (and the Python
API's ``out=``) all take ``out=<dir>``; without it each writes a new ``outputs/<name>/<timestamp>``
under the working folder (``<name>``: the protocol for ``run``, ``multirun/<protocol>`` for a
sweep, the verb otherwise; microseconds in the timestamp, so two commands never share a folder).
Hydra's own spellings ``hydra.run.dir=`` / ``hydra.sweep.dir=`` are refused with the message that
names ``out=``: there is one way to say it.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

from armlab.errors import ConfigError

__all__ = ["OLD_SPELLINGS", "default_out", "hydra_out", "take_out"]

#: Hydra's spellings of the output folder, refused in favour of ``out=``
OLD_SPELLINGS = ("hydra.run.dir", "hydra.sweep.dir")


def default_out(name: str) -> Path:
    """``outputs/<name>/<timestamp with microseconds>`` under the working folder."""
    return Path("outputs") / name / datetime.now().strftime("%Y-%m-%d_%H-%M-%S-%f")


def take_out(args: list[str], verb: str) -> tuple[Path | None, list[str]]:
    """Split ``out=<dir>`` from a verb's ``key=value`` arguments: (the folder or None, the rest).

    Raises:
        ConfigError: ``out=`` given twice or empty, or an old spelling (``hydra.run.dir=``,
            ``hydra.sweep.dir=``) in its place — the message names ``out=``.
    """
    found, rest = [], []
    for item in args:
        key, sep, value = item.partition("=")
        bare = key.lstrip("+~")
        if sep and bare in OLD_SPELLINGS:
            where = (
                "; in a --multirun it is the sweep folder, each job writing to <dir>/<job number>"
                if bare == "hydra.sweep.dir"
                else ""
            )
            raise ConfigError(
                f"{item}: armlab names the output folder of every verb with out=<dir> — write "
                f"out={value or '<dir>'} instead of {bare}=...{where}"
            )
        if sep and bare == "out":
            found.append(value)
        else:
            rest.append(item)
    if len(found) > 1:
        raise ConfigError(f"out= is given {len(found)} times ({found}); give the output folder once")
    if not found:
        return None, rest
    value = found[0].strip()
    if not value.strip("'\""):
        raise ConfigError(
            f"`armlab {verb} out=` needs a folder (e.g. out=outputs/my_{verb.replace('-', '_')}); "
            "leave out= away for a new timestamped one"
        )
    return Path(value.strip("'\"")).expanduser(), rest


def hydra_out(out: Path, *, multirun: bool) -> str:
    """The Hydra override that puts a run (or a sweep's jobs) into ``out``.

    Raises:
        ConfigError: a folder name Hydra cannot take even quoted (a single quote in it).
    """
    key = "hydra.sweep.dir" if multirun else "hydra.run.dir"
    text = str(out)
    if "'" in text or "\\" in text:
        raise ConfigError(f"out={text}: a folder name with a quote or backslash cannot be passed to Hydra")
    # always quoted: Hydra reads an unquoted 1e3 as a float (folder 1000.0), true as a bool, a
    # comma as a sweep; a quoted value is the literal string (${now:...} is still resolved)
    return f"{key}='{text}'"
