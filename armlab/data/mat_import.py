"""MATLAB ``.mat`` import of 1-DoF joint recordings (the ``.mat`` half of :mod:`armlab.data.joint_import`).

Read with ``matio`` (PyPI package mat-io; imported on first use): REKLAB ``nldat`` objects whose
channels are identified as position or torque by their names and units, or plain variables / a
struct / a table holding ``t_s`` (or a scalar ``fs_hz``), ``position_rad`` (or ``position``) and
``torque_Nm`` (or ``torque``). Layouts and errors: ``docs/data_import.md``.
"""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from armlab.data.joint_record import _RATE_RTOL, JointRecord, _check_samples
from armlab.errors import DataError

__all__ = ["read_mat"]

# .mat field names, first match wins.
_POSITION_FIELDS = ("position_rad", "position")
_TORQUE_FIELDS = ("torque_Nm", "torque")
# nldat channel names: a token starting a word (so "compose" is no position, "posPert1" is).
_POSITION_NAME = re.compile(r"(?:^|[^a-z])(?:pos|angle|theta)", re.IGNORECASE)
_TORQUE_NAME = re.compile(r"(?:^|[^a-z])(?:tq|trq|torque)", re.IGNORECASE)
_UNSET_UNITS = frozenset({"", "default units", "none", "unknown"})
_POSITION_UNITS = frozenset({"rad", "radian", "radians"})
_TORQUE_UNITS = frozenset({"nm", "n·m", "n.m", "n*m", "n-m", "newtonmeter", "newtonmeters"})
_MAT_LAYOUTS = (
    "nldat objects with one position channel (name starting pos/angle/theta, units rad or unset) "
    "and one torque channel (name starting tq/trq/torque, units N·m or unset); or variables, a "
    "struct or a table with t_s (or scalar fs_hz), position_rad (or position), torque_Nm (or torque)"
)


def _load_mat_file(path: Path) -> dict[str, Any]:
    # Imported here: matio imports pandas (~0.5 s) and, on import, sets a pandas option with a
    # deprecation warning that says nothing about the data.
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*infer_string.*")
        import matio
    try:
        contents = matio.load_from_mat(path)
    except Exception as err:  # matio raises its own MatReadError, ValueError, KeyError, OSError...
        raise DataError(
            f"{path.name}: not a readable MATLAB file ({type(err).__name__}: {err}); expected a .mat "
            f"file of version 5, 7 or 7.3"
        ) from None
    return {k: v for k, v in contents.items() if not k.startswith("__")}


def _texts(value: Any) -> list[str]:
    """A MATLAB char array or cell array of them as a list of str (column-major order)."""
    if value is None:
        return []
    a = np.asarray(value)
    if a.dtype == object:  # cell array
        return [" ".join(_texts(v)) for v in a.ravel(order="F")]
    return [str(v) for v in a.ravel()]  # char array: one str per row


def _scalar(value: Any) -> float | None:
    """A positive finite number from a 1x1 array, or None."""
    try:
        a = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        return None
    return float(a[0]) if a.size == 1 and math.isfinite(a[0]) and a[0] > 0 else None


def _vector(value: Any, where: str, name: str) -> np.ndarray:
    a = np.asarray(value)
    if a.dtype.kind not in "fiub" or sum(d > 1 for d in a.shape) > 1:
        raise DataError(f"{where}: {name!r} must be a real vector (1 x n or n x 1), got {_describe(value)}")
    return np.ascontiguousarray(a, dtype=float).ravel()


def _describe(value: Any) -> str:
    if getattr(value, "classname", None) == "nldat":
        return f"nldat, channels {_texts(value.properties.get('chanNames'))}"
    fields = _fields(value)
    if fields is not None:
        return f"struct/table with fields {list(fields)}"
    if hasattr(value, "classname"):
        return f"{value.classname} object"
    return f"{value.dtype} array {value.shape}" if isinstance(value, np.ndarray) else type(value).__name__


