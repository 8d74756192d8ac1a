"""Coloured Gaussian noise: white noise through a Butterworth filter, at unit stationary rms.

The simulators' slow random processes (a subject's activation fluctuation, a rig's torque
disturbance) and the EMG carrier are drawn here: ``rng.standard_normal`` in row order, lengthened
by a filtered and dropped burn-in, divided by the filter's exact white-noise gain, and drawn and
filtered in row blocks on two threads, bit-identical to one draw filtered at once
(:func:`lowpass_noise`). Moved from :mod:`armlab.dsp` unchanged (session 26).
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy import signal

from armlab.cpus import usable_cpus
from armlab.dsp import butterworth
from armlab.errors import ConfigError

__all__ = ["bandpass_noise", "lowpass_noise"]


def lowpass_noise(
    rng: np.random.Generator,
    shape: tuple[int, ...],
    fs_hz: float,
    corner_hz: float,
    *,
    burn_in_periods: float,
    name: str = "corner_hz",
) -> np.ndarray:
    """Unit-rms Gaussian noise through a 2nd-order Butterworth low-pass, stationary from sample 0.

    White noise of ``shape`` (time on axis 1), lengthened by a burn-in of
    ``burn_in_periods / corner_hz`` s that is filtered and dropped, is drawn by
    ``rng.standard_normal`` in row order and divided by the filter's exact white-noise gain (the
    rms of its impulse response over 20 corner periods), so its stationary rms is 1.

    The rows (axis 0) are drawn and filtered in blocks of about :data:`_BLOCK_SIZE` elements, the
    next block drawn while the last one is filtered on a second thread (SciPy releases the GIL):
    the generator fills an array in C order one normal after another, and every row is filtered
    alone, so the result is bit-identical to one ``standard_normal`` call of the whole lengthened
    shape filtered at once, without the whole burn-in ever in memory.

    Raises:
        ConfigError: ``corner_hz`` not in (0, fs_hz / 2), the message naming it as ``name``.
    """
    if not 0 < corner_hz < fs_hz / 2:
        raise ConfigError(f"{name} must lie in (0, {fs_hz / 2}) Hz (Nyquist), got {corner_hz}")
    return _filtered_noise(rng, shape, fs_hz, butterworth(corner_hz, fs_hz, 2), corner_hz, burn_in_periods)


def bandpass_noise(
    rng: np.random.Generator,
    shape: tuple[int, ...],
    fs_hz: float,
    band_hz: tuple[float, float],
    *,
    order: int = 2,
    burn_in_periods: float = 5.0,
    name: str = "band_hz",
) -> np.ndarray:
    """Unit-rms Gaussian noise through a Butterworth band-pass, stationary from sample 0.

    As :func:`lowpass_noise` (same drawing order, blocks and threads, burn-in dropped, divided by
    the exact white-noise gain so the stationary rms is 1), with the band-pass
    :func:`butterworth` ``(band_hz, fs_hz, order, btype="bandpass")`` (2 ``order`` poles, -3 dB at
    both edges); the burn-in and the gain's impulse response are counted in periods of the lower
    edge (the slowest poles).

    Args:
        rng: the only source of randomness.
        shape: (n_rows, n_samples, ...) the output's shape, time on axis 1.
        fs_hz: Hz, sample rate. band_hz: (low, high) Hz, the -3 dB edges.
        order: Butterworth order (>= 1). burn_in_periods: periods of ``band_hz[0]`` dropped.

    Raises:
        ConfigError: the band not ``0 < low < high < fs_hz / 2`` (the message naming ``name``) or
            ``order`` not a positive integer.
    """
    lo, hi = (float(b) for b in band_hz)
    if not 0 < lo < hi < fs_hz / 2:
        raise ConfigError(
            f"{name} must be (low, high) Hz with 0 < low < high < {fs_hz / 2} (Nyquist), got {band_hz}"
        )
    if not (isinstance(order, (int, np.integer)) and order >= 1):
        raise ConfigError(f"the band-pass order must be an integer >= 1, got {order!r}")
    sos = butterworth((lo, hi), fs_hz, int(order), btype="bandpass")
    return _filtered_noise(rng, shape, fs_hz, sos, lo, burn_in_periods)


def _filtered_noise(
    rng: np.random.Generator,
    shape: tuple[int, ...],
    fs_hz: float,
    sos: np.ndarray,
    slow_hz: float,
    burn_in_periods: float,
) -> np.ndarray:
    """White noise filtered by ``sos`` along axis 1 at unit stationary rms (see :func:`lowpass_noise`):
    burn-in and impulse response counted in periods of ``slow_hz``."""
    n_burn = int(math.ceil(burn_in_periods * fs_hz / slow_hz))
    impulse = np.zeros(int(math.ceil(20.0 * fs_hz / slow_hz)))
    impulse[0] = 1.0
    gain = math.sqrt(float(np.sum(signal.sosfilt(sos, impulse) ** 2)))  # output std per unit input
    row_shape = (n_burn + shape[1], *shape[2:])
    out = np.empty(shape)

    def keep(rows: slice, white: np.ndarray) -> None:
        np.divide(signal.sosfilt(sos, white, axis=1)[:, n_burn:], gain, out=out[rows])

    block = max(1, _BLOCK_SIZE // max(1, math.prod(row_shape)))
    blocks = [slice(r0, min(shape[0], r0 + block)) for r0 in range(0, shape[0], block)]
    if len(blocks) < 2 or usable_cpus() < 2:
        for rows in blocks:
            keep(rows, rng.standard_normal((rows.stop - rows.start, *row_shape)))
        return out
    with ThreadPoolExecutor(1) as filtering:
        pending = None
        for rows in blocks:
            white = rng.standard_normal((rows.stop - rows.start, *row_shape))  # while the last filters
            if pending is not None:
                pending.result()
            pending = filtering.submit(keep, rows, white)
        pending.result()
    return out


# elements of one block of rows lowpass_noise draws and filters (8 MB): large enough that handing a
# block to the filtering thread costs nothing next to its work, small enough to stay in cache
_BLOCK_SIZE = 1 << 20
