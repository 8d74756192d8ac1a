"""The bad-input battery (issue 22): every verb, config group, data file and fault below is refused
with exit status 2, one ``armlab: error:`` line that names the key or file and the problem with
its valid choice or bound, no traceback, and nothing written.

Every case is refused before any simulation or fit (the checks run up front), so each takes a
fraction of a second in-process; the data files are tiny and made once per module. A handful of
cases go through the real ``armlab`` entry point in a subprocess. Older bad-input cases stay in
tests/test_cli.py, tests/test_registry.py and tests/test_cli_diagnose.py (not repeated here).
"""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import h5py
import numpy as np
import pytest

import armlab.cli as cli
from armlab.cli import main
from armlab.data.h5io import write_trials
from armlab.data.trial import TrialSet
from armlab.errors import ArmlabWarning
from armlab.protocols.compose import compose

REPO = Path(__file__).resolve().parents[1]


def _csv(path: Path, fs: float, n: int, *, angle_scale=1.0, torque_scale=1.0, amp=0.02, k=100.0) -> Path:
    """A joint trial: a random angle (rad, rms ``amp``) and a spring torque -k·angle (N·m), scaled."""
    t = np.arange(n) / fs
    x = amp * np.random.default_rng(0).standard_normal(n)
    rows = np.column_stack([t, x * angle_scale, -k * x * torque_scale])
    np.savetxt(path, rows, delimiter=",", header="t_s,position_rad,torque_Nm", comments="", fmt="%.9g")
    return path


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("bad_input")
    f = {
        "ok": _csv(d / "ok.csv", 1000, 600),
        # 12 s at 40 Hz: past min_duration_s = 10 s; with a 15 Hz band, too slow for the reflex's
        # low-pass (up to 25 Hz; 100 Hz data, refused before for the torque sensor's digital
        # low-pass, are diagnosed since that candidate is an exact frequency response)
        "hz40": _csv(d / "hz40.csv", 40, 480),
        # in degrees: 0.1 rad rms peaks beyond pi "rad"; 0.005 rad rms stays below it (scale check)
        "deg_big": _csv(d / "deg_big.csv", 1000, 600, angle_scale=57.29578, amp=0.1),
        "deg_small": _csv(d / "deg_small.csv", 1000, 600, angle_scale=57.29578, amp=0.005),
        # in N·mm: 5 N·m rms peaks beyond 1000 "N·m"; 0.1 N·m rms stays below it (scale check)
        "nmm_big": _csv(d / "nmm_big.csv", 1000, 600, torque_scale=1000.0, amp=0.05),
        "nmm_small": _csv(d / "nmm_small.csv", 1000, 600, torque_scale=1000.0, amp=0.001),
        "huge": _csv(d / "huge.csv", 1000, 600, angle_scale=1e300, torque_scale=1e300),
        # in degrees AND N·mm, 0.002 rad rms (peaks ~0.4 deg, ~700 N·mm: inside both peak bounds), so
        # only the scale tells: raw 1745 lies inside 5-5000, in SI with one channel converted it is
        # 1.75 (units=Nmm: degrees) or 1e5 (units=deg: N·mm)
        "deg_nmm": _csv(d / "deg_nmm.csv", 1000, 600, angle_scale=57.29578, torque_scale=1000.0, amp=0.002),
    }
    header = "t_s,position_rad,torque_Nm\n"
    good = "".join(f"{i / 1000},{0.01 * np.sin(i)},{-np.sin(i)}\n" for i in range(50))
    texts = {
        "empty": "",
        "header_only": header,
        "missing_col": "t_s,position_rad\n0,0.1\n0.001,0.2\n",
        "nan_row": header + good + "0.05,nan,1\n",
        "nonmono": header + "0,0,0\n0.002,0.01,1\n0.001,0.02,2\n",
        "semicolon": header.replace(",", ";") + good.replace(",", ";"),
        "one_row": header + "0,0.01,1\n",
        "text_cell": header + "0,0.01,1\n0.001,abc,1\n",
        "nonuniform": header + "0,0,0\n0.001,0.01,1\n0.0025,0.02,2\n0.0035,0.01,1\n",
        "dup_header": "t_s,position_rad,torque_Nm,t_s\n0,0,0,0\n0.001,0,0,0\n",
    }
    for name, text in texts.items():
        f[name] = d / f"{name}.csv"
        f[name].write_text(text)
    f["garbage_mat"] = d / "garbage.mat"
    f["garbage_mat"].write_bytes(bytes(range(200)))
    f["fake_run"] = d / "fake_run"
    f["fake_run"].mkdir()
    (f["fake_run"] / "trials.h5").write_text(header + good)  # a CSV under the trial file's name
    f["txt"] = d / "trial.txt"
    f["txt"].write_text(header + good)
    f["binary"] = d / "binary.csv"
    f["binary"].write_bytes(bytes(range(256)) * 8)
    f["unreadable"] = d / "unreadable.csv"
    f["unreadable"].write_text(header + good)
    f["unreadable"].chmod(0)
    mixed = d / "mixed"
    mixed.mkdir()
    _csv(mixed / "a.csv", 1000, 600)
    _csv(mixed / "b.csv", 500, 300)
    f["mixed"] = mixed
    f["nonempty"] = d / "nonempty"
    f["nonempty"].mkdir()
    (f["nonempty"] / "keep.txt").write_text("results of an earlier run\n")
    # a tiny trials.h5 of a fractional_elbow run, and a copy whose first data chunk is destroyed
    run = d / "run"
    run.mkdir()
    trials = TrialSet(
        fs_hz=1000.0,
        onset_index=np.array([1, 1]),
        channels={"f_measured": np.random.default_rng(0).standard_normal((2, 500, 1))},
        units={"f_measured": "N"},
        trial_meta={},
        attrs={"protocol": "fractional_elbow", "config_yaml": ""},
    )
    write_trials(run / "trials.h5", trials)
    f["run"] = run
    bad = d / "bad_run"
    bad.mkdir()
    raw = bytearray((run / "trials.h5").read_bytes())
    with h5py.File(run / "trials.h5", "r") as h5:
        chunk = h5["channels/f_measured"].id.get_chunk_info(0)
    raw[chunk.byte_offset : chunk.byte_offset + chunk.size] = b"\xff" * chunk.size
    (bad / "trials.h5").write_bytes(bytes(raw))
    f["bad_run"] = bad
    cond = d / "cond_run"  # a conditioning_window trial file: 0.3 s recorded before onset
    cond.mkdir()
    write_trials(
        cond / "trials.h5",
        replace(trials, onset_index=np.array([300, 300]), attrs={"protocol": "conditioning_window"}),
    )
    f["cond_run"] = cond
    for name, units, scale in (("mm_run", "m", 1000.0), ("unit_run", "mm", 1.0)):
        folder = d / name  # hand positions of a conditioning trial file in mm, or labelled so
        folder.mkdir()
        pos = 0.4 + 0.01 * np.random.default_rng(1).standard_normal((2, 500, 2))
        hand = replace(
            trials,
            channels={"hand_pos": pos * scale, "hand_force": np.ones((2, 500, 2))},
            units={"hand_pos": units, "hand_force": "N"},
            attrs={"protocol": "conditioning_window", "arm_l1_m": 0.3, "arm_l2_m": 0.35},
        )
        write_trials(folder / "trials.h5", hand)
        f[name] = folder
    other = d / "other_run"
    other.mkdir()
    write_trials(other / "trials.h5", replace(trials, attrs={"protocol": "nope"}))
    f["other_run"] = other
    return f


