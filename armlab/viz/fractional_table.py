"""Table I of seeds/004 as text: the ``fractional_elbow`` identification beside the paper's values.

Reads the protocol's ``results`` dict (keys listed in :mod:`armlab.viz.fractional`); every key
that only a simulation has may be missing and prints as "—". Also holds the small formatting
helpers the figures and the recording share (number coercion, order and model labels, Table I's
row order).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["FFE", "format_fractional_table"]

FFE = "fractional_five_element"
_TABLE_MODELS = ("27", "28", "29", "A", "B")
_FIVE = ("M", "k1", "k2", "d1", "d2")
_FIVE_UNITS = {"M": "kg", "k1": "N/m", "k2": "N/m", "d1": "N·s/m", "d2": "N·s/m"}


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
