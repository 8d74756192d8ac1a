"""Writing run outputs that never overwrite anything (shared by the protocol edges)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from armlab.data.atomic import write_text_atomic
from armlab.errors import DataError

__all__ = ["check_new_dir", "json_default", "new_dir", "write_json", "write_new"]


def json_default(obj):
    """JSON encoding of NumPy arrays and scalars."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def check_new_dir(out: Path) -> None:
    """DataError unless ``out`` is absent or an empty folder. Called before expensive work too, so a
    refused output folder costs nothing (:func:`new_dir` checks again when it creates it)."""
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise DataError(
            f"out={out} {'is not empty' if out.is_dir() else 'is a file, not a directory'}; armlab never "
            "overwrites results: give a new folder (a new directory, or an empty one)"
        )


def new_dir(out: Path) -> Path:
    """An output folder that is new or empty (created); any other is a DataError."""
    check_new_dir(out)
    Path(out).mkdir(parents=True, exist_ok=True)
    return Path(out)


def write_new(path: Path, text: str) -> Path:
    """Write a text file that must not exist yet (armlab never overwrites results).

    Written under a temporary name and renamed when complete (:mod:`armlab.data.atomic`): an
    interrupted writer never leaves a truncated file under its name.
    """
    return write_text_atomic(path, text)


def write_json(path: Path, data: dict) -> Path:
    """``data`` as indented JSON in a new file."""
    return write_new(path, json.dumps(data, indent=2, default=json_default))
