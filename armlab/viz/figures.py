"""Static figures of the conditioning-window experiment (Figs. 4, 5 and 6 of the paper).

Every function takes the plain ``results`` dict the ``conditioning_window`` protocol writes (also
found in ``results.json``) or a plain dict of arrays, and a ``.png`` path; it returns the path it
wrote. Existing files are never overwritten. Matplotlib is driven through its object API with the
Agg canvas (no pyplot, no display, no global state).

``results`` keys read here: ``windows`` (one dict per observation window with ``t_obs_s``,
``cond``, ``K``, ``D``, ``xi``, ``eig_Ks``, ``eig_Ds``, ``K_rel_err``, ``D_rel_err``,
``xi_rel_err``, ``K_true``, ``D_true``, ``xi_true`` and a ``reduced`` sub-dict with the same keys
for the reduced model), ``ground_truth`` (``K``, ``D``, ``xi``), ``paper`` (the thresholds the
paper reports, s) and ``criteria`` (this run's thresholds per model, s, or ``None``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from armlab.errors import ConfigError, DataError
from armlab.viz._paths import DPI, save_png
from armlab.viz._ticks import plain_log_ticks

__all__ = [
    "plot_window_sweep",
    "plot_validation",
    "plot_error_vs_window",
]

_MODELS = ("full", "reduced")
_ENTRY_COLOURS = ("C0", "C1", "C2", "C3")
_MATRIX_ENTRIES = ((0, 0), (0, 1), (1, 0), (1, 1))
# (key in results["paper"], key in results["criteria"][model], short label)
_THRESHOLDS = (
    ("K_pd_after_s", "K_pd_from_s", "K p.d."),
    ("symmetric_after_s", "symmetric_from_s", "symmetric"),
    ("constant_after_s", "constant_from_s", "constant"),
)
_THRESHOLD_COLOURS = ("tab:purple", "tab:brown", "tab:olive")
_OUTSIDE = dict(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, borderaxespad=0.0)


def _windows(results: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    windows = results.get("windows")
    if not windows:
        raise DataError("results has no 'windows' list; expected one dict per observation window")
    for i, w in enumerate(windows):
        if "t_obs_s" not in w:
            raise DataError(f"results['windows'][{i}] has no 't_obs_s'")
    return list(windows)


def _model_part(window: Mapping[str, Any], model: str) -> Mapping[str, Any]:
    if model == "full":
        return window
    part = window.get("reduced")
    if part is None:
        raise DataError(f"window k={window.get('k')} has no 'reduced' entry; cannot plot the reduced model")
    return part


def _check_model(model: str) -> None:
    if model not in _MODELS:
        raise ConfigError(f"model must be one of {list(_MODELS)}, got {model!r}")


def _as_float(value: Any, shape: tuple[int, ...]) -> np.ndarray:
    """Return ``value`` as a float array of ``shape``, all-NaN where it is missing (``None``)."""
    if value is None:
        return np.full(shape, np.nan)
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise DataError(f"expected an entry of shape {shape}, got {arr.shape}")
    return arr


def _series(parts: Sequence[Mapping[str, Any]], key: str, shape: tuple[int, ...]) -> np.ndarray:
    """Stack ``part[key]`` over windows into ``(n_windows, *shape)``, NaN where missing."""
    return np.stack([_as_float(p.get(key), shape) for p in parts])


def _truth(results: Mapping[str, Any], windows: Sequence[Mapping[str, Any]], key: str, shape) -> np.ndarray:
    """Ground truth per window: ``window[key + '_true']``, else ``results['ground_truth'][key]``."""
    fallback = (results.get("ground_truth") or {}).get(key)
    return np.stack([_as_float(w.get(f"{key}_true", fallback), shape) for w in windows])


def _new_figure(n_rows: int, height_per_row: float, width: float = 9.5) -> tuple[Figure, np.ndarray]:
    fig = Figure(figsize=(width, 0.8 + height_per_row * n_rows), dpi=DPI)  # measured as saved
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(n_rows, 1, sharex=True))
    return fig, axes


_PAD_PX = 10.0  # px at DPI 120 (~0.08 in), margin around the measured labels and legends


def _fit_margins(fig: Figure, axes: np.ndarray) -> None:
    """Set the margins from the measured extents of labels, tick labels, legends and title.

    A layout engine would measure every axes twice and savefig would then draw the figure twice;
    measuring once here and drawing once in savefig halves the figure's cost. The stacked panels
    (one column, shared x) keep their order; the gap between panels fits the tallest overhang.
    """
    renderer = fig.canvas.get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    boxes = [(ax.get_position().transformed(fig.transFigure), ax.get_tightbbox(renderer)) for ax in axes]
    left = max(pos.x0 - tight.x0 for pos, tight in boxes) + _PAD_PX
    right = max(tight.x1 - pos.x1 for pos, tight in boxes) + 2 * _PAD_PX
    below = [pos.y0 - tight.y0 for pos, tight in boxes]
    above = [tight.y1 - pos.y1 for pos, tight in boxes]
    title = 0.0
    if fig._suptitle is not None:  # the title hangs from the top edge, the panels below it
        fig._suptitle.set(y=1.0 - _PAD_PX / height, va="top")
        title = fig._suptitle.get_window_extent(renderer).height + _PAD_PX
    top = max(above[0], 0.0) + title + 2 * _PAD_PX
    bottom = max(below[-1], 0.0) + _PAD_PX
    gap = max([b + a for b, a in zip(below[:-1], above[1:], strict=True)] + [0.0]) + _PAD_PX
    n = len(axes)
    panel = (height - top - bottom - (n - 1) * gap) / n
    fig.subplots_adjust(
        left=left / width,
        right=1.0 - right / width,
        bottom=bottom / height,
        top=1.0 - top / height,
        hspace=gap / panel if n > 1 else 0.0,
    )


def _threshold_lines(axes: np.ndarray, results: Mapping[str, Any], model: str | None) -> None:
    """Mark the paper's thresholds (dotted) and this run's (dash-dot) on every panel, in ms."""
    paper = results.get("paper") or {}
    run = ((results.get("criteria") or {}).get(model) or {}) if model else {}
    for (paper_key, run_key, label), colour in zip(_THRESHOLDS, _THRESHOLD_COLOURS, strict=True):
        for value, style, who in ((paper.get(paper_key), ":", "paper"), (run.get(run_key), "-.", "run")):
            if value is None or not np.isfinite(value):
                continue
            x_ms = 1e3 * float(value)
            for j, ax in enumerate(axes):
                ax.axvline(
                    x_ms,
                    color=colour,
                    ls=style,
                    lw=1.1,
                    label=f"{who}: {label} ({x_ms:.0f} ms)" if j == 0 else None,
                )


def _entry_panel(ax, x_ms, est, truth, names, unit: str) -> None:
    """Estimated entries as markers+line, their truth as dashed lines in the same colour."""
    for j, name in enumerate(names):
        colour = _ENTRY_COLOURS[j % len(_ENTRY_COLOURS)]
        ax.plot(x_ms, est[:, j], "o-", color=colour, ms=3.5, lw=1.2, label=name)
        if np.any(np.isfinite(truth[:, j])):
            ax.plot(x_ms, truth[:, j], "--", color=colour, lw=1.0, alpha=0.8)
    ax.set_ylabel(unit)
    ax.legend(**_OUTSIDE, title="markers: estimate\ndashed: truth", title_fontsize=7)
    ax.grid(True, alpha=0.3)


def plot_window_sweep(
    results: Mapping[str, Any], path: str | Path, model: str = "full", eigenvalues: bool = True
) -> Path:
    """Plot the estimates over the length of the observation window: Fig. 4 or Fig. 5.

    ``model="full"`` reproduces Fig. 4 (condition number, K, D and the inertial parameters ξ over
    T_obs); ``model="reduced"`` reproduces Fig. 5 (condition number, K and D with ξ fixed).
    Ground truth is drawn dashed in the colour of its entry; vertical lines mark the paper's
    thresholds (K positive definite after 320 ms, quasi-symmetric after 370 ms, quasi-constant
    after 400 ms; Sec. IV-D) and this run's own ``criteria`` thresholds.

    Args:
        results: the protocol's results dict (see the module docstring).
        path: the ``.png`` file to write; must not exist.
        model: ``"full"`` (Fig. 4) or ``"reduced"`` (Fig. 5).
        eigenvalues: add panels with eig(K_s) and eig(D_s), K_s = (K + Kᵀ)/2 (Sec. IV-D).

    Returns:
        The written path.

    Raises:
        ConfigError: ``model`` is not one of ``"full"``, ``"reduced"``.
        DataError: ``results`` lacks windows, or ``path`` exists.
    """
    _check_model(model)
    windows = _windows(results)
    parts = [_model_part(w, model) for w in windows]
    x_ms = 1e3 * np.array([float(w["t_obs_s"]) for w in windows])

    def flat(m: np.ndarray) -> np.ndarray:
        return m.reshape(len(m), 4)

    panels = (
        ["cond", "K", "D"] + (["xi"] if model == "full" else []) + (["eigK", "eigD"] if eigenvalues else [])
    )
    fig, axes = _new_figure(len(panels), 1.9)
    for ax, panel in zip(axes, panels, strict=True):
        if panel == "cond":
            ax.semilogy(x_ms, _series(parts, "cond", ()), "ko-", ms=3.5, lw=1.2, label="cond(W)")
            ax.set_ylabel("cond(W)")
            plain_log_ticks(ax.yaxis)
            ax.grid(True, which="both", alpha=0.3)
        elif panel in ("K", "D"):
            unit = "N·m/rad" if panel == "K" else "N·m·s/rad"
            _entry_panel(
                ax,
                x_ms,
                flat(_series(parts, panel, (2, 2))),
                flat(_truth(results, windows, panel, (2, 2))),
                [f"{panel}{i + 1}{j + 1}" for i, j in _MATRIX_ENTRIES],
                f"{panel} [{unit}]",
            )
        elif panel == "xi":
            _entry_panel(
                ax,
                x_ms,
                _series(parts, "xi", (3,)),
                _truth(results, windows, "xi", (3,)),
                ["ξ1", "ξ2", "ξ3"],
                "ξ [kg·m²]",
            )
        else:
            key, sym, unit = ("eig_Ks", "K", "N·m/rad") if panel == "eigK" else ("eig_Ds", "D", "N·m·s/rad")
            eig = _series(parts, key, (2,))
            for j in range(2):
                ax.plot(
                    x_ms, eig[:, j], "s-", color=_ENTRY_COLOURS[j], ms=3, lw=1.0, label=f"λ{j + 1}({sym}_s)"
                )
            ax.axhline(0.0, color="k", lw=0.8)
            ax.set_ylabel(f"eig({sym}_s) [{unit}]")
            ax.legend(**_OUTSIDE)
            ax.grid(True, alpha=0.3)
    _threshold_lines(axes, results, model)
    axes[0].legend(**_OUTSIDE)
    axes[-1].set_xlabel("length of the observation interval T_obs [ms]")
    fig_no = "Fig. 4" if model == "full" else "Fig. 5"
    what = "full model (K, D, ξ estimated)" if model == "full" else "reduced model (ξ fixed)"
    fig.suptitle(f"{fig_no}: estimates over T_obs, {what}", fontsize=10)
    _fit_margins(fig, axes)
    return save_png(fig, path)


def plot_validation(series: Mapping[str, Any], path: str | Path) -> Path:
    """Plot Δτ_ext of a validation trial, measured and predicted by both models: Fig. 6.

    Args:
        series: ``t_s`` (n,) s; ``dtau_measured``, ``dtau_full``, ``dtau_reduced`` (n, 2) N·m, the
            joint-torque deviations Δτ_ext = τ_ext − τ_0 (Sec. IV-C); ``t_obs_s`` float s, the end
            of the observation window (marked). A missing prediction is skipped.
        path: the ``.png`` file to write; must not exist.

    Returns:
        The written path.

    Raises:
        DataError: a required key is missing or arrays have inconsistent shapes, or ``path`` exists.
    """
    for key in ("t_s", "dtau_measured"):
        if key not in series:
            raise DataError(f"validation series has no {key!r}; keys are {sorted(series)}")
    t_ms = 1e3 * np.asarray(series["t_s"], dtype=float)
    n = t_ms.shape[0]
    curves = []
    for key, label, style in (
        ("dtau_measured", "measured", dict(color="k", lw=1.6)),
        ("dtau_full", "predicted, full model", dict(color="C0", ls="--", lw=1.3)),
        ("dtau_reduced", "predicted, reduced model", dict(color="C3", ls="-.", lw=1.3)),
    ):
        if series.get(key) is None:
            continue
        arr = np.asarray(series[key], dtype=float)
        if arr.shape != (n, 2):
            raise DataError(f"validation series {key!r} must have shape ({n}, 2), got {arr.shape}")
        curves.append((arr, label, style))
    fig, axes = _new_figure(2, 2.4)
    t_obs = series.get("t_obs_s")
    for j, ax in enumerate(axes):
        for arr, label, style in curves:
            ax.plot(t_ms, arr[:, j], label=label, **style)
        if t_ms.min() <= 0.0 <= t_ms.max():
            ax.axvline(0.0, color="0.5", lw=0.8, ls=":", label="onset t_p" if j == 0 else None)
        if t_obs is not None:
            ax.axvline(
                1e3 * float(t_obs),
                color="tab:purple",
                lw=1.1,
                ls="--",
                label=f"window end t_e (T_obs = {1e3 * float(t_obs):.0f} ms)" if j == 0 else None,
            )
        ax.set_ylabel(f"Δτ{j + 1} [N·m]")
        ax.grid(True, alpha=0.3)
    axes[0].legend(**_OUTSIDE)
    axes[-1].set_xlabel("t − t_p [ms]")
    fig.suptitle("Fig. 6: prediction of Δτ_ext for a trial not used in the training set", fontsize=10)
    _fit_margins(fig, axes)
    return save_png(fig, path)


def plot_error_vs_window(results: Mapping[str, Any], path: str | Path) -> Path:
    """Plot the relative errors of K, D and ξ against the truth over T_obs, for both models.

    Relative errors are as the protocol reports them (``K_rel_err`` etc., dimensionless); the
    reduced model has no ξ error (ξ is fixed). Log scale; the paper's thresholds are marked.

    Args:
        results: the protocol's results dict (see the module docstring).
        path: the ``.png`` file to write; must not exist.

    Returns:
        The written path.

    Raises:
        DataError: ``results`` lacks windows, or ``path`` exists.
    """
    windows = _windows(results)
    x_ms = 1e3 * np.array([float(w["t_obs_s"]) for w in windows])
    has_reduced = all(w.get("reduced") is not None for w in windows)
    fig, axes = _new_figure(3, 2.0)
    for ax, key, name in zip(axes, ("K_rel_err", "D_rel_err", "xi_rel_err"), ("K", "D", "ξ"), strict=True):
        err = _series(windows, key, ())
        ax.semilogy(
            x_ms, np.where(err > 0, err, np.nan), "o-", color="C0", ms=3.5, lw=1.2, label="full model"
        )
        if has_reduced and key != "xi_rel_err":
            red = _series([w["reduced"] for w in windows], key, ())
            ax.semilogy(
                x_ms,
                np.where(red > 0, red, np.nan),
                "s--",
                color="C3",
                ms=3.5,
                lw=1.2,
                label="reduced model (ξ fixed)",
            )
        ax.set_ylabel(f"rel. error of {name} [-]")
        plain_log_ticks(ax.yaxis)
        ax.grid(True, which="both", alpha=0.3)
    _threshold_lines(axes, results, None)
    for ax in axes:
        ax.legend(**_OUTSIDE)
    axes[-1].set_xlabel("length of the observation interval T_obs [ms]")
    fig.suptitle("Relative estimation error against the simulation's ground truth", fontsize=10)
    _fit_margins(fig, axes)
    return save_png(fig, path)
