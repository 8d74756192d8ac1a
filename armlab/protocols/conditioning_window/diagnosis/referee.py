"""The blind referee for the conditioning-window protocol: hidden effects in the simulated lab.

Each dataset is a session of the conditioning-window laboratory (:mod:`armlab.sim.lab`: LWR-class
robot, cuff, planar arm with linear muscles so that the truth is exact) on a random subject
(co-contraction and distal pre-load drawn per dataset): ``referee.cond_trials`` trials of each
window in ``referee.cond_windows`` (six directions; by default k = 26, T_k = 300 ms), ideal
encoders and white F/T force noise of ``referee.force_noise_N``. The hidden effects are the
lab's own reflex and compliant cuff and the catalogue effects it applies (friction, force-sensor
bandwidth, channel delay), at log-uniform magnitudes. Only ``hand_pos``, ``hand_force``, the
segment lengths and the trial labels are written to the dataset's ``trials.h5``: the diagnoser
never sees the truth.

The effect-to-noise ratio is measured on the scoring rows (0-400 ms after onset, both joints, in
the diagnosis band): the rms of what the calibrated nominal model cannot absorb of the noise-free
torque with the hidden effects (the residual of Eq. (9) fitted to it), over the rms of the noise
(noisy minus noise-free). In this protocol much of an effect is absorbed: a reflex or a cuff
changes the calibrated K, D and xi before it leaves a residual, so the raw rms of the effect
(with minus without it, kept as ``enr_raw`` in the truth) overstates what any held-out metric can
see.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.config.effects import EFFECTS, EffectsConfig
from armlab.config.schema import CuffConfig
from armlab.config.subject import SubjectConfig
from armlab.diagnosis.scoring import Dataset, log_uniform
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig

__all__ = [
    "COND_CLASSES",
    "describe",
    "make_cond_dataset",
]

#: Hidden-effect magnitudes (log-uniform), by effect: field -> (low, high).
_MAGNITUDES = {
    # ranges chosen on the tuning seed 7 so that the measured (unabsorbed) ENR spans ~0.3-5 at
    # 0.3 N noise (ENR ~0.17 per unit gain scale, ~0.2 per ms of delay, ~40/cutoff_hz)
    "reflex": {"gain_scale": (2.0, 30.0), "stretch_latency_s": (0.025, 0.05)},
    "cuff_compliance": {"stiffness_N_per_m": (3000.0, 40000.0)},
    "joint_friction": {"coulomb_Nm": (0.03, 0.6)},
    # Hz: F/T acquisition low-passes from a heavy 10 Hz setting to a light 80 Hz one
    "force_sensor_bandwidth": {"cutoff_hz": (10.0, 80.0)},
    # s: F/T over its own acquisition box or network, 1.5-12 ms behind the joint encoders
    "channel_delay": {"delay_s": (0.0015, 0.012)},
}

#: Class name -> (hidden effects, candidates excluded from the diagnosis).
COND_CLASSES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "none": ((), ()),
    **{name: ((name,), ()) for name in _MAGNITUDES},
    "reflex+cuff_compliance": (("reflex", "cuff_compliance"), ()),
    "joint_friction+channel_delay": (("joint_friction", "channel_delay"), ()),
    "left_out:reflex": (("reflex",), ("reflex",)),
}


def describe(ref: RefereeConfig) -> str:
    """The referee's datasets in words (``benchmark.md``)."""
    return (
        f"{ref.cond_trials} quintic trials per window k = {list(ref.cond_windows)} "
        f"(T_k = {', '.join(f'{40 + 10 * k} ms' for k in ref.cond_windows)}) "
        "in six directions at 1000 Hz; "
        f"F/T force noise {ref.force_noise_N:g} N"
    )


def _configs(hidden: tuple[str, ...], rng, ref: RefereeConfig):
    """(with effects, without effects) experiment configs and the drawn parameters."""
    base = ConditioningWindowConfig()
    base = replace(
        base,
        arm=replace(
            base.arm,
            muscle="linear",  # exact spring-damper truth (ENGINE_NOTES)
            cocontraction=float(rng.uniform(0.1, 0.4)),  # 1, activation (assumption: relaxed to firm)
            preload_N=float(rng.uniform(2.0, 8.0)),  # N, around the paper's 5 N (Sec. IV-B)
        ),
        # the referee's own nominal lab: rigid cuff (with CuffConfig's own damping for a hidden
        # cuff compliance), ideal sensors, a steady subject; hidden effects are added below
        cuff=CuffConfig(rigid=True),
        reflex=replace(base.reflex, enabled=False),
        sensors=replace(base.sensors, preset="ideal"),
        scenario=replace(base.scenario, k_values=list(ref.cond_windows), n_trials=ref.cond_trials),
        effects=EffectsConfig(),
        subject=SubjectConfig(),
    )
    cfg = base
    params: dict[str, dict] = {}
    effects = EffectsConfig()
    for name in hidden:
        values = {k: log_uniform(rng, lo, hi) for k, (lo, hi) in _MAGNITUDES[name].items()}
        params[name] = values
        if name == "reflex":
            g = values["gain_scale"]
            r = cfg.reflex
            cfg = replace(
                cfg,
                reflex=replace(
                    r,
                    enabled=True,
                    stretch_latency_s=values["stretch_latency_s"],
                    stretch_gain=g * r.stretch_gain,
                    velocity_gain=g * r.velocity_gain,
                    spinal_gain=g * r.spinal_gain,
                ),
            )
        elif name == "cuff_compliance":
            cfg = replace(
                cfg, cuff=replace(cfg.cuff, rigid=False, stiffness_N_per_m=values["stiffness_N_per_m"])
            )
        else:
            setattr(effects, name, EFFECTS[name](**values))
    noisy = replace(effects, force_sensor_noise=EFFECTS["force_sensor_noise"](std=ref.force_noise_N))
    return (
        replace(cfg, effects=noisy),
        replace(cfg, effects=effects),
        replace(base, effects=EffectsConfig()),
        params,
    )