# (id, argv with {name} placeholders for the files above and {tmp} for a fresh folder, the words
# the one error line must hold: the key or file, and the valid choice or bound)
RUN = [
    ("plus-unknown-key", ["+foo=1"], ["+foo=1", "'foo' is not read by protocol", "its groups"]),
    ("repeated-key", ["seed=1", "seed=2"], ["seed is given twice", "give it once"]),
    (
        "other-protocols-group",
        ["frf.welch_window=5000"],
        ["'frf' is not read by protocol 'conditioning_window'"],
    ),
    (
        "other-protocols-group-2",
        ["protocol=fractional_elbow", "arm.q0=[0,0]"],
        ["'arm' is not read", "elbow"],
    ),
    (
        "other-protocols-group-3",
        ["protocol=virtual_force_sensor", "estimator.lowpass_hz=10"],
        ["'estimator'", "vfs"],
    ),
    (
        "rate-cannot-resolve",
        ["sensors.fs_hz=50"],
        ["sensors.fs_hz=50", "T_k = 50 ms", "its velocity reaches 43.2 Hz", "sensors.fs_hz >= 86.4"],
    ),
    (  # 80 Hz divides the 2 kHz physics rate; only the velocity bound refuses it
        "rate-ideal-sensors",
        ["sensors.preset=ideal", "sensors.fs_hz=80"],
        ["sensors.fs_hz=80", ">= 86.4", ">= 222.4 to resolve its acceleration"],
    ),
    (
        "rate-not-dividing",
        ["sensors.fs_hz=333"],
        ["sensors.fs_hz=333", "whole number of physics steps", "1000.0"],
    ),
    ("rate-below-sensor-bw", ["sensors.fs_hz=250"], ["sensors.fs_hz=250", "Nyquist", "sensors.preset=ideal"]),
    ("window-not-in-scenario", ["scenario.k_values=[99]"], ["scenario.k_values [99]", "valid: 1..26"]),
    ("lowpass-above-nyquist", ["estimator.lowpass_hz=600"], ["estimator.lowpass_hz=600", "below 500 Hz"]),
    ("t-obs-too-long", ["estimator.t_obs_s=[5.0]"], ["[5.0] s are longer", "T_obs <= 0.550 s"]),
    ("t-obs-empty", ["estimator.t_obs_s=[]"], ["estimator.t_obs_s is empty", "null"]),
    ("baseline-too-long", ["estimator.baseline_s=5"], ["estimator.baseline_s=5", "<= 0.3 s"]),
    (
        "effect-unknown-key",
        ["effects=[joint_friction]", "effects.joint_friction.xyz=1"],
        ["has no key 'xyz'", "coulomb_Nm"],
    ),
    ("effect-unknown", ["effects.nonsense.a=1"], ["'nonsense'", "joint_friction"]),
    (
        "effect-bw-above-nyquist",
        ["effects=[force_sensor_bandwidth]", "effects.force_sensor_bandwidth.cutoff_hz=900"],
        ["force_sensor_bandwidth", "900", "Nyquist frequency 500"],
    ),
    ("nan-timestep", ["sim.timestep_s=nan"], ["sim.timestep_s", "nan"]),
    ("inf-rate", ["sensors.fs_hz=inf"], ["sensors.fs_hz=inf is not a finite number"]),
    ("inf-cuff", ["cuff.damping_Ns_per_m=inf"], ["cuff.damping_Ns_per_m", "inf"]),
    ("float-seed", ["seed=1.5"], ["seed=1.5", "could not be converted to Integer"]),
    ("negative-seed", ["seed=-1"], ["seed must be an integer in [0, 2**63)", "-1"]),
    ("huge-seed", ["seed=99999999999999999999999"], ["seed must be an integer in [0, 2**63)"]),
    ("group-without-options", ["output=3"], ["'output' has no options", "output.<field>", "figures"]),
    ("no-key", ["=3"], ["'=3' has no key", "key=value"]),
    ("unparsable-list", ["arm.q0=[0.1"], ["arm.q0=[0.1", "no viable alternative"]),
    ("unknown-launcher", ["hydra/launcher=nope"], ["hydra/launcher/nope", "joblib"]),
    ("adding-hydra-key", ["+hydra.foo=1"], ["+hydra.foo=1", "adds none", "hydra/launcher=joblib"]),
    ("bad-bool", ["output.figures=maybe"], ["output.figures", "not a valid bool"]),
    ("unknown-option", ["--foo"], ["['--foo']", "--multirun"]),
    ("hydra-run-dir", ["hydra.run.dir=x"], ["out=x instead of hydra.run.dir", "every verb"]),
    ("hydra-sweep-dir", ["-m", "seed=0,1", "hydra.sweep.dir=x"], ["out=x instead of hydra.sweep.dir"]),
    (
        "pair-of-one",
        ["protocol=fractional_elbow", "frf.band_hz=[1]"],
        ["frf.band_hz must hold 2 values", "[1.0]"],
    ),
    (
        "pair-of-three",
        ["protocol=virtual_force_sensor", "vfs.band_hz=[1,2,3]"],
        ["vfs.band_hz must hold 2 values"],
    ),
    ("negative-n-trials", ["scenario.n_trials=-3"], ["scenario.n_trials must be >= 2", "-3"]),
    ("negative-cuff", ["cuff.stiffness_N_per_m=-1"], ["cuff.stiffness_N_per_m must be > 0"]),
    ("sweep-bad-value", ["-m", "seed=0,abc"], ["seed=abc", "Integer"]),
    ("sweep-bad-window", ["-m", "scenario.k_values=[26],[99]"], ["scenario.k_values [99]", "1..26"]),
    ("sweep-bad-lowpass", ["-m", "estimator.lowpass_hz=20,900"], ["estimator.lowpass_hz=900", "below 500"]),
    ("fractional-rate", ["protocol=fractional_elbow", "sensors.fs_hz=100"], ["sensors.fs_hz = 100", "2000"]),
    (
        "fractional-subject-without-muscles",
        ["protocol=fractional_elbow", "subject.enabled=true", "elbow.impedance=five_element"],
        ["elbow.impedance=five_element has no muscles", "elbow.impedance=muscle"],
    ),
    (
        "fractional-windows",
        ["protocol=fractional_elbow", "scenario.k_values=[1]"],
        ["scenario.k_values=[1]", "unset"],
    ),
    (
        "fractional-welch",
        ["protocol=fractional_elbow", "frf.welch_window=100000000"],
        ["frf.welch_window = 100000000", "<= 80000"],
    ),
    ("fractional-band", ["protocol=fractional_elbow", "frf.band_hz=[1,1500]"], ["frf.band_hz", "< 1000"]),
    (
        "fractional-fir",
        ["protocol=fractional_elbow", "frf.fir_pass_hz=1100", "frf.fir_stop_hz=1200"],
        ["frf.fir_stop_hz=1200", "below 1000"],
    ),
    (
        "vfs-band",
        ["protocol=virtual_force_sensor", "vfs.band_hz=[0.2,600]"],
        ["vfs.band_hz upper edge 600", "500"],
    ),
    (
        "vfs-lowpass",
        ["protocol=virtual_force_sensor", "vfs.lowpass_hz=900"],
        ["vfs.lowpass_hz=900", "below 500"],
    ),
    (
        "vfs-rate",
        ["protocol=virtual_force_sensor", "sensors.fs_hz=333"],
        ["sensors.fs_hz=333", "whole number of physics steps"],
    ),
    ("vfs-sensors", ["protocol=virtual_force_sensor", "sensors.fs_hz=100"], ["sensors.fs_hz=100", "Nyquist"]),
    (
        "vfs-sg-window",
        ["protocol=virtual_force_sensor", "vfs.sg_window=60001"],
        ["vfs.sg_window=60001", "<= 50000"],
    ),
    (
        "vfs-nan",
        ["protocol=virtual_force_sensor", "capstan.kp_Nm_per_rad=nan"],
        ["capstan.kp_Nm_per_rad", "nan"],
    ),
]

