"""The Protocol interface: everything a paper's protocol declares, as typed values.

A protocol is one package under ``armlab/protocols/<name>/`` whose ``__init__`` builds one
:class:`Protocol` and whose single registration line is in :mod:`armlab.protocols.registry`. The
runner, the CLI (``run``, ``estimate``, ``view``, ``diagnose``, ``effects``,
``diagnose-benchmark``, ``--help``) and the docs read only these values; nothing outside the
package names the protocol.

Layering: a protocol never imports :mod:`armlab.viz` (it sits above the protocols). Its output
hooks receive the drawing API from the edge instead (:class:`OutputContext.viz`, the ``viz``
argument of the diagnosis hooks), so figures and recordings stay in the one package that imports
matplotlib and rerun.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.data.trial import TrialSet
from armlab.errors import ConfigError

__all__ = [
    "Command",
    "DiagnosisHooks",
    "OutputContext",
    "Protocol",
    "Referee",
    "Simulated",
]


@dataclass(frozen=True, eq=False)
class Simulated:
    """What a protocol's simulation hands to the shared run.

    Attributes:
        trials: the recorded trials (what is written to ``trials.h5``).
        scene_xml: the composed MJCF (written to ``scene.xml``).
        attrs: extra run-level attributes of the trial file, beside the stored config.
        estimate: runs the protocol's estimation on ``trials``: ``() -> (results, series)``;
            ``results`` is JSON-able (``results.json``), ``series`` feeds the figures.
    """

    trials: TrialSet
    scene_xml: str
    attrs: dict
    estimate: Callable[[], tuple[dict, dict]]


@dataclass(frozen=True, kw_only=True, eq=False)
class OutputContext:
    """What a protocol's output hook may draw from; ``viz`` is :mod:`armlab.viz`, handed in by the edge."""

    viz: Any
    out_dir: Path
    trials: TrialSet
    results: dict
    series: dict
    cfg: Any


@dataclass(frozen=True, kw_only=True, eq=False)
class Referee:
    """A protocol's blind referee (``armlab diagnose-benchmark``).

    Attributes:
        classes: class name -> (hidden effects, candidates excluded from the diagnosis).
        make_dataset: ``(cls, replicate, RefereeConfig, DiagnosisConfig, folder) -> Dataset``:
            simulate one pseudo-real dataset with the class's hidden effects and write its trial
            files into ``folder`` (:class:`armlab.diagnosis.scoring.Dataset`).
        describe: ``(RefereeConfig) -> str``: its datasets in words (trials, rate, noise), for
            ``benchmark.md``.
        settings: the protocol-specific ``RefereeConfig`` fields it reads (beside the shared
            ``protocol``, ``replicates``, ``seed``, ``classes``, ``jobs``); an override of another
            protocol's field is refused, never ignored.
        validate: ``(RefereeConfig, DiagnosisConfig) -> None``: refuses (ConfigError) settings
            whose datasets its diagnosis would refuse, before any dataset is simulated.
    """

    classes: Mapping[str, tuple[tuple[str, ...], tuple[str, ...]]]
    make_dataset: Callable[[str, int, RefereeConfig, DiagnosisConfig, Path], Any]
    describe: Callable[[RefereeConfig], str]
    settings: tuple[str, ...] = ()
    validate: Callable[[RefereeConfig, DiagnosisConfig], None] | None = None


@dataclass(frozen=True, kw_only=True, eq=False)
class DiagnosisHooks:
    """How ``armlab diagnose`` works for a protocol.

    Attributes:
        load: ``(path, DiagnosisConfig) -> data``: read measured trials (a file or a folder),
            with clear :class:`~armlab.errors.DataError` messages for bad files; with
            ``takes_units``, also ``units=`` (the ``units=`` of ``armlab diagnose``, e.g.
            ``"deg,Nmm"``: files whose units the user states).
        diagnose: ``(data, DiagnosisConfig) -> (results, series)``: localise, attribute and
            measure the gap (pure; results follow docs/diagnosis_schema.md).
        candidates: the catalogue effects it can score (its surrogate model family's names).
        rules: the acceptance thresholds that depend on the protocol's nominal model and scoring
            set (``none_tolerance``, ``min_explained``; used where the setting is left at None),
            with their reasons beside them in the protocol's package.
        report: ``(results, data_path=, figures=) -> str``: the Markdown report.
        figures: ``(viz, series, results, out_dir) -> [paths]``: the diagnosis figures.
        recording: ``(viz, series, path) -> path``: the rerun recording of the diagnosis.
        referee: its blind referee, if it has one (``referee.generator=default``).
        referees: further referees by generator name (``referee.generator=<name>``), e.g. one
            written by an independent generator to test rules tuned on the first.
        takes_units: its ``load`` reads ``units=`` (joint recordings in CSV or .mat); False for
            files that carry their units (trial files).
    """

    load: Callable[[Path, DiagnosisConfig], Any]
    diagnose: Callable[[Any, DiagnosisConfig], tuple[dict, dict]]
    candidates: tuple[str, ...]
    rules: Mapping[str, float]
    report: Callable[..., str]
    figures: Callable[[Any, dict, dict, Path], list[Path]]
    recording: Callable[[Any, dict, Path], Any]
    referee: Referee | None = None
    referees: Mapping[str, Referee] = field(default_factory=dict)
    takes_units: bool = False

    def referee_for(self, generator: str) -> Referee:
        """The referee of ``referee.generator``: ``"default"`` (:attr:`referee`) or a name of
        :attr:`referees`; :class:`~armlab.errors.ConfigError` naming the valid ones otherwise."""
        if generator == "default" and self.referee is not None:
            return self.referee
        if generator in self.referees:
            return self.referees[generator]
        valid = ["default"] * (self.referee is not None) + list(self.referees)
        raise ConfigError(f"referee.generator={generator!r} is no referee of this protocol; valid: {valid}")


