"""armlab.protocols.registry and the Protocol declarations: one registry, per-protocol configs, one
switch per physical effect, and no protocol named outside its own package."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from armlab.cli import main
from armlab.config.effects import EFFECTS
from armlab.errors import ConfigError
from armlab.protocols import Protocol, registry
from armlab.protocols.compose import check_effects, compose, config_groups

ARMLAB = Path(__file__).resolve().parents[1] / "armlab"


def _strings(path: Path) -> list[tuple[int, str]]:
    """String constants of a module that are not docstrings (docs may name a protocol)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docs = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        (n.lineno, n.value)
        for n in ast.walk(tree)
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs
    ]


def test_no_module_outside_a_protocols_package_names_it():
    names = registry.names()
    assert len(names) >= 4
    found = []
    for path in sorted(ARMLAB.rglob("*.py")):
        rel = path.relative_to(ARMLAB).as_posix()
        for line, text in _strings(path):
            for name in names:
                if name in text and not rel.startswith(f"protocols/{name}/"):
                    found.append(f"{rel}:{line} names {name!r}: {text[:60]!r}")
    assert found == []


def test_registering_twice_and_unknown_names_are_refused():
    p = registry.get(registry.DEFAULT_PROTOCOL)
    assert registry.register(p) is p  # the same object again: a no-op
    clone = Protocol(name=p.name, paper="x", summary="y")
    with pytest.raises(ConfigError, match=f"a protocol named '{p.name}' is already registered"):
        registry.register(clone)
    with pytest.raises(ConfigError, match=r"unknown protocol 'nope'; valid: \["):
        registry.get("nope")
    with pytest.raises(ConfigError, match="cannot be run; valid: "):
        registry.get(registry.DEFAULT_REFEREE, need="run")
    with pytest.raises(ConfigError, match="unknown capability 'fly'"):
        registry.names("fly")


@pytest.mark.parametrize("name", registry.names())
def test_protocol_declarations_are_consistent(name):
    p = registry.get(name)
    assert set(p.catalogue) <= set(EFFECTS)
    assert set(p.effects) <= set(p.catalogue)
    # one switch per physical effect: a lab effect is never also applied through the catalogue
    assert set(p.lab_effects) <= set(p.catalogue) and not set(p.lab_effects) & set(p.effects)
    if p.runs:
        default = p.schema()
        assert default.protocol_name == name
        for path in p.lab_effects.values():
            group, fieldname = path.split(".")
            assert hasattr(getattr(default, group), fieldname), path
        assert p.reestimate_group in config_groups(p)
        assert p.outputs is not None and p.format_table is not None
    if p.diagnosis is not None:
        assert set(p.diagnosis.candidates) <= set(p.catalogue)
        assert set(p.diagnosis.rules) == {"none_tolerance", "min_explained"}


@pytest.mark.parametrize("name", registry.names("run"))
def test_each_protocol_composes_only_its_own_groups(name):
    _, exp = compose([f"protocol={name}"])
    assert type(exp) is registry.get(name).schema
    others = {g for p in registry.protocols() if p.runs for g in config_groups(p)} - set(
        config_groups(registry.get(name))
    )
    for group in sorted(others):
        with pytest.raises(ConfigError, match=f"'{group}' is not read by protocol '{name}'; its groups: "):
            compose([f"protocol={name}", f"{group}.x=1"])


def test_foreign_group_on_the_command_line_names_the_protocols_groups(capsys, tmp_path):
    args = ["run", "protocol=conditioning_window", "frf.welch_window=5000", f"out={tmp_path / 'r'}"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "'frf' is not read by protocol 'conditioning_window'; its groups: ['sim', 'sensors'" in err
    assert "'estimator', 'subject']" in err and not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    ("protocol", "effect", "switch"),
    [
        ("conditioning_window", "reflex", "reflex.enabled"),
        ("conditioning_window", "cuff_compliance", "cuff.rigid"),
        ("conditioning_window", "cocontraction_variation", "subject.enabled"),
        ("virtual_force_sensor", "cable_drag", "capstan.drag"),
    ],
)
def test_a_lab_effect_is_switched_by_its_lab_field_only(protocol, effect, switch):
    _, exp = compose([f"protocol={protocol}", f"effects=[{effect}]"])
    with pytest.raises(
        ConfigError, match=f"part of the lab of protocol '{protocol}'; switch them with {switch}"
    ):
        check_effects(registry.get(protocol), exp)


