"""The one output convention (issue 21): ``out=<dir>`` for every verb, Hydra's spellings refused."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from hydra.core.override_parser.overrides_parser import OverridesParser

from armlab.data.outdir import default_out, hydra_out, take_out
from armlab.errors import ConfigError


def test_take_out_splits_the_folder_from_the_other_arguments():
    assert take_out(["seed=3", "out=a/b", "frf.x=1"], "run") == (Path("a/b"), ["seed=3", "frf.x=1"])
    assert take_out(["seed=3"], "run") == (None, ["seed=3"])
    assert take_out(["out='my runs/one'"], "run") == (Path("my runs/one"), [])


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["hydra.run.dir=r"], ["out=r instead of hydra.run.dir", "every verb"]),
        (["hydra.sweep.dir=s"], ["out=s instead of hydra.sweep.dir", "<dir>/<job number>"]),
        (["~hydra.run.dir=r"], ["instead of hydra.run.dir"]),
        (["out=a", "out=b"], ["out= is given 2 times", "once"]),
        (["out="], ["armlab diagnose out=", "needs a folder"]),
        (["out=''"], ["needs a folder"]),
    ],
)
def test_take_out_refuses_old_spellings_repeats_and_empty_folders(args, words):
    with pytest.raises(ConfigError) as err:
        take_out(args, "diagnose")
    assert all(w in str(err.value) for w in words), str(err.value)


@pytest.mark.parametrize(
    "folder",
    # 1e3, true, null, 123: Hydra reads them unquoted as a float, a bool, None, an int
    ["outputs/run_1", "/tmp/a b", "sweeps/a,b", "x[1]", "runs/${now:%H}", "é/ü", "a=b"]
    + ["1e3", "true", "null", "123"],
)
@pytest.mark.parametrize("multirun", [False, True])
def test_hydra_reads_the_override_as_the_literal_folder(folder, multirun):
    item = hydra_out(Path(folder), multirun=multirun)
    (parsed,) = OverridesParser.create().parse_overrides([item])
    assert parsed.key_or_group == ("hydra.sweep.dir" if multirun else "hydra.run.dir")
    assert not parsed.is_sweep_override()  # a comma in a folder name is not a sweep
    assert parsed.value() == folder


def test_take_out_expands_the_home_folder():
    assert take_out(["out=~/runs"], "run")[0] == Path.home() / "runs"


def test_hydra_out_refuses_what_hydra_cannot_quote():
    with pytest.raises(ConfigError, match="quote or backslash"):
        hydra_out(Path("it's"), multirun=False)


def test_default_out_is_a_new_timestamped_folder_under_the_working_folder():
    a = default_out("diagnose")
    time.sleep(0.002)  # 2 ms apart: the name resolves microseconds, so the folders differ
    b = default_out("diagnose")
    assert a.parts[:2] == ("outputs", "diagnose") and not a.is_absolute()
    assert a != b


def test_the_resume_command_keeps_a_folder_with_spaces_one_shell_word():
    import shlex

    from armlab.data.rundir import resume_command

    assert resume_command("/tmp/plain") == "armlab run resume=true out=/tmp/plain"  # unquoted as before
    assert shlex.split(resume_command("/tmp/my run")) == ["armlab", "run", "resume=true", "out=/tmp/my run"]
