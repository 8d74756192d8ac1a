"""The blind referee for ``stiffness_5dof_emg``: hidden effects in the protocol's default lab.

Each dataset is the stiffness stage at reduced scale (:data:`CONDITIONS`, :data:`N_PER_CONDITION`
disturbances each; realistic sensors), simulated by the protocol's own code
(:func:`armlab.protocols.stiffness_5dof_emg.experiment.simulate_stiffness_stage`) with one hidden
physical effect switched on in the lab through the protocol's own switches (as ``armlab run``
does, :mod:`armlab.protocols.stiffness_5dof_emg.lab_effects`), at a log-uniform magnitude:

- ``reflex``: the lab's stretch reflex (``reflex.enabled``) with its three gains scaled by a factor;
- ``cuff_compliance``: the cuff's weld softened (``cuff.time_constant_s``);
- ``marker_soft_tissue``: the forearm cluster lags pronation by a fraction
  (``effects.marker_soft_tissue.slip``);
- ``base_sensor_drift``: the base JR3 drifts at constant rates (``effects.base_sensor_drift``),
  random direction.

Only measured channels and the lab's attributes are written (``true_q`` and ``ground_truth`` are
dropped): the diagnoser never sees the truth. The effect-to-noise ratio, as the other referees:
the same plan simulated with ideal sensors with and without the effect, each reduced to the
diagnosis's rows (whitened by the noisy dataset's noise) and fitted by the nominal model; ENR =
rms of the difference of the two residuals (what the nominal model cannot absorb of the effect)
over the whitened noise's rms (1).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.diagnosis.scoring import Dataset, log_uniform

__all__ = [
    "CONDITIONS",
    "N_PER_CONDITION",
    "STIFF5_CLASSES",
    "describe",
    "make_stiff5_dataset",
]

CONDITIONS = ("X+10", "Z-10", "Z+5")  # three of the eight pre-loads (one per axis sign pattern)
N_PER_CONDITION = 20  # disturbances per condition (each direction twice)

#: Hidden-effect magnitudes (log-uniform), by effect: parameter -> (low, high).
_MAGNITUDES = {
    "reflex": {"gain_scale": (0.03, 1.0)},
    "cuff_compliance": {"time_constant_s": (0.002, 0.02)},
    "marker_soft_tissue": {"slip": (0.01, 0.3)},
    "base_sensor_drift": {"force_N_per_s": (0.01, 0.5), "torque_Nm_per_s": (0.001, 0.05)},
}

#: Class name -> (hidden effects, candidates excluded). New classes go last (random streams are
#: keyed by the class's index).
STIFF5_CLASSES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "none": ((), ()),
    **{name: ((name,), ()) for name in _MAGNITUDES},
}


def describe(ref: RefereeConfig) -> str:
    """The referee's datasets in words (``benchmark.md``)."""
    del ref
    return (
        f"the stiffness stage at {len(CONDITIONS)} pre-loads {list(CONDITIONS)} x {N_PER_CONDITION} "
        "quintic disturbances, realistic sensors (wrist and base JR3 at 2 kHz, Vicon 500 Hz)"
    )


