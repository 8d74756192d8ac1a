"""Units of imported joint recordings: the ``units=`` override and the plausibility check.

Every joint data verb (``armlab diagnose data=... protocol=joint_1dof``, ``armlab fit-joint``,
:func:`armlab.data.reklab.load_ankle_trial`) reads through
:func:`armlab.data.joint_import.load_joint_data`, which applies :func:`apply_units` to each trial:

* a channel whose unit the user states (``units=deg``, ``units=Nmm``, ``units=deg,Nmm``; SI is
  ``rad`` and ``Nm``) is converted to SI and trusted as stated;
* a channel left unstated is taken as SI and checked against human ranges, after the stated
  channel is converted (the torque/angle scale compares SI with SI, so stating one channel does
  not hide the other's unit); a value outside them is a :class:`~armlab.errors.DataError` that
  names the likely unit (degrees, N·mm) and the ``units=`` override that reads it, or
  ``units=rad,Nm`` to keep SI when the data really are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from armlab.data.joint_record import JointRecord
from armlab.errors import DataError

__all__ = [
    "ANGLE_UNITS",
    "MAX_ANGLE_RAD",
    "MAX_TORQUE_NM",
    "SCALE_RANGE_NM_PER_RAD",
    "TORQUE_UNITS",
    "JointUnits",
    "apply_units",
    "parse_units",
]

#: angle unit -> factor to rad
ANGLE_UNITS: dict[str, float] = {"rad": 1.0, "deg": math.pi / 180.0}
#: torque unit -> factor to N·m
TORQUE_UNITS: dict[str, float] = {"Nm": 1.0, "Nmm": 1e-3}

# rad: no human joint moves more than 180 deg either side of its reference (the largest ranges of
# motion, shoulder flexion/abduction, are ~180 deg in all), so |angle| > pi rad is not radians;
# the same angle in degrees exceeds it from 3.2 deg on.
MAX_ANGLE_RAD = math.pi
# N·m: the strongest human joint torques (knee extension, ankle plantarflexion, maximal voluntary
# contraction) are some 250-400 N·m; 1000 N·m is 2.5 times that. A torque of a few N·m written in
# N·mm exceeds it.
MAX_TORQUE_NM = 1000.0
# N·m/rad: rms(torque - mean) / rms(angle - mean), the impedance magnitude averaged over the
# perturbation's band. Lower bound: a relaxed elbow, the most compliant joint armlab's 1-DoF
# protocols study, has ~5-10 N·m/rad of stiffness, and its inertia and damping only raise the
# broadband ratio (the REKLAB ankle files give 83-227 N·m/rad, in degrees 1.4-4.0). Upper bound:
# 5x ~1000 N·m/rad, the stiffest joint impedances reported (ankle/knee under maximal
# co-contraction); the same ankle files with torque in N·mm give 83 000-227 000. Assumption-level
# bounds, stated: data outside them are refused unless the units are given explicitly.
SCALE_RANGE_NM_PER_RAD = (5.0, 5000.0)

_VALID = f"angle {list(ANGLE_UNITS)}, torque {list(TORQUE_UNITS)}"


@dataclass(frozen=True, kw_only=True)
class JointUnits:
    """The units the user stated for a recording's channels (None: SI assumed and checked)."""

    angle: str | None = None
    torque: str | None = None

    def __str__(self) -> str:
        return ",".join(u for u in (self.angle, self.torque) if u) or "(none stated)"


def parse_units(spec: str | None) -> JointUnits:
    """``"deg"``, ``"Nmm"``, ``"deg,Nmm"``, ``"rad,Nm"`` (order free, ``+`` also separates) ->
    :class:`JointUnits`; None or ``""``: nothing stated.

    Raises:
        DataError: an unknown unit, or two units for one channel.
    """
    if spec is None or not str(spec).strip():
        return JointUnits()
    angle = torque = None
    for token in str(spec).replace("+", ",").split(","):
        token = token.strip()
        if token in ANGLE_UNITS and angle is None:
            angle = token
        elif token in TORQUE_UNITS and torque is None:
            torque = token
        elif token in ANGLE_UNITS or token in TORQUE_UNITS:
            raise DataError(f"units={spec}: two units for one channel; give at most one of each: {_VALID}")
        else:
            raise DataError(
                f"units={spec}: unknown unit {token!r}; valid: {_VALID}, comma-separated (e.g. units=deg, "
                "units=Nmm, units=deg,Nmm; units=rad,Nm states SI)"
            )
    return JointUnits(angle=angle, torque=torque)


def _rms_dev(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean((x - np.mean(x)) ** 2)))


