"""Writing and reading trial files (HDF5): the on-disk form of a :class:`TrialSet`.

The layout is a contract for real lab data too; it is described in ``docs/trial_format.md``::

    /                         attrs: format = "armlab-trials", format_version = 1, fs_hz
    /onset_index              (n_trials,) int64
    /channels/<name>          (n_trials, n_samples, n_axes) float64, attr unit; gzip 1 + shuffle,
                              one chunk per trial
    /trial_meta/<key>         (n_trials,) any numeric, bool or string dtype
    /attrs/                   run-level attrs: scalars and strings as HDF5 attributes, lists and
                              arrays as datasets, dicts as subgroups (recursively)

Channels must be finite: a NaN or inf is refused on write and reported (channel and trials) on
read, because real data must be cleaned before it reaches estimation.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from armlab.data.atomic import atomic_path
from armlab.data.trial import TrialSet
from armlab.errors import DataError

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "write_trials",
    "read_trials",
    "read_trial_file",
]

FORMAT_NAME = "armlab-trials"
FORMAT_VERSION = 1
_GZIP_LEVEL = 1  # zlib level of every channel (1 fastest, 9 smallest; any level reads back)
_KIND = "armlab_kind"  # attribute tagging how a dataset/group under /attrs maps back to Python
_MAX_ATTR_STR = 8192  # chars; longer strings go to a dataset (HDF5 compact attributes cap at 64 KiB)
_STR = h5py.string_dtype("utf-8")


def _nonfinite_report(name: str, a: np.ndarray) -> str | None:
    bad = ~np.isfinite(a)
    if not bad.any():
        return None
    trials = np.flatnonzero(bad.any(axis=(1, 2)))
    first = int(np.flatnonzero(bad[trials[0]].any(axis=1))[0])
    return (
        f"channel {name!r} has NaN/inf in trial(s) {trials.tolist()} (first at trial {int(trials[0])}, "
        f"sample {first}); real data must be clean: drop or repair those trials before writing"
    )


# --- run-level attrs: Python values <-> HDF5 -----------------------------------------------------
def _leaf_kind(value: Any) -> str | None:
    """'bool', 'int', 'float' or 'str' if ``value`` is a rectangular nested list of one kind."""
    if isinstance(value, (list, tuple)):
        kinds = {_leaf_kind(v) for v in value}
        return kinds.pop() if len(kinds) == 1 else None
    if isinstance(value, (bool, np.bool_)):
        return "bool"
    if isinstance(value, (int, np.integer)):
        return "int"
    if isinstance(value, (float, np.floating)):
        return "float"
    if isinstance(value, str):
        return "str"
    return None


def _write_value(group: h5py.Group, key: str, value: Any, where: str) -> None:
    if not isinstance(key, str) or not key or "/" in key or key == ".":
        raise DataError(f"{where}: attr keys must be non-empty strings without '/', got {key!r}")
    here = f"{where}/{key}"
    if isinstance(value, Mapping):
        sub = group.create_group(key)
        sub.attrs[_KIND] = "dict"
        for k, v in value.items():
            _write_value(sub, k, v, here)
    elif isinstance(value, np.ndarray):
        if value.dtype.kind in "biuf":
            ds = group.create_dataset(key, data=value)
        elif value.dtype.kind == "U":
            ds = group.create_dataset(key, data=value.astype(object), dtype=_STR)
        else:
            raise DataError(
                f"{here}: numpy arrays of dtype {value.dtype} cannot be stored; use bool/int/float/str"
            )
        ds.attrs[_KIND] = "ndarray"
    elif isinstance(value, (list, tuple)):
        kind = _leaf_kind(value)
        arr = None
        if kind is not None:
            try:
                arr = np.array(value, dtype=object if kind == "str" else None)
            except ValueError:  # ragged
                arr = None
            if arr is not None and (
                arr.ndim == 0
                or (kind != "str" and arr.dtype == object)
                or (kind == "str" and not all(isinstance(x, str) for x in arr.flat))
            ):
                arr = None
        if arr is not None and kind == "str":
            ds = group.create_dataset(key, data=arr, dtype=_STR)
            ds.attrs[_KIND] = "list"
        elif arr is not None:
            ds = group.create_dataset(key, data=arr)
            ds.attrs[_KIND] = "list"
        else:  # mixed or ragged: a group with members "0", "1", ...
            sub = group.create_group(key)
            sub.attrs[_KIND] = "list"
            for i, v in enumerate(value):
                _write_value(sub, str(i), v, here)
    elif value is None:
        ds = group.create_dataset(key, data=h5py.Empty("f8"))
        ds.attrs[_KIND] = "none"
    elif isinstance(value, str) and len(value) > _MAX_ATTR_STR:
        ds = group.create_dataset(key, data=value, dtype=_STR)
        ds.attrs[_KIND] = "str"
    elif isinstance(value, (str, bool, int, float, np.bool_, np.integer, np.floating)):
        group.attrs[key] = value
    else:
        raise DataError(
            f"{here}: cannot store a {type(value).__name__}; use numbers, strings, None, lists, dicts "
            "or numpy arrays"
        )


def _attr_to_python(value: Any) -> Any:
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.generic):
        return value.item()
    return value


def _read_value(obj: h5py.Group | h5py.Dataset) -> Any:
    kind = _attr_to_python(obj.attrs.get(_KIND, "dict" if isinstance(obj, h5py.Group) else "ndarray"))
    if isinstance(obj, h5py.Group):
        items = {k: _attr_to_python(v) for k, v in obj.attrs.items() if k != _KIND}
        items.update({k: _read_value(obj[k]) for k in obj})
        if kind == "list":
            return [items[str(i)] for i in range(len(items))]
        return items
    if kind == "none":
        return None
    is_str = h5py.check_string_dtype(obj.dtype) is not None
    data = obj.asstr()[()] if is_str else obj[()]
    if kind == "str":
        return data
    arr = np.asarray(data)
    if is_str:
        arr = arr.astype(str)
    return arr.tolist() if kind == "list" else arr


# --- public API ------------------------------------------------------------------------------
def write_trials(path: str | os.PathLike[str], trials: TrialSet, overwrite: bool = False) -> Path:
    """Write ``trials`` to an HDF5 trial file, atomically.

    The file is written to a temporary file in the same directory and then renamed into place, so
    a reader never sees a half-written file and a failed write leaves no debris.

    Args:
        path: destination ``.h5`` file.
        trials: the trial set; channels must be finite.
        overwrite: replace an existing file. Without it an existing file is never touched.

    Returns:
        The path written.

    Raises:
        DataError: the file exists and ``overwrite`` is False; the directory does not exist; a
            channel has NaN/inf; an attr value cannot be stored.
    """
    path = Path(path)
    if not path.parent.is_dir():
        raise DataError(f"{path}: directory {path.parent} does not exist")
    if path.exists() and not overwrite:
        raise DataError(f"{path} already exists; pass overwrite=True to replace it")
    for name, a in trials.channels.items():
        report = _nonfinite_report(name, np.asarray(a, dtype=np.float64))
        if report:
            raise DataError(f"{path}: {report}")

    with atomic_path(path, overwrite=overwrite) as tmp, h5py.File(tmp, "w") as f:
        f.attrs["format"] = FORMAT_NAME
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["fs_hz"] = float(trials.fs_hz)
        f.create_dataset("onset_index", data=np.asarray(trials.onset_index, dtype=np.int64))
        ch = f.create_group("channels")
        for name, a in trials.channels.items():
            a = np.asarray(a, dtype=np.float64)
            if a.size:  # one chunk per trial, compressed
                ds = ch.create_dataset(
                    name,
                    data=a,
                    chunks=(1, *a.shape[1:]),
                    compression="gzip",
                    # level 1: the default run's 780 trials in 2.1 CPU-s and 93 MB; level 4 took
                    # 2.6 s for 91 MB (the noisy float64 mantissas barely compress at any level)
                    compression_opts=_GZIP_LEVEL,
                    shuffle=True,
                )
            else:  # HDF5 cannot chunk a zero-sized dimension
                ds = ch.create_dataset(name, data=a)
            ds.attrs["unit"] = str(trials.units[name])
        meta = f.create_group("trial_meta")
        for key, v in trials.trial_meta.items():
            v = np.asarray(v)
            if v.dtype.kind in "US":
                meta.create_dataset(key, data=v.astype(str).astype(object), dtype=_STR)
            elif v.dtype.kind in "biuf":
                meta.create_dataset(key, data=v)
            else:
                raise DataError(f"{path}: trial_meta[{key!r}] has dtype {v.dtype}; use bool/int/float/str")
        grp = f.create_group("attrs")
        for key, value in trials.attrs.items():
            _write_value(grp, key, value, "attrs")
    return path


def read_trials(path: str | os.PathLike[str]) -> TrialSet:
    """Read and validate a trial file written by :func:`write_trials` (or a real-lab importer).

    A damaged file (h5py's OSError on a corrupted block, a read refused by the system) is a
    :class:`DataError` naming it, like every other defect listed below.

    Args:
        path: the ``.h5`` file.

    Returns:
        The trial set, with numpy arrays for channels, onsets and metadata, and run attrs as
        nested dicts of Python scalars, strings, lists and numpy arrays.

    Raises:
        DataError: the file is missing or not HDF5; the format marker or version is wrong; a
            required group, dataset or unit is missing; shapes disagree; a channel has NaN/inf.
    """
    try:
        return _read_trials(Path(path))
    except OSError as e:  # h5py: a corrupted block ("Can't synchronously read data", checksum, ...)
        msg = " ".join(str(e).split())
        raise DataError(
            f"{path}: cannot be read, the file is damaged or unreadable ({msg}); restore it or run again"
        ) from None


def read_trial_file(
    path: str | os.PathLike[str], required: Sequence[str], reader: str
) -> tuple[Path, TrialSet]:
    """:func:`read_trials` of a trial file, or of the one ``.h5`` in a run folder, that must hold
    the ``required`` channels (what a diagnosis reads; ``reader`` names it in the messages).

    Returns:
        The file read (for messages naming it) and its trial set.

    Raises:
        DataError: a folder without exactly one ``.h5`` file, a file that is not ``.h5``, a missing
            channel, or what :func:`read_trials` raises.
    """
    path = Path(path)
    if path.is_dir():
        files = sorted(path.glob("*.h5"))
        if len(files) != 1:
            raise DataError(
                f"{path} holds {len(files)} .h5 files; give the trial file itself or a run folder "
                "with exactly one (trials.h5)"
            )
        path = files[0]
    if path.suffix != ".h5":
        raise DataError(
            f"{path.name}: {reader} reads armlab trial files (.h5, docs/trial_format.md); valid: a "
            "trials.h5 file or its run folder"
        )
    trials = read_trials(path)
    missing = [c for c in required if c not in trials.channels]
    if missing:
        raise DataError(f"{path.name} lacks channel(s) {missing}; have {sorted(trials.channels)}")
    return path, trials


def _read_trials(path: Path) -> TrialSet:
    if not path.is_file():
        raise DataError(f"{path}: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise DataError(f"{path}: not a readable HDF5 file ({e})") from None
    with f:
        fmt = _attr_to_python(f.attrs.get("format"))
        if fmt != FORMAT_NAME:
            raise DataError(f"{path}: root attr format is {fmt!r}, expected {FORMAT_NAME!r}")
        version = _attr_to_python(f.attrs.get("format_version"))
        if version != FORMAT_VERSION:
            raise DataError(
                f"{path}: format_version is {version!r}; this armlab reads version {FORMAT_VERSION}"
            )
        if "fs_hz" not in f.attrs:
            raise DataError(f"{path}: root attr 'fs_hz' (sample rate, Hz) is missing")
        fs_hz = float(f.attrs["fs_hz"])
        for req, cls in (("onset_index", h5py.Dataset), ("channels", h5py.Group)):
            if not isinstance(f.get(req), cls):
                what = "dataset" if cls is h5py.Dataset else "group"
                raise DataError(f"{path}: required {what} '{req}' is missing")
        onset = np.asarray(f["onset_index"][()])
        if onset.ndim != 1 or onset.dtype.kind not in "iu":
            raise DataError(
                f"{path}: onset_index must be a 1-D integer array, got {onset.dtype} {onset.shape}"
            )
        n_trials = onset.shape[0]
        channels: dict[str, np.ndarray] = {}
        units: dict[str, str] = {}
        n_samples = None
        for name, ds in f["channels"].items():
            if not isinstance(ds, h5py.Dataset) or ds.ndim != 3:
                raise DataError(
                    f"{path}: channel {name!r} must be a 3-D dataset (n_trials, n_samples, n_axes)"
                )
            if ds.shape[0] != n_trials:
                raise DataError(
                    f"{path}: channel {name!r} has shape {ds.shape} but onset_index says {n_trials} trials"
                )
            if n_samples is not None and ds.shape[1] != n_samples:
                raise DataError(
                    f"{path}: channel {name!r} has {ds.shape[1]} samples, other channels {n_samples}"
                )
            n_samples = ds.shape[1]
            if "unit" not in ds.attrs:
                raise DataError(f"{path}: channel {name!r} has no 'unit' attr")
            a = np.asarray(ds[()], dtype=np.float64)
            report = _nonfinite_report(name, a)
            if report:
                raise DataError(f"{path}: {report}")
            channels[name] = a
            units[name] = _attr_to_python(ds.attrs["unit"])
        if not channels:
            raise DataError(f"{path}: group 'channels' is empty; a trial file needs at least one channel")
        trial_meta: dict[str, np.ndarray] = {}
        if "trial_meta" in f:
            for key, ds in f["trial_meta"].items():
                if not isinstance(ds, h5py.Dataset) or ds.shape != (n_trials,):
                    shape = getattr(ds, "shape", "a group")
                    raise DataError(
                        f"{path}: trial_meta {key!r} has shape {shape} but onset_index says {n_trials} trials"
                    )
                is_str = h5py.check_string_dtype(ds.dtype) is not None
                trial_meta[key] = np.asarray(ds.asstr()[()]).astype(str) if is_str else ds[()]
        attrs = _read_value(f["attrs"]) if "attrs" in f else {}
    try:
        return TrialSet(
            fs_hz=fs_hz, onset_index=onset, channels=channels, units=units, trial_meta=trial_meta, attrs=attrs
        )
    except DataError as e:
        raise DataError(f"{path}: {e}") from None
