"""A toy protocol that exists only inside tests/: the proof that a protocol is a plug-in.

A 1-DoF mass-spring-damper (MuJoCo slide joint) pushed by a force motor with a random-phase
multisine; the force sensor adds white noise. Estimation: least squares of
``F = m·ẍ + b·ẋ + k·x`` on the recorded position and force. Diagnosis: the generic core
(:mod:`armlab.diagnosis.families`, :func:`armlab.diagnosis.attribution.select_effects`) with the
nominal mass-spring-damper and one candidate effect, a delay of the force channel.

Nothing outside tests/ names it: it is registered by the tests (``registry.register(PROTOCOL)``)
and reaches ``armlab run``, ``armlab estimate`` and ``armlab diagnose`` through the registry alone.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from armlab.config.schema import ExperimentConfig
from armlab.config.store import apply_overrides, stored_group
from armlab.data.h5io import read_trials
from armlab.data.trial import TrialSet
from armlab.diagnosis.attribution import held_out_gap, select_effects
from armlab.diagnosis.families import ModelFamily, NLParam, Surrogate, shift_columns
from armlab.dsp import five_point_derivatives
from armlab.errors import ConfigError, DataError
from armlab.protocols import registry
from armlab.protocols.base import DiagnosisHooks, OutputContext, Protocol, Simulated

NAME = "toy_msd"


@dataclass(kw_only=True)
class PlantConfig:
    """The mass-spring-damper (values of a small lab fixture)."""

    mass_kg: float = 0.5
    stiffness_N_per_m: float = 400.0
    damping_Ns_per_m: float = 4.0

    def __post_init__(self) -> None:
        if self.mass_kg <= 0 or self.stiffness_N_per_m <= 0:
            raise ConfigError("plant.mass_kg and plant.stiffness_N_per_m must be > 0")


@dataclass(kw_only=True)
class PushConfig:
    """The force motor's multisine and the force sensor."""

    amplitude_N: float = 4.0  # N, rms of the multisine
    band_hz: tuple[float, float] = (0.2, 15.0)
    duration_s: float = 12.0
    n_trials: int = 2
    noise_N: float = 0.1  # N, white noise of the force sensor
    force_delay_s: float = 0.0  # s, delay of the force channel (whole samples): the hidden effect
    substeps: int = 5  # physics steps per sample (RK4): the plant is integrated far beyond the fit


@dataclass(kw_only=True)
class FitConfig:
    """Least squares settings (the group ``armlab estimate`` takes)."""

    skip_s: float = 0.5  # s, start-up transient left out of the fit

    def __post_init__(self) -> None:
        if self.skip_s < 0:
            raise ConfigError(f"fit.skip_s must be >= 0, got {self.skip_s}")


@dataclass(kw_only=True)
class ToyConfig(ExperimentConfig):
    protocol_name: str = NAME
    plant: PlantConfig = field(default_factory=PlantConfig)
    push: PushConfig = field(default_factory=PushConfig)
    fit: FitConfig = field(default_factory=FitConfig)


def _mjcf(p: PlantConfig, dt: float) -> str:
    return f"""
<mujoco model="toy_msd">
  <option timestep="{dt}" integrator="RK4" gravity="0 0 0"/>
  <worldbody>
    <body name="cart">
      <joint name="slide" type="slide" axis="1 0 0" stiffness="{p.stiffness_N_per_m}"
             damping="{p.damping_Ns_per_m}"/>
      <geom type="box" size="0.05 0.05 0.05" mass="{p.mass_kg}"/>
    </body>
  </worldbody>
  <actuator><motor joint="slide" gear="1"/></actuator>
</mujoco>"""


def _multisine(rng: np.random.Generator, push: PushConfig, fs: float) -> np.ndarray:
    """The push at ``fs`` (the physics rate): a continuous multisine, no zero-order hold."""
    n = int(round(push.duration_s * fs))
    t = np.arange(n) / fs
    f = np.arange(push.band_hz[0], push.band_hz[1], 0.2)
    phase = rng.uniform(0.0, 2 * np.pi, f.size)
    u = np.sin(2 * np.pi * f[:, None] * t[None, :] + phase[:, None]).sum(axis=0)
    return push.amplitude_N * u / np.sqrt(np.mean(u**2))