def _suggest(units: JointUnits, *, angle: str | None = None, torque: str | None = None) -> str:
    """The ``units=`` that reads the file with the suspect channel in ``angle``/``torque``, keeping
    what the user stated for the other channel (``units=Nmm`` and degrees suspected: ``deg,Nmm``)."""
    return str(JointUnits(angle=angle or units.angle, torque=torque or units.torque))


def _check(record: JointRecord, units: JointUnits) -> None:
    """Check the channels left unstated in ``record``, which is already converted to SI for the
    stated ones: the peaks of an unstated channel are its raw values, and the torque/angle scale
    compares SI with SI, so one stated channel does not hide the other (a file in degrees and N·mm
    read with ``units=Nmm`` alone has the scale of degrees, ~1.75 for 100 N·m/rad, not the raw
    ratio ~1750 that lies inside the human range)."""
    where = f"{record.path.name}" + (f" ({record.name})" if record.name != record.path.stem else "")
    as_is = JointUnits(angle=units.angle or "rad", torque=units.torque or "Nm")
    keep = (
        "units=rad,Nm states that the data are SI"
        if units == JointUnits()
        else f"units={as_is} states that the unstated channel is SI"
    )
    deg, nmm = _suggest(units, angle="deg"), _suggest(units, torque="Nmm")
    if units.angle is None:
        angles = [record.position] + ([record.operating_point] if record.operating_point is not None else [])
        peak = max(float(np.max(np.abs(a))) for a in angles)
        if peak > 180.0:  # beyond the same range in degrees too
            raise DataError(
                f"{where}: the joint angle reaches {peak:.4g}, beyond any human joint's range in rad (<= pi) "
                f"and in degrees (<= 180); check the angle column"
            )
        if peak > MAX_ANGLE_RAD:
            raise DataError(
                f"{where}: the joint angle reaches {peak:.4g}, beyond any human joint's range (|angle| <= "
                f"pi rad = 180 deg): it looks like degrees; give units={deg} to read it so ({keep})"
            )
    if units.torque is None:
        peak = float(np.max(np.abs(record.torque)))
        if peak > 1000 * MAX_TORQUE_NM:  # beyond the same bound in N·mm too
            raise DataError(
                f"{where}: the torque reaches {peak:.4g}, beyond any human joint in N·m "
                f"(<= {MAX_TORQUE_NM:g}) and in N·mm (<= {1000 * MAX_TORQUE_NM:g}); check the torque column"
            )
        if peak > MAX_TORQUE_NM:
            raise DataError(
                f"{where}: the torque reaches {peak:.4g}, beyond any human joint (|torque| <= "
                f"{MAX_TORQUE_NM:g} N·m): it looks like N·mm; give units={nmm} to read it so ({keep})"
            )
    if units.angle is None or units.torque is None:
        dp, dt = _rms_dev(record.position), _rms_dev(record.torque)
        if dp == 0 or dt == 0:
            return  # a flat channel: no scale to judge (the fits refuse it on their own terms)
        scale = dt / dp
        lo, hi = SCALE_RANGE_NM_PER_RAD
        if scale < lo and units.angle is None:
            raise DataError(
                f"{where}: torque/angle scale {scale:.3g} N·m/rad (rms of their variations) is below any "
                f"human joint's ({lo:g}-{hi:g} N·m/rad): the angle looks like degrees (x 57.3 -> "
                f"{scale * 180 / math.pi:.3g} N·m/rad in rad); give units={deg} to read it so ({keep})"
            )
        if scale > hi and units.torque is None:
            raise DataError(
                f"{where}: torque/angle scale {scale:.3g} N·m/rad (rms of their variations) is above any "
                f"human joint's ({lo:g}-{hi:g} N·m/rad): the torque looks like N·mm (/ 1000 -> "
                f"{scale / 1000:.3g} N·m/rad); give units={nmm} to read it so ({keep})"
            )


def apply_units(record: JointRecord, units: JointUnits) -> JointRecord:
    """The record in SI (rad, N·m): stated units converted, then the unstated ones checked.

    Returns ``record`` itself when nothing is stated and the check passes (no copy, bit-identical).

    Raises:
        DataError: an unstated channel outside the human ranges above, naming the likely unit.
    """
    a = ANGLE_UNITS[units.angle] if units.angle else 1.0
    k = TORQUE_UNITS[units.torque] if units.torque else 1.0
    if a != 1.0 or k != 1.0:
        record = replace(
            record,
            position=record.position * a,
            torque=record.torque * k,
            operating_point=None if record.operating_point is None else record.operating_point * a,
        )
    _check(record, units)  # on the converted record: the scale compares SI with SI
    return record
