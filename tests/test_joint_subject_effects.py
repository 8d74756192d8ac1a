"""Subject effects of the joint_1dof diagnosis: a slowly time-varying stiffness that the tonic
torque does not reveal (``cocontraction_variation``'s local gains) and a slow voluntary torque
(``voluntary_torque``), both from leave-block-out local estimates (:mod:`...diagnosis.local`);
and the peer's scoring (:mod:`...diagnosis.peer`). Synthetic NumPy recordings with a known truth
(see conftest.py); the real ankle check is slow and skips without ``../shared/data``.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import (
    JOINT_B,
    JOINT_FS_HZ,
    JOINT_K,
    JointTrial,
    joint_derivatives,
    nominal_torque,
    prbs_position,
)
from scipy import signal

from armlab.config.diagnosis import DiagnosisConfig
from armlab.data import DEFAULT_REKLAB_ROOT
from armlab.protocols.joint_1dof.diagnosis.diagnose import diagnose_joint
from armlab.protocols.joint_1dof.diagnosis.local import BLOCK_S, crossfit_mean
from armlab.protocols.joint_1dof.diagnosis.peer import peer_vaf

# a reduced candidate list keeps these CI tests cheap; the reflex stays as the rival the new
# candidates must not be confused with
_CANDIDATES = ["reflex", "cocontraction_variation", "voluntary_torque"]
_NOISE = 0.15  # N·m, torque noise (the referee's JR3/ATI class at the ankle)


def _stiffness_varying(x, rng, *, depth=0.3, f_hz=0.2):
    """N·m: the nominal joint with K(t), B(t) = (1 + depth·sin(2π f t + φ))·(K, B): ±30 % at 0.2 Hz,
    with no tonic torque following it (the co-contraction the slow torque m(t) does not reveal)."""
    v, _ = joint_derivatives(x)
    t = np.arange(x.size) / JOINT_FS_HZ
    extra = depth * np.sin(2 * np.pi * f_hz * t + rng.uniform(0, 2 * np.pi))
    return nominal_torque(x) - extra * (JOINT_K * x + JOINT_B * v)


def _voluntary(x, rng, *, rms=0.5, bandwidth_hz=1.0):
    """N·m: the nominal joint plus a 0.5 N·m rms torque low-passed at 1 Hz, independent of x."""
    w = rng.standard_normal(x.size + 4000)
    s = signal.sosfiltfilt(signal.butter(2, bandwidth_hz, fs=JOINT_FS_HZ, output="sos"), w)[2000:-2000]
    return nominal_torque(x) + rms * s / np.std(s)


def _records(kind, seed, duration_s):
    rng = np.random.default_rng(seed)
    x = prbs_position(rng, duration_s)
    fn = {"stiffness": _stiffness_varying, "voluntary": _voluntary, "none": lambda x, rng: nominal_torque(x)}
    return [JointTrial(f"rep{k}", x, fn[kind](x, rng) + rng.normal(0, _NOISE, x.size)) for k in range(2)]


def test_crossfit_mean_never_uses_the_sample_it_predicts():
    """Changing one block's values leaves that block's own estimates unchanged (exactly: they are
    made from the other fold), and a constant is reproduced."""
    rng = np.random.default_rng(0)
    fs = 250.0
    z = rng.standard_normal(2000)
    block = int(round(BLOCK_S * fs))
    own = slice(10 * block, 11 * block)
    z2 = z.copy()
    z2[own] += 100.0
    a, b = crossfit_mean(z, fs, 0.25), crossfit_mean(z2, fs, 0.25)
    np.testing.assert_array_equal(a[own], b[own])
    assert np.max(np.abs(a - b)) > 1.0  # the other fold's estimates do see the change
    np.testing.assert_allclose(crossfit_mean(np.full(500, 3.0), fs, 0.25), 3.0, rtol=1e-12)


@pytest.mark.parametrize(
    ("kind", "expected"),
    [("stiffness", "cocontraction_variation"), ("voluntary", "voluntary_torque"), ("none", "none")],
)
def test_subject_effects_are_named_and_shrink_the_held_out_gap(kind, expected):
    # 18 s for the voluntary torque: its held-out part (4 s less the 2 s edge) must hold a few
    # periods of a 1 Hz process for the shrink to be measured (14 s gave 0.68 on this seed)
    duration_s = 18.0 if kind == "voluntary" else 14.0
    results, _ = diagnose_joint(
        _records(kind, seed=3, duration_s=duration_s), DiagnosisConfig(candidates=_CANDIDATES)
    )
    assert results["verdict"] == [expected]
    gap = results["gap"]
    if expected == "none":
        return
    excess = gap["nominal"] - gap["noise_floor"]
    shrink = (gap["nominal"] - gap["added"][-1]["held_out_gap"]) / excess
    # the held-out third is predicted from its neighbours' local estimates and gains fitted on the
    # first two thirds: measured 0.998 (stiffness) and 0.88-0.90 (voluntary, whose kernel passes
    # half its power at 0.53 Hz of a 1 Hz process) on 30 s trials; the target is 0.7
    assert shrink > 0.8


def test_peer_scoring_of_a_perfect_model_reaches_the_noise_limit():
    """A clean nominal joint scored as the peer is (fit 0-40 s, score the rest at 100 Hz): the
    nominal leaves only the noise; its VAF is 100 % less the noise's share of the 0-40 Hz torque."""
    rng = np.random.default_rng(5)
    x = prbs_position(rng, 45.0)
    y = nominal_torque(x)
    rec = [JointTrial("clean", x, y + rng.normal(0, 0.01, x.size))]
    _, series = diagnose_joint(rec, DiagnosisConfig(candidates=_CANDIDATES))
    tr = series["all"]["trials"][0]
    vaf = peer_vaf(tr, series["all"]["stages"][0])
    # noise 0.01 N·m white at 1 kHz keeps 40/500 of its variance below 40 Hz; the torque's
    # variance is ~y.var(): the expected loss is that ratio, within 30 % (the band edges)
    loss = 0.01**2 * 40 / 500 / np.var(y) * 100
    assert 100 - vaf == pytest.approx(loss, rel=0.3)


