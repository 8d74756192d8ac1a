"""Figures and the Rerun recording of ``armlab diagnose`` (where the gap is, how far it shrinks).

Inputs are what :func:`armlab.protocols.joint_1dof.diagnosis.diagnose.diagnose_joint` returns: ``results``
(pooled, or
per trial with a ``per_trial`` list; the same keys as ``results.json``, see
``docs/diagnosis_schema.md``) and ``series`` — ``{"all": group}`` when pooled, ``{trial name:
group}`` per trial — where each group holds ``trials`` (prepared trials with ``name``, ``t_s`` s,
``x`` rad, ``train`` mask), ``measured``, ``nominal`` and ``corrected`` (per trial, (n,) N·m torque
in the scoring band) and ``residual_tests_final`` (the residual tests of the final model).

:func:`diagnosis_figures` writes, into ``out_dir``:

- ``gap_by_band.png``: held-out gap per frequency band, one bar per stage (nominal, + each added
  effect), the noise floor as black ticks (log scale, % of the measured power in the band);
- ``gap_by_window.png``: the same per window after perturbation onset;
- ``residual_correlation.png``: residual autocorrelation and residual–velocity cross-correlation
  against lag, nominal and final model, with the ±95 % bound of a white residual;
- ``time_overlay.png``: the first seconds of the held-out part of (up to four) trials, measured,
  nominal and corrected torque above, both residuals below;
- ``vaf_per_trial.png``: held-out VAF per trial and stage, with the best VAF the noise allows;
- ``operating_point.png`` (time-varying recordings only, results holding ``operating_point``):
  stiffness and damping fitted in bins of the operating angle (± one standard error) and the
  time-varying nominal's quadratics, with its value at the mean angle as a dashed line.

:func:`diagnosis_recording` writes every trial's torques, residuals and joint angle on the
``trial_time`` timeline (s from the trial's start) into one ``.rrd`` file. Matplotlib is driven
through its object API with the Agg canvas; ``rerun`` is imported inside the recording function
only. Nothing is ever overwritten.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from armlab.errors import DataError
from armlab.viz._paths import fresh_path, recording, save_png
from armlab.viz._ticks import plain_log_ticks

__all__ = [
    "diagnosis_figures",
    "diagnosis_recording",
]

_DPI = 120
_STAGE_COLOURS = ("0.55", "C0", "C1", "C2")
_OVERLAY_S = 3.0  # s of the held-out part shown in the time overlay
_MAX_OVERLAY_TRIALS = 4
_MAX_COLUMNS = 4
_TIMELINE = "trial_time"
_SERIES_KEYS = ("trials", "measured", "nominal", "corrected")


def _groups(series: Mapping[str, Any], results: Mapping[str, Any]) -> list[tuple[str, Mapping, Mapping]]:
    """(label, results of the group, series of the group), pooled or one per trial."""
    per = results.get("per_trial")
    if per is None:
        if "all" not in series:
            raise DataError(f"pooled results need series['all']; series has {sorted(series)}")
        return [("all trials", results, series["all"])]
    missing = [p["trial"] for p in per if p["trial"] not in series]
    if missing:
        raise DataError(f"series has no entry for trials {missing}; it has {sorted(series)}")
    return [(p["trial"], p, series[p["trial"]]) for p in per]


def _stage_label(effects: Sequence[str]) -> str:
    return "nominal" if not effects else "+ " + " + ".join(effects)


def _verdict(r: Mapping[str, Any]) -> str:
    return " → ".join(r.get("verdict") or []) or "–"


def _grid(n: int, width: float, height: float) -> tuple[Figure, np.ndarray]:
    cols = min(n, _MAX_COLUMNS)
    rows = -(-n // cols)
    fig = Figure(figsize=(width * cols + 1.0, height * rows + 0.6), dpi=_DPI, layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax in axes[n:]:
        ax.set_visible(False)
    return fig, axes


def _pct(values: Sequence[Any]) -> np.ndarray:
    """Gap fractions as % (NaN where missing), clipped below for the log axis."""
    v = np.array([np.nan if x is None else float(x) for x in values], dtype=float) * 100.0
    return np.where(np.isfinite(v), np.maximum(v, 1e-4), np.nan)


def _gap_figure(groups, key: str, span_key: str, unit: str, title: str, path: Path) -> Path:
    fig, axes = _grid(len(groups), 4.6, 3.4)
    for ax, (label, r, _) in zip(axes, groups, strict=False):
        stages = r.get("how_far") or []
        slices = stages[0][key] if stages else r["where"][key]
        n_s = max(len(stages), 1)
        x = np.arange(len(slices))
        width = 0.8 / n_s
        for j, st in enumerate(stages):
            ax.bar(
                x - 0.4 + (j + 0.5) * width,
                _pct([b["gap"] for b in st[key]]),
                width,
                color=_STAGE_COLOURS[j % len(_STAGE_COLOURS)],
                label=f"{_stage_label(st['effects'])} ({100 * st['held_out_gap']:.2g} % overall)",
            )
        floor = _pct([b["floor"] for b in slices])
        ax.hlines(floor, x - 0.45, x + 0.45, colors="k", lw=2, label="noise floor")
        ax.set_yscale("log")
        plain_log_ticks(ax.yaxis)
        ax.set_xticks(x, [f"{b[span_key][0]:g}–{b[span_key][1]:g}" for b in slices])
        ax.set_xlabel(unit)
        ax.set_ylabel("held-out gap (% of measured power)")
        ax.set_title(f"{label}: {_verdict(r)}", fontsize=9)
        ax.grid(True, axis="y", which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title)
    return save_png(fig, path)


def _correlation_figure(groups, path: Path) -> Path:
    fig = Figure(figsize=(10.0, 3.0 * len(groups) + 0.6), dpi=_DPI, layout="constrained")
    axes = fig.subplots(len(groups), 2, squeeze=False)
    for (label, r, s), (ax_a, ax_c) in zip(groups, axes, strict=True):
        tests = [("nominal", r["where"]["residual_tests"], _STAGE_COLOURS[0])]
        final = s.get("residual_tests_final")
        stages = r.get("how_far") or []
        if final is not None and len(stages) > 1:
            tests.append((_stage_label(stages[-1]["effects"]), final, "C3"))
        for name, t, colour in tests:
            lag_ms = 1e3 * np.asarray(t["lags_s"], dtype=float)
            acf = np.array([np.nan if v is None else v for v in t["autocorrelation"]], dtype=float)
            ax_a.plot(
                lag_ms, acf, color=colour, label=f"{name} ({100 * t['whiteness_fraction_outside']:.0f} % out)"
            )
            peak = f"peak {t['peak_cross_value']:.2f} at {1e3 * t['peak_cross_lag_s']:.0f} ms"
            ax_c.plot(
                lag_ms,
                np.asarray(t["cross_correlation"], dtype=float),
                color=colour,
                label=f"{name} ({peak})",
            )
            ax_c.plot(1e3 * t["peak_cross_lag_s"], t["peak_cross_value"], "o", color=colour, ms=4)
        bound = tests[0][1]["bound"]
        for ax in (ax_a, ax_c):
            ax.axhspan(-bound, bound, color="0.85", label="±95 % bound (white)")
            ax.axhline(0.0, color="k", lw=0.5)
            ax.set_xlabel("lag (ms)")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        ax_a.set_ylabel("autocorrelation")
        ax_a.set_title(f"{label}: residual whiteness", fontsize=9)
        ax_c.set_ylabel("residual–velocity correlation")
        ax_c.set_xlabel("lag (ms; > 0: the residual follows the velocity)")
        ax_c.set_title(f"{label}: residual–velocity cross-correlation", fontsize=9)
    fig.suptitle("Residual tests on the held-out parts")
    return save_png(fig, path)


def _held_window(tr) -> np.ndarray:
    held = np.flatnonzero(np.asarray(tr.held, dtype=bool))
    if held.size == 0:
        held = np.arange(np.asarray(tr.t_s).size)
    t = np.asarray(tr.t_s)
    return held[t[held] < t[held[0]] + _OVERLAY_S]


def _overlay_figure(groups, path: Path) -> Path:
    items = [(label, r, s, i) for label, r, s in groups for i in range(len(s["trials"]))]
    items = items[:_MAX_OVERLAY_TRIALS]
    fig = Figure(figsize=(4.8 * len(items) + 0.6, 5.4), dpi=_DPI, layout="constrained")
    axes = fig.subplots(2, len(items), squeeze=False, sharex="col", height_ratios=[2, 1])
    for col, (_, r, s, i) in enumerate(items):
        tr = s["trials"][i]
        idx = _held_window(tr)
        t = np.asarray(tr.t_s)[idx]
        meas, nom, cor = (np.asarray(s[k][i])[idx] for k in ("measured", "nominal", "corrected"))
        final = _stage_label((r.get("how_far") or [{"effects": []}])[-1]["effects"])
        top, bottom = axes[0, col], axes[1, col]
        top.plot(t, meas, color="k", lw=1.2, label="measured")
        top.plot(t, nom, color=_STAGE_COLOURS[0], lw=1.0, ls="--", label="nominal")
        top.plot(t, cor, color="C3", lw=1.0, label=f"corrected ({final})")
        bottom.plot(t, meas - nom, color=_STAGE_COLOURS[0], lw=0.9, label="nominal")
        bottom.plot(t, meas - cor, color="C3", lw=0.9, label="corrected")
        top.set_title(f"{tr.name} (held out)", fontsize=9)
        top.set_ylabel("torque in band (N·m)")
        bottom.set_ylabel("residual (N·m)")
        bottom.set_xlabel("time (s)")
        for ax in (top, bottom):
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
    fig.suptitle("Held-out torque: measured, nominal simulation, corrected simulation")
    return save_png(fig, path)


def _vaf_figure(groups, path: Path) -> Path:
    rows = []  # (trial, effects in order, [VAF % per stage], best VAF % the noise allows)
    for _, r, _ in groups:
        stages = r.get("how_far") or []
        floor = 100.0 * (1.0 - float(r["gap"]["noise_floor"]))
        for i, p in enumerate(stages[0]["per_trial"] if stages else []):
            vafs = [float(st["per_trial"][i]["held_out_vaf_percent"]) for st in stages]
            rows.append((p["trial"], list(stages[-1]["effects"]), vafs, floor))
    same = len({tuple(e) for _, e, _, _ in rows}) <= 1
    fig = Figure(figsize=(max(4.5, 1.4 * len(rows) + 2.0), 4.2), dpi=_DPI, layout="constrained")
    ax = fig.subplots()
    n_s = max((len(v) for _, _, v, _ in rows), default=1)
    width = 0.8 / n_s
    for k, (_, effects, vafs, floor) in enumerate(rows):
        for j, vaf in enumerate(vafs):
            stage = _stage_label(effects[:j]) if same else ("nominal" if j == 0 else f"+ effect {j}")
            x = k - 0.4 + (j + 0.5) * width
            ax.bar(x, vaf, width, color=_STAGE_COLOURS[j % 4], label=stage if k == 0 else None)
            ax.annotate(f"{vaf:.1f}", (x, vaf), ha="center", va="bottom", fontsize=7)
        ax.hlines(
            floor, k - 0.45, k + 0.45, colors="k", lw=2, label="best VAF the noise allows" if k == 0 else None
        )
    lo = min((v for _, _, vafs, _ in rows for v in vafs), default=0.0)
    ax.set_ylim(max(0.0, lo - 10.0), 101.0)
    ticks = [name if same else f"{name}\n{' → '.join(e) or 'none'}" for name, e, _, _ in rows]
    ax.set_xticks(np.arange(len(rows)), ticks)
    ax.set_ylabel("held-out VAF (%)")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    fig.suptitle("Held-out VAF per trial, nominal and after each added effect", fontsize=10)
    return save_png(fig, path)


def _operating_point_figure(groups, path: Path) -> Path:
    fig, axes = _grid(2, 4.2, 3.4)
    for ax, (k, unit) in zip(axes, (("K", "N·m/rad"), ("B", "N·m·s/rad")), strict=False):
        for label, r, _ in groups:
            op = r["operating_point"]
            binned = op["binned"]["parameters"][k]
            ax.errorbar(
                op["binned"]["centres_rad"],
                binned["values"],
                yerr=binned["se"],
                fmt="o",
                ms=4,
                capsize=2,
                label=f"{label}: binned fit",
            )
            curves = op["curves"]
            ax.plot(curves["operating_angle_rad"], curves[k], lw=1.5, label=f"{label}: time-varying nominal")
            ax.axhline(op["coefficients"][k], color="0.5", ls="--", lw=1, label="at the mean angle")
        ax.set_xlabel("operating angle (rad)")
        ax.set_ylabel(f"{k} ({unit})")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    verdicts = "; ".join(f"{label}: {_verdict(r)}" for label, r, _ in groups)
    fig.suptitle(f"Impedance against the operating angle ({verdicts})", fontsize=10)
    return save_png(fig, path)


def diagnosis_figures(
    series: Mapping[str, Any], results: Mapping[str, Any], out_dir: str | Path
) -> list[Path]:
    """Write the diagnosis figures (module docstring) into ``out_dir``; returns the paths in order.

    Args:
        series: ``{"all": group}`` (pooled) or ``{trial name: group}`` (per trial), as returned by
            :func:`armlab.protocols.joint_1dof.diagnosis.diagnose.diagnose_joint`.
        results: the matching results dict.
        out_dir: folder to write into (created if needed).

    Returns:
        ``gap_by_band.png``, ``gap_by_window.png``, ``residual_correlation.png``,
        ``time_overlay.png`` and ``vaf_per_trial.png`` under ``out_dir``, then
        ``operating_point.png`` for a time-varying recording.

    Raises:
        DataError: ``series`` does not match ``results``, or a figure file already exists.
    """
    out = Path(out_dir)
    groups = _groups(series, results)
    varying = [g for g in groups if "operating_point" in g[1]]
    return [
        _gap_figure(
            groups, "bands", "band_hz", "band (Hz)", "Held-out gap by frequency band", out / "gap_by_band.png"
        ),
        _gap_figure(
            groups,
            "windows",
            "window_ms",
            "time after perturbation onset (ms)",
            "Held-out gap by time after onset",
            out / "gap_by_window.png",
        ),
        _correlation_figure(groups, out / "residual_correlation.png"),
        _overlay_figure(groups, out / "time_overlay.png"),
        _vaf_figure(groups, out / "vaf_per_trial.png"),
        *([_operating_point_figure(varying, out / "operating_point.png")] if varying else []),
    ]


def _entity(name: str, used: set[str]) -> str:
    base = re.sub(r"[^A-Za-z0-9_.-]", "_", str(name)) or "trial"
    out, k = base, 1
    while out in used:
        k += 1
        out = f"{base}_{k}"
    used.add(out)
    return out


def _blueprint(rrb, bases: Sequence[str]):
    tabs = [
        rrb.Vertical(
            rrb.TimeSeriesView(name="torque in band (N·m)", origin="/", contents=[f"/{b}/torque/**"]),
            rrb.TimeSeriesView(name="residual (N·m)", origin="/", contents=[f"/{b}/residual/**"]),
            rrb.TimeSeriesView(name="joint angle (rad)", origin="/", contents=[f"/{b}/angle"]),
            rrb.TextLogView(name="events", origin="/", contents=[f"/{b}/events"]),
            row_shares=[3, 2, 2, 1],
            name=b.split("/")[-1],
        )
        for b in bases
    ]
    return rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(timeline=_TIMELINE), collapse_panels=False)


def diagnosis_recording(
    series: Mapping[str, Any], path: str | Path, *, app_id: str = "armlab_diagnose"
) -> Path:
    """Write every trial's measured, nominal and corrected torque and residuals into one ``.rrd``.

    Layout (entity paths), all on the ``trial_time`` timeline (s from the trial's start, at the
    fitting rate):

    - ``trials/<trial>/torque/{measured,nominal,corrected}``: N·m, torque in the scoring band;
    - ``trials/<trial>/residual/{nominal,corrected}``: N·m, measured minus model torque;
    - ``trials/<trial>/angle``: rad, the band-limited joint angle;
    - ``trials/<trial>/events``: a text marker where the held-out part starts.

    A default blueprint holds one tab per trial. Scalars are rounded to float32 precision.

    Args:
        series: ``{"all": group}`` or ``{trial name: group}`` as returned by
            :func:`armlab.protocols.joint_1dof.diagnosis.diagnose.diagnose_joint`.
        path: the ``.rrd`` file to write; must not exist.
        app_id: the Rerun application id.

    Returns:
        The written path.

    Raises:
        DataError: ``path`` exists or is not ``.rrd``, or a series group lacks a key.
    """
    import rerun as rr
    import rerun.blueprint as rrb

    if not series:
        raise DataError("diagnosis_recording needs at least one series group")
    for key, group in series.items():
        missing = [k for k in _SERIES_KEYS if k not in group]
        if missing:
            raise DataError(f"series[{key!r}] lacks {missing}; expected the keys {list(_SERIES_KEYS)}")
    p = fresh_path(path, ".rrd")
    used: set[str] = set()
    todo = [
        (f"trials/{_entity(tr.name, used)}", group, i)
        for group in series.values()
        for i, tr in enumerate(group["trials"])
    ]
    with recording(p, app_id, _blueprint(rrb, [b for b, _, _ in todo])) as rec:
        for base, group, i in todo:
            tr = group["trials"][i]
            t = np.asarray(tr.t_s, dtype=float)
            time_col = [rr.TimeColumn(_TIMELINE, duration=t)]
            meas = np.asarray(group["measured"][i], dtype=float)
            nom = np.asarray(group["nominal"][i], dtype=float)
            cor = np.asarray(group["corrected"][i], dtype=float)
            lines = (
                ("torque/measured", meas, "measured", (20, 20, 20)),
                ("torque/nominal", nom, "nominal", (140, 140, 140)),
                ("torque/corrected", cor, "corrected", (214, 39, 40)),
                ("residual/nominal", meas - nom, "nominal residual", (140, 140, 140)),
                ("residual/corrected", meas - cor, "corrected residual", (214, 39, 40)),
                ("angle", np.asarray(tr.x, dtype=float), "joint angle", (31, 119, 180)),
            )
            for sub, values, name, colour in lines:
                rec.log(f"{base}/{sub}", rr.SeriesLines(names=name, colors=[colour]), static=True)
                rec.send_columns(
                    f"{base}/{sub}",
                    indexes=time_col,
                    columns=rr.Scalars.columns(scalars=np.asarray(values, np.float32).astype(np.float64)),
                )
            held = np.flatnonzero(np.asarray(tr.held, dtype=bool))
            if held.size:
                rec.send_columns(
                    f"{base}/events",
                    indexes=[rr.TimeColumn(_TIMELINE, duration=[float(t[held[0]])])],
                    columns=rr.TextLog.columns(
                        text=["held-out part starts: models fitted before, scored after"], level=["INFO"]
                    ),
                )
    return p
