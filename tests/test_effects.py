"""armlab.config.effects: the catalogue of unmodelled effects, its YAML options and composition."""

from __future__ import annotations

import math
from dataclasses import fields

import pytest

from armlab.cli import compose
from armlab.config import effects as fx
from armlab.config.effects import EFFECTS, LEVELS, EffectsConfig, enabled_effects
from armlab.config.store import CONFIG_DIR, available_options
from armlab.errors import ConfigError
from armlab.protocols import registry


def test_catalogue_entries_are_documented_and_switchable():
    assert list(EFFECTS) == [f.name for f in fields(EffectsConfig)]
    for name, cls in EFFECTS.items():
        assert cls.NAME == name
        assert cls.LEVEL in LEVELS
        assert cls.PHYSICS and cls.SOURCE
        assert any(name in p.catalogue for p in registry.protocols())  # it acts in some lab
        assert set(cls.SIGNED) <= {f.name for f in fields(cls)}
        params = cls().params()
        assert params and all(isinstance(v, float) and math.isfinite(v) for v in params.values())


def test_confusable_compliances_name_each_other_and_one_separating_trial():
    cuff, transmission = EFFECTS["cuff_compliance"], EFFECTS["transmission_compliance"]
    assert cuff.CONFUSABLE["transmission_compliance"] == transmission.CONFUSABLE["cuff_compliance"]


def test_effect_options_come_from_the_dataclasses_alone():
    # the dataclass is the single source of truth: every option is a ConfigStore node, no YAML
    # repeats a default
    assert available_options("effects") == sorted(EFFECTS)
    assert not (CONFIG_DIR / "effects").exists()
    for name, cls in EFFECTS.items():
        _, exp = compose([f"effects=[{name}]"])
        assert getattr(exp.effects, name) == cls()


@pytest.mark.parametrize(
    ("cls", "kw", "message"),
    [
        (fx.Reflex, {"delay_s": -0.01}, "effects.reflex.delay_s must be finite and >= 0, got -0.01"),
        (
            fx.JointFriction,
            {"coulomb_Nm": math.inf},
            "effects.joint_friction.coulomb_Nm must be finite and >= 0",
        ),
        (fx.ChannelDelay, {"delay_s": math.nan}, "effects.channel_delay.delay_s must be finite, got nan"),
        (
            fx.CuffCompliance,
            {"damping_Nms_per_rad": -1},
            "effects.cuff_compliance.damping_Nms_per_rad must be",
        ),
    ],
)
def test_bad_parameter_values_are_refused(cls, kw, message):
    with pytest.raises(ConfigError) as err:
        cls(**kw)
    assert message in str(err.value)


def test_signed_parameters_may_be_negative():
    assert fx.ChannelDelay(delay_s=-0.004).delay_s == -0.004  # force channel ahead of position
    assert fx.Reflex(direction=-1.0).direction == -1.0
    assert fx.ForceSensorDrift(bias=-0.2, drift_per_s=-0.01).params() == {"bias": -0.2, "drift_per_s": -0.01}


def test_each_protocol_names_the_catalogue_effects_of_its_lab():
    joint = registry.get("joint_1dof").catalogue
    assert {"reflex", "joint_friction", "channel_delay", "cuff_compliance"} <= set(joint)
    assert "cable_drag" not in joint and "plane_tilt" not in joint
    vfs = registry.get("virtual_force_sensor").catalogue
    assert vfs[0] == "reflex" and "cable_drag" in vfs
    for p in registry.protocols():
        assert set(p.catalogue) <= set(EFFECTS) and set(p.effects) <= set(p.catalogue)
        if p.diagnosis is not None:  # every candidate it scores acts in its lab
            assert set(p.diagnosis.candidates) <= set(p.catalogue)


def test_enabled_effects_in_catalogue_order():
    cfg = EffectsConfig(joint_friction=fx.JointFriction(), reflex=fx.Reflex(delay_s=0.03))
    on = enabled_effects(cfg)
    assert list(on) == ["reflex", "joint_friction"]
    assert on["reflex"].delay_s == 0.03
    assert enabled_effects(EffectsConfig()) == {}


def test_compose_switches_effects_on_and_tunes_them():
    _, exp = compose(["effects=[reflex,joint_friction]", "effects.reflex.delay_s=0.05"])
    on = enabled_effects(exp.effects)
    assert list(on) == ["reflex", "joint_friction"]
    assert on["reflex"] == fx.Reflex(delay_s=0.05)
    assert on["joint_friction"] == fx.JointFriction()


def test_compose_without_effects_leaves_all_off():
    _, exp = compose([])
    assert enabled_effects(exp.effects) == {}


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["effects=[reflex,nope]"], "unknown effect(s) ['nope']; valid: ['accel_misalignment', "),
        (
            ["effects.reflex.delay_s=0.05"],
            "effects.reflex.delay_s=0.05: effect 'reflex' is not switched on; add effects=[reflex] "
            "(selected: none)",
        ),
        (
            ["effects=[joint_friction]", "effects.reflex.gain_Nms_per_rad=3"],
            "effect 'reflex' is not switched on; add effects=[reflex] (selected: ['joint_friction'])",
        ),
        (
            ["effects=[reflex]", "effects.reflex.delay_s=-0.01"],
            "effects.reflex.delay_s must be finite and >= 0, got -0.01",
        ),
        (
            ["effects=[reflex]", "effects.reflex.nope=1"],
            "effects.reflex.nope=1: effect 'reflex' has no key 'nope'; its keys: "
            "['delay_s', 'gain_Nms_per_rad'",
        ),
    ],
)
def test_compose_errors_name_the_problem(overrides, message):
    with pytest.raises(ConfigError) as err:
        compose(overrides)
    assert message in str(err.value)
