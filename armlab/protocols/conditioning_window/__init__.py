"""Protocol ``conditioning_window``: conditioning vs. observation window (../shared/seeds/000).

The LWR-class robot perturbs the planar arm held at q0 through the cuff; 26 windows x 30 trials
of fifth-order perturbations; the full and reduced joint-space least squares per window, the
conditioning criteria, and the sim-to-real diagnosis of the paper's Eq. (9) model.
"""

from armlab.config.diagnosis import DiagnosisConfig
from armlab.protocols.base import DiagnosisHooks, Protocol, Referee
from armlab.protocols.conditioning_window import hooks
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.diagnosis.rules import RULES
from armlab.sim.lab import LAB_EFFECTS

__all__ = ["PROTOCOL", "ConditioningWindowConfig"]


def _load(path, cfg: DiagnosisConfig):
    from armlab.protocols.conditioning_window.diagnosis.data import load_cond_trials

    return load_cond_trials(path)


def _diagnose(data, cfg: DiagnosisConfig):
    from armlab.protocols.conditioning_window.diagnosis.diagnose import diagnose_cond

    return diagnose_cond(data, cfg)


def _report(results, *, data_path: str, figures) -> str:
    from armlab.protocols.conditioning_window.diagnosis.report import format_cond_report

    return format_cond_report(results, data_path=data_path, figures=figures)


def _figures(viz, series, results, out):
    return viz.cond_diagnosis_figures(series, results, out)


def _recording(viz, series, path):
    return viz.cond_diagnosis_recording(series, path)


def _make_dataset(cls, rep, ref, diag_cfg, folder):
    from armlab.protocols.conditioning_window.diagnosis.referee import make_cond_dataset

    return make_cond_dataset(cls, rep, ref, diag_cfg, folder)


def _describe(ref) -> str:
    from armlab.protocols.conditioning_window.diagnosis.referee import describe

    return describe(ref)


def _referee() -> Referee:
    from armlab.protocols.conditioning_window.diagnosis.referee import COND_CLASSES

    return Referee(classes=COND_CLASSES, make_dataset=_make_dataset, describe=_describe)


def _candidates() -> tuple[str, ...]:
    from armlab.protocols.conditioning_window.diagnosis.models import COND_SURROGATES

    return tuple(COND_SURROGATES)


PROTOCOL = Protocol(
    name="conditioning_window",
    paper="seeds/000: conditioning vs. excitation time (LWR-III, 2-DoF arm)",
    summary="LWR perturbs the planar arm; K, D, xi per observation window and when they become reliable",
    schema=ConditioningWindowConfig,
    groups={
        "arm": "planar_hill",
        "robot": "lwr",
        "sensors": "realistic",
        "scenario": "conditioning_window",
        "estimator": "joint_ls",
    },
    simulate=hooks.simulate,
    reestimate_group="estimator",
    reestimate=hooks.reestimate,
    outputs=hooks.outputs,
    format_table=hooks.format_table,
    effects=LAB_EFFECTS,
    lab_effects={"reflex": "reflex.enabled", "cuff_compliance": "cuff.rigid"},
    examples=(
        "run protocol=conditioning_window seed=3 arm=planar_linear reflex.enabled=false",
        "run --multirun protocol=conditioning_window seed=0,1,2 hydra/launcher=joblib",
        "estimate outputs/conditioning_window/<run> estimator.lowpass_hz=30",
        "diagnose data=outputs/conditioning_window/<run> protocol=conditioning_window",
    ),
    catalogue=(
        "reflex",
        "cuff_compliance",
        "joint_friction",
        "force_sensor_noise",
        "force_sensor_drift",
        "force_sensor_bandwidth",
        "accel_noise",
        "accel_misalignment",
        "encoder_quantisation",
        "channel_delay",
        "payload_mass",
        "cocontraction_variation",
        "plane_tilt",
        "torso_translation",
    ),
    diagnosis=DiagnosisHooks(
        load=_load,
        diagnose=_diagnose,
        candidates=_candidates(),
        rules=RULES,
        report=_report,
        figures=_figures,
        recording=_recording,
        referee=_referee(),
    ),
)
