"""Shared check of the scenes that run without collision detection (imported by their tests)."""

from __future__ import annotations

import copy
from collections.abc import Callable

import mujoco
import numpy as np


def assert_contacts_off_changes_nothing(scene, prepare: Callable[[mujoco.MjData], None], nstep: int) -> None:
    """The scene carries the no-contact flag, and stepping ``nstep`` steps from the state
    ``prepare`` writes gives the same state and sensors bit for bit with contacts back on."""
    assert scene.model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    assert 'contact="disable"' in scene.xml
    with_contacts = copy.copy(scene.model)
    with_contacts.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    runs = []
    for model in (scene.model, with_contacts):
        data = mujoco.MjData(model)
        prepare(data)
        mujoco.mj_step(model, data, nstep=nstep)
        runs.append(np.concatenate([data.qpos, data.qvel, data.act, data.sensordata]))
    assert np.all(np.isfinite(runs[0]))
    np.testing.assert_array_equal(runs[0], runs[1])
