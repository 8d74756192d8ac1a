"""Table and figures of the 5-DoF stiffness protocol (seeds/001: calibration, inertial, stiffness, EMG).

- :func:`format_stiffness5_table`: the calibration stage's centre errors and IK RMS, the inertial
  stage's xi_red errors and held-out gravity RMS (when they ran), which chain and xi_red the
  stiffness stage used; per pre-load condition the relative error of K̂_q against the truth, its
  smallest eigenvalue, the ellipsoid's major-axis error and its angle to the pre-load; then spec
  001's acceptance checks with their tolerances; the EMG maps' NRMSE when that stage ran.
- :func:`plot_stiffness5_figures`: ``kq_per_condition.png`` (the 15 unique entries of K_q per
  condition: estimate with the least-squares standard error against the truth) and
  ``ellipsoids_xz.png`` (the Fig. 3 stiffness ellipsoids projected on the X-Z plane, at each
  condition's pre-load force, estimate against truth) and, when the EMG stage ran,
  ``emg_nrmse.png`` (the EMG maps' NRMSE, network against linear, under both splits, beside the
  paper's 0.3378 and 0.39; spec 001 check 8).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from armlab.errors import DataError
from armlab.viz._paths import save_png

__all__ = ["format_stiffness5_table", "plot_stiffness5_figures"]

_JOINTS = ("sh flex", "sh abd", "sh rot", "elbow", "pron")


def format_stiffness5_table(results: Mapping[str, Any]) -> str:
    """The results of a stiffness-stage run as text (module docstring)."""
    rows = results.get("conditions") or []
    if not rows:
        raise DataError("results hold no condition to tabulate")
    truth = results.get("truth", "intrinsic")
    lines = []
    cal, inr = results.get("calibration"), results.get("inertial")
    if cal:
        lines.append(
            f"kinematic calibration ({cal['n_frames']} marker frames, {cal['n_held_out']} held out): "
            f"shoulder {1e3 * cal['shoulder_error_m']:.3f} mm, elbow {1e3 * cal['elbow_error_m']:.3f} mm, "
            f"wrist offset {1e3 * cal['wrist_offset_error_m']:.3f} mm from the truth; IK on the held-out "
            f"motion {cal['ik_rms_deg']:.3g} deg RMS"
        )
    if inr:
        worst = int(np.argmax(inr["xi_relative_error"]))
        lines.append(
            f"inertial trials ({inr['n_configurations']} configurations): xi_red largest relative error "
            f"{100 * inr['xi_relative_error'][worst]:.3g} % ({inr['names'][worst]}; m_total, c_x, c_y "
            f"also absorb the base sensor's offset), of the arm's first moments u, s "
            f"{100 * inr['arm_xi_max_relative_error']:.3g} %; gravity torque on {inr['n_held_out']} "
            f"held-out configurations {inr['gravity_rms_Nm']:.3g} N m RMS"
        )
    inputs = results.get("stiffness_inputs")
    if inputs:
        lines.append(f"stiffness stage used: chain {inputs['chain']}; xi_red {inputs['xi_red']}")
    lines += [
        f"K_q per condition ({results.get('sensor_preset', '?')} sensors; truth: {truth})",
        "  condition  trials  |K-K_true|/|K_true|  lambda_min  major axis err  to pre-load (est / true)",
    ]
    for r in rows:
        lines.append(
            f"  {r['condition']:9s}  {r['n_trials']:6d}  {100 * r['rel_error']:17.2f} %  "
            f"{r['min_eigenvalue_Nm_per_rad']:10.2f}  {r['major_axis_error_deg']:12.2f} deg  "
            f"{r['major_axis_to_preload_deg']:6.1f} / {r['true_major_axis_to_preload_deg']:.1f} deg"
        )
        if "diag_bias_vs_intrinsic_Nm_per_rad" in r:
            lines.append(
                "             diagonal K_hat - K_intrinsic (N m/rad): "
                + " ".join(f"{v:+.2f}" for v in r["diag_bias_vs_intrinsic_Nm_per_rad"])
            )
    emg = results.get("emg")
    if emg:
        paper = emg["paper"]
        lines.append(
            f"EMG maps ({emg['n_windows']} windows of {emg['window_samples']} samples; NRMSE network / "
            f"linear; "
            f"paper {paper['network_nrmse']:.4g} / never <= {paper['linear_nrmse_at_best']:g}, ratio <= "
            f"{paper['network_nrmse'] / paper['linear_nrmse_at_best']:.3f})"
        )
        for label, key in (
            ("random windows", "random_windows"),
            ("leave one condition out", "leave_one_condition_out"),
        ):
            sp = emg[key]
            lines.append(
                f"  {label:24s} {sp['network_nrmse']:.4f} / {sp['linear_nrmse']:.4f}  "
                f"ratio {sp['ratio']:.3f}  "
                f"(vs the true K_q: {sp['network_nrmse_vs_truth']:.4f} / {sp['linear_nrmse_vs_truth']:.4f})"
            )
    lines.append("spec 001 acceptance checks")
    for c in results.get("checks", []):
        mark = "PASS" if c["passed"] else "FAIL"
        lines.append(f"  {c['check']}  {c['what']}: {c['value']:.4g} (tolerance {c['tolerance']:g})  {mark}")
    return "\n".join(lines)


def _plot_kq(series: Mapping[str, Any]) -> Figure:
    names = list(series["names"])
    k_hat, k_true = np.asarray(series["K_hat"]), np.asarray(series["K_true"])
    k_std = np.asarray(series["K_ls_std"])
    x = np.arange(len(names))
    fig = Figure(figsize=(13, 11), constrained_layout=True)
    axes = fig.subplots(5, 5, sharex=True)
    for i in range(5):
        for j in range(5):
            ax = axes[i, j]
            if j < i:
                ax.set_axis_off()
                continue
            ax.plot(x, k_true[:, i, j], "s", color="0.55", ms=6, label="truth")
            ax.errorbar(
                x,
                k_hat[:, i, j],
                yerr=k_std[:, i, j],
                fmt="o",
                color="tab:orange",
                ms=4,
                label="SPD estimate",
            )
            ax.set_title(f"K[{_JOINTS[i]}, {_JOINTS[j]}]", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.set_xticks(x, names, rotation=90, fontsize=7)
    axes[0, 0].set_ylabel("N m/rad")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("Joint stiffness K_q per pre-load condition: SPD estimate (± LS standard error) vs truth")
    return fig


def _plot_ellipses(series: Mapping[str, Any]) -> Figure:
    names = list(series["names"])
    hat, true = np.asarray(series["ellipse_hat"]), np.asarray(series["ellipse_true"])
    forces = np.asarray(series["forces"])
    fig = Figure(figsize=(7, 7), constrained_layout=True)
    ax = fig.add_subplot()
    colours = [f"C{c % 10}" for c in range(len(names))]
    for c, name in enumerate(names):
        ax.plot(true[c, :, 0], true[c, :, 1], "--", color="0.5", lw=1.0, label="truth" if c == 0 else None)
        ax.plot(hat[c, :, 0], hat[c, :, 1], color=colours[c], lw=1.5, label=name)
        ax.plot(forces[c, 0], forces[c, 2], "+", color=colours[c])
    ax.set_aspect("equal")
    ax.set_xlabel("F_x (N)")
    ax.set_ylabel("F_z (N)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title("Stiffness ellipsoids (5 mm sphere) in the X-Z plane at each pre-load (cf. Fig. 3)")
    return fig


def _plot_emg_nrmse(emg: Mapping[str, Any]) -> Figure:
    splits = list(emg["splits"])
    x = np.arange(len(splits))
    fig = Figure(figsize=(7, 4.5), constrained_layout=True)
    ax = fig.add_subplot()
    net, lin = np.asarray(emg["network"]), np.asarray(emg["linear"])
    ax.bar(x - 0.18, net, 0.36, color="tab:orange", label=f"network ({emg['hidden']} softplus, K = L L^T)")
    ax.bar(x + 0.18, lin, 0.36, color="tab:blue", label="linear (ridge)")
    for i in range(len(splits)):
        ax.text(x[i], max(net[i], lin[i]) * 1.02, f"ratio {net[i] / lin[i]:.3f}", ha="center", fontsize=8)
    paper_net, paper_lin = emg["paper_network"], emg["paper_linear"]
    ax.axhline(paper_net, color="tab:orange", ls="--", lw=1, label=f"paper: network {paper_net:.4g}")
    ax.axhline(paper_lin, color="tab:blue", ls=":", lw=1, label=f"paper: linear never <= {paper_lin:g}")
    ax.set_xticks(x, splits)
    ax.set_ylabel("NRMSE (mean over entries of RMSE / std)")
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(
        f"EMG -> K_q on the test set: network vs linear (paper ratio <= {paper_net / paper_lin:.3f})"
    )
    return fig


def plot_stiffness5_figures(series: Mapping[str, Any], out_dir: str | Path) -> dict[str, Path]:
    """Write ``kq_per_condition.png``, ``ellipsoids_xz.png`` and, with the EMG stage,
    ``emg_nrmse.png`` into ``out_dir``.

    Args:
        series: ``names`` (n_c,), ``K_hat``/``K_ls_std``/``K_true`` (n_c, 5, 5) N m/rad,
            ``forces`` (n_c, 3) N, ``ellipse_hat``/``ellipse_true`` (n_c, m, 2) N X-Z outlines;
            optional ``emg``: ``splits``, ``network``/``linear`` NRMSE per split, ``paper_network``,
            ``paper_linear``.
        out_dir: the run directory (the files must not exist).

    Returns:
        ``{"kq_per_condition": path, "ellipsoids_xz": path}`` (and ``"emg_nrmse": path``).
    """
    out = Path(out_dir)
    written = {
        "kq_per_condition": save_png(_plot_kq(series), out / "kq_per_condition.png"),
        "ellipsoids_xz": save_png(_plot_ellipses(series), out / "ellipsoids_xz.png"),
    }
    if series.get("emg"):
        written["emg_nrmse"] = save_png(_plot_emg_nrmse(series["emg"]), out / "emg_nrmse.png")
    return written
