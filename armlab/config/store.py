"""Registration of the structured configs in Hydra's ConfigStore, and config loading helpers."""

from __future__ import annotations

from pathlib import Path

from hydra.core.config_store import ConfigStore
from omegaconf import DictConfig, OmegaConf

from armlab.config.schema import ExperimentConfig
from armlab.config.validate import check_finite
from armlab.errors import ConfigError

__all__ = [
    "CONFIG_DIR",
    "apply_overrides",
    "available_options",
    "stored_group",
    "to_experiment",
]

CONFIG_DIR = Path(__file__).resolve().parents[2] / "configs"


def available_options(group: str) -> list[str]:
    """Names of the options of a config group: ``configs/<group>/*.yaml`` and the typed nodes
    stored in Hydra's ConfigStore under that group (e.g. the effect catalogue)."""
    folder = CONFIG_DIR / group
    names = {p.stem for p in folder.glob("*.yaml")} if folder.is_dir() else set()
    try:
        names |= {n.removesuffix(".yaml") for n in ConfigStore.instance().list(group)}
    except OSError:  # no node stored under that group
        pass
    return sorted(names)


def to_experiment(cfg: DictConfig) -> ExperimentConfig:
    """Turn a composed config into its typed dataclass (a protocol's subclass of
    :class:`ExperimentConfig`), running every ``__post_init__`` check."""
    try:
        obj = OmegaConf.to_object(cfg)
    except ConfigError:
        raise
    except Exception as exc:  # OmegaConf validation errors carry a useful first line
        raise ConfigError(str(exc).splitlines()[0]) from None
    if not isinstance(obj, ExperimentConfig):
        raise ConfigError(f"composed config is a {type(obj).__name__}, not an ExperimentConfig")
    return obj


def apply_overrides(base, prefix: str, overrides: list[str] | None = None):
    """A config group updated by ``<prefix>.<field>=<value>`` overrides, validated.

    Args:
        base: the group's dataclass instance (its ``__post_init__`` checks run on the result) or a
            structured DictConfig of it.
        prefix: the group's name in the experiment config (e.g. ``"frf"``, ``"estimator"``).
        overrides: items like ``frf.welch_window=10000``, ``frf.band_hz=[0.5,40]``, ``x.y=null``.

    Returns:
        The updated dataclass instance.

    Raises:
        ConfigError: an item of another shape, an unknown field, or a value the schema rejects,
            each naming the valid choices or the problem.
    """
    cfg = base if isinstance(base, DictConfig) else OmegaConf.structured(base)
    for item in overrides or []:
        key, sep, value = item.partition("=")
        if not sep or not key.startswith(f"{prefix}.") or key.count(".") != 1:
            raise ConfigError(f"argument {item!r} must look like {prefix}.<field>=<value>")
        name = key.split(".", 1)[1]
        if name not in cfg:
            raise ConfigError(f"unknown {prefix} field {name!r}; valid: {sorted(cfg.keys())}")
        try:
            cfg = OmegaConf.merge(cfg, OmegaConf.from_dotlist([f"{name}={value}"]))
        except Exception as exc:  # OmegaConf type errors: keep their first line, name the field
            raise ConfigError(f"{item}: {str(exc).strip().splitlines()[0]}") from None
    try:
        obj = OmegaConf.to_object(cfg)
    except ConfigError:
        raise
    except Exception as exc:
        raise ConfigError(str(exc).strip().splitlines()[0]) from None
    check_finite(obj, prefix)
    return obj


def stored_group(schema, stored: DictConfig, name: str):
    """The config group ``name`` of a run's stored config on its schema (defaults for the fields
    the stored config lacks), as a structured DictConfig ready for :func:`apply_overrides`."""
    return OmegaConf.merge(OmegaConf.structured(schema), stored.get(name, {}))
