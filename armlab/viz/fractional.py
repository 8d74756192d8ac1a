"""Figures, table and Rerun recording of the ``fractional_elbow`` protocol (Figs. 4–6, Table I of seeds/004).

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

__all__ = [
    "plot_bode_fits",
    "plot_bode_literature",
    "plot_time_overlay",
    "format_fractional_table",
]

DPI = 120
FFE = "fractional_five_element"
_TABLE_MODELS = ("27", "28", "29", "A", "B")
_COLOURS = {"27": "C0", "28": "C1", "29": "C2", "A": "C4", "B": "C5", FFE: "C3"}
_LIT_STYLES = {
    "Diaz": dict(color="tab:cyan", ls="-."),
    "Speich": dict(color="tab:orange", ls="-."),
    "Vlugt": dict(color="tab:green", ls="-."),
    "Fu": dict(color="tab:purple", ls="-."),
    "Tejado": dict(color="k", ls=":", lw=2.0),
}
_OUTSIDE = dict(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, borderaxespad=0.0)
_FIVE = ("M", "k1", "k2", "d1", "d2")
_FIVE_UNITS = {"M": "kg", "k1": "N/m", "k2": "N/m", "d1": "N·s/m", "d2": "N·s/m"}


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


def _num(value: Any) -> float | None:
    """``value`` as a finite float, or ``None`` if it is missing or not finite."""
    if value is None:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if np.isfinite(v) else None


def _order(value: Any) -> str:
    """A (commensurate or fractional) order with at least one and at most three decimals: "1.0", "1.25"."""
    v = _num(value)
    if v is None:
        return "—"
    text = f"{v:.3f}".rstrip("0")
    return text + "0" if text.endswith(".") else text


def _model_label(key: str) -> str:
    """``"(27)"`` for the paper's numbered models, ``"A"`` for the lettered ones."""
    if key == FFE:
        return "fractional five-element"
    return f"({key})" if key.isdigit() else key


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


def _ordered(keys: Sequence[str]) -> list[str]:
    """Table I order (27, 28, 29, A, B), then any other key, the fractional five-element last."""
    first = [k for k in _TABLE_MODELS if k in keys]
    rest = [k for k in keys if k not in _TABLE_MODELS and k != FFE]
    return first + rest + ([FFE] if FFE in keys else [])


def _ffe_best(results: Mapping[str, Any]) -> tuple[float | None, float | None]:
    """(best order β, MSE at β in (rad/N)²) of the fractional five-element sweep, if known."""
    frac = results.get(FFE) or {}
    beta = _num(frac.get("best_order"))
    mse = frac.get("mse")
    if mse is None or np.ndim(mse) == 0:
        return beta, _num(mse)
    orders = np.asarray(frac.get("orders") if frac.get("orders") is not None else [], dtype=float)
    mse = np.asarray(mse, dtype=float)
    if beta is None or orders.shape != mse.shape:
        return beta, None
    hit = np.flatnonzero(np.isclose(orders, beta))
    return beta, (_num(mse[hit[0]]) if hit.size else None)


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


# ---------------------------------------------------------------------------------------------
# table
# ---------------------------------------------------------------------------------------------


def _cell(value: Any, fmt: str, scale: float = 1.0) -> str:
    v = _num(value)
    return "—" if v is None else format(v * scale, fmt)


