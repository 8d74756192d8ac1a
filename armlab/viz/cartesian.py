"""Figures and the printed table of the ``cartesian_online`` protocol (paper 002, thesis Ch. 3).

Inputs are what :func:`armlab.protocols.cartesian_online.results.estimate_cartesian` returns
(``results``) and the plain arrays the protocol's hooks hand over (``series``):

- ``convergence``: {label: (s,) %} the field error over the disc after each sequence (Exp. 4);
- ``convergence_limits``: ((sequence, %), ...) the limits of spec 002's check 6 (drawn if given);
- ``k_map``: ``grid`` (m, 2) m, ``k_true`` and ``k_hat`` (m, 2) N/m (the final Exp. 4 estimate),
  ``stops`` (s, 2) m, ``label``;
- ``force``: ``t`` (n,) s, ``measured`` and ``predicted`` (n, 2) N (Exp. 4's logged samples),
  ``fs_hz`` Hz (their sample rate), ``label``.

Exp. 5's orders come from ``results['exp5']``. Plots use matplotlib's object API with the Agg
canvas; every writer takes a fresh path and returns it. The recording is
:mod:`armlab.viz.cartesian_recording`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from armlab.viz._paths import save_png
from armlab.viz._ticks import plain_log_ticks

__all__ = [
    "format_cartesian_table",
    "plot_cartesian_figures",
]

_ENTRIES = ("k11", "k12", "k21", "k22", "d11", "d12", "d21", "d22")


def _short(measured: Any) -> str:
    """A check's measured figures on one line (numbers to 6 significant digits)."""
    if measured is None:
        return "not run"

    def fmt(v):
        if isinstance(v, float):
            return float(f"{v:.6g}")
        if isinstance(v, (list, tuple, np.ndarray)):
            return [fmt(x) for x in np.asarray(v).tolist()] if np.ndim(v) else fmt(float(v))
        if isinstance(v, dict):
            return {k: fmt(x) for k, x in v.items()}
        return v

    return json.dumps(fmt(dict(measured)), separators=(", ", ": "))


def format_cartesian_table(results: Mapping[str, Any]) -> str:
    """Spec 002's nine checks beside the thesis's claims, then the Exp. 4 convergence, as text."""
    lines = [
        f"{results.get('protocol', '')} (paper 002, thesis Ch. 3), level {results.get('level', 'A')}, "
        f"stiffness_scale {results.get('stiffness_scale', 1.0):g}, force noise "
        + ", ".join(f"{c} {n:g} N" for c, n in results.get("noise_std_N", {}).items() if n)
        + ("" if any(results.get("noise_std_N", {}).values()) else "0 N (the thesis)")
    ]
    for row in results.get("checks", []):
        verdict = {True: "PASS", False: "FAIL", None: "----"}[row["passed"]]
        applies = "" if row["applies"] else " (settings differ from the check's: not gated)"
        lines.append(f"{row['id']}. [{verdict}] {row['check']}{applies}")
        lines.append(f"     thesis:   {row['thesis']}")
        lines.append(f"     spec:     {row['spec']}")
        lines.append(f"     measured: {_short(row['measured'])}")
    for case in ("exp4", "exp4_noise"):
        cell = results.get(case)
        if not cell:
            continue
        for method, r in cell.items():
            if not isinstance(r, Mapping):
                continue
            f = np.asarray(r["field_max_pct"], dtype=float)
            picks = sorted({i for i in (0, 1, 4, 19) if i < len(f)} | {len(f) - 1})
            lines.append(
                f"{case} ({cell['noise_std_N']:g} N) {method}: field error after sequence "
                + ", ".join(f"{i + 1}: {f[i]:.3g} %" for i in picks)
            )
    e5 = results.get("exp5")
    if e5:
        for frame in ("cartesian", "polar"):
            sel = e5[frame]
            lines.append(
                f"exp5 {frame} orders (thesis): "
                + ", ".join(
                    f"{k} {tuple(sel[k]['order'])} ({tuple(e5['thesis_orders'][frame][k])})" for k in _ENTRIES
                )
            )
    cmp = results.get("level_b_vs_a")
    if cmp:
        lines.append(
            "level B vs level A on the same commanded paths (%): A; A on the path B executed; B with ideal "
            "sensors; B ideal with m*a taken out (accelerometer); B as measured. Effects (points): "
            "path = A executed - A, inertia = B ideal - A executed, sensors = B - B ideal:"
        )
        for name, r in cmp.items():
            lines.append(
                f"  {name:18s} A {r['level_a_pct']:8.3g}  A exec {r['level_a_executed_path_pct']:8.3g}  "
                f"B ideal {r['level_b_ideal_sensors_pct']:8.3g}  "
                f"B comp {r['level_b_inertia_compensated_pct']:8.3g}  "
                f"B {r['level_b_pct']:8.3g}  path {r['path_effect_points']:+8.3g}  "
                f"inertia {r['inertia_effect_points']:+8.3g}  sensors {r['sensor_effect_points']:+8.3g}  "
                f"peak m*a {r.get('inertial_force_peak_N', float('nan')):.3g} N"
                f"  ({r['what']})"
            )
    return "\n".join(lines)


def _convergence(series: Mapping[str, Any], path: Path) -> Path:
    fig = Figure(figsize=(7, 4.5))
    ax = fig.subplots()
    for label, err in series["convergence"].items():
        err = np.asarray(err, dtype=float)
        ax.semilogy(np.arange(1, len(err) + 1), err, "o-", ms=3, label=label)
    limits = np.asarray(series.get("convergence_limits", ()), dtype=float).reshape(-1, 2)
    if len(limits):
        ax.plot(limits[:, 0], limits[:, 1], "kv", ms=8, label="spec 002 check 6 limits (0.05 N)")
    plain_log_ticks(ax.yaxis)
    ax.axvline(2, color="0.6", ls=":", lw=1)
    ax.text(2.1, ax.get_ylim()[1], " thesis: 'converges by\n the second sequence'", va="top", fontsize=8)
    ax.set_xlabel("sequences of perturbations")
    ax.set_ylabel("field error, max over the disc (%)")
    ax.set_title("Exp. 4: convergence of the stiffness field (Eq. 3.1.2)")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    return save_png(fig, path)


