"""Exception types of adaptive_dd.

Every error subclasses a built-in so callers may catch ``ValueError``; each
message names the offending parameter, key, file or line and the value.
"""

from __future__ import annotations

import math

__all__ = [
    "DataError",
    "OutputError",
    "ParameterError",
    "ScenarioError",
    "SignalError",
    "UrdfError",
    "is_finite_number",
]


def is_finite_number(x) -> bool:
    """True for a finite ``int`` or ``float`` read from a file (a ``bool`` is not a number)."""
    return not isinstance(x, bool) and isinstance(x, int | float) and math.isfinite(x)


class ParameterError(ValueError):
    """A physical or base parameter, or a configuration value, is invalid."""


class SignalError(ValueError):
    """A state, torque or signal array has the wrong shape or non-finite values."""


class DataError(ValueError):
    """A user's recorded experiment (CSV) cannot be read; names file, line and column."""


class ScenarioError(ValueError):
    """A benchmark scenario (TOML) is invalid; names file, key and reason."""


class OutputError(ValueError):
    """An output folder or file cannot be created or written; names the path and the reason."""


class UrdfError(ValueError):
    """A robot description (URDF) cannot be used; names the file, the element and the reason."""
