"""Protocol ``joint_1dof``: a 1-DoF joint (ankle, elbow) under position perturbations.

Diagnosis only (no ``armlab run``): measured REKLAB-format recordings are diagnosed against the
nominal I s^2 + B s + K joint, and its referee simulates pseudo-real datasets with the
higher-fidelity MuJoCo model of ``models/joint_rig/``. It also brings ``armlab fit-joint``: the
FRF and Levy fits of real joint recordings.
"""

from armlab.config.diagnosis import DiagnosisConfig
from armlab.protocols.base import Command, DiagnosisHooks, Protocol, Referee
from armlab.protocols.joint_1dof.diagnosis.rules import RULES
from armlab.protocols.joint_1dof.fit_command import run_fit_joint

__all__ = ["PROTOCOL"]


def _load(path, cfg: DiagnosisConfig):
    from armlab.data.joint_import import load_joint_data

    return load_joint_data(path, min_duration_s=cfg.min_duration_s)


def _diagnose(data, cfg: DiagnosisConfig):
    from armlab.protocols.joint_1dof.diagnosis.diagnose import diagnose_joint

    return diagnose_joint(data, cfg)


def _report(results, *, data_path: str, figures) -> str:
    from armlab.protocols.joint_1dof.diagnosis.report import format_report

    return format_report(results, data_path=data_path, figures=figures)


def _figures(viz, series, results, out):
    return viz.diagnosis_figures(series, results, out)


def _recording(viz, series, path):
    return viz.diagnosis_recording(series, path)


def _make_dataset(cls, rep, ref, diag_cfg, folder):
    from armlab.protocols.joint_1dof.diagnosis.referee import make_dataset

    return make_dataset(cls, rep, ref, diag_cfg, folder)


def _describe(ref) -> str:
    from armlab.protocols.joint_1dof.diagnosis.referee import describe

    return describe(ref)


def _referee() -> Referee:
    from armlab.protocols.joint_1dof.diagnosis.referee import JOINT_CLASSES

    return Referee(classes=JOINT_CLASSES, make_dataset=_make_dataset, describe=_describe)


def _candidates() -> tuple[str, ...]:
    from armlab.protocols.joint_1dof.diagnosis.models import JOINT_SURROGATES

    return tuple(JOINT_SURROGATES)


PROTOCOL = Protocol(
    name="joint_1dof",
    paper="REKLAB ankle recordings (../shared/data/reklab_ankle); joint model of seeds/004",
    summary="diagnosis of 1-DoF joint recordings (CSV/MAT, REKLAB format); no simulated run",
    catalogue=(
        "reflex",
        "cuff_compliance",
        "transmission_compliance",
        "joint_friction",
        "force_sensor_noise",
        "force_sensor_drift",
        "force_sensor_bandwidth",
        "encoder_quantisation",
        "channel_delay",
        "payload_mass",
        "cocontraction_variation",
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
    examples=(
        "diagnose data=../shared/data/reklab_ankle protocol=joint_1dof diagnosis.per_trial=true",
        "diagnose-benchmark referee.protocol=joint_1dof referee.replicates=10",
        "fit-joint ../shared/data/reklab_ankle",
    ),
    commands=(
        Command(
            name="fit-joint",
            usage="fit-joint <csv|folder> [frf.<field>=<value>] [out=<dir>]",
            help="impedance/admittance fits of real 1-DoF joint recordings (t_s,position_rad,torque_Nm CSV)",
            run=run_fit_joint,
        ),
    ),
)
