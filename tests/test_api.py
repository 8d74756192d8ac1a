"""The Python API (armlab.run / load_run / diagnose): the same checks, files and numbers as the CLI."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import toy_protocol as toy

import armlab
from armlab.errors import ConfigError, DataError
from armlab.protocols import registry
from armlab.protocols._files import json_default

ROOT = Path(__file__).resolve().parents[1]
_VOLATILE = {"timing", "files"}  # wall-clock times and this run's own paths


@pytest.fixture
def registered():
    registry.register(toy.PROTOCOL)
    yield toy.PROTOCOL
    registry.unregister(toy.NAME)


def _arrays(path: Path) -> dict[str, bytes]:
    out: dict[str, bytes] = {}
    with h5py.File(path, "r") as f:
        f.visititems(
            lambda k, v: out.__setitem__(k, np.asarray(v).tobytes()) if isinstance(v, h5py.Dataset) else None
        )
    return out


def test_run_gives_the_cli_s_trials_and_results(registered, tmp_path):
    run = armlab.run(toy.NAME, ["seed=3"], out=tmp_path / "api")
    assert run.protocol == toy.NAME and run.dir == tmp_path / "api"
    assert (run.dir / ".hydra" / "config.yaml").is_file() and (run.dir / "results.json").is_file()
    cmd = [sys.executable, str(Path(toy.__file__)), "run", f"protocol={toy.NAME}", "seed=3"]
    proc = subprocess.run([*cmd, f"out={tmp_path / 'cli'}"], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert _arrays(run.dir / "trials.h5") == _arrays(tmp_path / "cli" / "trials.h5")
    cli = json.loads((tmp_path / "cli" / "results.json").read_text())
    api = json.loads((run.dir / "results.json").read_text())
    assert {k: v for k, v in api.items() if k not in _VOLATILE} == {
        k: v for k, v in cli.items() if k not in _VOLATILE
    }
    # the run recovers the plant as the CLI's does (tests/test_plugin_protocol.py: m, k within 1 %)
    assert run.results["protocol"] == toy.NAME and run.trials().n_trials >= 1
    assert run.table().startswith(toy.format_table(run.results))  # then the timing line


def test_load_run_reads_a_complete_folder_and_refuses_an_unfinished_one(registered, tmp_path):
    run = armlab.run(toy.NAME, ["seed=1"], out=tmp_path / "r")
    again = armlab.load_run(run.dir)
    assert again.results == json.loads(json.dumps(run.results, default=json_default))  # what run returned
    assert again.protocol == toy.NAME and again.config["seed"] == 1
    (run.dir / "results.json").unlink()
    with pytest.raises(DataError, match=r"incomplete run .*armlab run resume=true out="):
        armlab.load_run(run.dir)
    with pytest.raises(DataError, match="holds no results.json"):
        armlab.load_run(tmp_path)  # not a run folder


def test_run_refuses_bad_overrides_and_used_folders_before_writing(registered, tmp_path):
    with pytest.raises(ConfigError, match="'arm' is not read by protocol"):
        armlab.run(toy.NAME, ["arm.cocontraction=0.3"], out=tmp_path / "bad")
    assert not (tmp_path / "bad").exists()
    run = armlab.run(toy.NAME, ["seed=2"], out=tmp_path / "r")
    before = {p: p.read_bytes() for p in run.dir.rglob("*") if p.is_file()}
    with pytest.raises(DataError, match="holds a run of another configuration"):
        armlab.run(toy.NAME, ["seed=5"], out=run.dir)
    with pytest.raises(DataError, match="already holds results.json"):
        armlab.run(toy.NAME, ["seed=2"], out=run.dir)
    assert {p: p.read_bytes() for p in run.dir.rglob("*") if p.is_file()} == before
    own = tmp_path / "own"
    own.mkdir()
    (own / "notes.txt").write_text("mine")
    with pytest.raises(DataError, match="not an armlab run folder"):
        armlab.run(toy.NAME, out=own)
    # the run folder is out= here as on the command line: Hydra's spelling is refused, not ignored
    with pytest.raises(ConfigError, match="out=elsewhere instead of hydra.run.dir"):
        armlab.run(toy.NAME, ["hydra.run.dir=elsewhere"], out=tmp_path / "x")
    with pytest.raises(ConfigError, match="given twice"):
        armlab.run(toy.NAME, [f"out={tmp_path / 'y'}"], out=tmp_path / "x")
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_diagnose_returns_the_results_it_writes(registered, tmp_path):
    run = armlab.run(toy.NAME, ["seed=3"], out=tmp_path / "r")
    report = armlab.diagnose(run.dir, toy.NAME, out=tmp_path / "d", figures=False)
    assert report["verdict"] == ["none"]  # a clean toy run: nothing to explain (as through the CLI)
    assert report["dir"] == tmp_path / "d"
    assert json.loads((tmp_path / "d" / "results.json").read_text())["verdict"] == ["none"]
    with pytest.raises(ConfigError):
        armlab.diagnose(run.dir, "no_such_protocol", out=tmp_path / "d2")
