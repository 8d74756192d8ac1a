"""armlab.config.validate and armlab.config.choices: the one validation helper set, Literal choices."""

from __future__ import annotations

import re
from typing import Literal, get_args, get_origin

import pytest

from armlab.cli import compose
from armlab.config import capstan, choices, effects, schema
from armlab.config.validate import check, choice, options
from armlab.errors import ConfigError


@pytest.mark.parametrize(
    ("alias", "constant"),
    [
        (choices.MuscleModel, schema.MUSCLE_VARIANTS),
        (choices.SensorPreset, schema.SENSOR_PRESETS),
        (choices.XiSource, schema.XI_SOURCES),
        (choices.ElbowImpedance, schema.ELBOW_IMPEDANCES),
        (choices.CableMode, capstan.CABLE_MODES),
        (choices.VfsRobotModel, capstan.ROBOT_MODELS),
        (choices.StiffnessLabel, capstan.STIFFNESS_LABELS),
        (choices.PayloadLabel, capstan.PAYLOAD_LABELS),
        (choices.EffectLevel, effects.LEVELS),
    ],
)
def test_tuple_constants_are_the_literal_options(alias, constant):
    assert constant == get_args(alias) == options(alias)
    assert isinstance(constant, tuple)


def test_every_choice_is_a_literal_of_strings():
    for name in choices.__all__:
        alias = getattr(choices, name)
        assert get_origin(alias) is Literal, name
        assert get_args(alias) and all(isinstance(v, str) for v in get_args(alias)), name


def test_choice_reads_a_literal_and_a_tuple_alike():
    messages = []
    for valid in (choices.MuscleModel, ("hill", "linear")):
        with pytest.raises(ConfigError) as err:
            choice("arm.muscle", "foo", valid)
        messages.append(str(err.value))
        choice("arm.muscle", "linear", valid)  # a valid value passes
    assert messages == ["arm.muscle='foo' is not valid; choose one of ['hill', 'linear']"] * 2


def test_check_raises_config_error_with_the_message():
    check(True, "never raised")
    with pytest.raises(ConfigError, match=r"^sim.settle_s must be >= 0.2 s, got 0.0$"):
        check(False, "sim.settle_s must be >= 0.2 s, got 0.0")


def test_options_refuses_the_runtime_str_stand_in():
    # outside TYPE_CHECKING the config modules bind the choice names to str for OmegaConf: passing
    # one of those to choice() instead of the Literal of armlab.config.choices must fail loudly
    with pytest.raises(TypeError, match="Literal"):
        options(str)


@pytest.mark.parametrize(
    ("cls", "field", "path", "alias"),
    [
        (schema.ArmConfig, "muscle", "arm.muscle", choices.MuscleModel),
        (schema.ArmConfig, "model", "arm.model", choices.ArmModel),
        (schema.RobotConfig, "model", "robot.model", choices.RobotModel),
        (schema.SimConfig, "integrator", "sim.integrator", choices.Integrator),
        (schema.SensorsConfig, "preset", "sensors.preset", choices.SensorPreset),
        (schema.EstimatorConfig, "xi_source", "estimator.xi_source", choices.XiSource),
        (schema.ElbowConfig, "impedance", "elbow.impedance", choices.ElbowImpedance),
        (schema.DirectDriveConfig, "model", "motor.model", choices.MotorModel),
        (capstan.CapstanConfig, "cable", "capstan.cable", choices.CableMode),
        (capstan.VfsConfig, "robot_model", "vfs.robot_model", choices.VfsRobotModel),
    ],
)
def test_a_bad_choice_names_the_valid_options(cls, field, path, alias):
    for value in get_args(alias):
        cls(**{field: value})  # every option of the Literal is accepted
    message = f"{path}='bogus' is not valid; choose one of {list(get_args(alias))}"
    with pytest.raises(ConfigError, match=f"^{re.escape(message)}$"):
        cls(**{field: "bogus"})


def test_capstan_model_keeps_its_own_wording():
    with pytest.raises(ConfigError, match=re.escape("capstan.model='x'; valid: ['capstan_planar']")):
        capstan.CapstanConfig(model="x")


def test_a_bad_choice_on_the_command_line_is_refused_through_hydra():
    with pytest.raises(
        ConfigError, match=re.escape("arm.muscle='foo' is not valid; choose one of ['hill', 'linear']")
    ):
        compose(["arm.muscle=foo"])
    _, exp = compose(["arm.muscle=linear", "sim.integrator=RK4"])
    assert (exp.arm.muscle, exp.sim.integrator) == ("linear", "RK4")