def _clean_trials(trials):
    """What the diagnoser may see: measured channels, segment lengths, trial labels."""
    from armlab.data.trial import TrialSet

    return TrialSet(
        fs_hz=trials.fs_hz,
        onset_index=trials.onset_index,
        channels={k: trials.channels[k] for k in ("hand_pos", "hand_force")},
        units={"hand_pos": "m", "hand_force": "N"},
        trial_meta={k: trials.trial_meta[k] for k in ("group", "direction", "validate")},
        attrs={
            "protocol": "conditioning_window",
            "arm_l1_m": trials.attrs["arm_l1_m"],
            "arm_l2_m": trials.attrs["arm_l2_m"],
        },
    )


def _eq9_residual(cs) -> np.ndarray:
    """Residual of the nominal Eq. (9) least-squares fit to a scoring set's torque (all trials)."""
    from armlab.protocols.conditioning_window.diagnosis.models import cond_columns

    x = cond_columns(cs, (), {})
    return cs.y - x @ np.linalg.lstsq(x, cs.y, rcond=None)[0]


def make_cond_dataset(
    cls: str, replicate: int, ref: RefereeConfig, diag: DiagnosisConfig, folder: Path
) -> Dataset:
    """Simulate and write one dataset of class ``cls`` (deterministic in seed, class, replicate)."""
    from armlab.data.h5io import write_trials
    from armlab.protocols.conditioning_window.diagnosis.data import prepare_cond
    from armlab.protocols.conditioning_window.experiment import simulate_protocol

    if cls not in COND_CLASSES:
        raise KeyError(f"unknown referee class {cls!r}; valid: {list(COND_CLASSES)}")
    if folder.exists():  # before any simulation: nothing already written is touched
        raise FileExistsError(f"{folder} exists; the referee writes every dataset into a new folder")
    rng = np.random.default_rng([ref.seed, 100 + list(COND_CLASSES).index(cls), replicate])
    hidden, _ = COND_CLASSES[cls]
    noisy_cfg, clean_cfg, base_cfg, params = _configs(hidden, rng, ref)
    seed = int(rng.integers(2**31))
    rec, _ = simulate_protocol(replace(noisy_cfg, seed=seed))

    def prepared(cfg):
        tr = simulate_protocol(replace(cfg, seed=seed))[0].trials
        return prepare_cond(tr, band_hz=diag.band_hz, holdout_fraction=diag.holdout_fraction)

    y_noisy = prepare_cond(rec.trials, band_hz=diag.band_hz, holdout_fraction=diag.holdout_fraction).y
    clean = prepared(clean_cfg)
    noise_rms = float(np.sqrt(np.mean((y_noisy - clean.y) ** 2)))
    effect_rms = unabsorbed_rms = 0.0
    if hidden:
        base = prepared(base_cfg)
        effect_rms = float(np.sqrt(np.mean((clean.y - base.y) ** 2)))
        # the part of the effect the calibrated nominal model cannot absorb: the residual of
        # Eq. (9) fitted to the noise-free recording with the effects (all trials), less the
        # residual it leaves on the same recording without them (the linearisation's own, a few
        # 1e-4 of the noise)
        unabsorbed = _eq9_residual(clean) - _eq9_residual(base)
        unabsorbed_rms = float(np.sqrt(np.mean(unabsorbed**2)))
    folder.mkdir(parents=True, exist_ok=False)
    write_trials(folder / "trials.h5", _clean_trials(rec.trials))
    truth = {
        "class": cls,
        "hidden": list(hidden),
        "effect_params": params,
        "subject": {
            "cocontraction": noisy_cfg.arm.cocontraction,
            "preload_N": noisy_cfg.arm.preload_N,
            **rec.trials.attrs["ground_truth"],
        },
        "effect_rms_Nm": effect_rms,
        "unabsorbed_effect_rms_Nm": unabsorbed_rms,
        "noise_rms_Nm": noise_rms,
        "enr_raw": effect_rms / noise_rms,
    }
    return Dataset(cls=cls, replicate=replicate, folder=folder, truth=truth, enr=unabsorbed_rms / noise_rms)