def _simulate(params: dict, hidden, preset: str, seed: int):
    from armlab.config.effects import BaseSensorDrift, MarkerSoftTissue
    from armlab.protocols.stiffness_5dof_emg.config import Stiffness5dofConfig, TrialsConfig
    from armlab.protocols.stiffness_5dof_emg.experiment import simulate_stiffness_stage
    from armlab.protocols.stiffness_5dof_emg.lab_effects import apply_recorded_effects, build_effect_lab

    cfg = Stiffness5dofConfig(
        stages=["stiffness"],
        trials=TrialsConfig(n_per_condition=N_PER_CONDITION, conditions=list(CONDITIONS)),
    )
    cfg.seed = seed
    cfg.sensors.preset = preset
    if "reflex" in hidden:
        s = params["reflex"]["gain_scale"]
        cfg.reflex.enabled = True
        cfg.reflex.stretch_gain *= s
        cfg.reflex.velocity_gain *= s
        cfg.reflex.spinal_gain *= s
    if "cuff_compliance" in hidden:
        cfg.cuff.time_constant_s = params["cuff_compliance"]["time_constant_s"]
    if "marker_soft_tissue" in hidden:
        cfg.effects.marker_soft_tissue = MarkerSoftTissue(slip=params["marker_soft_tissue"]["slip"])
    if "base_sensor_drift" in hidden:
        p = params["base_sensor_drift"]
        rate = np.r_[
            p["force_N_per_s"] * np.asarray(p["force_direction"]),
            p["torque_Nm_per_s"] * np.asarray(p["torque_direction"]),
        ]
        cfg.effects.base_sensor_drift = BaseSensorDrift(
            **dict(zip(BaseSensorDrift.SIGNED, map(float, rate), strict=True))
        )
    lab = build_effect_lab(cfg)
    tr = apply_recorded_effects(cfg, simulate_stiffness_stage(cfg, lab), lab)
    ch = {k: v for k, v in tr.channels.items() if k != "true_q"}
    attrs = {k: v for k, v in tr.attrs.items() if k != "ground_truth"}
    return replace(tr, channels=ch, units={k: v for k, v in tr.units.items() if k in ch}, attrs=attrs)


def _nominal_residual(cs) -> np.ndarray:
    from armlab.protocols.stiffness_5dof_emg.diagnosis.models import stiff5_columns

    x = stiff5_columns(cs, (), {})
    return cs.yw - x @ np.linalg.lstsq(x, cs.yw, rcond=None)[0]


def make_stiff5_dataset(
    cls: str, replicate: int, ref: RefereeConfig, diag: DiagnosisConfig, folder: Path
) -> Dataset:
    """Simulate and write one dataset of class ``cls`` (deterministic in seed, class, replicate)."""
    from armlab.data.h5io import write_trials
    from armlab.protocols.stiffness_5dof_emg.diagnosis.data import prepare_stiff5

    del diag
    if cls not in STIFF5_CLASSES:
        raise KeyError(f"unknown referee class {cls!r}; valid: {list(STIFF5_CLASSES)}")
    if folder.exists():
        raise FileExistsError(f"{folder} exists; the referee writes every dataset into a new folder")
    rng = np.random.default_rng([ref.seed, 500 + list(STIFF5_CLASSES).index(cls), replicate])
    hidden, _ = STIFF5_CLASSES[cls]
    params = {n: {k: log_uniform(rng, lo, hi) for k, (lo, hi) in _MAGNITUDES[n].items()} for n in hidden}
    if "base_sensor_drift" in params:
        for k in ("force_direction", "torque_direction"):
            v = rng.standard_normal(3)
            params["base_sensor_drift"][k] = (v / np.linalg.norm(v)).tolist()
    seed = int(rng.integers(2**31))
    noisy = _simulate(params, hidden, "realistic", seed)
    cs = prepare_stiff5(noisy)
    eff = prepare_stiff5(_simulate(params, hidden, "ideal", seed))
    nom = prepare_stiff5(_simulate({}, (), "ideal", seed))
    r_eff = _nominal_residual(replace(eff, noise_var=cs.noise_var))
    r_nom = _nominal_residual(replace(nom, noise_var=cs.noise_var))
    enr = float(np.sqrt(np.mean((r_eff - r_nom) ** 2)))
    folder.mkdir(parents=True, exist_ok=False)
    write_trials(folder / "trials.h5", noisy)
    truth = {
        "class": cls,
        "hidden": list(hidden),
        "effect_params": params,
        "unabsorbed_effect_rms_whitened": enr,
    }
    return Dataset(cls=cls, replicate=replicate, folder=folder, truth=truth, enr=enr)
