"""Shared fixtures: composed lab scenes and their settled hold states, built once per session."""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from armlab.config.schema import ArmConfig, CuffConfig, RobotConfig, SimConfig
from armlab.models.scene import Scene, build_scene
from armlab.sim.hold import HoldState, settle

# Modules whose tests simulate, diagnose or start `armlab` processes for ~15 s of CPU or more
# (the module's user + system time, its `armlab` and joblib processes included), run first.
# `make test` spreads modules over two xdist workers (`-n 2 --dist loadfile
# --no-loadscope-reorder`: a module's shared fixtures are computed once, in one worker): started
# last, one of these would leave a worker running it alone while the other has finished; started
# first, the many small modules fill in around them. The order changes no result: every test
# module is independent (the suite passes in this order and in the alphabetical one).
HEAVY_FIRST = (  # CPU seconds measured on the 2-core machine, heaviest first
    "test_resume.py",  # ~73 s: interrupted and resumed runs and sweeps, in armlab processes
    "test_referee.py",  # ~45 s: two small blind benchmarks (joblib workers)
    "test_virtual_force_sensor.py",  # ~27 s
    "test_cli.py",  # ~26 s
    "test_conditioning_fidelity.py",  # ~23 s: the default conditioning run
    "test_fractional_subject.py",  # ~20 s
    "test_cond_diagnosis.py",  # ~20 s
    "test_plugin_protocol.py",  # ~19 s
    "test_published_fractional.py",  # ~17 s
    "test_bad_input.py",  # ~16 s
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Stable-sort the collected tests: the HEAVY_FIRST modules in that order, then the rest as
    collected (the order inside a module is kept)."""
    rank = {name: i for i, name in enumerate(HEAVY_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(HEAVY_FIRST)))


@dataclass(frozen=True)
class Lab:
    arm: ArmConfig
    scene: Scene
    hold: HoldState
    rigid: bool


_CACHE: dict[tuple[str, bool], Lab] = {}


def make_lab(muscle: str, rigid: bool) -> Lab:
    """Scene with default configs (SimConfig(): 0.5 ms Euler) settled for SimConfig().settle_s."""
    key = (muscle, rigid)
    if key not in _CACHE:
        arm = ArmConfig(muscle=muscle)
        sim = SimConfig()
        scene = build_scene(arm, CuffConfig(rigid=rigid), RobotConfig(), sim)
        _CACHE[key] = Lab(arm=arm, scene=scene, hold=settle(scene, arm, sim.settle_s), rigid=rigid)
    return _CACHE[key]


@pytest.fixture(
    scope="session",
    params=[("hill", True), ("hill", False), ("linear", True), ("linear", False)],
    ids=lambda p: f"{p[0]}-{'rigid' if p[1] else 'compliant'}",
)
def lab(request) -> Lab:
    return make_lab(*request.param)


# ---------------------------------------------------------------------------------------------
# Synthetic 1-DoF joint trials for the diagnosis tests (tests/test_joint_*.py, test_localise.py,
# test_attribution.py, test_diagnose.py): a position-imposed joint with known I, B, K and the
# catalogue effects written directly in NumPy, independent of armlab.diagnosis.families.
# ---------------------------------------------------------------------------------------------

JOINT_FS_HZ = 1000.0  # Hz, recorded rate
JOINT_I = 0.02  # kg·m², ankle + foot inertia (Kearney & Hunter 1990 range 0.01-0.03)
JOINT_B = 0.8  # N·m·s/rad, same source
JOINT_K = 120.0  # N·m/rad, same source


@dataclass(frozen=True, eq=False)
class JointTrial:
    """The fields :func:`armlab.protocols.joint_1dof.diagnosis.data.prepare_trials` reads from an "
    "imported trial."""

    name: str
    position: np.ndarray  # (n,) rad
    torque: np.ndarray  # (n,) N·m
    fs_hz: float = JOINT_FS_HZ


def prbs_steps(rng, duration_s: float, *, amplitude=0.03, clock_s=0.15, fs_hz=JOINT_FS_HZ) -> np.ndarray:
    """(n,) rad, a pseudo-random binary sequence: ±amplitude, a new random level every clock_s."""
    n = int(round(duration_s * fs_hz))
    clock = int(round(clock_s * fs_hz))
    return np.repeat(amplitude * rng.choice([-1.0, 1.0], size=n // clock + 1), clock)[:n]


def smooth(steps: np.ndarray, smooth_hz: float = 15.0, fs_hz: float = JOINT_FS_HZ) -> np.ndarray:
    """Zero-phase 2nd-order Butterworth smoothing (the actuator's finite bandwidth)."""
    return signal.sosfiltfilt(signal.butter(2, smooth_hz, fs=fs_hz, output="sos"), steps)


def prbs_position(rng, duration_s: float, *, highpass_hz: float | None = None, **kw) -> np.ndarray:
    """(n,) rad, smoothed PRBS; optionally high-passed (removes its sub-Hz content)."""
    x = smooth(prbs_steps(rng, duration_s, **kw))
    if highpass_hz is not None:
        hp = signal.butter(2, highpass_hz, btype="highpass", fs=JOINT_FS_HZ, output="sos")
        x = signal.sosfiltfilt(hp, x)
    return x


def joint_derivatives(x: np.ndarray, fs_hz: float = JOINT_FS_HZ) -> tuple[np.ndarray, np.ndarray]:
    """(rad/s, rad/s²) by central differences (2nd-order accurate at the ends too)."""
    v = np.gradient(x, 1.0 / fs_hz, edge_order=2)
    return v, np.gradient(v, 1.0 / fs_hz, edge_order=2)


def nominal_torque(x: np.ndarray, *, I=JOINT_I, B=JOINT_B, K=JOINT_K) -> np.ndarray:
    """N·m, the measured torque of the nominal joint: it resists the motion, -(I·a + B·v + K·x)."""
    v, a = joint_derivatives(x)
    return -(I * a + B * v + K * x)


def reflex_torque(x: np.ndarray, *, delay_s: float, gain: float, cutoff_hz: float = 3.0) -> np.ndarray:
    """N·m, -gain × 2nd-order low-pass (ζ = 0.7) of the rectified velocity delayed by delay_s."""
    v, _ = joint_derivatives(x)
    t = np.arange(x.size) / JOINT_FS_HZ
    w = 2 * np.pi * cutoff_hz
    b, a = signal.bilinear([w * w], [1.0, 1.4 * w, w * w], JOINT_FS_HZ)
    return -gain * signal.lfilter(b, a, np.maximum(np.interp(t - delay_s, t, v, left=0.0), 0.0))


def friction_torque(x: np.ndarray, *, coulomb: float) -> np.ndarray:
    """N·m, Coulomb friction -coulomb·sign(v)."""
    v, _ = joint_derivatives(x)
    return -coulomb * np.sign(v)


def presliding_friction_torque(x: np.ndarray, *, coulomb: float, presliding_rad: float) -> np.ndarray:
    """N·m, a bristle (LuGre without Stribeck or micro-damping, i.e. Dahl) friction, stepped
    sample by sample: the deflection z follows dz = dx - |dx|·z / z_max and is held at rest;
    the force is -coulomb·z / z_max, z_max = presliding_rad."""
    z, out = 0.0, np.empty(x.size)
    for k, dx in enumerate(np.diff(x, prepend=x[0])):
        z += dx - abs(dx) * z / presliding_rad
        out[k] = -coulomb * z / presliding_rad
    return out


def delayed(z: np.ndarray, delay_s: float) -> np.ndarray:
    """z(t - delay_s), the channel at rest (its first value) before the start."""
    t = np.arange(z.size) / JOINT_FS_HZ
    return np.interp(t - delay_s, t, z, left=z[0])


def lowpassed(z: np.ndarray, cutoff_hz: float) -> np.ndarray:
    """Causal 2nd-order Butterworth low-pass (a sensor's bandwidth), started at rest on z[0]."""
    b, a = signal.butter(2, cutoff_hz, fs=JOINT_FS_HZ)
    return signal.lfilter(b, a, z - z[0]) + z[0]


def compliant_torque(
    x: np.ndarray, *, k: float, c: float = 0.0, I=JOINT_I, B=JOINT_B, K=JOINT_K
) -> np.ndarray:
    """N·m, the joint Z = I·s² + B·s + K behind a series spring k and damper c (N·m·s/rad).

    Undamped: -k·Z/(Z + k) applied to x. Damped: the limb angle θ_l = (c·s + k)/(Z + c·s + k)·x,
    then the spring's torque -(k·(x - θ_l) + c·(ẋ - θ̇_l)) (a computation of its own, not the
    diagnosis' surrogate's polynomial division).
    """
    if c == 0.0:
        b, a = signal.bilinear([k * I, k * B, k * K], [I, B, K + k], JOINT_FS_HZ)
        return -(signal.lfilter(b, a, x - x[0]) + k * K / (K + k) * x[0])
    b, a = signal.bilinear([c, k], [I, B + c, K + k], JOINT_FS_HZ)
    limb = signal.lfilter(b, a, x - x[0]) + k / (K + k) * x[0]
    v, _ = joint_derivatives(x)
    v_limb, _ = joint_derivatives(limb)
    return -(k * (x - limb) + c * (v - v_limb))


def slow_activation(rng, n: int, *, depth: float, bandwidth_hz: float = 0.2) -> np.ndarray:
    """(n,) 1, zero-mean slow co-contraction fluctuation of rms ``depth``."""
    c = signal.sosfiltfilt(signal.butter(2, bandwidth_hz, fs=JOINT_FS_HZ, output="sos"), rng.normal(size=n))
    c = c - c.mean()
    return depth * c / np.sqrt(np.mean(c**2))


def cocontraction_torque(x: np.ndarray, c: np.ndarray, *, tonic_Nm: float) -> np.ndarray:
    """N·m, stiffness and damping scaled by 1 + c(t), plus the tonic torque tonic_Nm·(1 + c)."""
    v, a = joint_derivatives(x)
    return -(JOINT_I * a + (1.0 + c) * (JOINT_B * v + JOINT_K * x)) + tonic_Nm * (1.0 + c)


def reflex_joint_torque(x: np.ndarray) -> np.ndarray:
    """N·m, the nominal joint plus a 40 ms, gain-2 reflex (a clear but moderate reflex gap)."""
    return nominal_torque(x) + reflex_torque(x, delay_s=0.04, gain=2.0)


def noisy_joint_record(name: str, seed: int, *, reflex_gain: float, coulomb_Nm: float = 0.0, duration_s=10.0):
    """A 1-DoF joint trial under a smoothed PRBS: nominal + 45 ms reflex + friction + 0.05 N·m noise."""
    rng = np.random.default_rng(seed)
    x = prbs_position(rng, duration_s)
    torque = (
        nominal_torque(x)
        + reflex_torque(x, delay_s=0.045, gain=reflex_gain)  # 45 ms latency (Kearney 1997)
        + friction_torque(x, coulomb=coulomb_Nm)
    )
    return JointTrial(name, x, torque + 0.05 * rng.standard_normal(x.size))


def joint_trials(x: np.ndarray, torque_fn, rng, *, repeats: int = 2, noise_std: float = 0.15):
    """``repeats`` recordings of one position sequence, each with its own white torque noise."""
    return [
        JointTrial(f"rep{k}", x, torque_fn(x) + rng.normal(0.0, noise_std, x.size)) for k in range(repeats)
    ]


def prepared(records, cfg=None, **kw):
    """(trials, scoring high-pass, measured torque in the scoring band) as diagnose_joint makes them
    (``kw``: further arguments of prepare_trials, e.g. ``edge_s``)."""
    from armlab.config.diagnosis import DiagnosisConfig
    from armlab.protocols.joint_1dof.diagnosis.diagnose import prepare_scoring

    return prepare_scoring(records, cfg or DiagnosisConfig(), **kw)


# --- output files ---------------------------------------------------------------------------------
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def assert_png(path: Path) -> None:
    """``path`` is a PNG file with content."""
    assert path.is_file(), path
    assert path.read_bytes()[:8] == PNG_MAGIC, path
    # a blank 120-dpi figure is already several kB; ours has content
    assert path.stat().st_size > 10_000, path


def verify_rrd(path: Path, home: Path) -> None:
    """``rerun rrd verify`` accepts ``path``; skips without the rerun CLI next to the interpreter.

    ``home``: a private HOME, which keeps the CLI's analytics config out of the user's.
    """
    exe = Path(sys.executable).parent / "rerun"
    if not exe.is_file():
        pytest.skip("no rerun CLI next to the interpreter; cannot verify the .rrd")
    env = {**os.environ, "HOME": str(home), "XDG_CONFIG_HOME": str(home / ".config")}
    subprocess.run([str(exe), "analytics", "disable"], env=env, capture_output=True, timeout=30, check=False)
    done = subprocess.run(
        [str(exe), "rrd", "verify", str(path)], env=env, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stdout + done.stderr
