"""armlab: a MuJoCo-based simulated perturbation laboratory for the human arm."""

from armlab.errors import (
    ArmlabError,
    ConfigError,
    DataError,
    EstimationError,
    ModelError,
)

__all__ = [
    "ArmlabError",
    "ConfigError",
    "DataError",
    "EstimationError",
    "ModelError",
]

__version__ = "0.1.0"
