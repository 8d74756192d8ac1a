"""Importer for 1-DoF joint-perturbation recordings: imposed joint angle in, measured torque out.

One :class:`JointRecord` per trial, read by :func:`load_joint_data` from a CSV file, a MATLAB
``.mat`` file, or a folder of them; :func:`write_joint_csv` writes the CSV form. The accepted
layouts, units, sign conventions and every error are documented in ``docs/data_import.md``:

* CSV, comma-separated, one header row naming at least ``t_s,position_rad,torque_Nm`` (any order,
  extra columns ignored), or the time-varying REKLAB layout ``t_s,position_perturbation_rad,
  torque_perturbation_Nm,ankle_position_rad`` (position and torque are then the perturbation
  columns, ``ankle_position_rad`` the slow operating point).
* ``.mat`` (v5/v7 or v7.3, read with ``matio`` from the PyPI package mat-io): REKLAB ``nldat``
  objects whose channels are identified as position or torque by their names and units; or plain
  variables / a struct / a table holding ``t_s`` (or a scalar ``fs_hz``), ``position_rad`` (or
  ``position``) and ``torque_Nm`` (or ``torque``).

Every trial is checked: finite values, time strictly increasing with a constant step (relative
tolerance 1e-6 of the step plus 1e-9 s), at least two samples. Signs are as recorded.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from armlab.data.joint_record import _RATE_RTOL, JointRecord, _check_samples
from armlab.data.joint_units import JointUnits, apply_units, parse_units
from armlab.errors import DataError

__all__ = [
    "JOINT_COLUMNS",
    "TIME_VARYING_COLUMNS",
    "SUPPORTED_SUFFIXES",
    "load_joint_data",
    "write_joint_csv",
]

#: CSV header of a stationary trial: time (s), imposed joint angle (rad), measured torque (N·m).
JOINT_COLUMNS: tuple[str, ...] = ("t_s", "position_rad", "torque_Nm")
#: CSV header of a time-varying trial (REKLAB ``tv_pilot``): perturbation about a moving angle.
TIME_VARYING_COLUMNS: tuple[str, ...] = (
    "t_s",
    "position_perturbation_rad",
    "torque_perturbation_Nm",
    "ankle_position_rad",
)
#: File suffixes :func:`load_joint_data` reads (case-insensitive).
SUPPORTED_SUFFIXES: tuple[str, ...] = (".csv", ".mat")

# Time needs more digits than the signals: at 100 s, 9 significant digits resolve only 1 µs, too
# coarse for the uniformity check at kHz rates that are not decimal (e.g. 2048 Hz). 15 digits
# print k/1000 s as written and round-trip any time to ~1e-15 relative.
_TIME_FMT = "%.15g"
_SIGNAL_FMT = "%.9g"


# --- CSV ------------------------------------------------------------------------------------------
def _csv_layout(path: Path, header: list[str]) -> tuple[str, ...]:
    """The layout the header claims; DataError on missing or duplicated columns."""
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise DataError(
            f"{path.name}: duplicate column(s) {dup} in the header {header}; names must be unique"
        )
    time_varying = any(c in header for c in TIME_VARYING_COLUMNS[1:])
    expected, other = (
        (TIME_VARYING_COLUMNS, JOINT_COLUMNS) if time_varying else (JOINT_COLUMNS, TIME_VARYING_COLUMNS)
    )
    missing = [c for c in expected if c not in header]
    other_sep = [sep for sep in (";", "\t", "|") if any(sep in h for h in header)]
    if missing and other_sep:
        raise DataError(
            f"{path.name}: the header {header} looks {other_sep[0]!r}-separated; armlab reads "
            f"comma-separated CSV with the columns {list(expected)} (or {list(other)})"
        )
    if missing:
        raise DataError(
            f"{path.name}: missing column(s) {missing}; expected {list(expected)} (the other layout: "
            f"{list(other)}; extra columns are ignored), found {header}"
        )
    return expected


def _first_bad_cell(path: Path, header: list[str], usecols: list[int]) -> str | None:
    """Where np.loadtxt failed, in words (a short row or a non-numeric cell); slow path only."""
    row = 0
    with path.open(encoding="utf-8-sig") as fh:
        next(fh)
        for line in fh:
            if not line.strip():
                continue  # np.loadtxt skips blank lines too
            row += 1
            cells = line.rstrip("\r\n").split(",")
            if len(cells) <= max(usecols):
                return f"data row {row} has {len(cells)} cell(s), the header has {len(header)} columns"
            for j in usecols:
                try:
                    float(cells[j])
                except ValueError:
                    return (
                        f"non-numeric cell {cells[j].strip()!r} at data row {row}, column {header[j]!r}; "
                        f"cells must be decimal numbers (nan/inf are refused later)"
                    )
    return None


def _read_csv(path: Path) -> JointRecord:
    with path.open(encoding="utf-8-sig") as fh:
        first = fh.readline()
        if not first.strip():
            raise DataError(
                f"{path.name}: is empty; expected a header row with columns {list(JOINT_COLUMNS)} "
                f"(or {list(TIME_VARYING_COLUMNS)}) and data rows below it"
            )
        has_rows = any(line.strip() for line in fh)
    header = [h.strip() for h in first.split(",")]
    layout = _csv_layout(path, header)
    if not has_rows:
        raise DataError(f"{path.name}: has no data rows below the header; a trial needs at least 2")
    usecols = [header.index(c) for c in layout]
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, usecols=usecols, ndmin=2, encoding="utf-8-sig")
    except ValueError as err:
        where = _first_bad_cell(path, header, usecols) or f"could not parse the numbers ({err})"
        raise DataError(f"{path.name}: {where}") from None
    col = dict(zip(layout, data.T, strict=True))
    t = np.ascontiguousarray(col["t_s"])
    signals = {c: np.ascontiguousarray(col[c]) for c in layout[1:]}
    fs = _check_samples(path.name, t, signals, "row")
    return JointRecord(
        name=path.stem,
        t_s=t,
        position=signals[layout[1]],
        torque=signals[layout[2]],
        fs_hz=fs,
        path=path,
        operating_point=signals.get("ankle_position_rad"),
    )


# --- public entry points --------------------------------------------------------------------------
def _read_file(path: Path) -> list[JointRecord]:
    suffix = path.suffix.lower()
    try:
        if suffix == ".csv":
            return [_read_csv(path)]
        if suffix == ".mat":
            from armlab.data.mat_import import read_mat  # matio is imported only for .mat files

            return read_mat(path)
    except UnicodeDecodeError as exc:
        raise DataError(
            f"{path}: is not a text CSV (byte {exc.start} is not UTF-8: a binary file?); expected comma-"
            f"separated text with the header {','.join(JOINT_COLUMNS)}"
        ) from None
    except OSError as exc:
        raise DataError(f"{path}: cannot be read ({exc.strerror or exc}); check its permissions") from None
    raise DataError(
        f"{path.name}: unsupported file type {path.suffix or '(no extension)'!r}; supported: "
        f"{list(SUPPORTED_SUFFIXES)} or a folder holding such files"
    )


def load_joint_data(
    path: Path | str, *, min_duration_s: float = 0.0, units: str | JointUnits | None = None
) -> tuple[JointRecord, ...]:
    """Read joint-perturbation trials from one file or a folder (format in docs/data_import.md).

    Args:
        path: a ``.csv`` file (one trial), a ``.mat`` file (one trial per mapped variable), or a
            folder: every ``*.csv`` and ``*.mat`` in it, by file name, not recursive.
        min_duration_s: s, refuse any trial shorter than this (``n_samples / fs_hz``).
        units: the units of the angle and torque columns when they are not SI (``"deg"``,
            ``"Nmm"``, ``"deg,Nmm"``; ``"rad,Nm"`` states SI); unstated channels are read as rad
            and N·m and checked against human ranges (:mod:`armlab.data.joint_units`).

    Returns:
        The trials, in file-name order and, within a ``.mat``, variable-name order.

    Raises:
        DataError: the path does not exist or has an unsupported suffix; a folder holds no
            supported file, has files of different sample rates or two trials of one name; a
            file's columns or variables are missing or unmappable, its cells non-numeric or
            non-finite, its time not strictly increasing or not uniformly sampled; a trial is
            shorter than ``min_duration_s``; a file that is not text or cannot be read; an
            unstated unit outside human ranges (the message names the likely unit); an unknown
            unit.
    """
    path = Path(path)
    stated = units if isinstance(units, JointUnits) else parse_units(units)
    if not (math.isfinite(min_duration_s) and min_duration_s >= 0):
        raise DataError(f"min_duration_s must be a finite number of seconds >= 0, got {min_duration_s}")
    if not path.exists():
        raise DataError(
            f"{path} does not exist; expected a {' or '.join(SUPPORTED_SUFFIXES)} file or a folder of them"
        )
    if path.is_dir():
        files = sorted(
            (p for p in path.iterdir() if p.is_file() and p.suffix.lower() in SUPPORTED_SUFFIXES),
            key=lambda p: p.name,
        )
        if not files:
            raise DataError(
                f"{path}: no trial files; looked for {', '.join('*' + s for s in SUPPORTED_SUFFIXES)} "
                f"directly in the folder (subfolders are not searched)"
            )
    else:
        files = [path]
    records = [apply_units(r, stated) for f in files for r in _read_file(f)]
    names = [r.name for r in records]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise DataError(f"{path}: several trials named {dup}; rename the files so each trial name is unique")
    ref = records[0].fs_hz
    if path.is_dir() and any(abs(r.fs_hz - ref) > _RATE_RTOL * ref for r in records):
        rates = ", ".join(f"{r.name}: {r.fs_hz:.9g} Hz" for r in records)
        raise DataError(
            f"{path}: the files have different sample rates ({rates}); one folder must hold one rate "
            f"(resample, or load the files separately)"
        )
    for r in records:
        if r.duration_s < min_duration_s:
            raise DataError(
                f"{r.path.name}: trial {r.name!r} lasts {r.duration_s:.9g} s, shorter than "
                f"min_duration_s = {min_duration_s:.9g} s"
            )
    return tuple(records)


def write_joint_csv(
    path: Path | str,
    record: JointRecord | None = None,
    *,
    t_s: np.ndarray | None = None,
    position: np.ndarray | None = None,
    torque: np.ndarray | None = None,
    operating_point: np.ndarray | None = None,
    overwrite: bool = False,
) -> Path:
    """Write one trial as a CSV that :func:`load_joint_data` reads back.

    Columns :data:`JOINT_COLUMNS`, or :data:`TIME_VARYING_COLUMNS` when an operating point is
    given. Signals are written with 9 significant digits (``%.9g``, relative rounding <= 5e-9),
    time with 15 (``%.15g``: exact for decimal times such as k/1000 s, and fine enough for the
    uniformity check at any rate).

    Args:
        path: the ``.csv`` file to create.
        record: the trial; or, instead, the arrays below.
        t_s: (n,) s, strictly increasing with a constant step.
        position: (n,) rad.
        torque: (n,) N·m.
        operating_point: (n,) rad, optional (taken from ``record`` when a record is given).
        overwrite: replace an existing file; by default an existing file is refused.

    Returns:
        The path written.
    """
    path = Path(path)
    if record is not None:
        if any(v is not None for v in (t_s, position, torque, operating_point)):
            raise DataError(
                "write_joint_csv: give a JointRecord or the arrays t_s, position, torque, not both"
            )
        t_s, position, torque, operating_point = (
            record.t_s,
            record.position,
            record.torque,
            record.operating_point,
        )
    if t_s is None or position is None or torque is None:
        raise DataError("write_joint_csv: give a JointRecord or all three arrays t_s, position and torque")
    if path.suffix.lower() != ".csv":
        raise DataError(f"{path.name}: write_joint_csv writes CSV; the file name must end in .csv")
    columns = JOINT_COLUMNS if operating_point is None else TIME_VARYING_COLUMNS
    values = [np.asarray(v, dtype=float) for v in (t_s, position, torque, operating_point)[: len(columns)]]
    if any(v.ndim != 1 or v.shape != values[0].shape for v in values):
        raise DataError(f"{path.name}: arrays must be 1-D of one length, got {[v.shape for v in values]}")
    _check_samples(path.name, values[0], dict(zip(columns[1:], values[1:], strict=True)), "row")
    fmt = [_TIME_FMT] + [_SIGNAL_FMT] * (len(columns) - 1)
    try:
        with path.open("w" if overwrite else "x", encoding="utf-8", newline="\n") as fh:
            np.savetxt(
                fh, np.column_stack(values), delimiter=",", header=",".join(columns), comments="", fmt=fmt
            )
    except FileExistsError:
        raise DataError(f"{path}: file already exists; pass overwrite=True to replace it") from None
    except FileNotFoundError:
        raise DataError(f"{path}: folder {path.parent} does not exist; create it first") from None
    return path
