"""Figures of the ``fractional_elbow`` protocol (Figs. 4–6 of seeds/004).

Table I's text is :mod:`armlab.viz.fractional_table`, the recording :mod:`armlab.viz.fractional_recording`.

Inputs are what :func:`armlab.protocols.fractional_elbow.experiment.estimate_fractional` returns, or the same
keys read back from a run directory:

``series`` (plain dict of arrays):

- ``f_hz`` (n,) Hz: the frequency grid of the measured response.
- ``G`` (n,) complex, rad/N: measured arm response θ/F (Eq. 22); ``coherence`` (n,) (unused here).
- ``G_true`` (n,) complex rad/N or ``None``: the simulation's true response (absent in real data).
- ``fits``: {key: (n,) complex rad/N} with any of ``27``, ``28``, ``29``, ``A``, ``B`` (the Levy fits
  of Table I) and ``fractional_five_element`` (the five-element model with a fractional order β).
- ``literature`` (optional): {name: (n,) complex rad/N} of Table II (``Diaz``, ``Speich``,
  ``Vlugt``, ``Fu``) and the paper's own model (30), ``Tejado``.
- ``time`` (optional): ``t_s`` (m,) s, ``force_N`` (m,) N, ``theta_rad`` (m,) rad (mean removed),
  ``models`` {key: (m,) rad}, ``vaf_pct`` {key: VAF %}.

``results`` (plain dict): ``models`` {key: ``alpha``, ``mse`` (rad/N)², ``mad`` rad/N, ``r2``,
``n_params``, ``bandwidth_hz``, optional ``rel_rms_error_vs_truth``}; ``fractional_five_element``
(``best_order``, ``orders``, ``cost``, ``mse``, optional ``true_order``, ``best``, ``rel_err``);
``time_vaf_pct``; ``paper_table_I``; ``tracking_error`` (per trial, fraction); optional
``five_element_fit`` (``M`` kg, ``k1``/``k2`` N/m, ``d1``/``d2`` N·s/m at the handle),
``five_element_rel_err`` and ``literature_bandwidth_hz``. Every key that only a simulation has
(truth, relative errors) may be missing.

Plots are written through matplotlib's object API with the Agg canvas (no pyplot, no display);
every writer takes a fresh path, never overwrites, and returns the path it wrote. ``rerun`` is
imported only by :mod:`armlab.viz.fractional_recording`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from armlab.errors import ConfigError, DataError
from armlab.viz._paths import save_png
from armlab.viz.fractional_table import FFE, _ffe_best, _model_label, _num, _order, _ordered

__all__ = [
    "plot_bode_fits",
    "plot_bode_literature",
    "plot_time_overlay",
]

DPI = 120
_COLOURS = {"27": "C0", "28": "C1", "29": "C2", "A": "C4", "B": "C5", FFE: "C3"}
_LIT_STYLES = {
    "Diaz": dict(color="tab:cyan", ls="-."),
    "Speich": dict(color="tab:orange", ls="-."),
    "Vlugt": dict(color="tab:green", ls="-."),
    "Fu": dict(color="tab:purple", ls="-."),
    "Tejado": dict(color="k", ls=":", lw=2.0),
}
_OUTSIDE = dict(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, borderaxespad=0.0)


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


def _response(series: Mapping[str, Any], key: str, n: int) -> np.ndarray | None:
    """``series[key]`` as a complex (n,) array, ``None`` if missing."""
    value = series.get(key)
    if value is None:
        return None
    arr = np.asarray(value, dtype=complex)
    if arr.shape != (n,):
        raise DataError(f"series[{key!r}] must have shape ({n},) like f_hz, got {arr.shape}")
    return arr


def _grid(series: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The frequency grid and the measured response, checked."""
    for key in ("f_hz", "G"):
        if series.get(key) is None:
            raise DataError(f"series has no {key!r}; keys are {sorted(series)}")
    f = np.asarray(series["f_hz"], dtype=float)
    if f.ndim != 1 or f.size == 0 or np.any(f <= 0):
        raise DataError(f"series['f_hz'] must be a non-empty 1-D array of positive Hz, got shape {f.shape}")
    G = _response(series, "G", f.size)
    assert G is not None
    return f, G


def _curves(series: Mapping[str, Any], group: str, n: int) -> dict[str, np.ndarray]:
    """{name: (n,) complex} of ``series[group]``, skipping ``None`` entries; ``{}`` if absent."""
    out = {}
    for name, value in (series.get(group) or {}).items():
        if value is None:
            continue
        arr = np.asarray(value, dtype=complex)
        if arr.shape != (n,):
            raise DataError(f"series[{group!r}][{name!r}] must have shape ({n},), got {arr.shape}")
        out[str(name)] = arr
    return out


