"""The edge of ``armlab diagnose`` and ``armlab diagnose-benchmark``: files in, files out.

``run_diagnosis`` reads measured trials, runs the protocol's diagnosis hooks (from the registry) and
writes ``results.json``, ``report.md``, the figures and ``diagnosis.rrd`` into a new folder.
``run_benchmark`` makes the referee's pseudo-real datasets, diagnoses each from its files alone
(in parallel through joblib, the launcher Hydra's joblib plugin also uses) and writes the scores.
Nothing already written is overwritten: an existing non-empty output folder is an error.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from armlab import progress
from armlab.config.diagnosis import REFEREE_SHARED_FIELDS, DiagnosisConfig, RefereeConfig
from armlab.config.store import apply_overrides
from armlab.data.rundir import require_complete
from armlab.errors import ConfigError, DataError
from armlab.protocols import registry
from armlab.protocols._files import check_new_dir, new_dir, write_json, write_new
from armlab.runner.memory import small_pages

__all__ = [
    "run_benchmark",
    "run_diagnosis",
    "run_diagnoser",
]


@small_pages()  # no page-fault stalls in its large arrays (armlab.runner.memory)
def run_diagnoser(
    data: Path, protocol: str, cfg: DiagnosisConfig, units: str | None = None
) -> tuple[dict, dict]:
    """Diagnose the trial files at ``data`` with a protocol's hooks (no output files): (results, series).

    ``units``: the data's units as the user states them (``units=`` of ``armlab diagnose``); only
    a protocol whose hooks declare ``takes_units`` reads them, any other refuses them.
    """
    hooks = registry.get(protocol, need="diagnose").diagnosis
    if units is None:
        loaded = hooks.load(Path(data), cfg)
    elif hooks.takes_units:
        loaded = hooks.load(Path(data), cfg, units=units)
    else:
        raise ConfigError(
            f"units={units}: protocol {protocol!r} reads files that carry their units (its trial files); "
            "units= applies to joint recordings (CSV or .mat) of protocols "
            f"{[n for n in registry.names('diagnose') if registry.get(n).diagnosis.takes_units]}"
        )
    results, series = hooks.diagnose(loaded, cfg)
    results["data"] = str(data)
    return results, series


@small_pages()
def run_diagnosis(
    data: Path,
    protocol: str,
    overrides: list[str] | None,
    out_dir: Path,
    *,
    figures: bool = True,
    units: str | None = None,
) -> tuple[Path, dict]:
    """Diagnose and write ``results.json``, ``report.md``, figures and ``diagnosis.rrd``.

    ``units``: see :func:`run_diagnoser`. A non-empty ``out_dir`` is refused before the diagnosis.
    """
    hooks = registry.get(protocol, need="diagnose").diagnosis
    cfg = apply_overrides(DiagnosisConfig(), "diagnosis", overrides)
    if not Path(data).exists():
        raise DataError(f"data {str(data)!r} does not exist; give a trial file or a folder of them")
    require_complete(Path(data))  # a run folder (or its trials.h5) of a run that did not finish
    check_new_dir(out_dir)
    t0 = time.perf_counter()
    progress.stage("diagnose")  # its steps, where the protocol reports them, follow
    results, series = run_diagnoser(Path(data), protocol, cfg, units)
    results["timing_s"] = {"diagnosis": time.perf_counter() - t0}
    out = new_dir(out_dir)
    names: list[str] = []
    if figures:
        progress.stage("figures and recording")
        from armlab import viz  # figures and recordings at the edge only

        names = [p.name for p in hooks.figures(viz, series, results, out)]
        hooks.recording(viz, series, out / "diagnosis.rrd")
    write_json(out / "results.json", results)
    write_new(out / "report.md", hooks.report(results, data_path=str(data), figures=names))
    return out, results


def _one_case(cls: str, rep: int, ref: RefereeConfig, diag_cfg: DiagnosisConfig, root: Path) -> dict:
    # the benchmark reports whole cases; a case's own stages (run in this process with jobs=1)
    # would replace that stage on the display
    with progress.reporting(progress.NULL_SINK):
        return _case(cls, rep, ref, diag_cfg, root)


def _case(cls: str, rep: int, ref: RefereeConfig, diag_cfg: DiagnosisConfig, root: Path) -> dict:
    from armlab.diagnosis.scoring import expected_verdict, score_case

    referee = registry.get(ref.protocol, need="referee").diagnosis.referee_for(ref.generator)
    folder = root / "datasets" / f"{cls.replace(':', '-').replace('+', '-')}_{rep:02d}"
    ds = referee.make_dataset(cls, rep, ref, diag_cfg, folder / "trials")
    write_json(folder / "truth.json", ds.truth)
    excluded = list(referee.classes[cls][1])
    cfg = apply_overrides(diag_cfg, "diagnosis", [f"diagnosis.exclude=[{','.join(excluded)}]"])
    t0 = time.perf_counter()
    results, _ = run_diagnoser(folder / "trials", ref.protocol, cfg)
    seconds = time.perf_counter() - t0
    write_json(folder / "results.json", results)
    score = score_case(cls, results, expected_verdict(cls, referee.classes))
    return {**score, "replicate": rep, "enr": ds.enr, "seconds": seconds, "truth": ds.truth}


@small_pages()
def run_benchmark(overrides: list[str] | None, out_dir: Path) -> tuple[Path, dict]:
    """Run the referee: make, diagnose and score every (class, replicate); write the summary."""
    from joblib import Parallel, delayed

    from armlab.diagnosis.benchmark_summary import format_benchmark, summarise

    ref_items = [o for o in overrides or [] if o.startswith("referee.")]
    diag_items = [o for o in overrides or [] if o.startswith("diagnosis.")]
    bad = [o for o in overrides or [] if o not in ref_items + diag_items]
    if bad:
        raise ConfigError(
            f"arguments {bad} must look like referee.<field>=<value> or diagnosis.<field>=<value>"
        )
    ref = apply_overrides(RefereeConfig(), "referee", ref_items)
    if ref.protocol is None:
        ref = replace(ref, protocol=registry.DEFAULT_REFEREE)
    diag_cfg = apply_overrides(DiagnosisConfig(), "diagnosis", diag_items)
    referee = registry.get(ref.protocol, need="referee").diagnosis.referee_for(ref.generator)
    shared = REFEREE_SHARED_FIELDS
    foreign = [
        o for o in ref_items if o.partition("=")[0].split(".", 1)[1] not in (*shared, *referee.settings)
    ]
    if foreign:
        raise ConfigError(
            f"{foreign}: not read by the {ref.protocol} referee; it reads "
            f"{[f'referee.{n}' for n in (*shared, *referee.settings)]}"
        )
    all_classes = referee.classes
    classes = list(ref.classes) if ref.classes is not None else list(all_classes)
    unknown = [c for c in classes if c not in all_classes]
    if unknown:
        raise ConfigError(f"unknown referee classes {unknown} for {ref.protocol}; valid: {list(all_classes)}")
    if referee.validate is not None:  # settings its diagnosis would refuse: before any dataset
        referee.validate(ref, diag_cfg)
    out = new_dir(out_dir)
    t0 = time.perf_counter()
    jobs = [(c, r) for c in classes for r in range(ref.replicates)]
    progress.stage("diagnose-benchmark", len(jobs), "cases")
    cases = []
    # in order, each case as soon as it and those before it are done
    for case in Parallel(n_jobs=ref.jobs, return_as="generator")(
        delayed(_one_case)(c, r, ref, diag_cfg, out) for c, r in jobs
    ):
        cases.append(case)
        progress.advance()
    summary = summarise(cases)
    summary["timing_s"] = time.perf_counter() - t0
    summary["median_diagnosis_s"] = float(np.median([c["seconds"] for c in cases]))
    write_json(out / "benchmark.json", {"summary": summary, "cases": cases})
    write_new(out / "benchmark.md", format_benchmark(summary, ref, referee.describe(ref)))
    return out, summary
