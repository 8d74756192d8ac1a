"""The sim-to-real diagnosis of ``joint_1dof``: the nominal joint I s² + B s + K.

Data (:mod:`.data`), its surrogate family (:mod:`.models`), the diagnosis (:mod:`.diagnose`), its
referee on the MuJoCo joint rig (:mod:`.referee`) and the second one on an independent ODE plant
(:mod:`.referee_ode`, ``referee.generator=ode``), its report (:mod:`.report`) and acceptance
rules (:mod:`.rules`); :data:`HOOKS` is what the protocol declares.
"""

from armlab.data.joint_import import load_joint_data
from armlab.protocols.base import DiagnosisHooks, Referee
from armlab.protocols.joint_1dof.diagnosis.diagnose import check_referee, diagnose_joint
from armlab.protocols.joint_1dof.diagnosis.models import JOINT_SURROGATES
from armlab.protocols.joint_1dof.diagnosis.referee import JOINT_CLASSES, describe, make_dataset
from armlab.protocols.joint_1dof.diagnosis.referee_ode import (
    ODE_CLASSES,
    check_ode_referee,
    describe_ode,
    make_ode_dataset,
)
from armlab.protocols.joint_1dof.diagnosis.report import format_report
from armlab.protocols.joint_1dof.diagnosis.rules import RULES

__all__ = ["HOOKS"]

HOOKS = DiagnosisHooks(
    load=lambda path, cfg, units=None: load_joint_data(path, min_duration_s=cfg.min_duration_s, units=units),
    diagnose=diagnose_joint,
    candidates=tuple(JOINT_SURROGATES),
    rules=RULES,
    report=format_report,
    figures=lambda viz, series, results, out: viz.diagnosis_figures(series, results, out),
    recording=lambda viz, series, path: viz.diagnosis_recording(series, path),
    referee=Referee(
        classes=JOINT_CLASSES,
        make_dataset=make_dataset,
        describe=describe,
        settings=("n_trials", "trial_s", "fs_hz", "noise_std_Nm"),
        validate=check_referee,
    ),
    referees={
        "ode": Referee(
            classes=ODE_CLASSES,
            make_dataset=make_ode_dataset,
            describe=describe_ode,
            settings=("n_trials", "ode_trial_s"),
            validate=check_ode_referee,
        )
    },
    takes_units=True,
)
