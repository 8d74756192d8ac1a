"""Protocol ``stiffness_5dof_emg``: 5-DoF arm stiffness by joint-space perturbations (../shared/seeds/001).

The seated arm (three shoulder hinges, elbow flexion, pronation/supination) holds a displayed
force (8 pre-load conditions) while the LWR, welded to its wrist through a 6-D cuff, applies
quintic joint-space disturbances; the wrist JR3 and the forearm marker cluster give K_q per
condition by Eqs. (10), (14)-(17), drawn as the Fig. 3 stiffness ellipsoids. Before them the
kinematic calibration (random motion, joint centres by Eqs. (7)-(9)) gives the chain and the
inertial trials (40 held configurations, Eq. (22)) give xi_red, which the stiffness estimate uses
(``stages``); the EMG stage (opt-in) records 8 electrodes during the stiffness trials and maps
them to K_q by the network of Eqs. (20)-(21) against a linear map (spec 001 check 8).
"""

from armlab.protocols.base import Protocol
from armlab.protocols.stiffness_5dof_emg import hooks, preflight
from armlab.protocols.stiffness_5dof_emg.config import (
    CalibrationConfig,
    CuffConfig,
    EmgConfig,
    EstimationConfig,
    InertialConfig,
    Stiffness5dofConfig,
    TrialsConfig,
)
from armlab.protocols.stiffness_5dof_emg.diagnosis import HOOKS
from armlab.protocols.stiffness_5dof_emg.lab_effects import LAB_EFFECTS

__all__ = [
    "PROTOCOL",
    "CalibrationConfig",
    "CuffConfig",
    "EmgConfig",
    "EstimationConfig",
    "InertialConfig",
    "Stiffness5dofConfig",
    "TrialsConfig",
]

PROTOCOL = Protocol(
    name="stiffness_5dof_emg",
    paper="seeds/001: 5-DoF limb stiffness by joint-space perturbations, SPD estimate, EMG (stages 1-4)",
    summary="seated 5-DoF arm: calibration, 40 inertial holds, LWR + 6-D cuff, 8 pre-loads x 50 "
    "quintic disturbances; SPD K_q, ellipsoids",
    schema=Stiffness5dofConfig,
    groups={"sensors": "realistic"},
    simulate=hooks.simulate,
    validate=preflight.validate,
    reestimate_group="estimation",
    reestimate=hooks.reestimate,
    outputs=hooks.outputs,
    format_table=hooks.format_table,
    effects=LAB_EFFECTS,
    lab_effects={"reflex": "reflex.enabled", "cuff_compliance": "cuff.time_constant_s"},
    catalogue=("reflex", "cuff_compliance", "marker_soft_tissue", "base_sensor_drift", "torso_translation"),
    diagnosis=HOOKS,
    examples=(
        "run protocol=stiffness_5dof_emg sensors=ideal",
        "run protocol=stiffness_5dof_emg stages=[stiffness]",
        "run protocol=stiffness_5dof_emg stages=[calibration,inertial,stiffness,emg]",
        "run protocol=stiffness_5dof_emg reflex.enabled=true",
        "run protocol=stiffness_5dof_emg trials.n_per_condition=20 trials.conditions=[Z-10,Z+10]",
        "estimate outputs/stiffness_5dof_emg/<run> estimation.post_interval_s=[0.25,0.4]",
        "run protocol=stiffness_5dof_emg cuff.time_constant_s=0.01 effects=[base_sensor_drift]",
        "diagnose data=outputs/stiffness_5dof_emg/<run> protocol=stiffness_5dof_emg",
        "diagnose-benchmark referee.protocol=stiffness_5dof_emg referee.replicates=2",
    ),
)