OTHER = [
    ("estimate-no-dir", ["estimate"], ["estimate needs a run directory"]),
    # one output convention (issue 21): every verb names its folder out=<dir>, the Hydra spelling is refused
    ("estimate-out-not-empty", ["estimate", "{run}", "out={run}"], ["is not empty", "never overwrites"]),
    ("estimate-hydra-dir", ["estimate", "{run}", "hydra.run.dir=x"], ["out=x instead of hydra.run.dir"]),
    ("diagnose-hydra-dir", ["diagnose", "data={run}", "protocol=joint_1dof", "hydra.run.dir=x"], ["out=x"]),
    ("fit-joint-hydra-dir", ["fit-joint", "{run}", "hydra.sweep.dir=x"], ["instead of hydra.sweep.dir"]),
    ("benchmark-empty-out", ["diagnose-benchmark", "out="], ["diagnose-benchmark out=", "needs a folder"]),
    ("estimate-damaged-h5", ["estimate", "{bad_run}"], ["trials.h5: cannot be read", "damaged"]),
    ("estimate-unknown-protocol", ["estimate", "{other_run}"], ["protocol 'nope'", "valid"]),
    ("estimate-bad-arg", ["estimate", "{run}", "badarg"], ["'badarg'", "frf.<field>=<value>"]),
    ("estimate-other-group", ["estimate", "{run}", "estimator.lowpass_hz=30"], ["frf.<field>=<value>"]),
    ("estimate-nan", ["estimate", "{run}", "frf.welch_overlap=nan"], ["frf.welch_overlap", "[0, 1)"]),
    ("estimate-inf", ["estimate", "{run}", "frf.fir_attenuation_db=inf"], ["frf.fir_attenuation_db=inf"]),
    (
        "estimate-lowpass-above-nyquist",
        ["estimate", "{cond_run}", "estimator.lowpass_hz=900"],
        ["estimator.lowpass_hz=900", "below 500 Hz"],
    ),
    (
        "estimate-baseline-too-long",
        ["estimate", "{cond_run}", "estimator.baseline_s=5"],
        ["estimator.baseline_s=5", "<= 0.3 s"],
    ),
    ("estimate-pair-of-one", ["estimate", "{run}", "frf.band_hz=[1]"], ["frf.band_hz must hold 2 values"]),
    ("estimate-not-hdf5", ["estimate", "{fake_run}"], ["trials.h5: not a readable HDF5 file"]),
    ("view-no-dir", ["view"], ["view needs exactly one run directory"]),
    ("view-two-dirs", ["view", "a", "b"], ["view needs exactly one run directory"]),
    ("view-file", ["view", "{ok}"], ["trials.rrd not found", "output.recording=true"]),
    (
        "diagnose-binary",
        ["diagnose", "data={binary}", "protocol=joint_1dof"],
        ["binary.csv", "not a text CSV"],
    ),
    (
        "diagnose-40hz",
        ["diagnose", "data={hz40}", "protocol=joint_1dof", "diagnosis.band_hz=15"],
        ["sampled at 40 Hz", "'reflex'", "cutoff_hz up to 25 Hz", ">= 50 Hz", "diagnosis.exclude="],
    ),
    ("diagnose-degrees", ["diagnose", "data={deg_big}", "protocol=joint_1dof"], ["deg_big.csv", "units=deg"]),
    (
        "diagnose-degrees-scale",
        ["diagnose", "data={deg_small}", "protocol=joint_1dof"],
        ["scale", "units=deg"],
    ),
    ("diagnose-nmm", ["diagnose", "data={nmm_big}", "protocol=joint_1dof"], ["N·mm", "units=Nmm"]),
    ("diagnose-nmm-scale", ["diagnose", "data={nmm_small}", "protocol=joint_1dof"], ["scale", "units=Nmm"]),
    (
        "diagnose-deg-nmm-read-as-nmm",  # the stated N·mm converted first: the angle's degrees show
        ["diagnose", "data={deg_nmm}", "protocol=joint_1dof", "units=Nmm"],
        ["deg_nmm.csv", "scale 1.75 N·m/rad", "looks like degrees", "units=deg,Nmm", "units=rad,Nmm"],
    ),
    (
        "diagnose-deg-nmm-read-as-deg",  # the stated degrees converted first: the torque's N·mm show
        ["diagnose", "data={deg_nmm}", "protocol=joint_1dof", "units=deg"],
        ["deg_nmm.csv", "scale 1e+05 N·m/rad", "looks like N·mm", "units=deg,Nmm", "units=deg,Nm"],
    ),
    (
        "diagnose-bad-unit",
        ["diagnose", "data={ok}", "protocol=joint_1dof", "units=kg"],
        ["unknown unit 'kg'", "deg"],
    ),
    (
        "diagnose-two-units",
        ["diagnose", "data={ok}", "protocol=joint_1dof", "units=deg,rad"],
        ["two units for one channel", "Nmm"],
    ),
    (
        "diagnose-damaged-h5",
        ["diagnose", "data={bad_run}", "protocol=conditioning_window"],
        ["trials.h5: cannot be read", "damaged"],
    ),
    (
        "diagnose-h5-in-mm",
        ["diagnose", "data={mm_run}", "protocol=conditioning_window"],
        ["'hand_pos' reaches", "<= 1 m", "looks like mm"],
    ),
    (
        "diagnose-h5-unit",
        ["diagnose", "data={unit_run}", "protocol=conditioning_window"],
        ["'hand_pos' is in 'mm'", "'m'"],
    ),
    (
        "diagnose-units-for-h5",
        ["diagnose", "data={bad_run}", "protocol=conditioning_window", "units=deg"],
        ["units=deg", "joint_1dof"],
    ),
    (
        "diagnose-units-published",
        ["diagnose", "data=published", "protocol=joint_1dof", "units=deg"],
        ["units="],
    ),
    (
        "diagnose-out-not-empty",
        ["diagnose", "data={ok}", "protocol=joint_1dof", "out={nonempty}"],
        ["nonempty is not empty", "new folder"],
    ),
    ("diagnose-empty", ["diagnose", "data={empty}", "protocol=joint_1dof"], ["empty.csv: is empty", "t_s"]),
    ("diagnose-header-only", ["diagnose", "data={header_only}", "protocol=joint_1dof"], ["no data rows"]),
    ("diagnose-missing-col", ["diagnose", "data={missing_col}", "protocol=joint_1dof"], ["['torque_Nm']"]),
    ("diagnose-nan-row", ["diagnose", "data={nan_row}", "protocol=joint_1dof"], ["NaN or inf", "row 51"]),
    ("diagnose-nonmono", ["diagnose", "data={nonmono}", "protocol=joint_1dof"], ["not strictly increasing"]),
    (
        "diagnose-semicolon",
        ["diagnose", "data={semicolon}", "protocol=joint_1dof"],
        ["';'-separated", "comma"],
    ),
    (
        "diagnose-huge",
        ["diagnose", "data={huge}", "protocol=joint_1dof"],
        ["huge.csv", "check the angle column"],
    ),
    ("diagnose-one-row", ["diagnose", "data={one_row}", "protocol=joint_1dof"], ["1 data row", "at least 2"]),
    (
        "diagnose-text-cell",
        ["diagnose", "data={text_cell}", "protocol=joint_1dof"],
        ["non-numeric cell 'abc'"],
    ),
    (
        "diagnose-txt",
        ["diagnose", "data={txt}", "protocol=joint_1dof"],
        ["unsupported file type '.txt'", ".csv"],
    ),
    (
        "diagnose-nonuniform",
        ["diagnose", "data={nonuniform}", "protocol=joint_1dof"],
        ["non-uniform sampling"],
    ),
    (
        "diagnose-dup-header",
        ["diagnose", "data={dup_header}", "protocol=joint_1dof"],
        ["duplicate column(s)"],
    ),
    (
        "diagnose-garbage-mat",
        ["diagnose", "data={garbage_mat}", "protocol=joint_1dof"],
        ["garbage.mat", "7.3"],
    ),
    (
        "diagnose-empty-folder",
        ["diagnose", "data={nonempty}", "protocol=joint_1dof"],
        ["no trial files", "*.csv"],
    ),
    ("diagnose-mixed-rates", ["diagnose", "data={mixed}", "protocol=joint_1dof"], ["different sample rates"]),
    (
        "diagnose-inf-setting",
        ["diagnose", "data={ok}", "protocol=joint_1dof", "diagnosis.bic_margin=inf"],
        ["diagnosis.bic_margin=inf is not a finite number"],
    ),
    (
        "diagnose-negative-margin",
        ["diagnose", "data={ok}", "protocol=joint_1dof", "diagnosis.bic_margin=-3"],
        ["diagnosis.bic_margin must be >= 0"],
    ),
    ("effects-empty-protocol", ["effects", "protocol="], ["no effects for protocol ''", "valid protocols"]),
    (
        "benchmark-rate-too-low",
        [
            "diagnose-benchmark",
            "referee.fs_hz=40",
            "diagnosis.band_hz=15",
            "referee.classes=[none]",
            "referee.replicates=1",
        ],
        ["referee.fs_hz=40", "'reflex'", ">= 50 Hz"],
    ),
    (
        "benchmark-band-too-high",
        ["diagnose-benchmark", "diagnosis.band_hz=120", "diagnosis.highpass_hz=0.3"],
        ["referee.fs_hz=1000", "diagnosis.band_hz=120", "267 Hz"],
    ),
    ("benchmark-no-jobs", ["diagnose-benchmark", "referee.jobs=0"], ["referee.jobs must be", "-1"]),
    ("benchmark-bad-jobs", ["diagnose-benchmark", "referee.jobs=abc"], ["referee.jobs=abc", "Integer"]),
    (
        "benchmark-out-not-empty",
        ["diagnose-benchmark", "referee.replicates=1", "out={nonempty}"],
        ["nonempty is not empty", "new folder"],
    ),
    ("fit-joint-no-file", ["fit-joint"], ["fit-joint needs a CSV file or folder"]),
    (
        "fit-joint-mixed-rates",
        ["fit-joint", "{mixed}"],
        ["a: 1000 Hz, b: 500 Hz", "one folder must hold one rate"],
    ),
    ("fit-joint-binary", ["fit-joint", "{binary}"], ["binary.csv", "not a text CSV"]),
    ("fit-joint-degrees", ["fit-joint", "{deg_big}"], ["deg_big.csv", "units=deg"]),
    ("fit-joint-nmm", ["fit-joint", "{nmm_big}"], ["nmm_big.csv", "units=Nmm"]),
    ("fit-joint-bad-unit", ["fit-joint", "{ok}", "units=Nmm,deg,rad"], ["two units for one channel"]),
    ("fit-joint-welch", ["fit-joint", "{ok}"], ["frf.welch_window = 5000", "recording ok.csv", "<= 600"]),
    ("fit-joint-band", ["fit-joint", "{ok}", "frf.band_hz=[1,900]"], ["frf.band_hz upper edge 900", "< 500"]),
    ("fit-joint-bad-arg", ["fit-joint", "{ok}", "bogus"], ["'bogus'", "frf.<field>=<value>"]),
    ("fit-joint-missing", ["fit-joint", "{tmp}/nope.csv"], ["nope.csv does not exist", ".csv"]),
    ("fit-joint-out-not-empty", ["fit-joint", "{ok}", "out={nonempty}"], ["is not empty", "new directory"]),
]


