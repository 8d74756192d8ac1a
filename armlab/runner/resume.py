"""Run folders that are never overwritten, and ``resume=true`` that finishes interrupted ones.

Hydra's own saving of ``.hydra/`` is switched off (``hydra.output_subdir: null`` in
configs/config.yaml: Hydra 1.3 writes those files before the task runs, so a refused rerun used to
rewrite them). :func:`prepare_run_dir` decides, per run folder and before anything is written:

- new folder: write ``.hydra/config.yaml``, ``hydra.yaml``, ``overrides.yaml`` (new files), run;
- complete (``results.json``): refused, or with ``resume=true`` left untouched (skipped);
- incomplete: refused (naming the command that finishes it), or with ``resume=true`` its partial
  outputs and temporaries are removed, its stored ``.hydra`` files kept (after checking they hold
  this configuration), and it runs again (same config, same seed: the same trials).

:func:`stored_overrides` and :func:`sweep_jobs` let the CLI check a run or sweep folder up front.
"""

from __future__ import annotations

from pathlib import Path

from omegaconf import OmegaConf

from armlab.data.atomic import atomic_path
from armlab.data.rundir import METADATA_DIR, clean_partial, refusal, run_state
from armlab.errors import DataError
from armlab.protocols._files import write_new

__all__ = [
    "given_folder",
    "keep_file",
    "plan_launch",
    "prepare_run_dir",
    "restore_file",
    "stored_overrides",
    "sweep_jobs",
]


def prepare_run_dir(
    folder: Path, *, resume: bool, config_yaml: str, hydra_yaml: str, overrides_yaml: str
) -> bool:
    """Make ``folder`` ready for this run; False when it is complete and ``resume`` skips it.

    Raises:
        DataError: the folder is complete or incomplete and ``resume`` is off, or it holds another
            configuration.
    """
    folder = Path(folder)
    state = run_state(folder)
    if state == "foreign":
        raise refusal(folder, state)
    stored = folder / METADATA_DIR / "config.yaml"
    if state != "new" and stored.is_file() and stored.read_text() != config_yaml:
        raise DataError(
            f"{folder} holds a run of another configuration ({stored}); resume it with the overrides "
            f"in {stored.with_name('overrides.yaml')}, or choose a new output folder"
        )
    if state != "new" and not resume:
        raise refusal(folder, state)
    if state == "complete":
        return False
    if state == "incomplete":
        clean_partial(folder)
    meta = folder / METADATA_DIR
    meta.mkdir(parents=True, exist_ok=True)
    for name, text in (
        ("config.yaml", config_yaml),
        ("hydra.yaml", hydra_yaml),
        ("overrides.yaml", overrides_yaml),
    ):
        if not (meta / name).is_file():  # a resumed run keeps the files it started with
            write_new(meta / name, text)
    return True


def stored_overrides(folder: Path) -> tuple[str, list[str]] | None:
    """The protocol and task overrides a run folder was started with (None: no stored config)."""
    meta = Path(folder) / METADATA_DIR
    if not (meta / "config.yaml").is_file() or not (meta / "overrides.yaml").is_file():
        return None
    cfg = OmegaConf.load(meta / "config.yaml")
    return str(cfg.get("protocol_name")), [str(o) for o in OmegaConf.load(meta / "overrides.yaml")]


#: what a sweep folder holds besides its job folders: Hydra's record of the sweep and submitit's logs
_SWEEP_RECORDS = ("multirun.yaml", ".submitit")


def sweep_jobs(sweep_dir: Path) -> dict[str, list[str]]:
    """The job folders (``hydra.sweep.subdir``: the job number) of a sweep folder by state:
    ``{"complete": [...], "incomplete": [...], "foreign": [...]}``; any entry that is neither a job
    folder nor a sweep record (``multirun.yaml``, ``.submitit``) counts as foreign too."""
    jobs: dict[str, list[str]] = {"complete": [], "incomplete": [], "foreign": []}
    sweep_dir = Path(sweep_dir)
    if not sweep_dir.is_dir():
        return jobs
    for p in sorted(sweep_dir.iterdir()):
        if p.is_dir() and p.name.isdigit():
            state = run_state(p)
        else:
            state = "new" if p.name in _SWEEP_RECORDS else "foreign"
        if state != "new":
            jobs[state].append(p.name)
    return jobs