def simulate(cfg: ToyConfig) -> Simulated:
    fs, sub = cfg.sensors.fs_hz, cfg.push.substeps
    xml = _mjcf(cfg.plant, 1.0 / (fs * sub))
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(cfg.seed)
    push = np.stack([_multisine(rng, cfg.push, fs * sub) for _ in range(cfg.push.n_trials)])
    x0 = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    state, _ = rollout.rollout(model, data, np.tile(x0, (push.shape[0], 1)), push[:, :, None])
    # FULLPHYSICS is (time, qpos, ...); state k is after step k: the sample at t = j / fs is the
    # state after step j·sub - 1 (the start, at rest, for j = 0)
    qpos = np.concatenate([np.zeros((push.shape[0], 1)), state[:, :, 1]], axis=1)
    position = qpos[:, ::sub][:, : push.shape[1] // sub]
    force = push[:, ::sub]
    d = int(round(cfg.push.force_delay_s * fs))
    delayed = np.concatenate([np.repeat(force[:, :1], d, axis=1), force[:, : force.shape[1] - d]], axis=1)
    measured = delayed + cfg.push.noise_N * rng.standard_normal(force.shape)
    truth = {"m": cfg.plant.mass_kg, "b": cfg.plant.damping_Ns_per_m, "k": cfg.plant.stiffness_N_per_m}
    trials = TrialSet(
        fs_hz=fs,
        onset_index=np.ones(force.shape[0], dtype=int),  # no onset: the push starts at once
        channels={"force": measured[:, :, None], "position": position[:, :, None]},
        units={"force": "N", "position": "m"},
        trial_meta={"trial": np.arange(force.shape[0])},
        attrs={"protocol": NAME, "seed": cfg.seed, **{f"true_{k}": v for k, v in truth.items()}},
    )
    return Simulated(trials, xml, {}, lambda: (estimate(trials, cfg.fit), {}))


def estimate(trials: TrialSet, fit: FitConfig) -> dict:
    """Least squares of F = m a + b v + k x over every trial after ``skip_s``."""
    x = np.asarray(trials.channels["position"])[:, :, 0]
    v, a = five_point_derivatives(x, trials.fs_hz, axis=-1)
    s = int(round(fit.skip_s * trials.fs_hz))
    if s >= x.shape[1] - 10:
        raise DataError(
            f"fit.skip_s = {fit.skip_s} s leaves no samples; valid: < {x.shape[1] / trials.fs_hz} s"
        )
    phi = np.stack([a[:, s:].ravel(), v[:, s:].ravel(), x[:, s:].ravel()], axis=1)
    y = np.asarray(trials.channels["force"])[:, s:, 0].ravel()
    m, b, k = np.linalg.lstsq(phi, y, rcond=None)[0]
    fitted = {"m": float(m), "b": float(b), "k": float(k)}
    truth = {n: float(trials.attrs[f"true_{n}"]) for n in fitted if f"true_{n}" in trials.attrs}
    return {
        "protocol": NAME,
        "fit": fitted,
        "truth": truth,
        "rel_err": {n: abs(fitted[n] - truth[n]) / truth[n] for n in truth},
        "skip_s": fit.skip_s,
    }


def reestimate(trials: TrialSet, stored, overrides: list[str]) -> dict:
    return estimate(trials, apply_overrides(stored_group(FitConfig, stored, "fit"), "fit", overrides))


def outputs(ctx: OutputContext) -> dict:
    path = ctx.out_dir / "toy.txt"
    with path.open("x") as fh:
        fh.write(format_table(ctx.results, ctx.viz) + "\n")
    return {"table": path}


def format_table(results: dict, viz=None) -> str:
    f, t = results["fit"], results.get("truth", {})
    return "  ".join(f"{n} = {f[n]:.4g} (truth {t.get(n, float('nan')):.4g})" for n in ("m", "b", "k"))


# --- diagnosis through the generic core --------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Prepared:
    fs_hz: float
    t_s: np.ndarray
    a: np.ndarray
    v: np.ndarray
    x: np.ndarray
    train: np.ndarray
    held: np.ndarray


def _columns(tr: _Prepared, model, theta) -> np.ndarray:
    phi = np.stack([tr.a, tr.v, tr.x], axis=1)
    if any(s.name == "channel_delay" for s in model):
        phi = shift_columns(tr.t_s, phi, theta["channel_delay.delay_s"])
    return phi


def _linear_names(model) -> tuple[str, ...]:
    return ("m", "b", "k", *[f"{s.name}.{n}" for s in model for n in s.linear])


FAMILY = ModelFamily(columns=_columns, linear_names=_linear_names)
CANDIDATES = {
    "channel_delay": Surrogate(
        "channel_delay", "output", (NLParam("delay_s", -0.01, 0.02, (-0.004, 0.0, 0.004, 0.008)),)
    )
}
RULES = {"none_tolerance": 0.5, "min_explained": 0.5}


def load(path: Path, cfg) -> TrialSet:
    path = Path(path)
    return read_trials(path / "trials.h5" if path.is_dir() else path)


def diagnose(trials: TrialSet, cfg) -> tuple[dict, dict]:
    cfg = cfg.with_rules(RULES)
    x = np.asarray(trials.channels["position"])[:, :, 0]
    f = np.asarray(trials.channels["force"])[:, :, 0]
    v, a = five_point_derivatives(x, trials.fs_hz, axis=-1)
    s = int(0.5 * trials.fs_hz)
    n = x.shape[1] - s
    split = s + int(round(n * (1 - cfg.holdout_fraction)))
    idx = np.arange(x.shape[1])
    prepared = [
        _Prepared(
            trials.fs_hz, idx / trials.fs_hz, a[i], v[i], x[i], (idx >= s) & (idx < split), idx >= split
        )
        for i in range(x.shape[0])
    ]
    y = [f[i] for i in range(x.shape[0])]
    # noise floor from second differences of the force (the push is band-limited far below fs/2)
    noise_var = float(np.median(np.diff(f, 2, axis=-1) ** 2) / 0.4549 / 6.0)
    n_h = sum(int(tr.held.sum()) for tr in prepared)
    floor = noise_var * n_h / sum(float(np.sum(yy[tr.held] ** 2)) for yy, tr in zip(y, prepared, strict=True))
    sel = select_effects(prepared, y, None, CANDIDATES, floor, cfg, band_share=1.0, family=FAMILY)
    gaps = [held_out_gap(m, prepared, y)[0] for m in sel.stages]
    ranking = [
        {k: v for k, v in e.items() if k != "model"} for e in (sel.rankings[0] if sel.rankings else [])
    ]
    results = {
        "protocol": NAME,
        "verdict": sel.verdict,
        "trials": [f"trial{i}" for i in range(len(prepared))],
        "gap": {
            "nominal": gaps[0],
            "noise_floor": floor,
            "added": [{"effect": e, "held_out_gap": g} for e, g in zip(sel.verdict, gaps[1:], strict=False)],
        },
        "ranking": ranking,
        "how_far": [
            {"stage": "+".join(m.effects) or "nominal", "held_out_gap": g}
            for m, g in zip(sel.stages, gaps, strict=True)
        ],
        "settings": {"none_tolerance": cfg.none_tolerance, "min_explained": cfg.min_explained},
    }
    return results, {}


def report(results: dict, *, data_path: str, figures) -> str:
    return f"# Toy diagnosis of {data_path}\n\nverdict: {', '.join(results['verdict'])}\n"


PROTOCOL = Protocol(
    name=NAME,
    paper="none: a test fixture",
    summary="1-DoF mass-spring-damper pushed by a force motor (tests only)",
    schema=ToyConfig,
    groups={"sensors": "ideal"},
    simulate=simulate,
    reestimate_group="fit",
    reestimate=reestimate,
    outputs=outputs,
    format_table=format_table,
    catalogue=("channel_delay",),
    diagnosis=DiagnosisHooks(
        load=load,
        diagnose=diagnose,
        candidates=tuple(CANDIDATES),
        rules=RULES,
        report=report,
        figures=lambda viz, series, results, out: [],
        recording=lambda viz, series, path: None,
    ),
)


if __name__ == "__main__":  # as a user's plug-in would: register, then hand over to armlab's CLI
    from armlab.cli import main

    registry.register(PROTOCOL)
    raise SystemExit(main(sys.argv[1:]))