def _assert_refused(argv: list[str], words: list[str], capsys) -> str:
    assert main(argv) == 2
    out = capsys.readouterr()
    assert "Traceback" not in out.out + out.err
    errors = [line for line in out.err.splitlines() if line.startswith("armlab: error:")]
    assert len(errors) == 1, out.err
    assert "internal error" not in errors[0], errors[0]  # a specific message, not the safety net
    for word in words:
        assert word in errors[0], f"{word!r} not in {errors[0]!r}"
    return errors[0]


@pytest.mark.parametrize(("argv", "words"), [pytest.param(a, w, id=i) for i, a, w in RUN])
def test_run_is_refused_before_its_folder_exists(argv, words, tmp_path, capsys):
    _assert_refused(["run", *argv, f"out={tmp_path / 'out'}"], words, capsys)
    assert not (tmp_path / "out").exists()  # refused before Hydra made the run folder


@pytest.mark.parametrize(("argv", "words"), [pytest.param(a, w, id=i) for i, a, w in OTHER])
def test_verb_is_refused(argv, words, files, tmp_path, capsys):
    names = {k: str(v) for k, v in files.items()}
    argv = [a.format(tmp=tmp_path, **names) for a in argv]
    before = {
        p: sorted(q.name for q in p.iterdir()) for p in (files["run"], files["nonempty"], files["bad_run"])
    }
    if argv[0] in ("diagnose", "diagnose-benchmark", "fit-joint") and not any(
        a.startswith("out=") for a in argv
    ):
        argv.append(f"out={tmp_path / 'out'}")
    _assert_refused(argv, words, capsys)
    assert not (tmp_path / "out").exists()
    assert before == {p: sorted(q.name for q in p.iterdir()) for p in before}  # nothing written


