"""Never-overwrite, atomic outputs, incomplete folders, ``resume=true``, workers that stop with their parent.

Most runs use the toy protocol (tests/toy_protocol.py: ~2 s a run), launched as a user's plug-in
would be (``python tests/toy_protocol.py run ...``); the joblib sweep uses a small conditioning
run because loky workers import armlab afresh and know only the registered protocols.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import toy_protocol as toy

from armlab.cli import main
from armlab.data import read_trials
from armlab.data.atomic import atomic_path, is_temporary
from armlab.data.rundir import clean_partial, partial_files, require_complete, run_state
from armlab.errors import DataError
from armlab.protocols import registry
from armlab.runner.interrupt import Interrupted, stop_with_parent

ROOT = Path(__file__).resolve().parents[1]
TOY = [f"protocol={toy.NAME}", "seed=3"]
# a small conditioning run: two windows, 7 trials each, no figures or recording (as tests/test_cli.py)
SMALL = ["scenario.k_values=[1,26]", "scenario.n_trials=7", "output.recording=false", "output.figures=false"]


def _toy_cli(*args: str, wait: bool = True, cwd: Path = ROOT):
    cmd = [sys.executable, str(Path(toy.__file__)), *args]
    if not wait:
        return subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=300)


def _armlab(*args: str, wait: bool = True):
    cmd = [str(Path(sys.executable).with_name("armlab")), *args]
    if not wait:
        return subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _temporaries(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*") if is_temporary(p)]


def _trial_data(path: Path) -> dict[str, bytes]:
    """Every dataset of a trial file as raw bytes (strings as their text): bit-identical comparison."""
    out: dict[str, bytes] = {}

    def visit(name: str, obj) -> None:
        if isinstance(obj, h5py.Dataset):
            a = np.asarray(obj[()])
            out[name] = repr(a.tolist()).encode() if a.dtype == object else a.tobytes()

    with h5py.File(path) as f:
        f.visititems(visit)
    return out


def _results(folder: Path) -> dict:
    """results.json without wall-clock timings and output paths (they name the folder)."""
    r = json.loads((folder / "results.json").read_text())
    return {k: v for k, v in r.items() if k not in ("timing", "files")}


def _same_run(a: Path, b: Path) -> None:
    assert _trial_data(a / "trials.h5") == _trial_data(b / "trials.h5")
    assert _results(a) == _results(b)


def _wait_for(path: Path, proc: subprocess.Popen, timeout_s: float = 120.0) -> None:
    end = time.monotonic() + timeout_s
    while not path.exists():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < end, f"{path} never appeared"
        time.sleep(0.05)


@pytest.fixture(scope="module")
def toy_run(tmp_path_factory) -> Path:
    """One complete, uninterrupted toy run (seed 3): the reference of the resumed ones."""
    run_dir = tmp_path_factory.mktemp("resume") / "ref"
    proc = _toy_cli("run", *TOY, f"out={run_dir}")
    assert proc.returncode == 0, proc.stderr
    return run_dir


@pytest.fixture
def registered():
    registry.register(toy.PROTOCOL)
    yield
    registry.unregister(toy.NAME)


@pytest.fixture
def incomplete(toy_run, tmp_path) -> Path:
    """A copy of the reference run as an interrupted run leaves it: no results.json, a temporary."""
    run_dir = tmp_path / "run"
    shutil.copytree(toy_run, run_dir)
    (run_dir / "results.json").unlink()
    (run_dir / ".trials.h5.x1y2z3.tmp").write_bytes(b"half a file")
    return run_dir


# --- never overwrite -----------------------------------------------------------------------------
def test_refused_rerun_leaves_every_file_byte_identical(toy_run, tmp_path):
    run_dir = tmp_path / "run"
    shutil.copytree(toy_run, run_dir)
    before = _snapshot(run_dir)
    assert {".hydra/config.yaml", ".hydra/hydra.yaml", ".hydra/overrides.yaml"} <= set(before)
    proc = _toy_cli("run", f"protocol={toy.NAME}", "seed=5", f"out={run_dir}")
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "already holds results.json" in proc.stderr
    assert "resume=true" in proc.stderr and "Traceback" not in proc.stderr
    assert _snapshot(run_dir) == before  # .hydra/*.yaml included: it still says seed 3


def test_resume_leaves_a_complete_run_untouched(toy_run, tmp_path, registered, capsys):
    run_dir = tmp_path / "run"
    shutil.copytree(toy_run, run_dir)
    before = _snapshot(run_dir)
    assert main(["run", "resume=true", f"out={run_dir}"]) == 0
    assert "left untouched" in capsys.readouterr().out
    assert _snapshot(run_dir) == before


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["resume=yes", "out=/nonexistent"], "resume=true or resume=false"),
        (["resume=true", "resume=false", "out=/nonexistent"], "give it once"),
        (["resume=true", *TOY], "resume=true needs the folder to finish: add out=<folder>"),
        (["--multirun", "resume=true", "seed=0,1"], "add out=<sweep_folder>"),
    ],
)
def test_bad_resume_arguments_are_refused(args, message, registered, capsys):
    assert main(["run", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_resume_with_other_overrides_than_the_folders_is_refused(incomplete, registered, capsys):
    before = _snapshot(incomplete)
    assert main(["run", "resume=true", f"protocol={toy.NAME}", "seed=4", f"out={incomplete}"]) == 2
    err = capsys.readouterr().err
    assert "was started as protocol=toy_msd with overrides ['seed=3']" in err
    assert _snapshot(incomplete) == before


# --- incomplete folders: one rule, every verb ----------------------------------------------------
@pytest.mark.parametrize(
    "verb",
    [
        ["run", f"protocol={toy.NAME}", "seed=3", "out={d}"],
        ["estimate", "{d}"],
        ["view", "{d}"],
        ["diagnose", "data={d}", f"protocol={toy.NAME}", "out={d}_diag"],
        ["diagnose", "data={d}/trials.h5", f"protocol={toy.NAME}", "out={d}_diag"],
    ],
    ids=["run", "estimate", "view", "diagnose-folder", "diagnose-file"],
)
def test_every_verb_recognises_an_incomplete_folder(verb, incomplete, registered, capsys):
    before = _snapshot(incomplete)
    assert main([a.format(d=incomplete) for a in verb]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is an incomplete run (no results.json" in err
    assert f"armlab run resume=true out={incomplete}" in err
    assert _snapshot(incomplete) == before and not Path(f"{incomplete}_diag").exists()


@pytest.mark.parametrize(
    ("files", "argv", "words"),
    [
        ({"notes.txt": "mine"}, [], "is not an armlab run folder"),
        ({"notes.txt": "mine", "multirun.yaml": "mine"}, ["resume=true"], "is not an armlab run folder"),
        ({"multirun.yaml": "hydra: {}"}, [], "holds the record of another sweep"),
    ],
    ids=["own-file", "own-file-resume", "old-sweep-record"],
)
def test_a_sweep_never_writes_into_a_folder_of_other_files(files, argv, words, tmp_path, capsys):
    """The sweep folder itself, not only its job folders: the user's files and another sweep's
    multirun.yaml (Hydra would replace it) are refused before anything is written."""
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    before = _snapshot(tmp_path)
    assert main(["run", "--multirun", *argv, "seed=0,1", f"out={tmp_path}"]) == 2
    err = capsys.readouterr().err
    assert err.count("armlab: error:") == 1 and words in err
    assert _snapshot(tmp_path) == before


def test_partial_files_keep_the_metadata_and_log(incomplete):
    assert run_state(incomplete) == "incomplete"
    names = {p.name for p in partial_files(incomplete)}
    assert names == {"trials.h5", "scene.xml", "toy.txt", ".trials.h5.x1y2z3.tmp"}
    clean_partial(incomplete)
    assert sorted(p.name for p in incomplete.iterdir()) == [".hydra", "cli.log"]
    with pytest.raises(DataError, match="incomplete run"):
        require_complete(incomplete)
    (incomplete / "results.json").write_text("{}")
    with pytest.raises(DataError, match="a complete run is never touched"):
        clean_partial(incomplete)


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "resume=true", "out={d}"],
        ["run", "out={d}"],
        ["run", "--multirun", "resume=true", "seed=0,1", "out={p}"],
    ],
    ids=["resume", "run", "sweep-resume"],
)
def test_a_folder_of_the_users_own_files_is_never_written_into_nor_cleaned(argv, tmp_path, capsys):
    """A non-empty folder that is not a run folder (no .hydra/config.yaml, no scene.xml) is refused,
    resume included: resume removes partial outputs, and these are not armlab's to remove."""
    own = tmp_path / "0"  # also a sweep's job 0
    (own / "sub").mkdir(parents=True)
    (own / "notes.csv").write_text("t,x\n0,1\n")
    (own / "sub" / "a.txt").write_text("mine")
    before = _snapshot(tmp_path)
    assert run_state(own) == "foreign"
    assert main([a.format(d=own, p=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("armlab: error:") == 1 and "is not an armlab run folder" in err
    assert _snapshot(tmp_path) == before
    with pytest.raises(DataError, match="not an armlab run folder"):
        clean_partial(own)
    assert _snapshot(tmp_path) == before


# --- resume ----------------------------------------------------------------------------------------
def test_resume_finishes_an_incomplete_run_identically(toy_run, incomplete):
    hydra_before = {k: v for k, v in _snapshot(incomplete).items() if k.startswith(".hydra")}
    proc = _toy_cli("run", "resume=true", f"out={incomplete}")  # its own overrides
    assert proc.returncode == 0, proc.stderr
    _same_run(toy_run, incomplete)
    assert not _temporaries(incomplete)
    assert {k: v for k, v in _snapshot(incomplete).items() if k.startswith(".hydra")} == hydra_before


def test_sigterm_mid_run_leaves_no_temporary_and_resume_finishes_it(toy_run, tmp_path):
    run_dir = tmp_path / "run"
    proc = _toy_cli("run", *TOY, f"out={run_dir}", wait=False)
    _wait_for(run_dir / ".hydra" / "overrides.yaml", proc)  # written just before simulating
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "interrupted (SIGTERM)" in err and "Traceback" not in err and err.count("\n") == 1
    assert f"`armlab run resume=true out={run_dir}`" in err
    assert run_state(run_dir) == "incomplete" and not _temporaries(run_dir)
    done = _toy_cli("run", "resume=true", f"out={run_dir}")
    assert done.returncode == 0, done.stderr
    _same_run(toy_run, run_dir)


def test_interrupted_sweep_resumes_to_the_uninterrupted_results(tmp_path):
    """The issue's case: a 3-job multirun stopped by SIGTERM mid-job, then resumed."""
    sweep = ["--multirun", f"protocol={toy.NAME}", "seed=0,1,2"]
    ref = tmp_path / "ref"
    proc = _toy_cli("run", *sweep, f"out={ref}")
    assert proc.returncode == 0, proc.stderr
    run = tmp_path / "run"
    proc = _toy_cli("run", *sweep, f"out={run}", wait=False)
    _wait_for(run / "1" / ".hydra" / "overrides.yaml", proc)  # job 0 done, job 1 simulating
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM
    assert f"`armlab run --multirun resume=true out={run} <same sweep>`" in err
    assert run_state(run / "0") == "complete" and run_state(run / "1") == "incomplete"
    assert not (run / "2").exists() and not _temporaries(run)
    finished = _snapshot(run / "0")
    sweep_record = (run / "multirun.yaml").read_bytes()
    # without resume=true the whole sweep is refused up front, naming its jobs; nothing changes
    refused = _toy_cli("run", *sweep, f"out={run}")
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1
    assert "complete: ['0'], incomplete: ['1']" in refused.stderr and "resume=true" in refused.stderr
    resumed = _toy_cli("run", "resume=true", *sweep, f"out={run}")
    assert resumed.returncode == 0, resumed.stderr
    assert f"{run / '0'} is complete (results.json); left untouched" in resumed.stdout
    assert _snapshot(run / "0") == finished and (run / "multirun.yaml").read_bytes() == sweep_record
    for job in ("0", "1", "2"):
        _same_run(ref / job, run / job)
    assert not _temporaries(run)


def test_an_interrupted_sweep_without_out_names_its_default_folder_as_one_shell_word(tmp_path):
    # no out=: Hydra's default folder (outputs/multirun/<protocol>/<time> under the working
    # folder, here a folder with a space) is the one the message tells to resume, quoted
    work = tmp_path / "my work"
    work.mkdir()
    proc = _toy_cli("run", "--multirun", f"protocol={toy.NAME}", "seed=0,1,2", wait=False, cwd=work)
    end = time.monotonic() + 120
    while not list(work.glob("outputs/multirun/*/*/1/.hydra/overrides.yaml")):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < end, "job 1 never started"
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM
    (sweep,) = {p.parents[2] for p in work.glob("outputs/multirun/*/*/1/.hydra/overrides.yaml")}
    command = err.split("`")[1]
    words = ["armlab", "run", "--multirun", "resume=true", f"out={sweep}", "<same", "sweep>"]
    assert shlex.split(command) == words


# slow (make test-all, beside the Ray and submitit multiruns): ~32 s of CI's 5-minute budget for the
# launcher's processes; the resume logic itself is checked in CI by the serial sweep above
@pytest.mark.slow
def test_joblib_sweep_interrupted_resumes_bit_identical_to_a_serial_one(tmp_path):
    """Same seed, serial or joblib, interrupted or not: bit-identical trials (~20 s)."""
    sweep = ["--multirun", "seed=0,1,2", *SMALL]
    serial = tmp_path / "serial"
    assert _armlab("run", *sweep, f"out={serial}").returncode == 0
    run = tmp_path / "joblib"
    proc = _armlab("run", *sweep, "hydra/launcher=joblib", f"out={run}", wait=False)
    _wait_for(run / "1" / ".hydra" / "overrides.yaml", proc)
    proc.send_signal(signal.SIGTERM)
    proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM
    assert run_state(run / "1") == "incomplete"
    # no sweep given: the one stored in multirun.yaml is reused
    resumed = _armlab("run", "--multirun", "resume=true", "hydra/launcher=joblib", f"out={run}")
    assert resumed.returncode == 0, resumed.stderr
    # each joblib job logs its own progress lines, named by its number (tests/test_progress.py)
    assert re.search(r"^armlab \[job [12]\]: simulate 14/14 trials, done in ", resumed.stderr, re.M)
    for job in ("0", "1", "2"):
        _same_run(serial / job, run / job)
    assert not _temporaries(run)


# --- atomic outputs ------------------------------------------------------------------------------
def test_an_interrupted_writer_leaves_neither_temporary_nor_final_file(tmp_path):
    path = tmp_path / "trials.h5"
    with pytest.raises(Interrupted), atomic_path(path) as tmp:
        tmp.write_bytes(b"half")
        raise Interrupted(signal.SIGTERM)
    assert list(tmp_path.iterdir()) == []
    with atomic_path(path) as tmp:
        tmp.write_bytes(b"whole")
    assert path.read_bytes() == b"whole" and list(tmp_path.iterdir()) == [path]
    with pytest.raises(DataError, match="never overwrites"), atomic_path(path):
        pass
    assert path.read_bytes() == b"whole" and list(tmp_path.iterdir()) == [path]


def test_an_interrupted_recording_is_not_left_under_its_name(tmp_path):
    import rerun as rr

    from armlab.viz._paths import recording

    path = tmp_path / "trials.rrd"
    with pytest.raises(Interrupted), recording(path, "armlab") as rec:
        rec.log("x", rr.Scalars(1.0))
        raise Interrupted(signal.SIGTERM)
    assert list(tmp_path.iterdir()) == []
    with recording(path, "armlab") as rec:
        rec.log("x", rr.Scalars(1.0))
    assert path.stat().st_size > 0 and list(tmp_path.iterdir()) == [path]


# --- re-estimation records its overrides ---------------------------------------------------------
def test_estimate_folder_records_its_overrides(toy_run, tmp_path, registered, capsys):
    run_dir = tmp_path / "run"
    shutil.copytree(toy_run, run_dir)
    assert main(["estimate", str(run_dir), "fit.skip_s=2.0"]) == 0
    (out,) = run_dir.glob("reestimate_*")
    assert (out / "overrides.yaml").read_text() == "- fit.skip_s=2.0\n"
    stored = read_trials(run_dir / "trials.h5").attrs["config_yaml"]
    assert (out / "config.yaml").read_text().strip() == stored.strip()
    results = json.loads((out / "results.json").read_text())
    assert results["reestimate"] == {
        "run": str(run_dir),
        "trials": str(run_dir / "trials.h5"),
        "overrides": ["fit.skip_s=2.0"],
    }
    assert results["skip_s"] == 2.0


# --- workers stop with their parent --------------------------------------------------------------
_WORKER = """
import os, sys, time
from armlab.runner.interrupt import handle_termination, stop_with_parent
stop_with_parent(int(sys.argv[1]))
print("ready", flush=True)
try:
    with handle_termination():
        while True:
            time.sleep(0.05)
except KeyboardInterrupt as exc:
    open(sys.argv[2], "w").write(type(exc).__name__)
"""
_PARENT = """
import subprocess, sys, time
child = subprocess.Popen([sys.executable, "-c", sys.argv[1], str(__import__("os").getpid()), sys.argv[2]],
                         stdout=subprocess.PIPE, text=True)
child.stdout.readline()
print(child.pid, flush=True)
time.sleep(600)
"""


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie waiting for its new parent to reap it has stopped)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_a_worker_stops_when_its_parent_is_killed(tmp_path):
    marker = tmp_path / "stopped"
    parent = subprocess.Popen(
        [sys.executable, "-c", _PARENT, _WORKER, str(marker)], stdout=subprocess.PIPE, text=True
    )
    child_pid = int(parent.stdout.readline())
    parent.kill()  # SIGKILL: the parent cannot tell anyone
    parent.wait()
    end = time.monotonic() + 30
    while not marker.exists() and time.monotonic() < end:
        time.sleep(0.05)
    assert marker.read_text() == "Interrupted"  # the worker ran its cleanup path and stopped
    end = time.monotonic() + 30
    while _alive(child_pid) and time.monotonic() < end:
        time.sleep(0.05)
    if _alive(child_pid):
        os.kill(child_pid, signal.SIGKILL)
        pytest.fail("the worker outlived its parent")


def test_signal_handlers_are_restored_after_the_block():
    from armlab.runner.interrupt import handle_termination

    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Interrupted, match="SIGTERM"), handle_termination():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler raises at once; never reached
    assert signal.getsignal(signal.SIGTERM) is before


def test_stop_with_parent_does_nothing_in_the_parent_itself():
    import threading

    stop_with_parent(os.getpid())
    assert not any(t.name == "armlab-parent-watcher" for t in threading.enumerate())


def test_the_python_api_refuses_an_unfinished_folder_before_simulating(incomplete, registered, monkeypatch):
    from armlab.cli import compose
    from armlab.runner import run

    _, cfg = compose(TOY)
    monkeypatch.setattr(run, "_run", lambda *a: pytest.fail("simulated before refusing"))
    with pytest.raises(DataError, match=r"holds outputs of an unfinished run \(.*trials\.h5.*resume=true"):
        run.run_protocol(cfg, incomplete)


def test_measured_trial_files_are_not_run_folders(tmp_path):
    (tmp_path / "trials.h5").write_bytes(b"")  # real data converted to the trial format: no run
    require_complete(tmp_path)
    require_complete(tmp_path / "trials.h5")
    (tmp_path / "scene.xml").write_text("<mujoco/>")  # armlab run wrote this one
    with pytest.raises(DataError, match="incomplete run"):
        require_complete(tmp_path / "trials.h5")


def test_a_sweep_combination_checked_only_in_its_job_is_refused_there(tmp_path):
    """Up front each sweep value is checked with the others at their first value; the job checks
    its own combination: (fs 400 Hz, low-pass 200 Hz) is the 4th job and is refused before it
    writes anything (its folder holds only Hydra's log)."""
    sweep = tmp_path / "sw"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "armlab.cli",
            "run",
            "-m",
            "sensors.fs_hz=1000,400",
            "estimator.lowpass_hz=30,200",
            "scenario.k_values=[26]",
            "scenario.n_trials=2",
            "output.recording=false",
            "output.figures=false",
            "output.print_table=false",
            f"out={sweep}",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "estimator.lowpass_hz=200 Hz is at or above the Nyquist frequency 200 Hz" in proc.stderr
    assert all((sweep / j / "results.json").is_file() for j in ("0", "1", "2"))
    assert sorted(p.name for p in (sweep / "3").iterdir()) == ["cli.log"]


def test_sigterm_stops_any_verb_with_its_exit_status_and_no_temporary(tmp_path):
    """Not only `run`: a diagnosis stopped by SIGTERM runs its writers' cleanup (exit 143, one
    line, no .tmp left), instead of dying where it stood."""
    from armlab.data.reklab import DEFAULT_REKLAB_ROOT

    if not DEFAULT_REKLAB_ROOT.is_dir():
        pytest.skip(f"the REKLAB recordings are not at {DEFAULT_REKLAB_ROOT}")
    out = tmp_path / "diag"
    cmd = [
        sys.executable,
        "-m",
        "armlab.cli",
        "diagnose",
        f"data={DEFAULT_REKLAB_ROOT}",
        "protocol=joint_1dof",
    ]
    proc = subprocess.Popen([*cmd, f"out={out}"], stderr=subprocess.PIPE, text=True)
    time.sleep(6.0)  # past the imports, inside the diagnosis (it takes ~1 min)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "Traceback" not in err and "armlab: interrupted (SIGTERM)" in err
    assert not (out.exists() and _temporaries(out))
