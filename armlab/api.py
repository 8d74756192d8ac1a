"""armlab from Python (a notebook, a script): run a protocol, load a run, diagnose data.

    import armlab

    run = armlab.run("conditioning_window", ["seed=3", "scenario.k_values=[1,26]"])
    run.results["criteria"]            # the same dict as the run folder's results.json
    run.trials().channels["ft_force"]  # the trial data (trials.h5), read when asked for
    again = armlab.load_run(run.dir)   # any complete run folder, made here or by `armlab run`
    report = armlab.diagnose("../shared/data/reklab_ankle", "joint_1dof")

Each call goes through the same checks and writers as the command line: the overrides are
validated before anything is simulated (one :class:`~armlab.errors.ConfigError` naming the valid
choices), the run folder gets the same files as ``armlab run`` makes (``.hydra/config.yaml``,
``overrides.yaml``, ``results.json`` written last, never overwritten), so ``armlab estimate``,
``armlab view`` and ``armlab run resume=true out=<dir>`` work on it. ``out=`` names the output
folder as it does for every verb (armlab.data.outdir); without it, ``outputs/<protocol>/<time>``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["RunResult", "diagnose", "load_run", "run"]

#: what a run made from Python records as its Hydra settings (it was launched without Hydra)
_NO_HYDRA = "# made by armlab.run (the Python API): no Hydra launch, no Hydra settings\n"


@dataclass(frozen=True)
class RunResult:
    """A complete run folder and its results.

    Attributes:
        dir: the run folder.
        protocol: the protocol that ran.
        results: the contents of ``results.json`` (docs/results_schema.md).
        config: the composed configuration (``.hydra/config.yaml``; empty if the folder has none).
    """

    dir: Path
    protocol: str
    results: dict[str, Any]
    config: dict[str, Any]

    def trials(self):
        """The run's trial data (:class:`armlab.data.trial.TrialSet`, read from ``trials.h5``)."""
        from armlab.data.h5io import read_trials

        return read_trials(self.dir / "trials.h5")

    def table(self) -> str:
        """The results as text, as ``armlab run`` prints them."""
        from armlab.runner.run import format_table

        return format_table(self.results)


def run(
    protocol: str | None = None,
    overrides: Sequence[str] = (),
    *,
    out: str | Path | None = None,
) -> RunResult:
    """Simulate and estimate one protocol; the outputs go to a new run folder.

    Args:
        protocol: a registered protocol (``armlab --help`` lists them); None: the default one.
        overrides: ``<group>.<field>=<value>`` items, as on the command line (``seed=3``).
        out: the run folder (must be new or empty); None: ``outputs/<protocol>/<time>`` under the
            working folder, as ``armlab run`` names it.

    Raises:
        ConfigError: a bad protocol or override (before anything is written).
        DataError: ``out`` already holds a run or other files.
        SimulationError: a trial became unstable (named with its time and quantity).
    """
    from omegaconf import OmegaConf

    from armlab.data.outdir import default_out, take_out
    from armlab.errors import ConfigError
    from armlab.protocols.compose import check_effects, compose, split_protocol
    from armlab.runner.resume import prepare_run_dir
    from armlab.runner.run import run_protocol

    given, overrides = take_out(list(overrides), "run")  # out= in the list as on the command line;
    if given is not None and out is not None:  # hydra.run.dir= refused, naming out= (armlab.data.outdir)
        raise ConfigError(f"the run folder is given twice (out={out} and out={given} in overrides)")
    out = given if out is None else out

    items = [*([f"protocol={protocol}"] if protocol else []), *overrides]
    cfg, exp = compose(items)
    spec, task = split_protocol(items)
    check_effects(spec, exp)
    out = default_out(spec.name) if out is None else Path(out)  # as `armlab run` names it
    config_yaml = OmegaConf.to_yaml(cfg)
    prepare_run_dir(
        out,
        resume=False,
        config_yaml=config_yaml,
        hydra_yaml=_NO_HYDRA,
        overrides_yaml=OmegaConf.to_yaml(OmegaConf.create(list(task))),
    )
    results = run_protocol(exp, out, config_yaml)
    return RunResult(dir=out, protocol=spec.name, results=results, config=_container(cfg))


def load_run(folder: str | Path) -> RunResult:
    """A complete run folder (made by :func:`run` or ``armlab run``).

    Raises:
        DataError: the folder is not a run folder, or its run did not finish (the message names the
            command that finishes it).
    """
    import json

    from omegaconf import OmegaConf

    from armlab.data.rundir import MARKER, METADATA_DIR, require_complete
    from armlab.errors import DataError

    folder = Path(folder)
    require_complete(folder)
    if not (folder / MARKER).is_file():
        raise DataError(f"{folder} holds no {MARKER}; give a run folder made by `armlab run` or armlab.run")
    try:
        results = json.loads((folder / MARKER).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataError(f"{folder / MARKER} cannot be read ({exc}); it is damaged") from None
    stored = folder / METADATA_DIR / "config.yaml"
    config = _container(OmegaConf.load(stored)) if stored.is_file() else {}
    protocol = str(results.get("protocol") or config.get("protocol_name") or "")
    return RunResult(dir=folder, protocol=protocol, results=results, config=config)


def diagnose(
    data: str | Path,
    protocol: str,
    overrides: Sequence[str] = (),
    *,
    out: str | Path | None = None,
    units: str | None = None,
    figures: bool = True,
) -> dict[str, Any]:
    """Where the sim-to-real gap of ``data`` lies, which effect explains it, how far it shrinks.

    Args:
        data: a trial file or a folder of them (``armlab diagnose data=...``).
        protocol: a protocol that can diagnose (``armlab --help``).
        overrides: ``diagnosis.<field>=<value>`` items.
        out: the new output folder; None: ``outputs/diagnose/<time>`` as ``armlab diagnose`` names it.
        units: the units of imported joint data (``"deg"``, ``"Nmm"``, ``"deg,Nmm"``; docs/data_import.md).
        figures: draw the report's figures.

    Returns:
        The diagnosis results (also written to ``<out>/results.json`` with ``report.md``), with
        ``"dir"`` set to the output folder.
    """
    from armlab.data.outdir import default_out
    from armlab.runner.diagnose import run_diagnosis

    folder = Path(out) if out is not None else default_out("diagnose")
    folder, results = run_diagnosis(
        Path(data), protocol, list(overrides), folder, figures=figures, units=units
    )
    return {**results, "dir": folder}


def _container(cfg) -> dict[str, Any]:
    from omegaconf import OmegaConf

    return OmegaConf.to_container(cfg, resolve=True)