#: The REKLAB lab's own held-out total VAF (%), shared/data/README.md (parallel cascade, scored on
#: 40-60 s at 100 Hz).
PEER_VAF = {"z_df": 96.6, "z_pf": 90.8, "z_df2": 96.0, "z_df3": 95.1, "z_pf2": 89.0}
#: The README's parametric intrinsic-only fit scored the same way (%): the check of the scorer.
PEER_INTRINSIC_VAF = {"z_df": 87.0, "z_pf": 63.0, "z_df2": 93.0, "z_df3": 85.0, "z_pf2": 72.0}


@pytest.fixture(scope="module")
def ankle():
    if not all((DEFAULT_REKLAB_ROOT / f"{n}.csv").is_file() for n in PEER_VAF):
        pytest.skip(f"REKLAB ankle data not present at {DEFAULT_REKLAB_ROOT}")
    from armlab.data.joint_import import load_joint_data

    recs = [r for r in load_joint_data(DEFAULT_REKLAB_ROOT, min_duration_s=10.0) if r.name in PEER_VAF]
    return diagnose_joint(recs, DiagnosisConfig(per_trial=True))


def _peer_scored(series):
    """Per trial, (nominal, final) held-out VAF % scored as the peer is."""
    return {
        n: (peer_vaf(ser["trials"][0], ser["stages"][0]), peer_vaf(ser["trials"][0], ser["stages"][-1]))
        for n, ser in series.items()
    }


@pytest.mark.slow
def test_real_ankle_reflex_named_and_the_nominal_scored_as_the_peer(ankle):
    """Issue 18 item 5 (README's table): the reflex is in the verdict on >= 4 of 5 trials; the
    nominal scored as the peer reproduces the README's parametric intrinsic-only figures (within 1.5
    points: they are given rounded, and our derivatives and decimation differ, see peer.py); the
    final model scored as the peer reaches the peer's VAF on z_pf2 (measured 92.0 vs 89.0)."""
    results, series = ankle
    assert sum("reflex" in v for v in results["verdict"].values()) >= 4
    scored = _peer_scored(series)
    for name, (nominal, _) in scored.items():
        assert nominal == pytest.approx(PEER_INTRINSIC_VAF[name], abs=1.5)
    assert scored["z_pf2"][1] >= PEER_VAF["z_pf2"]


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="measured (ours vs peer) z_df 94.8 vs 96.6, z_df2 93.6 vs 96.0, z_df3 93.2 vs 95.1, z_pf 90.3 "
    "vs 90.8 (z_pf2 92.0 vs 89.0; without the torque-derived columns 93.9, 93.6, 91.4, 90.3, 87.7): "
    "what is left (position only) lies 77-91 % below 3 Hz, 18-41 % below the 0.3 Hz scoring band; "
    "the peer's structure refitted here (I, B, K and a free 0.6 s IRF of the rectified velocity, "
    "100 Hz) reaches 95.5, 95.7, 93.6, 90.8, 88.0; a sensor bandwidth or channel delay moves the "
    "gap by < 0.002",
)
def test_real_ankle_final_reaches_the_peer_on_every_trial(ankle):
    # like for like as well: the peer's model predicts the torque from the position alone, while the
    # torque-derived columns (tonic level x angle, local estimates) predict part of the torque from
    # the torque itself; with the co-contraction columns in a model the default score passed the
    # peer everywhere (97.7 / 93.0 / 98.1 / 97.2 / 95.9) without a better physical model
    _, series = ankle
    scored = _peer_scored(series)
    assert all(scored[n][1] >= PEER_VAF[n] for n in PEER_VAF)
    assert all(
        peer_vaf(ser["trials"][0], ser["stages"][-1], position_only=True) >= PEER_VAF[n]
        for n, ser in series.items()
    )
