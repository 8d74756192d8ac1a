"""armlab: a MuJoCo-based simulated perturbation laboratory for the human arm.

From Python: ``armlab.run(protocol, overrides)``, ``armlab.load_run(folder)`` and
``armlab.diagnose(data, protocol)`` (:mod:`armlab.api`; imported when first used, so that
``import armlab`` stays light).
"""

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
    "RunResult",
    "diagnose",
    "load_run",
    "run",
]

_API = ("RunResult", "diagnose", "load_run", "run")


def __getattr__(name: str):
    if name in _API:
        from armlab import api

        return getattr(api, name)
    raise AttributeError(f"module 'armlab' has no attribute {name!r}")


__version__ = "0.1.0"