def _fields(value: Any) -> dict[str, Any] | None:
    """The named fields of a 1x1 struct or a table (matio reads tables as DataFrames); else None."""
    if isinstance(value, np.ndarray) and value.dtype.names and value.size == 1:
        return {n: value.ravel()[0][n] for n in value.dtype.names}
    if hasattr(value, "columns") and hasattr(value, "to_numpy"):
        return {str(c): value[c].to_numpy() for c in value.columns}
    return None


def _is_trial_fields(fields: dict[str, Any]) -> bool:
    return any(k in fields for k in _POSITION_FIELDS) and any(k in fields for k in _TORQUE_FIELDS)


def _from_fields(fields: dict[str, Any], where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(t_s, position, torque, fs_hz) from fields named as in :data:`JOINT_COLUMNS` (or plain)."""
    pos_key = next(k for k in _POSITION_FIELDS if k in fields)
    tq_key = next(k for k in _TORQUE_FIELDS if k in fields)
    position, torque = _vector(fields[pos_key], where, pos_key), _vector(fields[tq_key], where, tq_key)
    fs_given = _scalar(fields["fs_hz"]) if "fs_hz" in fields else None
    if "fs_hz" in fields and fs_given is None:
        raise DataError(f"{where}: 'fs_hz' must be a scalar rate > 0 Hz, got {_describe(fields['fs_hz'])}")
    if "t_s" in fields:
        t = _vector(fields["t_s"], where, "t_s")
    elif fs_given is not None:
        t = np.arange(position.size) / fs_given
    else:
        raise DataError(f"{where}: has {pos_key!r} and {tq_key!r} but no time; add 't_s' (s) or 'fs_hz' (Hz)")
    if not t.size == position.size == torque.size:
        sizes = {"t_s": t.size, pos_key: position.size, tq_key: torque.size}
        raise DataError(f"{where}: the vectors differ in length {sizes}; they must have one sample each")
    fs = _check_samples(where, t, {pos_key: position, tq_key: torque}, "sample")
    if fs_given is not None and abs(fs - fs_given) > _RATE_RTOL * fs_given:
        raise DataError(f"{where}: 'fs_hz' = {fs_given:.9g} Hz but 't_s' gives {fs:.9g} Hz; they must agree")
    return t, position, torque, fs if "t_s" in fields else fs_given


def _nldat_roles(names: list[str], units: list[str], where: str) -> tuple[list[int], list[int]]:
    """Indices of the position and the torque channels, from channel names, checked by units."""
    if len(units) == 1:  # nldat's default: one 'Default Units' for every channel
        units = units * len(names)
    if len(units) != len(names):
        raise DataError(f"{where}: {len(names)} channel name(s) {names} but {len(units)} unit(s) {units}")
    pos, tq = [], []
    for i, (name, unit) in enumerate(zip(names, units, strict=True)):
        u = (
            ""
            if unit.strip().lower() in _UNSET_UNITS
            else unit.strip().strip("()[]").lower().replace(" ", "")
        )
        named_pos, named_tq = bool(_POSITION_NAME.search(name)), bool(_TORQUE_NAME.search(name))
        if named_pos and named_tq:
            raise DataError(f"{where}: channel {name!r} names both a position and a torque; rename it")
        if named_pos or (not named_tq and u in _POSITION_UNITS):
            if u and u not in _POSITION_UNITS:
                raise DataError(
                    f"{where}: position channel {name!r} has units {unit!r}; accepted: rad or unset"
                )
            pos.append(i)
        elif named_tq or u in _TORQUE_UNITS:
            if u and u not in _TORQUE_UNITS:
                raise DataError(
                    f"{where}: torque channel {name!r} has units {unit!r}; accepted: N·m or unset"
                )
            tq.append(i)
    return pos, tq


def _from_nldat(value: Any, where: str) -> tuple[np.ndarray, np.ndarray, list[str], float | None]:
    """(t_s, (samples, channels) data, channel names, fs_hz or None) of a REKLAB nldat object."""
    p = value.properties
    names = _texts(p.get("chanNames"))
    data = np.asarray(p.get("dataSet"))
    if data.ndim == 3 and data.shape[2] == 1:  # one realisation
        data = data[:, :, 0]
    if data.dtype.kind not in "fiu" or data.ndim != 2 or data.shape[1] != len(names):
        raise DataError(
            f"{where}: dataSet must be real (samples, channels) with one column per channel name "
            f"{names}, got {data.dtype} {data.shape}"
        )
    domain = np.asarray(p.get("domainValues", np.nan), dtype=float).ravel()
    if domain.size == data.shape[0] and np.all(np.isfinite(domain)):  # explicit sample times
        return domain, data.astype(float), names, None
    incr = _scalar(p.get("domainIncr"))  # domainValues = NaN: uniform, domainStart + k * domainIncr
    if incr is None:
        raise DataError(f"{where}: domainIncr must be a sampling increment > 0 s, got {p.get('domainIncr')}")
    start = np.asarray(p.get("domainStart", 0.0), dtype=float).ravel()
    t = (float(start[0]) if start.size else 0.0) + np.arange(data.shape[0]) * incr
    return t, data.astype(float), names, 1.0 / incr


def read_mat(path: Path) -> list[JointRecord]:
    variables = _load_mat_file(path)
    if not variables:
        raise DataError(f"{path.name}: holds no variables; expected {_MAT_LAYOUTS}")
    found = "; ".join(f"{k} ({_describe(v)})" for k, v in sorted(variables.items()))
    if _is_trial_fields(variables):  # plain top-level variables; other variables are ignored
        t, pos, tq, fs = _from_fields(variables, path.name)
        return [JointRecord(name=path.stem, t_s=t, position=pos, torque=tq, fs_hz=fs, path=path)]
    trials: dict[str, tuple] = {}  # variable -> (t, position, torque, fs)
    slow: dict[str, tuple] = {}  # variable -> (t, position, fs): position-only nldat
    unmapped = []
    for var, value in sorted(variables.items()):
        where = f"{path.name}: variable {var!r}"
        fields = _fields(value)
        if fields is not None and _is_trial_fields(fields):
            trials[var] = _from_fields(fields, where)
        elif getattr(value, "classname", None) == "nldat":
            t, data, names, fs = _from_nldat(value, where)
            pos, tq = _nldat_roles(names, _texts(value.properties.get("chanUnits")), where)
            used = pos + tq if len(pos) == 1 and len(tq) <= 1 else []  # other channels are ignored
            if used:  # only the channels used are checked
                fs_t = _check_samples(where, t, {names[i]: data[:, i] for i in used}, "sample")
                fs = fs_t if fs is None else fs
            if used and tq:
                trials[var] = (t, data[:, pos[0]], data[:, tq[0]], fs)
            elif used and data.shape[1] == 1:  # a lone position: candidate operating point
                slow[var] = (t, data[:, 0], fs)
            else:
                unmapped.append(var)
        elif fields is not None or hasattr(value, "classname"):
            unmapped.append(var)  # an object or struct we cannot read as a trial
        # plain arrays and strings beside objects are ignored, like extra CSV columns
    operating: dict[str, tuple[str, np.ndarray]] = {}
    for var, (t, angle, _fs) in slow.items():
        same = [
            k for k, tr in trials.items() if tr[0].size == t.size and np.allclose(tr[0], t, rtol=0, atol=1e-9)
        ]
        if len(same) != 1 or same[0] in operating:
            unmapped.append(var)
        else:
            operating[same[0]] = (var, angle)
    if unmapped or not trials:
        bad = sorted(unmapped) if trials else sorted(variables)
        raise DataError(
            f"{path.name}: cannot map variable(s) {bad} to a position and a torque channel; variables "
            f"found: {found}. Expected {_MAT_LAYOUTS} (a single position-only nldat with the time base "
            f"of exactly one trial is that trial's operating point)"
        )
    several = len(trials) > 1
    return [
        JointRecord(
            name=f"{path.stem}/{var}" if several else path.stem,
            t_s=t,
            position=pos,
            torque=tq,
            fs_hz=fs,
            path=path,
            operating_point=operating[var][1] if var in operating else None,
        )
        for var, (t, pos, tq, fs) in trials.items()
    ]
