"""Tests for armlab.estimation.joint_centres (seed paper 001, Eqs. (7)-(9)): the spec's acceptance
check 1 on marker data generated with MuJoCo from models/arm_5dof."""

from __future__ import annotations

import numpy as np
import pytest
from arm5_data import add_marker_noise, markers, random_motion
from numpy.testing import assert_allclose

from armlab.errors import DataError, EstimationError
from armlab.estimation import joint_centre
from armlab.models import joint_centre_truth, load_arm_5dof

ARM = load_arm_5dof()
Q = random_motion(ARM, np.random.default_rng(11))  # 30 s at 500 Hz (spec check 1)
POS, ROT = markers(ARM, Q)
TRUTH = joint_centre_truth(ARM, Q)
TORSO, UPPER, FOREARM = 0, 1, 2


def _errors(pos, rot) -> tuple[float, float]:
    """Mean distance (m) of the estimated shoulder and elbow centres from the true ones."""
    sh = joint_centre(pos[:, TORSO], rot[:, TORSO], pos[:, UPPER], rot[:, UPPER])
    el = joint_centre(pos[:, UPPER], rot[:, UPPER], pos[:, FOREARM], rot[:, FOREARM])
    e_sh = np.linalg.norm(sh.centre - TRUTH.shoulder, axis=1).mean()
    e_el = np.linalg.norm(el.centre - TRUTH.elbow, axis=1).mean()
    return float(e_sh), float(e_el)


def test_ideal_markers_recover_the_centres_exactly():
    sh = joint_centre(POS[:, TORSO], ROT[:, TORSO], POS[:, UPPER], ROT[:, UPPER])
    el = joint_centre(POS[:, UPPER], ROT[:, UPPER], POS[:, FOREARM], ROT[:, FOREARM])
    # consistent data: the linear least squares is exact to rounding (1e-9 m, far inside the
    # spec's 0.5 mm of check 1)
    assert_allclose(sh.d1, TRUTH.d_shoulder[0], atol=1e-9)
    assert_allclose(sh.d2, TRUTH.d_shoulder[1], atol=1e-9)
    assert_allclose(el.d1, TRUTH.d_elbow[0], atol=1e-9)
    assert_allclose(el.d2, TRUTH.d_elbow[1], atol=1e-9)
    # spec check 1 (ideal markers) allows 0.5 mm: the 1e-9 m above is far inside it
    assert sh.rms_gap < 1e-9 and el.rms_gap < 1e-9


def test_noisy_markers_within_3_mm():
    pos, rot = add_marker_noise(POS, ROT, np.random.default_rng(12))
    e_sh, e_el = _errors(pos, rot)
    assert e_sh < 3e-3 and e_el < 3e-3, (e_sh, e_el)  # spec check 1: 0.2 mm / 0.3 deg noise, 30 s


def test_bad_input_is_refused():
    with pytest.raises(DataError, match="same number of samples"):
        joint_centre(POS[:10, 0], ROT[:10, 0], POS[:9, 1], ROT[:9, 1])
    with pytest.raises(DataError, match=r"shape \(N, 3, 3\)"):
        joint_centre(POS[:, 0], ROT[:, 0, :2], POS[:, 1], ROT[:, 1])
    still = np.repeat(ROT[:1], 50, axis=0)  # no relative rotation: the centre is not determined
    with pytest.raises(EstimationError, match="rank"):
        joint_centre(POS[:50, 0], still[:, 0], POS[:50, 1], still[:, 1])
