"""adaptive_dd: identification and adaptive control of robot arms across payload changes.

Subpackages
-----------
plant
    Base parameters, dynamics (eqs. 3-9), sampled-data simulator, Pinocchio check.
identification
    Derivative filters (M1, M2), regressor splits, recursive least squares (eq. 14)
    and better estimators.
controllers
    PD, computed torque, adaptive computed torque, Slotine-Li.
benchmark
    Payload-swap tracking benchmark driven by TOML scenarios.
"""

from adaptive_dd import _numba_cache

_numba_cache.configure()  # before any kernel is decorated: see adaptive_dd/_numba_cache.py

from adaptive_dd.errors import (  # noqa: E402
    DataError,
    ParameterError,
    ScenarioError,
    SignalError,
)

__version__ = "0.2.0"


def __getattr__(name: str):
    """The library entry points, imported on first use (keeps ``import adaptive_dd`` light)."""
    lazy = {
        "Simulation": "adaptive_dd.simulation",
        "run_trial": "adaptive_dd.simulation",
        "load_scenario": "adaptive_dd.benchmark.scenario",
        "run_benchmark": "adaptive_dd.benchmark.runner",
        "make_controller": "adaptive_dd.controllers",
    }
    if name in lazy:
        import importlib

        return getattr(importlib.import_module(lazy[name]), name)
    raise AttributeError(f"module 'adaptive_dd' has no attribute {name!r}")


__all__ = [
    "DataError",
    "ParameterError",
    "ScenarioError",
    "SignalError",
    "Simulation",
    "__version__",
    "load_scenario",
    "make_controller",
    "run_benchmark",
    "run_trial",
]
