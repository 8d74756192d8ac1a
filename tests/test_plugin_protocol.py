"""A protocol defined only in tests/ runs through `armlab run`, `estimate` and `diagnose`.

The toy (tests/toy_protocol.py) is registered here and nowhere else; no file of the package, its
configs or its docs names it. It proves the plug-in shape: the runner, the CLI and the diagnosis
core find everything they need in the registered :class:`armlab.protocols.Protocol`.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import toy_protocol as toy

from armlab.cli import main
from armlab.protocols import registry

ROOT = Path(__file__).resolve().parents[1]


def _cli(*args: str) -> subprocess.CompletedProcess:
    """``armlab <args>`` in a fresh process that first registers the toy (tests/toy_protocol.py)."""
    cmd = [sys.executable, str(Path(toy.__file__)), *args]
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)


@pytest.fixture
def registered():
    registry.register(toy.PROTOCOL)
    yield toy.PROTOCOL
    registry.unregister(toy.NAME)


def test_no_file_outside_tests_names_the_toy():
    hits = subprocess.run(
        ["git", "grep", "-l", toy.NAME, "--", ":!tests"], cwd=ROOT, capture_output=True, text=True
    ).stdout.split()
    assert hits == []


def test_help_lists_the_registered_toy_and_forgets_it_after(registered, capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert f"  {toy.NAME}: " in out and "plant.<field>" in out and "armlab estimate takes fit.<field>" in out
    registry.unregister(toy.NAME)
    assert main(["--help"]) == 0
    assert toy.NAME not in capsys.readouterr().out


def test_run_estimate_recovers_the_plant(tmp_path):
    run_dir = tmp_path / "run"
    proc = _cli("run", f"protocol={toy.NAME}", "seed=3", f"out={run_dir}")
    assert proc.returncode == 0, proc.stderr
    results = json.loads((run_dir / "results.json").read_text())
    assert results["protocol"] == toy.NAME and (run_dir / "toy.txt").is_file()
    assert (run_dir / "trials.h5").is_file() and (run_dir / "scene.xml").is_file()
    # 0.1 N of white force noise on a 4 N rms push over 24 s: the least squares of F = m a + b v + k x
    # is within 1 % on m and k (seen: 0.1 %, 0.01 %); the damping force is ~5 % of the push at the
    # band's top, so b is within 2 % (seen: 0.5 %)
    assert results["rel_err"]["m"] < 0.01 and results["rel_err"]["k"] < 0.01
    assert results["rel_err"]["b"] < 0.02
    proc = _cli("estimate", str(run_dir), "fit.skip_s=2.0")
    assert proc.returncode == 0, proc.stderr
    (re_dir,) = run_dir.glob("reestimate_*")
    again = json.loads((re_dir / "results.json").read_text())
    assert again["skip_s"] == 2.0 and again["rel_err"]["k"] < 0.01  # same bound as above
    assert "k = " in proc.stdout
    proc = _cli("estimate", str(run_dir), "estimator.lowpass_hz=3")
    assert proc.returncode == 2 and "must look like fit.<field>=<value>" in proc.stderr


# refusals in this process (the toy registered by the fixture): a fresh process that registers
# it is checked above and below, and the refusals happen before any run starts
def test_override_of_a_group_the_toy_does_not_read_is_refused(registered, tmp_path, capsys):
    assert main(["run", f"protocol={toy.NAME}", "arm.cocontraction=0.3", f"out={tmp_path / 'r'}"]) == 2
    err = capsys.readouterr().err
    assert f"'arm' is not read by protocol '{toy.NAME}'" in err and "'plant'" in err
    assert not (tmp_path / "r").exists()


def test_effects_it_does_not_simulate_are_refused(registered, tmp_path, capsys):
    assert main(["run", f"protocol={toy.NAME}", "effects=[reflex]", f"out={tmp_path / 'r'}"]) == 2
    assert f"effects ['reflex'] are not simulated by protocol '{toy.NAME}'" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(("delay_s", "verdict"), [(0.0, ["none"]), (0.003, ["channel_delay"])])
def test_diagnose_through_the_generic_core(tmp_path, delay_s, verdict):
    run_dir = tmp_path / "run"
    proc = _cli("run", f"protocol={toy.NAME}", f"push.force_delay_s={delay_s}", f"out={run_dir}")
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "diag"
    proc = _cli("diagnose", f"data={run_dir}", f"protocol={toy.NAME}", f"out={out}")
    assert proc.returncode == 0, proc.stderr
    results = json.loads((out / "results.json").read_text())
    assert results["verdict"] == verdict
    if delay_s:  # the core's fit finds the hidden delay within a third of a sample (seen: 0.1 ms off)
        assert results["ranking"][0]["params"]["channel_delay.delay_s"] == pytest.approx(delay_s, abs=3e-4)
    assert (out / "report.md").read_text().startswith(f"# Toy diagnosis of {run_dir}")
    assert f"verdict {' -> '.join(verdict)}" in proc.stdout
