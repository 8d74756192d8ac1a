"""The sim-to-real diagnosis of ``cartesian_online``: the thesis's quadratic field as the nominal model.

Data (:mod:`.data`), its surrogate family (:mod:`.models`), the diagnosis (:mod:`.diagnose`), its
referee (:mod:`.referee`), its report (:mod:`.report`) and acceptance rules (:mod:`.rules`);
:data:`HOOKS` is what the protocol declares.
"""

from armlab.protocols.base import DiagnosisHooks, Referee
from armlab.protocols.cartesian_online.diagnosis.data import load_cart_trials
from armlab.protocols.cartesian_online.diagnosis.diagnose import diagnose_cart
from armlab.protocols.cartesian_online.diagnosis.models import CART_SURROGATES
from armlab.protocols.cartesian_online.diagnosis.referee import CART_CLASSES, describe, make_cart_dataset
from armlab.protocols.cartesian_online.diagnosis.report import format_cart_report
from armlab.protocols.cartesian_online.diagnosis.rules import RULES

__all__ = ["HOOKS"]

HOOKS = DiagnosisHooks(
    load=lambda path, cfg: load_cart_trials(path),
    diagnose=diagnose_cart,
    candidates=tuple(CART_SURROGATES),
    rules=RULES,
    report=format_cart_report,
    figures=lambda viz, series, results, out: viz.cart_diagnosis_figures(series, results, out),
    recording=lambda viz, series, path: viz.cart_diagnosis_recording(series, path),
    referee=Referee(
        classes=CART_CLASSES,
        make_dataset=make_cart_dataset,
        describe=describe,
        settings=("force_noise_N",),
    ),
)
