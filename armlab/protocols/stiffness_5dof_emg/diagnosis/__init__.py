"""The sim-to-real diagnosis of ``stiffness_5dof_emg``: the paper's static K_q model as the nominal.

Data (:mod:`.data`), its surrogate family (:mod:`.models`), the diagnosis (:mod:`.diagnose`), its
referee (:mod:`.referee`), its report (:mod:`.report`) and acceptance rules (:mod:`.rules`);
:data:`HOOKS` is what the protocol declares.
"""

from armlab.protocols.base import DiagnosisHooks, Referee
from armlab.protocols.stiffness_5dof_emg.diagnosis.data import load_stiff5_trials
from armlab.protocols.stiffness_5dof_emg.diagnosis.diagnose import diagnose_stiff5
from armlab.protocols.stiffness_5dof_emg.diagnosis.models import STIFF5_SURROGATES
from armlab.protocols.stiffness_5dof_emg.diagnosis.referee import (
    STIFF5_CLASSES,
    describe,
    make_stiff5_dataset,
)
from armlab.protocols.stiffness_5dof_emg.diagnosis.report import format_stiff5_report
from armlab.protocols.stiffness_5dof_emg.diagnosis.rules import RULES

__all__ = ["HOOKS"]

HOOKS = DiagnosisHooks(
    load=lambda path, cfg: load_stiff5_trials(path),
    diagnose=diagnose_stiff5,
    candidates=tuple(STIFF5_SURROGATES),
    rules=RULES,
    report=format_stiff5_report,
    figures=lambda viz, series, results, out: viz.stiff5_diagnosis_figures(series, results, out),
    recording=lambda viz, series, path: viz.stiff5_diagnosis_recording(series, path),
    referee=Referee(classes=STIFF5_CLASSES, make_dataset=make_stiff5_dataset, describe=describe),
)
