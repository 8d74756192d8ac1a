"""The blind referee of ``armlab diagnose``: pseudo-real datasets with hidden effects, then scoring.

For the 1-DoF joint protocol every dataset is made by the higher-fidelity MuJoCo simulation
(:func:`armlab.sim.joint_rig.simulate_joint_rig`) of a random subject, under two REKLAB-style
pseudo-random position sequences each recorded twice (the repeats give the diagnoser its noise
floor), with the class's hidden effects at a random magnitude. The trials are written as CSV
files; the diagnoser is then run on that folder alone (:func:`run_diagnoser`), and never sees
the truth, which stays in the referee's own records. Classes:

- ``none`` (no effect), one class per single effect, the pair ``reflex+joint_friction``, and
  ``left_out:reflex`` (a reflex hidden but absent from the candidate list: expected ``unknown``).

The effect-to-noise ratio (ENR) of a dataset is measured, not set: the rms difference between the
noise-free torque with and without the hidden effects in the scoring band, divided by the noise
rms in the same band. Magnitudes are drawn log-uniformly over ranges that put the ENR around
0.3-10 at the configured noise.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.config.effects import EFFECTS, EffectsConfig
from armlab.diagnosis.scoring import Dataset, log_uniform
from armlab.dsp import butterworth, zero_phase

__all__ = [
    "JOINT_CLASSES",
    "describe",
    "make_dataset",
]

#: Hidden-effect magnitude ranges (log-uniform), by effect: field -> (low, high).
_MAGNITUDES = {
    # ranges chosen on the tuning seed so that the measured ENR spans ~0.3-10 at 0.15 N·m noise
    "reflex": {"gain_Nms_per_rad": (0.1, 3.0), "delay_s": (0.03, 0.06)},
    "cuff_compliance": {"stiffness_Nm_per_rad": (1500.0, 50000.0)},
    "transmission_compliance": {"stiffness_Nm_per_rad": (8000.0, 150000.0)},
    "joint_friction": {"coulomb_Nm": (0.02, 0.6)},
    "force_sensor_bandwidth": {"cutoff_hz": (25.0, 200.0)},
    # whole samples at 1 kHz: 1 ms is already ENR ~5, so this class has no weak cases
    "channel_delay": {"delay_s": (0.001, 0.004)},
    "cocontraction_variation": {"depth": (0.005, 0.15)},
}
#: Fixed settings of the hidden effects (not swept).
_FIXED = {
    "cuff_compliance": {"damping_Nms_per_rad": 0.2},
    "cocontraction_variation": {"bandwidth_hz": 0.2, "tonic_torque_Nm": 2.0},
}

#: Class name -> (hidden effects, candidates excluded from the diagnosis).
JOINT_CLASSES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "none": ((), ()),
    **{name: ((name,), ()) for name in _MAGNITUDES},
    "reflex+joint_friction": (("reflex", "joint_friction"), ()),
    "left_out:reflex": (("reflex",), ("reflex",)),
}


def _effects_for(hidden: tuple[str, ...], rng) -> tuple[EffectsConfig, dict]:
    cfg = EffectsConfig()
    params = {}
    for name in hidden:
        values = {k: log_uniform(rng, lo, hi) for k, (lo, hi) in _MAGNITUDES[name].items()}
        values.update(_FIXED.get(name, {}))
        setattr(cfg, name, EFFECTS[name](**values))
        params[name] = values
    return cfg, params


def _band_rms(z: np.ndarray, fs: float, lo: float, hi: float) -> float:
    sos = butterworth((lo, hi), fs, 4, btype="bandpass")
    return float(np.sqrt(np.mean(zero_phase(sos, z, axis=-1) ** 2)))


def describe(ref: RefereeConfig) -> str:
    """The referee's datasets in words (``benchmark.md``)."""
    return (
        f"{ref.n_trials} trials × {ref.trial_s:g} s at {ref.fs_hz:g} Hz; "
        f"torque noise {ref.noise_std_Nm:g} N·m"
    )


def make_dataset(
    cls: str, replicate: int, ref: RefereeConfig, diag: DiagnosisConfig, folder: Path
) -> Dataset:
    """Simulate and write one dataset of class ``cls`` (deterministic in seed, class, replicate)."""
    from armlab.data.joint_import import write_joint_csv
    from armlab.perturbations.prbs import prbs_position
    from armlab.sim.joint_rig import JointSubject, simulate_joint_rig

    if cls not in JOINT_CLASSES:
        raise KeyError(f"unknown referee class {cls!r}; valid: {list(JOINT_CLASSES)}")
    if folder.exists():  # before any simulation: nothing already written is touched
        raise FileExistsError(f"{folder} exists; the referee writes every dataset into a new folder")
    rng = np.random.default_rng([ref.seed, list(JOINT_CLASSES).index(cls), replicate])
    subject = JointSubject(
        inertia_kgm2=float(rng.uniform(0.01, 0.03)),  # kg·m², ankle range (Kearney & Hunter 1990)
        damping_Nms_per_rad=float(rng.uniform(0.3, 1.5)),  # N·m·s/rad, same source
        stiffness_Nm_per_rad=float(rng.uniform(50.0, 200.0)),  # N·m/rad, same source
        tonic_torque_Nm=float(rng.uniform(-5.0, 5.0)),  # N·m
    )
    hidden, _ = JOINT_CLASSES[cls]
    effects, params = _effects_for(hidden, rng)
    n = int(round(ref.trial_s * ref.fs_hz))
    n_seq = ref.n_trials // 2
    seqs = [prbs_position(n, ref.fs_hz, rng=rng) for _ in range(n_seq)]
    reference = np.stack([seqs[i % n_seq] for i in range(ref.n_trials)])
    sim_seed = int(rng.integers(2**32))
    rec = simulate_joint_rig(
        reference,
        ref.fs_hz,
        subject,
        effects,
        noise_std_Nm=ref.noise_std_Nm,
        rng=np.random.default_rng(sim_seed),
    )
    if hidden:
        # noise-free measured torque with and without the hidden effects (same random draws)
        with_fx = simulate_joint_rig(
            reference, ref.fs_hz, subject, effects, noise_std_Nm=0.0, rng=np.random.default_rng(sim_seed)
        )
        base = simulate_joint_rig(
            reference,
            ref.fs_hz,
            subject,
            EffectsConfig(),
            noise_std_Nm=0.0,
            rng=np.random.default_rng(sim_seed),
        )
        effect_rms = _band_rms(with_fx.torque - base.torque, ref.fs_hz, diag.highpass_hz, diag.band_hz)
    else:
        effect_rms = 0.0
    noise_rms = ref.noise_std_Nm * math.sqrt((diag.band_hz - diag.highpass_hz) / (0.5 * ref.fs_hz))
    folder.mkdir(parents=True, exist_ok=False)
    for i in range(ref.n_trials):
        name = f"seq{i % n_seq}_rep{i // n_seq}"
        write_joint_csv(folder / f"{name}.csv", t_s=rec.t_s, position=rec.position[i], torque=rec.torque[i])
    truth = {
        "class": cls,
        "hidden": list(hidden),
        "effect_params": params,
        "subject": {
            "I": subject.inertia_kgm2 + subject.pedal_inertia_kgm2,
            "B": subject.damping_Nms_per_rad,
            "K": subject.stiffness_Nm_per_rad,
        },
        "effect_rms_Nm": effect_rms,
        "noise_rms_Nm": noise_rms,
    }
    return Dataset(cls=cls, replicate=replicate, folder=folder, truth=truth, enr=effect_rms / noise_rms)