@dataclass(frozen=True, kw_only=True, eq=False)
class Command:
    """An extra CLI verb a protocol brings (e.g. ``fit-joint``).

    ``run(args, viz) -> exit status``; ``usage`` is its line in ``armlab --help``.
    """

    name: str
    usage: str
    help: str
    run: Callable[[list[str], Any], int]


@dataclass(frozen=True, kw_only=True, eq=False)
class Protocol:
    """One paper's protocol, as the runner, CLI and docs see it.

    Attributes:
        name: the protocol's name (``protocol=<name>`` on the command line).
        paper: where it comes from (``../shared/seeds/<id>``, short title).
        summary: one line for ``armlab --help``.
        schema: its experiment dataclass (a subclass of
            :class:`~armlab.config.schema.ExperimentConfig` holding only the groups it reads);
            None for a diagnosis-only protocol.
        groups: config group -> default option (``configs/<group>/<option>.yaml``) composed
            before the protocol's own ``configs/protocol/<name>.yaml`` (if that file exists).
        simulate: ``(cfg) -> Simulated``.
        preload: ``() -> None``, optional: loads what the simulation will need and can load before
            it starts (compiled code from numba's cache); the runner calls it on a background
            thread while the run starts (imports, plan), when a core is idle, instead of during
            the simulation, whose rollout keeps every core busy.
        validate: ``(cfg) -> None``: the checks that need no simulation (the scenario, sample rates
            against the perturbation and the sensors, filter cut-offs against Nyquist, windows
            against the record): :class:`~armlab.errors.ConfigError` on a setting that cannot run,
            :class:`~armlab.errors.ArmlabWarning` on one that runs but measures nothing it is set
            for. Run by :func:`armlab.protocols.compose.compose`, so ``armlab run`` refuses before
            its run folder exists.
        reestimate_group: the config group ``armlab estimate`` takes overrides of.
        reestimate: ``(trials, stored_config, overrides) -> results``: estimation again on a
            saved ``trials.h5`` with the run's stored config updated by the overrides.
        outputs: ``(OutputContext) -> {key: path}``: its figures, tables and recording.
        format_table: ``(results, viz) -> str``: the table ``armlab run``/``estimate`` print
            (``viz`` is handed in by the edge, as for ``outputs``).
        effects: the catalogue effects its simulation applies; any other switched-on effect is
            refused, never ignored.
        catalogue: the catalogue effects that can act in this protocol's lab (what
            ``armlab effects protocol=<name>`` lists), applied by its simulation or not.
        lab_effects: catalogue effects that are part of this protocol's nominal lab, each with
            the one config field that switches it (``{"reflex": "reflex.enabled"}``): the lab
            models that physics in its own terms (a muscle-stretch reflex, a translational cuff),
            so ``effects=[<name>]`` is refused for it and the message names that field. An effect
            is either applied through the catalogue (``effects``) or mapped here, never both.
        diagnosis: its ``armlab diagnose`` hooks, if any.
        commands: extra CLI verbs.
        examples: command lines for ``armlab --help`` (without the leading ``armlab``).
    """

    name: str
    paper: str
    summary: str
    schema: type | None = None
    groups: Mapping[str, str] = field(default_factory=dict)
    simulate: Callable[[Any], Simulated] | None = None
    preload: Callable[[], None] | None = None
    validate: Callable[[Any], None] | None = None
    reestimate_group: str | None = None
    reestimate: Callable[[TrialSet, Any, list[str]], dict] | None = None
    outputs: Callable[[OutputContext], dict] | None = None
    format_table: Callable[[dict, Any], str] | None = None
    effects: tuple[str, ...] = ()
    catalogue: tuple[str, ...] = ()
    lab_effects: Mapping[str, str] = field(default_factory=dict)
    diagnosis: DiagnosisHooks | None = None
    commands: tuple[Command, ...] = ()
    examples: tuple[str, ...] = ()

    @property
    def runs(self) -> bool:
        """True if ``armlab run`` can simulate it."""
        return self.simulate is not None and self.schema is not None
