"""Bode figure of joint-impedance fits of real recordings (``armlab fit-joint``).

Input: ``{trial name: series}`` as returned by :func:`armlab.protocols.joint_1dof.frf.fit_joint_frf`
(``f_hz``, complex ``Z`` in N·m/rad, ``Z_fits`` with ``integer`` and ``fractional``). One column
per trial: magnitude (dB re 1 N·m/rad) above, phase (deg) below; measured points, the integer
``I s² + B s + K`` fit and the fractional ``I s² + B s^alpha + K`` fit.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from armlab.errors import DataError
from armlab.viz._paths import DPI, fresh_path, save_png
from armlab.viz._ticks import plain_log_ticks

__all__ = ["plot_joint_bode"]

_FITS = (("integer", "C0", "I s² + B s + K"), ("fractional", "C3", "I s² + B s^α + K"))


def plot_joint_bode(series: Mapping[str, Mapping], path: str | Path) -> Path:
    """Write the impedance Bode plot of every trial; returns the path written (never overwrites)."""
    if not series:
        raise DataError("plot_joint_bode needs at least one trial's series")
    path = fresh_path(path, ".png")
    n = len(series)
    fig = Figure(figsize=(3.2 * n + 0.6, 5.2), dpi=DPI, layout="constrained")
    axes = fig.subplots(2, n, sharex=True, squeeze=False)
    for col, (name, s) in enumerate(series.items()):
        f, Z = np.asarray(s["f_hz"]), np.asarray(s["Z"])
        mag, ph = axes[0, col], axes[1, col]
        mag.semilogx(f, 20 * np.log10(np.abs(Z)), ".", color="0.4", ms=3, label="measured")
        ph.semilogx(f, np.degrees(np.unwrap(np.angle(Z))), ".", color="0.4", ms=3)
        for key, colour, label in _FITS:
            if key in s.get("Z_fits", {}):
                Zf = np.asarray(s["Z_fits"][key])
                mag.semilogx(f, 20 * np.log10(np.abs(Zf)), color=colour, lw=1.4, label=label)
                ph.semilogx(f, np.degrees(np.unwrap(np.angle(Zf))), color=colour, lw=1.4)
        mag.set_title(name)
        plain_log_ticks(mag.xaxis)
        plain_log_ticks(ph.xaxis)
        mag.grid(True, which="both", alpha=0.3)
        ph.grid(True, which="both", alpha=0.3)
        ph.set_xlabel("frequency (Hz)")
    axes[0, 0].set_ylabel("|Z| (dB re 1 N·m/rad)")
    axes[1, 0].set_ylabel("phase (deg)")
    axes[0, 0].legend(fontsize=7)
    return save_png(fig, path)
