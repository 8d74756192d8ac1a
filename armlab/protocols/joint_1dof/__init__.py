"""Protocol ``joint_1dof``: a 1-DoF joint (ankle, elbow) under position perturbations.

Diagnosis only (no ``armlab run``): measured REKLAB-format recordings are diagnosed against the
nominal I s^2 + B s + K joint, and its referee simulates pseudo-real datasets with the
higher-fidelity MuJoCo model of ``models/joint_rig/``. It also brings ``armlab fit-joint``: the
FRF and Levy fits of real joint recordings.
"""

from armlab.protocols.base import Command, Protocol
from armlab.protocols.joint_1dof.diagnosis import HOOKS
from armlab.protocols.joint_1dof.fit_command import run_fit_joint

__all__ = ["PROTOCOL"]


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
        "position_sensor_noise",
        "channel_delay",
        "payload_mass",
        "cocontraction_variation",
        "voluntary_torque",
        "operating_point_impedance",
    ),
    diagnosis=HOOKS,
    examples=(
        "diagnose data=../shared/data/reklab_ankle protocol=joint_1dof diagnosis.per_trial=true",
        "diagnose-benchmark referee.protocol=joint_1dof referee.replicates=10",
        "diagnose-benchmark referee.protocol=joint_1dof referee.generator=ode referee.replicates=10",
        "fit-joint ../shared/data/reklab_ankle",
    ),
    commands=(
        Command(
            name="fit-joint",
            usage="fit-joint <csv|mat|folder> [frf.<field>=<value>] [units=<deg|Nmm|deg,Nmm>] [out=<dir>]",
            help="impedance/admittance fits of real 1-DoF joint recordings (t_s,position_rad,torque_Nm CSV)",
            run=run_fit_joint,
        ),
    ),
)
