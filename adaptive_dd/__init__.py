"""adaptive_dd: identification and adaptive control of a two-link direct-drive arm.

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

from adaptive_dd.errors import (
    DataError,
    ParameterError,
    ScenarioError,
    SignalError,
)

__version__ = "0.1.0"

__all__ = [
    "DataError",
    "ParameterError",
    "ScenarioError",
    "SignalError",
    "__version__",
]
