"""Tables, figures and the rerun recording of the virtual-force-sensor protocol (seeds/003).

- :func:`format_vfs_tables`: Tables III-VI as text, each identified value beside the truth and
  the paper's figure.
- :func:`plot_vfs_figures`: ``fig4_forces.png`` (like Fig. 4: six seconds of a fixture trial,
  position, acceleration and the force of both methods) and ``fig5_identified_vs_theory.png``
  (like Fig. 5: identified against theoretical k_xx, k_yy, k_s and m, both methods).
- :func:`write_vfs_recording`: every trial's encoders, torques, accelerometer and F/T channels on
  a ``trial_time`` timeline, decimated, with the tables as a text document.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from armlab.data.trial import TrialSet
from armlab.errors import DataError
from armlab.viz._paths import fresh_path, recording, save_png

__all__ = ["format_vfs_tables", "plot_vfs_figures", "write_vfs_recording"]

_DPI = 120
_SEGMENT_S = (20.0, 26.0)  # s, the six-second window of Fig. 4
_METHOD_LABEL = {"method1": "Method 1 (virtual sensor)", "method2": "Method 2 (F/T sensor)"}


def _fmt_ms(cell: Mapping[str, Any], digits: int) -> str:
    return f"{cell['mean']:.{digits}f} ± {cell['std']:.{digits}f}"


def format_vfs_tables(results: Mapping[str, Any]) -> str:
    """Tables III-VI of a ``virtual_force_sensor`` run as text (mean ± std, truth, paper)."""
    lines: list[str] = []
    robot = results.get("robot_id")
    if robot:
        lines.append("Table VI (robot dynamics, mean ± std over trials; paper's value; relative error)")
        for row in robot["table_VI"]:
            lines.append(
                f"  {row['name']:7s} {row['mean']:.5f} ± {row['std']:.5f}   paper {row['paper']:.5f} "
                f"± {row['paper_std']:.5f}   {100 * row['rel_err_vs_paper']:+6.2f} %"
            )
        vaf = np.asarray(robot["vaf_pct"])
        lines.append(
            f"  VAF tau1 {vaf[:, 0].min():.2f}-{vaf[:, 0].max():.2f} %, "
            f"tau2 {vaf[:, 1].min():.2f}-{vaf[:, 1].max():.2f} %"
        )
    fixture = results.get("fixture")
    if fixture:
        paper = results.get("paper_table_III", {})
        lines.append(
            "Table III (mass-spring system; mean ± std; truth = Table I; relative error; paper M1/M2)"
        )
        for label, cell in fixture["table_III"].items():
            for n in ("k_xx", "k_yy", "k_s", "m"):
                if n not in cell["method1"]:
                    continue
                c1, c2 = cell["method1"][n], cell["method2"][n]
                pap = ""
                if label in paper:
                    p = paper[label]
                    idx = ("k_xx", "k_yy", "k_s").index(n) if n != "m" else None
                    pap = (
                        f"   paper {p[0][idx]:.2f} / {p[1][idx]:.2f}"
                        if idx is not None
                        else f"   paper {p[0]:.3f} / {p[1]:.3f}"
                    )
                digits = 3 if n == "m" else 2
                lines.append(
                    f"  {label} {n:4s} truth {c1['truth']:8.{digits}f} | "
                    f"M1 {_fmt_ms(c1, digits)} ({100 * c1['rel_err']:+6.2f} %)"
                    f" | M2 {_fmt_ms(c2, digits)} ({100 * c2['rel_err']:+6.2f} %){pap}"
                )
        lines.append("Table IV (VAF of Method 1, x, y %)")
        for k_label, row in fixture["table_IV"].items():
            lines.append(
                "  " + k_label + "  " + "  ".join(f"{m}: {v[0]:.1f}, {v[1]:.1f}" for m, v in row.items())
            )
    arm = results.get("arm")
    if arm:
        lines.append("Table V (arm; mean over trials; rows x, y)")
        for method, cell in arm["table_V"].items():
            for name, unit in (("M", "kg"), ("B", "N s/m"), ("K", "N/m")):
                m = np.asarray(cell[name]["mean"])
                t = cell[name].get("truth")
                truth = f"  truth {np.round(t, 3).tolist()}" if t is not None else ""
                lines.append(f"  {method} {name} ({unit}) {np.round(m, 3).tolist()}{truth}")
            lines.append(
                f"  {method} Xv (m) {np.round(cell['xv']['mean'], 4).tolist()}  "
                f"VAF {np.round(cell['vaf_pct']['mean'], 1).tolist()} %"
            )
    return "\n".join(lines)


def _fig4(series: Mapping[str, Any], path: Path) -> Path | None:
    fx = series.get("fixture")
    if not fx:
        return None
    sig, fs = fx["signals"], series["fs_hz"]
    j = len(fx["idx"]) - 1  # the last configuration (K5/M5 with every label run), its last trial
    i0, i1 = (int(t * fs) for t in _SEGMENT_S)
    i1 = min(i1, sig.x.shape[1])
    t = np.arange(i0, i1) / fs
    fig = Figure(figsize=(9, 7))
    axes = fig.subplots(3, 2, sharex=True)
    for a, axis in enumerate("xy"):
        axes[0, a].plot(t, 1000 * sig.x[j, i0:i1, a])
        axes[0, a].set_ylabel(f"{axis} (mm)")
        axes[1, a].plot(t, sig.x_ddot[j, i0:i1, a])
        axes[1, a].set_ylabel(f"{axis}'' (m/s²)")
        axes[2, a].plot(t, sig.f_sensor[j, i0:i1, a], label="F/T sensor (Method 2)")
        axes[2, a].plot(t, sig.f_virtual[j, i0:i1, a], "--", label="virtual sensor (Method 1)")
        axes[2, a].set_ylabel(f"F_ext,{axis} (N)")
        axes[2, a].set_xlabel("time (s)")
    axes[2, 0].legend(fontsize=8)
    fig.suptitle(f"Fig. 4: {fx['stiffness'][j]} / {fx['payload'][j]}, smoothed identification signals")
    fig.tight_layout()
    return save_png(fig, path)


def _fig5(results: Mapping[str, Any], path: Path) -> Path | None:
    fixture = results.get("fixture")
    if not fixture:
        return None
    truth = results["truth"]["fixture"]
    fig = Figure(figsize=(9, 8))
    axes = fig.subplots(2, 2).ravel()
    for ax, name, unit in zip(axes, ("k_xx", "k_yy", "k_s", "m"), ("N/m", "N/m", "N/m", "kg"), strict=True):
        for method, marker in (("method1", "o"), ("method2", "s")):
            xs, ys = [], []
            for e in fixture["trials"]:
                label = e["payload"] if name == "m" else e["stiffness"]
                xs.append(truth[label][name])
                ys.append(e[method][name])
            ax.plot(xs, ys, marker, ms=4, alpha=0.7, label=_METHOD_LABEL[method])
        lo, hi = ax.get_xlim()
        ax.plot([lo, hi], [lo, hi], "k:", lw=1)
        ax.set_xlabel(f"theoretical {name} ({unit})")
        ax.set_ylabel(f"identified {name} ({unit})")
    axes[0].legend(fontsize=8)
    fig.suptitle("Fig. 5: identified vs theoretical (Table I) parameters")
    fig.tight_layout()
    return save_png(fig, path)


def plot_vfs_figures(
    results: Mapping[str, Any], series: Mapping[str, Any], out_dir: str | Path
) -> dict[str, Path]:
    """Write Fig. 4 and Fig. 5 (module docstring) into ``out_dir``; returns name -> path."""
    out_dir = Path(out_dir)
    written = {}
    for key, path in (
        ("fig4", _fig4(series, out_dir / "fig4_forces.png")),
        ("fig5", _fig5(results, out_dir / "fig5_identified_vs_theory.png")),
    ):
        if path is not None:
            written[key] = path
    return written


def write_vfs_recording(
    path: str | Path,
    trials: TrialSet,
    results: Mapping[str, Any] | None = None,
    max_hz: float = 100.0,
    *,
    application_id: str = "armlab",
) -> Path:
    """Every trial's ``theta``, ``tau``, ``acc_site``, ``ft_site`` (x, y) and the true end-effector
    position as scalar series ``trials/<kind>_<labels>_<i>/<channel>/<axis>`` on ``trial_time``,
    decimated to ``max_hz`` (the 0-2 Hz motion sampled 50-fold at the default); the tables as
    the text document ``results``. ``application_id``: the recording's rerun application (the
    protocol's hook passes ``armlab_<protocol>``)."""
    import rerun as rr

    if not (np.isfinite(max_hz) and max_hz > 0):
        raise DataError(f"max_hz must be a positive number of Hz, got {max_hz!r}")
    p = fresh_path(path, ".rrd")
    step = max(1, int(round(trials.fs_hz / max_hz)))
    times = np.arange(0, trials.n_samples, step) / trials.fs_hz
    with recording(p, application_id) as rec:
        meta = trials.trial_meta
        for i in range(trials.n_trials):
            name = "_".join(
                x for x in (str(meta["kind"][i]), str(meta["stiffness"][i]), str(meta["payload"][i])) if x
            )
            base = f"trials/{name}_{int(meta['trial'][i])}"
            for ch in ("theta", "tau", "acc_site", "ft_site", "true_x"):
                if ch not in trials.channels:
                    continue
                data = np.asarray(trials.channels[ch][i, ::step], dtype=np.float32).astype(np.float64)
                for a, axis in enumerate(("1", "2") if ch in ("theta", "tau") else ("x", "y")):
                    rec.send_columns(
                        f"{base}/{ch}/{axis}",
                        indexes=[rr.TimeColumn("trial_time", duration=times)],
                        columns=rr.Scalars.columns(scalars=data[:, a]),
                    )
        if results is not None:
            rec.log("results", rr.TextDocument(format_vfs_tables(results)), static=True)
    return p
