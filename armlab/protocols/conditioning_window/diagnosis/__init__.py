"""The sim-to-real diagnosis of ``conditioning_window``: the paper's Eq. (9) as the nominal model.

Data (:mod:`.data`), its surrogate family (:mod:`.models`), the diagnosis (:mod:`.diagnose`), its
referee (:mod:`.referee`), its report (:mod:`.report`) and acceptance rules (:mod:`.rules`);
:data:`HOOKS` is what the protocol declares.
"""

from armlab.protocols.base import DiagnosisHooks, Referee
from armlab.protocols.conditioning_window.diagnosis.data import load_cond_trials
from armlab.protocols.conditioning_window.diagnosis.diagnose import diagnose_cond
from armlab.protocols.conditioning_window.diagnosis.models import COND_SURROGATES
from armlab.protocols.conditioning_window.diagnosis.referee import COND_CLASSES, describe, make_cond_dataset
from armlab.protocols.conditioning_window.diagnosis.report import format_cond_report
from armlab.protocols.conditioning_window.diagnosis.rules import RULES

__all__ = ["HOOKS"]

HOOKS = DiagnosisHooks(
    load=lambda path, cfg: load_cond_trials(path),
    diagnose=diagnose_cond,
    candidates=tuple(COND_SURROGATES),
    rules=RULES,
    report=format_cond_report,
    figures=lambda viz, series, results, out: viz.cond_diagnosis_figures(series, results, out),
    recording=lambda viz, series, path: viz.cond_diagnosis_recording(series, path),
    referee=Referee(
        classes=COND_CLASSES,
        make_dataset=make_cond_dataset,
        describe=describe,
        settings=("cond_trials", "cond_windows", "force_noise_N"),
    ),
)
