"""The switchable lab effects of ``stiffness_5dof_emg`` applied to a run (what the diagnosis names).

Three effects beyond the reflex (``reflex.enabled``), each switched in one place:

- ``cuff.time_constant_s`` > 0: the cuff's weld made compliant before the simulation
  (:func:`armlab.sim.arm5_lab_effects.soften_cuff`; the catalogue's ``cuff_compliance``, in this
  lab's own terms: a MuJoCo weld time constant);
- ``effects=[marker_soft_tissue]`` (``effects.marker_soft_tissue.slip``): the recorded forearm
  cluster lags the bone's pronation (:func:`armlab.sim.arm5_lab_effects.marker_soft_tissue`, from
  the true angles the simulation knows);
- ``effects=[base_sensor_drift]`` (``effects.base_sensor_drift.<axis>_N_per_s`` …): the base JR3
  drifts at constant rates since each record's start (its tare after the previous trial) —
  :func:`armlab.sim.arm5_lab_effects.base_sensor_drift`, the time counted from the start of the
  record's random wait.

Both sensor-level effects act on the stiffness stage's recorded channels (the trial file); the
calibration and inertial stages stay as simulated.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from armlab.data.trial import TrialSet
from armlab.protocols.stiffness_5dof_emg.config import Stiffness5dofConfig
from armlab.protocols.stiffness_5dof_emg.experiment import StiffnessLab, build_lab
from armlab.sim.arm5_lab_effects import base_sensor_drift, marker_soft_tissue, soften_cuff

__all__ = [
    "LAB_EFFECTS",
    "apply_recorded_effects",
    "build_effect_lab",
]

#: The catalogue effects this protocol applies through ``effects=[...]`` (the cuff and the reflex
#: are switched by their own fields, ``cuff.time_constant_s`` and ``reflex.enabled``).
LAB_EFFECTS = ("marker_soft_tissue", "base_sensor_drift")


def build_effect_lab(cfg: Stiffness5dofConfig) -> StiffnessLab:
    """The composed lab (:func:`~armlab.protocols.stiffness_5dof_emg.experiment.build_lab`), its
    cuff softened when ``cfg.cuff.time_constant_s`` > 0."""
    lab = build_lab()
    if cfg.cuff.time_constant_s > 0.0:
        soften_cuff(lab.scene.model, cfg.cuff.time_constant_s)
    return lab


def apply_recorded_effects(cfg: Stiffness5dofConfig, trials: TrialSet, lab: StiffnessLab) -> TrialSet:
    """The stiffness trials with the switched-on sensor-level effects applied to their channels.

    Args:
        cfg: the experiment (``cfg.effects``).
        trials: the simulated stiffness trials, with ``true_q`` (n_trials, n, 5) rad.
        lab: the lab that simulated them (its arm's kinematic chain).

    Returns:
        ``trials`` unchanged when neither effect is on; else a copy with ``forearm_marker_pos`` /
        ``_quat`` and/or ``base_force`` / ``base_torque`` replaced and the effects' parameters in
        ``attrs['ground_truth']['lab_effects']``.
    """
    on = {n: getattr(cfg.effects, n) for n in LAB_EFFECTS if getattr(cfg.effects, n) is not None}
    if not on:
        return trials
    ch = dict(trials.channels)
    if "marker_soft_tissue" in on:
        ch["forearm_marker_pos"], ch["forearm_marker_quat"] = marker_soft_tissue(
            ch["forearm_marker_pos"],
            ch["forearm_marker_quat"],
            ch["true_q"],
            np.asarray(trials.attrs["q0_rad"], float),
            on["marker_soft_tissue"].slip,
            lab.kin,
        )
    if "base_sensor_drift" in on:
        ch["base_force"], ch["base_torque"] = base_sensor_drift(
            ch["base_force"],
            ch["base_torque"],
            np.asarray(on["base_sensor_drift"].rates(), float),
            np.arange(ch["base_force"].shape[1]) / trials.fs_hz,
            np.asarray(trials.trial_meta["wait_s"], float),
        )
    truth = dict(trials.attrs.get("ground_truth", {}))
    truth["lab_effects"] = {n: e.params() for n, e in on.items()}
    return replace(trials, channels=ch, attrs={**trials.attrs, "ground_truth": truth})