def test_an_unreadable_file_is_named(files, tmp_path, capsys):
    path = files["unreadable"]
    try:
        path.read_bytes()
    except PermissionError:
        pass
    else:
        pytest.skip("this user reads a file with mode 000 (root): a permission error cannot be made here")
    _assert_refused(
        ["diagnose", f"data={path}", "protocol=joint_1dof"], ["unreadable.csv", "permissions"], capsys
    )


def test_a_stated_unit_reads_the_file(files):
    from armlab.data.joint_import import load_joint_data

    (deg,) = load_joint_data(files["deg_small"], units="deg")
    (rad,) = load_joint_data(files["ok"])
    (nmm,) = load_joint_data(files["nmm_small"], units="Nmm")
    assert np.std(deg.position) == pytest.approx(0.005, rel=0.1)  # 0.005 rad rms, read from degrees
    assert np.std(nmm.torque) / np.std(nmm.position) == pytest.approx(100.0, rel=1e-6)
    assert np.std(rad.torque) / np.std(rad.position) == pytest.approx(100.0, rel=1e-6)
    (same,) = load_joint_data(files["ok"], units="rad,Nm")  # SI stated: read as it is
    assert np.array_equal(same.torque, rad.torque)
    # degrees and N·mm both stated: read in SI with the true K = 100 N·m/rad. Of a pure spring the
    # rms ratio is K exactly; what differs is rounding only: the CSV's 9 significant digits
    # (<= 5e-9 relative per value) and the 7-digit degree factor the file was written with
    # (57.29578 vs 180/pi, 8.6e-9), so rel=1e-6 is > 50 times their sum
    (both,) = load_joint_data(files["deg_nmm"], units="deg,Nmm")
    assert np.std(both.torque) / np.std(both.position) == pytest.approx(100.0, rel=1e-6)
    assert np.std(both.position) == pytest.approx(0.002, rel=0.1)  # 0.002 rad rms, read from degrees