def _fit_label(key: str, results: Mapping[str, Any] | None) -> str:
    """Legend text of a fitted model: structure key, α and R² (or β for the five-element sweep)."""
    results = results or {}
    if key == FFE:
        beta, mse = _ffe_best(results)
        text = "fractional five-element"
        if beta is not None:
            text += f" β={_order(beta)}"
        if mse is not None:
            text += f", MSE={mse:.3g}"
        return text
    entry = (results.get("models") or {}).get(key) or {}
    alpha, r2 = _num(entry.get("alpha")), _num(entry.get("r2"))
    extras = ([f"α={_order(alpha)}"] if alpha is not None else []) + (
        [f"R²={r2:.3f}"] if r2 is not None else []
    )
    return " ".join([_model_label(key), ", ".join(extras)]).strip()


def _bode_axes(title: str) -> tuple[Figure, Any, Any]:
    fig = Figure(figsize=(10.0, 6.6), layout="constrained")
    FigureCanvasAgg(fig)
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True)
    for ax in (ax_mag, ax_ph):
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _pos: f"{x:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
    ax_mag.set_ylabel("magnitude [dB re 1 rad/N]")
    ax_ph.set_ylabel("phase [deg]")
    ax_ph.set_xlabel("frequency [Hz]")
    fig.suptitle(title, fontsize=10)
    return fig, ax_mag, ax_ph


def _db(G: np.ndarray) -> np.ndarray:
    mag = np.abs(G)
    return 20.0 * np.log10(np.where(mag > 0, mag, np.nan))


def _phase_deg(G: np.ndarray) -> np.ndarray:
    return np.degrees(np.unwrap(np.angle(G)))


def _bode_line(ax_mag, ax_ph, f: np.ndarray, G: np.ndarray, label: str, **style) -> None:
    ax_mag.plot(f, _db(G), label=label, **style)
    ax_ph.plot(f, _phase_deg(G), **style)


def _measured(ax_mag, ax_ph, f: np.ndarray, G: np.ndarray) -> None:
    style = dict(ls="none", marker="o", ms=3.0, mfc="none", mec="0.35", mew=0.8)
    ax_mag.plot(f, _db(G), label="measured (Welch estimate)", **style)
    ax_ph.plot(f, _phase_deg(G), **style)


# ---------------------------------------------------------------------------------------------
# figures
# ---------------------------------------------------------------------------------------------


def plot_bode_fits(series: Mapping[str, Any], results: Mapping[str, Any] | None, path: str | Path) -> Path:
    """Bode plot of the measured response and every fitted model: Fig. 4 of the paper.

    Magnitude (dB of rad/N) and phase (deg) over log frequency. The measured response θ/F is drawn
    as open markers, each fit of ``series['fits']`` as a line labelled with its structure key, its
    commensurate order α and its R² (from ``results['models']``), the fractional five-element model
    with its order β; the simulation's true response (``series['G_true']``), where there is one,
    dashed black.

    Args:
        series: the protocol's series dict (see the module docstring); ``f_hz`` and ``G`` required.
        results: the protocol's results dict for the labels, or ``None`` (labels without indices).
        path: the ``.png`` file to write; must not exist.

    Returns:
        The written path.

    Raises:
        DataError: ``f_hz``/``G`` missing, a response of the wrong shape, or ``path`` exists.
    """
    f, G = _grid(series)
    fits = _curves(series, "fits", f.size)
    truth = _response(series, "G_true", f.size)
    fig, ax_mag, ax_ph = _bode_axes("Fig. 4: frequency responses of the identified models (θ/F)")
    _measured(ax_mag, ax_ph, f, G)
    for key in _ordered(list(fits)):
        lw = 1.8 if key == FFE else 1.3
        _bode_line(
            ax_mag, ax_ph, f, fits[key], _fit_label(key, results), color=_COLOURS.get(key), lw=lw, alpha=0.9
        )
    if truth is not None:
        _bode_line(ax_mag, ax_ph, f, truth, "ground truth (simulation)", color="k", ls="--", lw=1.3)
    ax_mag.legend(**_OUTSIDE)
    return save_png(fig, path)


