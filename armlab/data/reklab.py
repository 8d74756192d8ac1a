"""Importer for the real ankle recordings of the REKLAB (McGill) public data set.

The files live outside the repository, in ``shared/data/reklab_ankle/`` next to it (see that
folder's README): CSV with header ``t_s,position_rad,torque_Nm`` sampled at 1 kHz, one file per
trial (``z_df*`` dorsiflexor and ``z_pf*`` plantarflexor contractions under stochastic position
perturbation); ``tv_pilot.csv`` has ``t_s,position_perturbation_rad,torque_perturbation_Nm,
ankle_position_rad`` (perturbation about a slowly moving operating point). Parsing and validation
are those of :func:`armlab.data.joint_import.load_joint_data` (errors listed in docs/data_import.md);
this module adds the trial names and the default folder.

Signs are as recorded. In the stationary trials the torque is in antiphase with the position at
low frequency (the torque/position phase is near ±180 deg below ~2 Hz), so an impedance
``I s² + B s + K`` with positive parameters is ``-torque / position``.
"""

from __future__ import annotations

from pathlib import Path

from armlab.data.joint_import import load_joint_data
from armlab.data.joint_record import JointRecord
from armlab.errors import DataError

__all__ = [
    "DEFAULT_REKLAB_ROOT",
    "AnkleTrial",
    "list_ankle_trials",
    "load_ankle_trial",
]

#: ``<repo>/../shared/data/reklab_ankle``, anchored on this file (not the working directory).
DEFAULT_REKLAB_ROOT: Path = Path(__file__).resolve().parents[3] / "shared" / "data" / "reklab_ankle"


#: One ankle recording: the generic joint record (``t_s``, ``position`` rad, ``torque`` N·m as
#: recorded, ``fs_hz``, ``name`` the file stem, ``path``, and ``operating_point`` rad for
#: ``tv_pilot``, None otherwise).
AnkleTrial = JointRecord


def list_ankle_trials(root: Path | str = DEFAULT_REKLAB_ROOT) -> tuple[str, ...]:
    """Names (file stems) of the CSV trials in ``root``, sorted; empty if ``root`` is absent."""
    root = Path(root)
    if not root.is_dir():
        return ()
    return tuple(sorted(p.stem for p in root.glob("*.csv")))


def load_ankle_trial(name: str, root: Path | str = DEFAULT_REKLAB_ROOT) -> AnkleTrial:
    """Read one trial, e.g. ``load_ankle_trial("z_df")``.

    Args:
        name: file stem, one of :func:`list_ankle_trials`.
        root: folder of the CSV files.

    Returns:
        The :class:`AnkleTrial`.
    """
    path = Path(root) / f"{name}.csv"
    if not path.is_file():
        have = list_ankle_trials(root)
        raise DataError(f"no ankle trial {name!r}: {path} does not exist; available: {list(have) or 'none'}")
    (record,) = load_joint_data(path)  # parsing and every check: armlab.data.joint_import
    return record