def test_a_reflex_slower_than_every_window_is_warned_once(capsys, tmp_path):
    slow = ["reflex.stretch_latency_s=0.9", "reflex.spinal_latency_s=1.0"]
    with pytest.warns(ArmlabWarning, match=r"exceed every observation window \(longest T_obs = 0.5 s\)"):
        compose(slow)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmlabWarning)
        compose(["reflex.stretch_latency_s=0.03"])  # acts inside the windows: no warning
    # through the CLI: one warning line, printed once although a sweep composes twice, then the
    # refusal of an effect this lab does not simulate
    argv = ["run", "-m", *slow, "seed=0,1", "effects=[cable_drag]", f"out={tmp_path / 's'}"]
    assert main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert [line.split(":")[1] for line in err] == [" warning", " error"], err
    assert err[0].startswith("armlab: warning: reflex latencies") and "reflex.enabled=false" in err[0]


def test_a_rate_that_aliases_the_acceleration_is_warned_not_refused():
    from armlab.config.integration import check_steps_per_sample
    from armlab.config.schema import SimConfig
    from armlab.config.validate import divisor_rates
    from armlab.errors import ConfigError
    from armlab.protocols.conditioning_window.preflight import (
        QUINTIC_ACCEL_BAND_PER_S,
        QUINTIC_VELOCITY_BAND_PER_S,
        check_rate,
        quintic_band,
    )

    # the bounds are the quintic move's 99.9 % energy bands (velocity 2.155, acceleration 5.560),
    # rounded up to 3 digits
    c_v, c_a = quintic_band(1), quintic_band(2)
    assert c_v == pytest.approx(2.155, abs=1e-3) and c_v <= QUINTIC_VELOCITY_BAND_PER_S < c_v + 0.01
    assert c_a == pytest.approx(5.560, abs=1e-3) and c_a <= QUINTIC_ACCEL_BAND_PER_S < c_a + 0.01
    # a sample-rate sweep with ideal sensors: 200 Hz runs, with one warning naming the bound
    with pytest.warns(ArmlabWarning, match=r"sensors.fs_hz=200 aliases the acceleration .* >= 222.4") as rec:
        compose(["sensors.preset=ideal", "sensors.fs_hz=200"])
    assert len([w for w in rec if issubclass(w.category, ArmlabWarning)]) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmlabWarning)
        compose([])  # 1 kHz: no warning
    # the rates the "whole number of physics steps" refusal suggests are never refused by the rate
    # check (for T_k = 50 ms: below 86.4 Hz), at the default step and the coarsest one
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ArmlabWarning)  # 100-200 Hz: warned, not refused
        for timestep_s in (SimConfig().timestep_s, 1e-3):
            for fs in divisor_rates(1.0 / timestep_s):
                check_steps_per_sample(timestep_s, fs)
                try:
                    check_rate(fs, 0.05)
                except ConfigError as exc:
                    pytest.fail(f"suggested rate {fs} refused: {exc}")