def plot_bode_literature(
    series: Mapping[str, Any], path: str | Path, results: Mapping[str, Any] | None = None
) -> Path:
    """Bode plot of this run's model beside the arm models of the literature: Fig. 6 of the paper.

    Draws the measured response (markers), the identified integer model (27) and the fractional
    five-element model of this run, and every model of ``series['literature']`` (Table II: Diaz,
    Speich, Vlugt, Fu; the paper's own model (30), ``Tejado``, black dotted as in Fig. 6). A
    missing ``literature`` key leaves only this run's curves.

    Args:
        series: the protocol's series dict; ``f_hz`` and ``G`` required.
        path: the ``.png`` file to write; must not exist.
        results: optional results dict: adds α/R² of the fits and the −3 dB bandwidths
            (``results['literature_bandwidth_hz']``) to the labels.

    Returns:
        The written path.

    Raises:
        DataError: ``f_hz``/``G`` missing, a response of the wrong shape, or ``path`` exists.
    """
    f, G = _grid(series)
    fits = _curves(series, "fits", f.size)
    literature = _curves(series, "literature", f.size)
    bw = (results or {}).get("literature_bandwidth_hz") or {}
    fig, ax_mag, ax_ph = _bode_axes("Fig. 6: this run's models and arm models reported in the literature")
    _measured(ax_mag, ax_ph, f, G)
    for key in ("27", FFE):
        if key in fits:
            _bode_line(ax_mag, ax_ph, f, fits[key], _fit_label(key, results), color=_COLOURS[key], lw=1.8)
    for name in [n for n in _LIT_STYLES if n in literature] + [n for n in literature if n not in _LIT_STYLES]:
        label = "Tejado: paper's model (30), α=1.4" if name == "Tejado" else name
        b = _num(bw.get(name))
        if b is not None:
            label += f", BW {b:.2f} Hz"
        style = dict(lw=1.3)
        style.update(_LIT_STYLES.get(name, dict(ls="-.")))
        _bode_line(ax_mag, ax_ph, f, literature[name], label, **style)
    ax_mag.legend(**_OUTSIDE)
    return save_png(fig, path)


def plot_time_overlay(
    series: Mapping[str, Any],
    path: str | Path,
    seconds: float = 10.0,
    *,
    models: Sequence[str] | None = None,
) -> Path:
    """Measured elbow angle and every model's angle for the measured force: Fig. 5 of the paper.

    Shows the first ``seconds`` of ``series['time']`` (which already starts after the start-up
    transient): the measured angle θ (mean removed, black) and each model's steady-state angle for
    the same measured force (legend with its VAF %), in mrad; the force in a small panel below.

    Args:
        series: the protocol's series dict with a ``time`` entry (see the module docstring).
        path: the ``.png`` file to write; must not exist.
        seconds: length of the shown stretch, s (> 0).
        models: keys of ``series['time']['models']`` to draw (default: all, Table I order).

    Returns:
        The written path.

    Raises:
        ConfigError: ``seconds`` is not positive.
        DataError: ``series`` has no ``time`` entry, arrays disagree in length, or ``path`` exists.
    """
    if not (np.isfinite(seconds) and seconds > 0):
        raise ConfigError(f"seconds must be a positive number of s, got {seconds!r}")
    time = series.get("time")
    if not time:
        raise DataError(f"series has no 'time' entry (the time-domain overlay); keys are {sorted(series)}")
    for key in ("t_s", "theta_rad"):
        if time.get(key) is None:
            raise DataError(f"series['time'] has no {key!r}; keys are {sorted(time)}")
    t = np.asarray(time["t_s"], dtype=float)
    m = t.size
    if m == 0:
        raise DataError("series['time']['t_s'] is empty")

    def arr(value: Any, name: str) -> np.ndarray:
        a = np.asarray(value, dtype=float)
        if a.shape != (m,):
            raise DataError(f"series['time'][{name}] must have shape ({m},) like t_s, got {a.shape}")
        return a

    keep = t <= t[0] + seconds
    theta = arr(time["theta_rad"], "'theta_rad'")
    curves = {
        str(k): arr(v, f"'models'][{k!r}") for k, v in (time.get("models") or {}).items() if v is not None
    }
    names = _ordered(list(curves)) if models is None else [k for k in models if k in curves]
    vaf = time.get("vaf_pct") or {}
    force = time.get("force_N")

    fig = Figure(figsize=(12.0, 6.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax_th, ax_f = fig.subplots(2, 1, sharex=True, gridspec_kw=dict(height_ratios=[3, 1]))
    ax_th.plot(t[keep], 1e3 * theta[keep], color="k", lw=1.8, label="measured θ")
    for key in names:
        label = _model_label(key)
        v = _num(vaf.get(key))
        if v is not None:
            label += f", VAF {v:.1f} %"
        ax_th.plot(t[keep], 1e3 * curves[key][keep], color=_COLOURS.get(key), lw=1.0, alpha=0.85, label=label)
    ax_th.set_ylabel("angle θ [mrad]")
    ax_th.grid(True, alpha=0.3)
    ax_th.legend(**_OUTSIDE)
    if force is not None:
        ax_f.plot(t[keep], arr(force, "'force_N'")[keep], color="0.3", lw=0.9, label="measured force")
        ax_f.legend(**_OUTSIDE)
    ax_f.set_ylabel("force [N]")
    ax_f.set_xlabel("time in the trial [s]")
    ax_f.grid(True, alpha=0.3)
    fig.suptitle(
        f"Fig. 5: time responses of the identified models to the measured force "
        f"({t[0]:.1f}–{t[keep][-1]:.1f} s of the trial)",
        fontsize=10,
    )
    return save_png(fig, path)
