"""Registration of the structured configs in Hydra's ConfigStore, and config loading helpers."""

from __future__ import annotations

from pathlib import Path

from hydra.core.config_store import ConfigStore
from omegaconf import DictConfig, OmegaConf

from armlab.config.schema import ExperimentConfig
from armlab.errors import ConfigError

__all__ = [
    "CONFIG_DIR",
    "available_options",
    "register_configs",
    "to_experiment",
]

CONFIG_DIR = Path(__file__).resolve().parents[2] / "configs"


def register_configs() -> None:
    """Register the experiment schema as ``base_config`` (idempotent)."""
    ConfigStore.instance().store(name="base_config", node=ExperimentConfig)


def available_options(group: str) -> list[str]:
    """Names of the YAML options of a config group (``configs/<group>/*.yaml``)."""
    folder = CONFIG_DIR / group
    return sorted(p.stem for p in folder.glob("*.yaml")) if folder.is_dir() else []


def to_experiment(cfg: DictConfig) -> ExperimentConfig:
    """Turn a composed config into the typed dataclass, running every ``__post_init__`` check."""
    try:
        obj = OmegaConf.to_object(cfg)
    except ConfigError:
        raise
    except Exception as exc:  # OmegaConf validation errors carry a useful first line
        raise ConfigError(str(exc).splitlines()[0]) from None
    if not isinstance(obj, ExperimentConfig):
        raise ConfigError(f"composed config is a {type(obj).__name__}, not an ExperimentConfig")
    return obj
