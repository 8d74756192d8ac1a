"""Sweeps beyond one machine (issue 21 item 4): the same 3-job multirun through Hydra's Ray launcher
(a local Ray instance) and its submitit launcher (submitit_local) gives what the serial runs give.

Slow (`make test-all`, which installs the extras armlab[ray] and armlab[slurm]): starting Ray costs
~10 s. Each job must write only into its own folder: the check compares every job's trial arrays
and results with a serial run of the same seed, and that no job folder holds another's files.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

pytestmark = pytest.mark.slow

TINY = [
    "protocol=conditioning_window",
    "scenario.k_values=[1,26]",
    "scenario.n_trials=4",
    "output.recording=false",
    "output.figures=false",
    "output.print_table=false",
    "progress=false",
]
SEEDS = (0, 1, 2)


def _armlab(*args: str, cwd: Path, env: dict | None = None) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).with_name("armlab")
    return subprocess.run([str(exe), *args], cwd=cwd, capture_output=True, text=True, timeout=900, env=env)


def _arrays(path: Path) -> dict[str, np.ndarray]:
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.update({name: obj[()]}) if isinstance(obj, h5py.Dataset) else None)
    return out


def _results(path: Path) -> dict:
    r = json.loads(path.read_text())
    r.pop("timing", None)
    r.pop("files", None)
    return r


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("serial")
    for seed in SEEDS:
        proc = _armlab("run", *TINY, f"seed={seed}", f"out={tmp / str(seed)}", cwd=tmp)
        assert proc.returncode == 0, proc.stderr
    return tmp


@pytest.mark.parametrize(
    ("launcher", "module"),
    [
        ("ray", "hydra_plugins.hydra_ray_launcher"),
        ("submitit_local", "hydra_plugins.hydra_submitit_launcher"),
    ],
)
def test_a_three_job_multirun_equals_the_serial_runs(launcher, module, serial, tmp_path):
    pytest.importorskip(
        module, reason=f"the {launcher} launcher is an optional extra (make test-all installs it)"
    )
    sweep = tmp_path / "sweep"
    env = {**os.environ, "RAY_DEDUP_LOGS": "0", "RAY_AUTH_MODE": "disabled"}
    seeds = ",".join(map(str, SEEDS))
    proc = _armlab(
        "run",
        "--multirun",
        *TINY,
        f"seed={seeds}",
        f"hydra/launcher={launcher}",
        f"out={sweep}",
        cwd=tmp_path,
        env=env,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    for job, seed in enumerate(SEEDS):
        folder = sweep / str(job)
        assert _results(folder / "results.json") == _results(serial / str(seed) / "results.json")
        got, want = _arrays(folder / "trials.h5"), _arrays(serial / str(seed) / "trials.h5")
        assert got.keys() == want.keys()
        for name in want:
            np.testing.assert_array_equal(got[name], want[name], err_msg=name)
        made = sorted(p.name for p in folder.iterdir())
        assert made == sorted(p.name for p in (serial / str(seed)).iterdir()), made  # its own files only