def test_an_effect_the_lab_does_not_simulate_is_refused_not_ignored(capsys, tmp_path):
    _, exp = compose(["protocol=conditioning_window", "effects=[plane_tilt]"])
    with pytest.raises(ConfigError, match=r"effects \['plane_tilt'\] are not simulated by protocol"):
        check_effects(registry.get("conditioning_window"), exp)
    _, exp = compose(["protocol=conditioning_window", "effects=[joint_friction]"])
    check_effects(registry.get("conditioning_window"), exp)  # applied by the lab: accepted
    assert exp.effects.joint_friction == EFFECTS["joint_friction"]()
    args = ["run", "effects=[reflex]", f"out={tmp_path / 'r'}"]
    assert main(args) == 2  # refused before anything is written
    assert "switch them with reflex.enabled" in capsys.readouterr().err and not (tmp_path / "r").exists()


def test_sweeping_protocols_and_repeating_keys_are_refused():
    with pytest.raises(ConfigError, match="a sweep over protocols is not supported"):
        compose(["protocol=conditioning_window,fractional_elbow"])
    with pytest.raises(ConfigError, match="seed is given twice"):
        compose(["seed=1", "seed=2"])


def test_readme_protocol_table_matches_the_registry():
    # the docs follow the registry: the README's protocol table has one row per registered protocol
    readme = (ARMLAB.parent / "README.md").read_text(encoding="utf-8")
    table = [line.split("|")[1].strip().strip("`") for line in readme.splitlines() if line.startswith("| `")]
    assert table == registry.names()


def test_referee_settings_of_another_protocol_are_refused(capsys, tmp_path):
    args = ["diagnose-benchmark", "referee.protocol=conditioning_window", "referee.noise_std_Nm=0.3"]
    assert main([*args, f"out={tmp_path / 'b'}"]) == 2
    err = capsys.readouterr().err
    assert "['referee.noise_std_Nm=0.3']: not read by the conditioning_window referee" in err
    assert "'referee.force_noise_N'" in err and not (tmp_path / "b").exists()
    from dataclasses import fields

    from armlab.config.diagnosis import REFEREE_SHARED_FIELDS, RefereeConfig

    declared = set(REFEREE_SHARED_FIELDS)
    for p in registry.protocols():
        if p.diagnosis is not None:
            for referee in (p.diagnosis.referee, *p.diagnosis.referees.values()):
                declared |= set(referee.settings) if referee is not None else set()
    assert declared == {f.name for f in fields(RefereeConfig)}  # every field is someone's


@pytest.mark.parametrize(
    ("override", "says"),
    [
        ("capstan.id_ee_mass_kg=abc", "could not be converted to Float"),
        ("seed=x", "could not be converted to Integer"),
    ],
)
def test_a_mistyped_value_says_what_is_wrong_with_it(override, says):
    # Hydra's own message is only "Error merging override ..."; the reason is in its cause
    protocol = "virtual_force_sensor" if override.startswith("capstan") else "conditioning_window"
    with pytest.raises(ConfigError, match=f"{override.split('=')[0]}.*{says}"):
        compose([f"protocol={protocol}", override])


@pytest.mark.parametrize(
    ("protocol", "override", "valid"),
    [
        ("conditioning_window", "arm.nonexistent=1", "preload_N"),
        ("conditioning_window", "+arm.foo=1", "cocontraction"),
        ("virtual_force_sensor", "capstan.drag_stifness_N_per_m=1", "drag_stiffness_N_per_m"),
        ("fractional_elbow", "motor.sensed_mass=0.1", "sensed_mass_kg"),
    ],
)
def test_an_unknown_key_is_refused_with_the_keys_its_group_has(protocol, override, valid):
    # Hydra says only "Key 'x' not in 'ArmConfig'" (and '+' would add the key silently)
    with pytest.raises(ConfigError, match=f"has no key .*its keys: .*'{valid}'"):
        compose([f"protocol={protocol}", override])