def test_an_unforeseen_exception_is_one_line_and_debug_shows_it(monkeypatch, capsys):
    def boom(args):
        raise RuntimeError("unexpected\nstate")

    monkeypatch.setattr(cli, "_effects", boom)
    assert main(["effects"]) == 2
    err = capsys.readouterr().err
    assert err == (
        "armlab: error: internal error: RuntimeError: unexpected state (please report it; rerun with "
        "ARMLAB_DEBUG=1 for the traceback)\n"
    )
    monkeypatch.setenv("ARMLAB_DEBUG", "1")
    with pytest.raises(RuntimeError, match="unexpected"):
        main(["effects"])


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        pytest.param(["run", "+foo=1"], ["'foo' is not read"], id="run-plus-key"),
        pytest.param(["fit-joint", "{binary}"], ["binary.csv", "not a text CSV"], id="fit-joint-binary"),
        pytest.param(["estimate", "{bad_run}"], ["damaged"], id="estimate-damaged"),
    ],
)
def test_the_entry_point_prints_one_line(argv, words, files, tmp_path):
    names = {k: str(v) for k, v in files.items()}
    argv = [a.format(**names) for a in argv] + (["out=" + str(tmp_path / "r")] if argv[0] == "run" else [])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    env.pop("ARMLAB_DEBUG", None)
    exe = Path(sys.executable).with_name("armlab")
    proc = subprocess.run(
        [str(exe), *argv], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("armlab: error:") and all(w in lines[0] for w in words)
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    "verb", ["run", "estimate", "view", "diagnose", "effects", "diagnose-benchmark", "fit-joint"]
)
def test_help_of_every_verb_prints_the_usage(verb, capsys, tmp_path):
    assert main([verb, "--help"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: armlab <verb> [args]") and "units=" in out


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["out={t}/a", "out={t}/b"], ["out= is given 2 times"]),
        (["out=''"], ["armlab run out=", "needs a folder"]),
        (["out="], ["armlab run out=", "needs a folder"]),
        (["hydra.run.dir={t}/a"], ["instead of hydra.run.dir=", "every verb"]),
    ],
    ids=["twice", "quoted-empty", "empty", "hydra-spelling"],
)
def test_the_run_folder_is_given_once_and_not_empty(argv, words, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # an empty folder would be the working folder
    (tmp_path / "mine.txt").write_text("the user's own file")
    _assert_refused(["run", *[a.format(t=tmp_path) for a in argv]], words, capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.txt"]