def format_fractional_table(results: Mapping[str, Any]) -> str:
    """Plain-text summary of the identification, like Table I of the paper, beside the paper's values.

    Rows: models (27), (28), (29), A, B and the fractional five-element model (those present);
    columns: α (β for the five-element model), MSE (×10⁻⁷ (rad/N)²), MAD (×10⁻⁴ rad/N), R², number
    of parameters, −3 dB bandwidth (Hz), time-domain VAF (%), the error of |Ĝ| against the true
    response where the run has a truth, and the paper's α, MSE, MAD, R² and #param (Table I). Below
    the table: the best fractional order β (and the true one), the force-tracking error of each
    trial, and the five-element fit with its relative errors where known. Missing values print
    as "—".

    Args:
        results: the protocol's results dict (see the module docstring).

    Returns:
        The table as one string (lines joined by newlines, no trailing newline).
    """
    models = results.get("models") or {}
    paper = results.get("paper_table_I") or {}
    vaf = results.get("time_vaf_pct") or {}
    frac = results.get(FFE) or {}
    keys = _ordered([k for k in models] + ([FFE] if frac else []))
    has_truth = any(_num((models.get(k) or {}).get("rel_rms_error_vs_truth")) is not None for k in keys)

    header = ["model", "α", "MSE", "MAD", "R²", "#par", "BW Hz", "VAF %"]
    if has_truth:
        header.append("|G| err %")
    header += ["|", "paper α", "MSE", "MAD", "R²", "#par"]
    rows = []
    for key in keys:
        if key == FFE:
            beta, mse = _ffe_best(results)
            entry = {**frac, **(frac.get("best_indices") or {}), "alpha": beta, "mse": mse}
        else:
            entry = models.get(key) or {}
        label = _model_label(key) if key != FFE else "frac. five-element"
        if entry.get("stable") is False:
            label += " UNSTABLE"
        row = [
            label,
            _order(entry.get("alpha")),
            _cell(entry.get("mse"), ".2f", 1e7),
            _cell(entry.get("mad"), ".2f", 1e4),
            _cell(entry.get("r2"), ".3f"),
            _cell(entry.get("n_params"), ".0f"),
            _cell(entry.get("bandwidth_hz"), ".2f"),
            _cell(vaf.get(key), ".1f"),
        ]
        if has_truth:
            row.append(_cell(entry.get("rel_rms_error_vs_truth"), ".1f", 100.0))
        p = paper.get(key) or {}
        row += [
            "|",
            _order(p.get("alpha")),
            _cell(p.get("mse"), ".2f", 1e7),
            _cell(p.get("mad"), ".2f", 1e4),
            _cell(p.get("r2"), ".2f"),
            _cell(p.get("n_params"), ".0f"),
        ]
        rows.append(row)
    widths = [max(len(r[j]) for r in [header, *rows]) for j in range(len(header))]

    def line(cells: Sequence[str]) -> str:
        return "  ".join(
            c.ljust(w) if j == 0 else c.rjust(w) for j, (c, w) in enumerate(zip(cells, widths, strict=True))
        )

    out = [
        "Identification summary (cf. Table I of the paper). MSE ×10⁻⁷ (rad/N)², MAD ×10⁻⁴ rad/N; "
        "BW: −3 dB bandwidth; VAF: time-domain variance accounted for.",
        line(header),
        "-" * len(line(header)),
        *(line(r) for r in rows),
    ]
    for key in keys:
        rej = (models.get(key) or {}).get("rejected_unstable") if key != FFE else None
        if rej:
            out.append(
                f"{_model_label(key)}: α = {_order(rej.get('alpha'))} fits better (MSE "
                f"{_cell(rej.get('mse'), '.2f', 1e7)}) but is unstable: rejected, the best stable α kept"
            )
    if results.get("stability_rule"):
        out.append(f"rule: {results['stability_rule']}")
    beta, true_beta = _num(frac.get("best_order")), _num(frac.get("true_order"))
    if beta is not None:
        out.append(
            f"best fractional order β = {_order(beta)}"
            + (f" (true {_order(true_beta)})" if true_beta is not None else "")
        )
    errors = [e for e in (_num(x) for x in (results.get("tracking_error") or [])) if e is not None]
    if errors:
        out.append("force-tracking error per trial: " + ", ".join(f"{100 * e:.1f} %" for e in errors))

    def params(d: Mapping[str, Any], units: Mapping[str, str] = _FIVE_UNITS) -> str:
        return ", ".join(f"{n} = {_cell(d.get(n), '.4g')} {units[n]}" for n in _FIVE if n in d)

    def rel(d: Mapping[str, Any]) -> str:
        return ", ".join(f"{n} {_cell(d.get(n), '.1f', 100.0)} %" for n in _FIVE if n in d)

    fe = results.get("five_element_fit")
    if fe:
        out.append("five-element fit (integer): " + params(fe))
        if results.get("five_element_rel_err"):
            out.append(
                "  rel. error vs the intrinsic truth (muscles, activations frozen): "
                + rel(results["five_element_rel_err"])
            )
        if results.get("five_element_rel_err_effective"):
            out.append(
                "  rel. error vs the effective truth (reflex included): "
                + rel(results["five_element_rel_err_effective"])
            )
    if frac.get("best"):
        units = {**_FIVE_UNITS, "d2": "N·s^β/m"}  # the springpot's coefficient
        out.append(f"fractional five-element fit (β = {_order(beta)}): " + params(frac["best"], units))
        if frac.get("rel_err"):
            out.append("  rel. error vs the intrinsic truth: " + rel(frac["rel_err"]))
    return "\n".join(out)
