"""Random-phase multisine force references (fractional-elbow paper, seeds/004, Sec. III-A).

The reference is a sum of equal-amplitude sinusoids on a regular grid inside a band, each with a
random phase (unpredictable to the subject, so that anticipatory reactions are not triggered),
scaled so that its peak never exceeds ``peak_N``, with raised-cosine tapers at both ends.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import yaml

from armlab.errors import ConfigError
from armlab.perturbations.scenario import SCENARIO_DIR, available_scenarios

__all__ = [
    "ForceScenario",
    "load_force_scenario",
    "multisine",
]


@dataclass(frozen=True, kw_only=True)
class ForceScenario:
    """A multisine force-perturbation protocol.

    Attributes:
        name: scenario name (file stem).
        band_hz: (lo, hi) Hz, component frequencies.
        spacing_hz: Hz, grid of the components.
        peak_N: N, bound on ``|F_ref|``.
        duration_s: s, recorded trial length; ``fs_hz`` Hz its sample rate.
        taper_s: s, raised-cosine fade at both ends.
        settle_s: s, unrecorded hold before the force starts.
        n_trials: trials (their frequency responses are averaged).
    """

    name: str
    band_hz: tuple[float, float]
    spacing_hz: float
    peak_N: float
    duration_s: float
    fs_hz: float
    taper_s: float
    settle_s: float
    n_trials: int

    @property
    def n_samples(self) -> int:
        return int(round(self.duration_s * self.fs_hz))

    @property
    def frequencies_hz(self) -> np.ndarray:
        """(n_components,) Hz, the grid multiples of ``spacing_hz`` inside the band."""
        lo, hi = self.band_hz
        k = np.arange(
            int(np.ceil(lo / self.spacing_hz - 1e-9)), int(np.floor(hi / self.spacing_hz + 1e-9)) + 1
        )
        return k * self.spacing_hz


def multisine(scenario: ForceScenario, rng: np.random.Generator) -> np.ndarray:
    """One force reference: (n_samples,) N, peak exactly ``peak_N``.

    Phases are uniform in [0, 2 pi) from ``rng``; the components lie on the record's FFT bins
    (``spacing_hz`` a multiple of ``1 / duration_s``), so the sum is one inverse FFT. The sum is
    normalised to its peak after tapering, so ``max |F_ref| = peak_N``.
    """
    n = scenario.n_samples
    bins = scenario.frequencies_hz * n / scenario.fs_hz  # components sit on the record's FFT bins
    k = np.rint(bins).astype(int)
    if not np.allclose(bins, k, atol=1e-6):
        raise ConfigError(
            f"spacing_hz = {scenario.spacing_hz} Hz is not a multiple of 1 / duration_s = "
            f"{1 / scenario.duration_s:g} Hz; each component must be periodic in the trial"
        )
    phases = rng.uniform(0.0, 2 * np.pi, k.size)
    spectrum = np.zeros(n // 2 + 1, dtype=complex)
    spectrum[k] = np.exp(1j * phases) * (n / 2)  # unit cosines cos(2 pi f t + phase)
    x = np.fft.irfft(spectrum, n)
    n_taper = int(round(scenario.taper_s * scenario.fs_hz))
    if n_taper:
        ramp = 0.5 * (1 - np.cos(np.pi * np.arange(n_taper) / n_taper))
        x[:n_taper] *= ramp
        x[-n_taper:] *= ramp[::-1]
    return scenario.peak_N * x / np.max(np.abs(x))


def _need(raw: dict, key: str, name: str):
    if key not in raw:
        raise ConfigError(f"scenarios/{name}.yaml lacks {key!r}")
    return raw[key]


def load_force_scenario(name: str, n_trials: int | None = None) -> ForceScenario:
    """Load and validate ``scenarios/<name>.yaml`` (profile ``multisine``)."""
    path = SCENARIO_DIR / f"{name}.yaml"
    if not path.is_file():
        raise ConfigError(f"unknown scenario {name!r}; available: {available_scenarios()}")
    raw = yaml.safe_load(path.read_text()) or {}
    if raw.get("profile") != "multisine":
        raise ConfigError(
            f"{path.name}: profile {raw.get('profile')!r} is not a force scenario; valid: ['multisine']"
        )
    lo, hi = (float(v) for v in _need(raw, "band_hz", name))
    fs = float(_need(raw, "fs_hz", name))
    scen = ForceScenario(
        name=str(raw.get("name", name)),
        band_hz=(lo, hi),
        spacing_hz=float(_need(raw, "spacing_hz", name)),
        peak_N=float(_need(raw, "peak_N", name)),
        duration_s=float(_need(raw, "duration_s", name)),
        fs_hz=fs,
        taper_s=float(raw.get("taper_s", 0.0)),
        settle_s=float(raw.get("settle_s", 0.0)),
        n_trials=int(n_trials if n_trials is not None else _need(raw, "n_trials", name)),
    )
    if not 0 < lo < hi < fs / 2:
        raise ConfigError(
            f"{path.name}: band_hz must satisfy 0 < low < high < Nyquist ({fs / 2} Hz), got {(lo, hi)}"
        )
    if not 0 < scen.spacing_hz <= lo:
        raise ConfigError(f"{path.name}: spacing_hz must lie in (0, band low {lo}] Hz, got {scen.spacing_hz}")
    if scen.peak_N <= 0 or scen.duration_s <= 2 * scen.taper_s or scen.n_trials < 1 or scen.settle_s < 0:
        raise ConfigError(
            f"{path.name}: need peak_N > 0, duration_s > 2 taper_s, settle_s >= 0 and n_trials >= 1; "
            f"got {scen.peak_N}, {scen.duration_s}, {scen.taper_s}, {scen.settle_s}, {scen.n_trials}"
        )
    return scen
