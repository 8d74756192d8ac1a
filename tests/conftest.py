"""Shared fixtures: composed lab scenes and their settled hold states, built once per session."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from armlab.config.schema import ArmConfig, CuffConfig, RobotConfig, SimConfig
from armlab.models.scene import Scene, build_scene
from armlab.sim.hold import HoldState, settle


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