def _k_maps(series: Mapping[str, Any], path: Path) -> Path:
    km = series["k_map"]
    g, kt, kh = (np.asarray(km[k], dtype=float) for k in ("grid", "k_true", "k_hat"))
    err = 100 * np.abs(kh - kt) / np.abs(kt)
    fig = Figure(figsize=(11, 6.5))
    axes = fig.subplots(2, 3)
    for a, name in enumerate(("K_xx", "K_yy")):
        lo, hi = min(kt[:, a].min(), kh[:, a].min()), max(kt[:, a].max(), kh[:, a].max())
        for j, (values, title, kw) in enumerate(
            (
                (kt[:, a], f"{name} truth (N/m)", dict(vmin=lo, vmax=hi)),
                (kh[:, a], f"{name} estimate (N/m)", dict(vmin=lo, vmax=hi)),
                (err[:, a], f"{name} error (%)", dict(cmap="magma")),
            )
        ):
            ax = axes[a, j]
            sc = ax.scatter(g[:, 0], g[:, 1], c=values, s=9, marker="s", **kw)
            ax.plot(*np.asarray(km["stops"]).T, "w.", ms=4)
            ax.set_aspect("equal")
            ax.set_title(title, fontsize=9)
            fig.colorbar(sc, ax=ax, shrink=0.8)
            ax.set_xlabel("x (m)")
            ax.set_ylabel("y (m)")
    fig.suptitle(f"K̂ maps vs truth over the circle's disc: {km['label']}", fontsize=10)
    fig.tight_layout()
    return save_png(fig, path)


def _force(series: Mapping[str, Any], path: Path) -> Path:
    fo = series["force"]
    t, meas, pred = (np.asarray(fo[k], dtype=float) for k in ("t", "measured", "predicted"))
    fig = Figure(figsize=(9, 5.5))
    axes = fig.subplots(2, 1, sharex=True)
    idx = np.arange(len(t))
    for a, name in enumerate("xy"):
        axes[a].plot(idx, meas[:, a], lw=1, label="measured")
        axes[a].plot(idx, pred[:, a], "--", lw=1, label="predicted (final estimate)")
        axes[a].plot(idx, meas[:, a] - pred[:, a], lw=0.8, label="residual")
        axes[a].set_ylabel(f"F_{name} (N)")
    axes[1].set_xlabel(f"logged sample (perturbations only, {float(fo['fs_hz']):g} Hz)")
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"Exp. 4 force prediction: {fo['label']}", fontsize=10)
    return save_png(fig, path)


def _orders(results: Mapping[str, Any], path: Path) -> Path:
    e5 = results["exp5"]
    fig = Figure(figsize=(10, 4.5))
    axes = fig.subplots(1, 2, sharey=True)
    x = np.arange(len(_ENTRIES))
    for ax, frame, coords in zip(axes, ("cartesian", "polar"), (("x", "y"), ("ρ", "θ")), strict=True):
        sel = [e5[frame][k]["order"] for k in _ENTRIES]
        thesis = [e5["thesis_orders"][frame][k] for k in _ENTRIES]
        ax.bar(x - 0.2, [o[0] for o in sel], 0.2, label=f"selected, order in {coords[0]}")
        ax.bar(x, [o[1] for o in sel], 0.2, label=f"selected, order in {coords[1]}")
        ax.plot(x - 0.2, [o[0] for o in thesis], "k_", ms=14, mew=2, label="thesis")
        ax.plot(x, [o[1] for o in thesis], "k_", ms=14, mew=2)
        for i, k in enumerate(_ENTRIES):
            ax.text(
                x[i] + 0.2, 0.05, f"R²adj\n{e5[frame][k]['r2_adj']:.4f}", fontsize=6, rotation=90, va="bottom"
            )
        ax.set_xticks(x, _ENTRIES)
        n_sel = e5["parameter_count"][frame]
        n_th = e5["parameter_count"][f"thesis_orders_{frame}"]
        ax.set_title(f"{frame}: {n_sel} parameters selected (thesis {n_th})", fontsize=10)
        ax.set_ylabel("polynomial order")
        ax.legend(fontsize=7)
    fig.suptitle(
        f"Exp. 5: orders by R²_adj >= {results['settings']['r2_adj_threshold']:g} (separable polynomials)",
        fontsize=10,
    )
    return save_png(fig, path)


def plot_cartesian_figures(
    series: Mapping[str, Any], results: Mapping[str, Any], out_dir: str | Path
) -> dict:
    """Write the protocol's figures into ``out_dir``; returns {key: path} of those written.

    ``convergence.png`` (Exp. 4 field error per sequence, with and without noise),
    ``k_maps.png`` (K̂ vs truth over the disc), ``force_prediction.png`` (Exp. 4) and
    ``orders.png`` (Exp. 5, polar vs Cartesian orders beside the thesis's).
    """
    out = Path(out_dir)
    written = {}
    if series.get("convergence"):
        written["convergence"] = _convergence(series, out / "convergence.png")
    if series.get("k_map"):
        written["k_maps"] = _k_maps(series, out / "k_maps.png")
    if series.get("force"):
        written["force_prediction"] = _force(series, out / "force_prediction.png")
    if results.get("exp5"):
        written["orders"] = _orders(results, out / "orders.png")
    return written
