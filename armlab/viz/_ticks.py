"""Plain-text tick labels for logarithmic axes.

Matplotlib labels a log axis with mathtext (``$\\mathdefault{10^{-2}}$``), and parsing each new
label costs ~15 ms: about 0.5 s of the conditioning protocol's four figures went to it. The labels
here are plain Unicode text ("10⁻²", "2×10⁻²"), laid out like any other text.
"""

from __future__ import annotations

import math

from matplotlib.axis import Axis
from matplotlib.ticker import Formatter

__all__ = [
    "plain_log_ticks",
]

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
# a value is a power of ten when its mantissa is 1 to within this (floating-point tick positions)
_DECADE_TOL = 1e-6
# decades visible below which every minor tick is labelled (matplotlib's minor_thresholds[1])
_ALL_MINOR_DECADES = 0.4


def _power(exponent: int) -> str:
    return "10" + str(exponent).translate(_SUPERSCRIPT)


class _LogLabels(Formatter):
    """Decades as "10ⁿ"; with ``minor``, the ticks between them by matplotlib's own rule for log
    labels: none where the view holds more than one decade tick, the 2×, 3×, 4× and 6× ones
    ("2×10ⁿ") where it spans more than 0.4 decade, every one below that (also "3.1×10ⁿ")."""

    def __init__(self, minor: bool) -> None:
        self.minor = minor

    def __call__(self, x: float, pos: int | None = None) -> str:
        if not (math.isfinite(x) and x > 0):
            return ""
        exponent = math.floor(math.log10(x) + _DECADE_TOL)
        mantissa = x / 10.0**exponent
        if abs(mantissa - 1.0) < _DECADE_TOL:
            return "" if self.minor else _power(exponent)
        if not self.minor or self.axis is None:
            return ""
        lo, hi = sorted(self.axis.get_view_interval())
        if lo <= 0:
            return ""
        l_lo, l_hi = math.log10(lo), math.log10(hi)
        decade_ticks = math.floor(l_hi) - math.floor(math.nextafter(l_lo, -math.inf))
        if decade_ticks > 1:
            return ""
        whole = abs(mantissa - round(mantissa)) < _DECADE_TOL
        if l_hi - l_lo > _ALL_MINOR_DECADES and not (whole and round(mantissa) in (2, 3, 4, 6)):
            return ""
        return f"{round(mantissa, 6):g}×{_power(exponent)}"


def plain_log_ticks(axis: Axis) -> None:
    """Label the log-scaled ``axis`` (``ax.xaxis`` or ``ax.yaxis``) with plain-text powers of ten."""
    axis.set_major_formatter(_LogLabels(minor=False))
    axis.set_minor_formatter(_LogLabels(minor=True))
