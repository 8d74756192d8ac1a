"""The single-effect variants of the lab that the published-threshold diagnosis tries.

:class:`Variant` names one change of an :class:`ExperimentConfig` (values set, then factors
applied, by ``"<group>.<field>"`` path); :func:`candidate_variants` gives the default catalogue used
by :func:`armlab.reproduction.conditioning.diagnose_thresholds`: reflex (toggle, gains,
stretch latency), cuff (toggle, stiffness), sensors, muscle model, co-contraction and low-pass.
Pure computation.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from armlab.config.schema import ExperimentConfig
from armlab.errors import ConfigError
from armlab.protocols._files import new_dir, write_json, write_new

__all__ = [
    "write_study",
    "COCONTRACTION_FACTORS",
    "CUFF_STIFFNESS_FACTORS",
    "LOWPASS_ALT_HZ",
    "REFLEX_GAIN_FACTOR",
    "STRETCH_LATENCIES_S",
    "Variant",
    "candidate_variants",
    "variant",
]

# s, short-latency stretch reflex 25-50 ms (conditioning paper II-B); the nominal is 35 ms
STRETCH_LATENCIES_S = (0.025, 0.050)
REFLEX_GAIN_FACTOR = 2.0  # on the assumed reflex gains of ReflexConfig (assumption: a doubling)
CUFF_STIFFNESS_FACTORS = (0.5, 2.0)  # on the configured cuff stiffness (conditioning default 3 kN/m)
COCONTRACTION_FACTORS = (0.5, 2.0)  # on the nominal activation 0.2 of ArmConfig (assumption)
LOWPASS_ALT_HZ = 40.0  # Hz, the alternative cutoff named in EstimatorConfig (paper IV-C gives none)


@dataclass(frozen=True, kw_only=True)
class Variant:
    """One named change of the config: ``set_values`` assigned, then ``scale`` factors applied.

    Paths are ``"<group>.<field>"`` of the protocol's experiment (e.g. ``"reflex.enabled"``); both
    published studies (conditioning thresholds, the virtual-force-sensor Table III pattern) use it.
    """

    name: str
    effect: str  # the effect family: reflex, cuff, sensors, muscle, cocontraction, filter, drag, ...
    description: str
    set_values: tuple[tuple[str, object], ...] = ()
    scale: tuple[tuple[str, float], ...] = ()

    @property
    def change(self) -> str:
        """The change in words: ``group.field=value`` and ``group.field xfactor``, comma-joined."""
        return ", ".join(
            [f"{path}={value}" for path, value in self.set_values]
            + [f"{path} x{factor:g}" for path, factor in self.scale]
        )

    def apply(self, cfg: ExperimentConfig) -> ExperimentConfig:
        """The varied config (each group's ``__post_init__`` validates the new values)."""
        for path, value in self.set_values:
            cfg = _with(cfg, path, value)
        for path, factor in self.scale:
            cfg = _with(cfg, path, _get(cfg, path) * factor)
        return cfg


def _split(cfg: ExperimentConfig, path: str) -> tuple[str, str]:
    group, _, name = path.partition(".")
    groups = [f.name for f in dataclasses.fields(cfg) if dataclasses.is_dataclass(getattr(cfg, f.name))]
    if group not in groups:
        raise ConfigError(f"variant path {path!r}: unknown group {group!r}; valid: {groups}")
    names = [f.name for f in dataclasses.fields(getattr(cfg, group))]
    if name not in names:
        raise ConfigError(f"variant path {path!r}: unknown field {name!r}; valid: {names}")
    return group, name


def _get(cfg: ExperimentConfig, path: str):
    group, name = _split(cfg, path)
    return getattr(getattr(cfg, group), name)


def _with(cfg: ExperimentConfig, path: str, value) -> ExperimentConfig:
    group, name = _split(cfg, path)
    return replace(cfg, **{group: replace(getattr(cfg, group), **{name: value})})


def variant(name: str, effect: str, description: str, sets=(), scale=()) -> Variant:
    """A :class:`Variant` from lists of ``(path, value)`` sets and ``(path, factor)`` scales."""
    return Variant(
        name=name, effect=effect, description=description, set_values=tuple(sets), scale=tuple(scale)
    )


def candidate_variants(cfg: ExperimentConfig) -> list[Variant]:
    """The default single changes, toggles taken relative to ``cfg`` (12 variants)."""
    on, rigid, k_cuff = cfg.reflex.enabled, cfg.cuff.rigid, cfg.cuff.stiffness_N_per_m
    sensors = "ideal" if cfg.sensors.preset == "realistic" else "realistic"
    muscle = "linear" if cfg.arm.muscle == "hill" else "hill"
    gains = [(f"reflex.{g}_gain", REFLEX_GAIN_FACTOR) for g in ("stretch", "velocity", "spinal")]
    reflex_on = [("reflex.enabled", True)]
    return [
        variant(
            f"reflex_{'off' if on else 'on'}",
            "reflex",
            f"reflexes {'off' if on else 'on'}",
            [("reflex.enabled", not on)],
        ),
        variant("reflex_gain_x2", "reflex", "every reflex gain x2 (reflex on)", reflex_on, gains),
        *(
            variant(
                f"reflex_latency_{t * 1e3:.0f}ms",
                "reflex",
                f"stretch-reflex latency {t * 1e3:.0f} ms (reflex on)",
                [*reflex_on, ("reflex.stretch_latency_s", t)],
            )
            for t in STRETCH_LATENCIES_S
        ),
        variant(
            f"cuff_{'compliant' if rigid else 'rigid'}",
            "cuff",
            f"{'compliant' if rigid else 'rigid'} cuff",
            [("cuff.rigid", not rigid)],
        ),
        *(
            variant(
                f"cuff_stiffness_x{f:g}",
                "cuff",
                f"compliant cuff, {k_cuff * f:.0f} N/m",
                [("cuff.rigid", False)],
                [("cuff.stiffness_N_per_m", f)],
            )
            for f in CUFF_STIFFNESS_FACTORS
        ),
        variant(f"sensors_{sensors}", "sensors", f"{sensors} sensors", [("sensors.preset", sensors)]),
        variant(f"muscle_{muscle}", "muscle", f"{muscle} muscles", [("arm.muscle", muscle)]),
        *(
            variant(
                f"cocontraction_x{f:g}",
                "cocontraction",
                f"co-contraction {cfg.arm.cocontraction * f:g}",
                scale=[("arm.cocontraction", f)],
            )
            for f in COCONTRACTION_FACTORS
        ),
        variant(
            f"lowpass_{LOWPASS_ALT_HZ:g}hz",
            "filter",
            f"low-pass {LOWPASS_ALT_HZ:g} Hz (same recording)",
            [("estimator.lowpass_hz", LOWPASS_ALT_HZ)],
        ),
    ]


def write_study(out_dir: Path, run: Callable[[], dict], format_report: Callable[[dict], str]) -> dict:
    """Run a published-figure study and write its ``results.json`` and ``report.md`` into ``out_dir``.

    ``out_dir`` is checked before ``run`` simulates anything: it must be new or empty (nothing is
    overwritten).

    Raises:
        DataError: ``out_dir`` is not empty.
    """
    out_dir = new_dir(out_dir)
    result = run()
    write_json(out_dir / "results.json", result)
    write_new(out_dir / "report.md", format_report(result))
    return result