def given_folder(overrides: list[str], key: str) -> Path | None:
    """The folder given as ``key=<path>`` (None: not given, or an interpolation Hydra resolves)."""
    values = [o.partition("=")[2].strip().strip("'\"") for o in overrides if o.partition("=")[0] == key]
    if not values or not values[-1] or "${" in values[-1]:  # an empty one is refused by compose
        return None
    return Path(values[-1])


def _task_overrides(overrides: list[str]) -> list[str]:
    return [o for o in overrides if not o.startswith(("hydra.", "hydra/", "protocol="))]


def plan_launch(overrides: list[str], *, multirun: bool, resume: bool) -> tuple[list[str], str | None]:
    """Check a run's or sweep's output folder before Hydra starts; returns (overrides, note).

    ``overrides`` are the ones to launch (with ``resume=true`` and none given, those the folder
    was started with); ``note`` is set when there is nothing to run (a complete folder, resumed).

    Raises:
        DataError: a folder that holds results without ``resume=true``; resume without the folder;
            resume with overrides other than the folder's.
    """
    key = "hydra.sweep.dir" if multirun else "hydra.run.dir"
    folder = given_folder(overrides, key)
    if folder is None:
        if resume:
            what = "sweep folder" if multirun else "folder"
            raise DataError(f"resume=true needs the {what} to finish: add out=<{what.replace(' ', '_')}>")
        return overrides, None  # a fresh timestamped folder
    if multirun:
        jobs = sweep_jobs(folder)
        if jobs["foreign"]:  # a job folder that is not a run, or the user's own files
            name = jobs["foreign"][0]
            raise refusal(folder / name if name.isdigit() else folder, "foreign")
        if not resume and (jobs["complete"] or jobs["incomplete"]):
            raise DataError(
                f"sweep folder {folder} already holds jobs (complete: {jobs['complete']}, incomplete: "
                f"{jobs['incomplete']}); armlab never overwrites a run — add resume=true to run only the "
                "missing and incomplete jobs (complete ones are left untouched), or choose a new "
                "out=<folder>"
            )
        stored_file = folder / "multirun.yaml"
        if not resume and stored_file.is_file():  # Hydra would replace the record of that sweep
            raise DataError(
                f"sweep folder {folder} holds the record of another sweep ({stored_file.name}); add "
                "resume=true to finish that sweep, or choose a new out=<folder>"
            )
        stored = None
        if resume and stored_file.is_file():
            cfg = OmegaConf.load(stored_file)
            stored = str(cfg.get("protocol_name")), [str(o) for o in cfg.hydra.overrides.task]
    else:
        state = run_state(folder)
        if state == "foreign" or (state != "new" and not resume):
            raise refusal(folder, state)
        if state == "complete":
            return overrides, f"{folder} is complete (results.json); left untouched"
        stored = stored_overrides(folder) if resume else None
    if stored is None:
        return overrides, None
    protocol, task = stored
    given = _task_overrides(overrides)
    named = [o.partition("=")[2] for o in overrides if o.startswith("protocol=")]
    if not given and not named:  # resume with the folder's own overrides
        return [f"protocol={protocol}", *task, *overrides], None
    if sorted(given) != sorted(task) or (named and named[-1] != protocol):
        raise DataError(
            f"{folder} was started as protocol={protocol} with overrides {task}; resume it with the "
            f"same ones (or none: they are reused), not protocol={named[-1] if named else protocol} {given}"
        )
    return overrides, None


def keep_file(path: Path):
    """The bytes of ``path`` now (None: absent), to put back with :func:`restore_file`."""
    return Path(path).read_bytes() if Path(path).is_file() else None


def restore_file(path: Path, content: bytes | None) -> None:
    """Put back what :func:`keep_file` read if something rewrote it (Hydra rewrites ``multirun.yaml``
    of a resumed sweep; the sweep keeps the record it started with). Atomic replace."""
    path = Path(path)
    if content is None or not path.is_file() or path.read_bytes() == content:
        return
    with atomic_path(path, overwrite=True) as tmp:
        tmp.write_bytes(content)
