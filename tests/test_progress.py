"""Progress of long commands: the sink computation reports to, its two displays, ``progress=false``.

The CLI runs are tiny (a conditioning run of 2 windows x 4 trials, a diagnose-benchmark of one
case) with stderr a pipe, as in CI: they log plain lines. No timing is asserted.
"""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from test_resume import _same_run

from armlab import progress
from armlab.cli import main
from armlab.runner.progress import LineSink, display

ROOT = Path(__file__).resolve().parents[1]
TINY = ["scenario.k_values=[1,2]", "scenario.n_trials=4", "output.recording=false", "output.figures=false"]
TIME = r"\d+\.\d s"


def _armlab(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    exe = Path(sys.executable).with_name("armlab")
    return subprocess.run([str(exe), *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=300)


def _progress_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("armlab: ") and "error" not in line]


class FakeClock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


# --- the sink and its line display ---------------------------------------------------------------
def test_computation_without_a_display_reports_to_nothing():
    progress.stage("simulate", 3, "trials")  # no sink set: the default ignores it
    progress.advance(3)
    stream = io.StringIO()
    sink = LineSink(stream, clock=FakeClock())
    with progress.reporting(sink):
        with progress.scope("bias"), progress.scope(""):
            progress.stage("simulate", 2, "trials")
            progress.advance(2)
    progress.stage("estimate")  # the block is over: not the sink's any more
    sink.close(ok=True)
    assert stream.getvalue().splitlines() == [
        "armlab: bias: simulate 2/2 trials, done in 0.0 s",
        "armlab: finished in 0.0 s",
    ]


def test_log_lines_are_throttled_and_estimate_what_is_left():
    clock, stream = FakeClock(), io.StringIO()
    sink = LineSink(stream, prefix="armlab [job 2]", every_s=5.0, clock=clock)
    sink.stage("simulate")  # the edge names the stage; the computation then gives its size
    sink.stage("simulate", 780, "trials")
    for _ in range(12):  # 60 trials a second
        clock.t += 1.0
        sink.advance(60)
    clock.t += 5.0
    sink.advance(59.7)  # a lock-step rollout's fraction: whole trials shown, never rounded up
    clock.t += 0.5
    sink.stage("outputs")  # size unknown
    clock.t += 2.0
    sink.close(ok=True)
    assert stream.getvalue().splitlines() == [
        "armlab [job 2]: simulate 300/780 trials, 5.0 s elapsed, ~8 s left",
        "armlab [job 2]: simulate 600/780 trials, 10.0 s elapsed, ~3 s left",
        "armlab [job 2]: simulate 779/780 trials, 17.0 s elapsed, ~0 s left",
        "armlab [job 2]: simulate 779/780 trials, done in 17.5 s",
        "armlab [job 2]: outputs, done in 2.0 s",
        "armlab [job 2]: finished in 19.5 s",
    ]


def test_a_failed_command_leaves_no_finished_line():
    stream = io.StringIO()
    with pytest.raises(RuntimeError), display(stream=stream):
        progress.stage("simulate", 4, "trials")
        raise RuntimeError("boom")
    assert stream.getvalue() == ""  # its one error line is the command's to print


def test_a_terminal_gets_the_live_display():
    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    screen = Terminal()
    with display(stream=screen):
        progress.stage("simulate", 3, "trials")
        progress.advance(3)
        progress.stage("outputs")
    shown = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", screen.getvalue())
    assert "simulate" in shown and "3/3 trials" in shown and "outputs" in shown
    assert "finished in" not in shown  # the log line is for logs; a terminal sees the rows


def test_display_off_installs_nothing():
    stream = io.StringIO()
    with display(False, stream=stream):
        progress.stage("simulate", 1, "trials")
        progress.advance()
    assert stream.getvalue() == ""


# --- through the command line --------------------------------------------------------------------
@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The same tiny run with progress (stderr a pipe: log lines) and with ``progress=false``."""
    tmp = tmp_path_factory.mktemp("progress")
    shown = _armlab("run", *TINY, f"out={tmp / 'shown'}", cwd=tmp)
    quiet = _armlab("run", *TINY, "progress=false", f"out={tmp / 'quiet'}", cwd=tmp)
    assert shown.returncode == 0 and quiet.returncode == 0, shown.stderr + quiet.stderr
    return tmp, shown, quiet


def test_a_run_off_a_terminal_logs_each_stage_and_a_final_line(runs):
    _, shown, _ = runs
    lines = _progress_lines(shown.stderr)
    ends = [line for line in lines if ", done in " in line or line.startswith("armlab: finished")]
    expected = [
        rf"armlab: simulate 8/8 trials, done in {TIME}",
        rf"armlab: estimate 5/5 windows, done in {TIME}",
        rf"armlab: effective truth: simulate 8/8 trials, done in {TIME}",  # one per (window, direction)
        rf"armlab: effective truth: estimate 5/5 windows, done in {TIME}",
        # the linearisation bias runs beside the estimation, on a thread that reports nothing
        rf"armlab: outputs, done in {TIME}",
        rf"armlab: finished in {TIME}",
    ]
    assert len(ends) == len(expected), ends
    assert all(re.fullmatch(e, s) for e, s in zip(expected, ends, strict=True)), ends
    # lines during a long stage (a loaded machine) have the shape of the module's docstring
    during = re.compile(r"armlab: [a-z :]+ \d+/\d+ [a-z]+, \d+\.\d s elapsed(, ~\d+ s left)?")
    assert all(during.fullmatch(line) for line in lines if line not in ends)
    assert lines[-1] == ends[-1]
    assert "outputs: " in shown.stdout and "armlab: " not in shown.stdout  # the table stays on stdout


def test_progress_false_shows_nothing_and_changes_no_result(runs):
    tmp, shown, quiet = runs
    assert _progress_lines(quiet.stderr) == []
    _same_run(tmp / "shown", tmp / "quiet")  # trials.h5 bit-identical, results.json equal (timing aside)


def test_diagnose_benchmark_logs_its_cases(tmp_path):
    out = tmp_path / "bench"
    args = ["referee.replicates=1", "referee.classes=[none]", "referee.trial_s=10", "referee.jobs=1"]
    proc = _armlab("diagnose-benchmark", *args, f"out={out}", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = _progress_lines(proc.stderr)
    assert re.fullmatch(rf"armlab: diagnose-benchmark 1/1 cases, done in {TIME}", lines[-2])
    assert re.fullmatch(rf"armlab: finished in {TIME}", lines[-1])
    assert (out / "benchmark.json").is_file()


VERBS = ["run", "estimate", "diagnose", "diagnose-benchmark", "fit-joint", "effects"]


@pytest.mark.parametrize("verb", VERBS)
@pytest.mark.parametrize(
    ("args", "shown"),
    [
        (["progress=maybe"], "maybe"),
        (["progress="], ""),
        (["progress=true", "progress=false"], "['true', 'false']"),
    ],
    ids=["maybe", "empty", "twice"],
)
def test_a_bad_progress_value_is_one_line(verb, args, shown, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([verb, *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"armlab: error: progress={shown}:")
    assert "progress=true" in err[0] and "progress=false" in err[0]
    assert list(tmp_path.iterdir()) == []
