"""``armlab fit-joint``: impedance and admittance fits of real 1-DoF joint recordings (edge module).

Reads CSV trials (one file, or every ``*.csv`` of a folder; format of :mod:`armlab.data.reklab`),
runs :func:`armlab.protocols.joint_1dof.frf.fit_joint_frf` on each and writes, in a fresh run
directory, ``results.json`` (``{"trials": {name: per-trial results}, "frf": settings}``; keys in
docs/results_schema.md), ``table.txt`` (the printed table) and ``bode_impedance.png``.
"""

from __future__ import annotations

from pathlib import Path

from omegaconf import OmegaConf

from armlab import progress
from armlab.config.schema import FrfConfig
from armlab.config.store import apply_overrides
from armlab.data.joint_import import load_joint_data
from armlab.data.outdir import default_out, take_out
from armlab.errors import ConfigError
from armlab.protocols._files import check_new_dir, write_json, write_new
from armlab.protocols.joint_1dof.frf import JOINT_BAND_HZ, fit_joint_frf

__all__ = [
    "fit_joint_recordings",
    "format_joint_table",
    "joint_frf_config",
    "run_fit_joint",
]


def joint_frf_config(overrides: list[str] | None = None) -> FrfConfig:
    """Frequency-response settings for joint data: the protocol's, with the joint band by default,
    updated by ``frf.<field>=<value>`` overrides."""
    return apply_overrides(FrfConfig(band_hz=JOINT_BAND_HZ), "frf", overrides)


def fit_joint_recordings(
    source: Path | str, frf: FrfConfig, out_dir: Path | str, *, viz, units: str | None = None
) -> dict:
    """Fit every trial of ``source`` and write the outputs into the new directory ``out_dir``.

    The trials are read by :func:`armlab.data.joint_import.load_joint_data`, with every check of
    the other data verbs (one sample rate per folder, units within human ranges unless ``units``
    states them, e.g. ``"deg"``). ``viz`` is :mod:`armlab.viz`, handed in by the edge (a
    protocol never imports it).
    """
    out_dir = Path(out_dir)
    check_new_dir(out_dir)  # before the fits
    trials, series = {}, {}
    records = load_joint_data(Path(source), units=units)
    for trial in records:  # every file checked before the first fit
        frf.check_recording(trial.fs_hz, trial.n_samples, f"recording {trial.path.name}")
    progress.stage("fit", len(records), "trials")
    for trial in records:
        name = trial.name
        res, ser = fit_joint_frf(trial.position, trial.torque, trial.fs_hz, frf, name)
        res["time_varying"] = trial.operating_point is not None  # an LTI fit is only a summary there
        res["source"] = str(trial.path)
        trials[name], series[name] = res, ser
        progress.advance()
    results = {
        "protocol": "joint_frf",
        "frf": OmegaConf.to_container(OmegaConf.structured(frf)),
        "trials": trials,
    }
    out_dir.mkdir(parents=True, exist_ok=True)
    progress.stage("outputs")
    results["files"] = {"bode": str(viz.plot_joint_bode(series, out_dir / "bode_impedance.png"))}
    write_new(out_dir / "table.txt", format_joint_table(results) + "\n")
    write_json(out_dir / "results.json", results)
    return results


def format_joint_table(results: dict) -> str:
    """One line per trial: integer and fractional impedance, best admittance models."""
    lines = [
        "trial    coh  | I s²+B s+K: I [kg m²]  B      K     R²    "
        "| I s²+B s^a+K: a    I       B      K     R²    "
        "| admittance: best integer (R²), best fractional (alpha, R²)"
    ]
    for name, r in results["trials"].items():
        i, fr = r["impedance"]["integer"], r["impedance"]["fractional"]
        ad = r["admittance"]
        bi, bf = ad["best_integer"], ad["best_fractional"]
        best_int = f"{bi} ({ad['models'][bi]['r2']:.3f})" if bi else "-"
        best_frac = f"{bf} ({ad['models'][bf]['alpha']:.1f}, {ad['models'][bf]['r2']:.3f})" if bf else "-"
        lines.append(
            f"{name:8s} {r['mean_coherence']:.2f} | "
            f"{i['I']:18.4f} {i['B']:6.2f} {i['K']:6.0f} {i['r2']:6.3f} | "
            f"{fr['alpha']:14.1f} {fr['I']:7.4f} {fr['B']:6.2f} {fr['K']:6.0f} {fr['r2']:6.3f} | "
            f"{best_int}, {best_frac}{'  (time-varying: LTI summary)' if r.get('time_varying') else ''}"
        )
    lo, hi = results["frf"]["band_hz"]
    lines.append(
        f"band {lo:g}-{hi:g} Hz, Welch {results['frf']['welch_window']} samples; R² on magnitudes (Eq. 26)"
    )
    return "\n".join(lines)


def run_fit_joint(args: list[str], viz) -> int:
    """``armlab fit-joint <csv|mat|folder> [frf.<field>=<value>] [units=<u>] [out=<dir>]``."""
    if not args or "=" in args[0]:
        raise ConfigError("fit-joint needs a CSV file or folder: armlab fit-joint <csv|folder> [frf.<f>=<v>]")
    out, items = take_out(args[1:], "fit-joint")
    out = out or default_out("fit-joint")
    rest, units = [], None
    for item in items:
        if item.startswith("units="):
            units = item.partition("=")[2]
        else:
            rest.append(item)
    results = fit_joint_recordings(Path(args[0]), joint_frf_config(rest), out, viz=viz, units=units)
    print(format_joint_table(results))
    print(f"outputs: {out}")
    return 0
