"""Issue 18's robust "none": a recording that the nominal model I θ̈ + B θ̇ + K θ explains exactly
is diagnosed "none" at every noise level from 1e-4 to 1e-1 of the torque's rms.

The recordings come from a generator of their own (not armlab's simulator): a 30-tone multisine
joint angle with its analytic velocity and acceleration, torque = I θ̈ + B θ̇ + K θ plus white
noise, written in REKLAB's CSV layout and read back as a user's file would be.
"""

from __future__ import annotations

import numpy as np
import pytest

from armlab.config.diagnosis import DiagnosisConfig
from armlab.data.joint_import import write_joint_csv
from armlab.runner.diagnose import run_diagnoser

FS = 1000.0  # Hz
I, B, K = 0.016, 0.7, 40.0  # kg·m², N·m·s/rad, N·m/rad: an ankle's order (REKLAB's trials)


def _clean(folder, rel_noise: float, seed: int = 0, duration_s: float = 40.0):
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration_s * FS)) / FS
    f = np.linspace(0.5, 15.0, 30)  # Hz, inside the scoring band
    amp = 0.02 / np.sqrt(f.size / 2) / (1.0 + f / 5.0)  # rad, ~0.01 rad rms
    w = 2 * np.pi * f[:, None]
    arg = w * t + rng.uniform(0, 2 * np.pi, f.size)[:, None]
    x = np.sum(amp[:, None] * np.sin(arg), axis=0)
    v = np.sum(amp[:, None] * w * np.cos(arg), axis=0)
    a = -np.sum(amp[:, None] * w**2 * np.sin(arg), axis=0)
    tau = I * a + B * v + K * x
    tau = tau + rng.normal(0.0, rel_noise * np.std(tau), tau.size)
    return write_joint_csv(folder / f"clean_{rel_noise:g}.csv", t_s=t, position=x, torque=tau)


@pytest.mark.parametrize(
    "rel_noise",
    [
        pytest.param(1e-4, marks=pytest.mark.slow),
        1e-3,
        pytest.param(1e-2, marks=pytest.mark.slow),
        pytest.param(1e-1, marks=pytest.mark.slow),
    ],
)
def test_a_perfect_nominal_model_gives_none_at_every_noise_level(tmp_path, rel_noise):
    results, _ = run_diagnoser(_clean(tmp_path, rel_noise), "joint_1dof", DiagnosisConfig())
    assert results["verdict"] == ["none"], (rel_noise, results["verdict"], results["gap"])
