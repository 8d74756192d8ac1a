"""Scenario files: a missing key is named, never a bare KeyError."""

from __future__ import annotations

import pytest
import yaml

from armlab.errors import ConfigError
from armlab.perturbations import scenario as scen


def test_missing_interpolation_key_is_named(tmp_path, monkeypatch):
    raw = yaml.safe_load((scen.SCENARIO_DIR / "conditioning_window.yaml").read_text())
    assert scen.load_scenario("conditioning_window").name == "conditioning_window"
    for key in ("k", "base_s", "step_s"):
        broken = {**raw, "interpolation": {k: v for k, v in raw["interpolation"].items() if k != key}}
        (tmp_path / "broken.yaml").write_text(yaml.safe_dump(broken))
        monkeypatch.setattr(scen, "SCENARIO_DIR", tmp_path)
        with pytest.raises(ConfigError, match=f"missing key '{key}'"):
            scen.load_scenario("broken")
        monkeypatch.undo()
