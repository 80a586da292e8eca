"""Exception types of adaptive_dd.

Every error subclasses a built-in so callers may catch ``ValueError``; each
message names the offending parameter, key, file or line and the value.
"""

from __future__ import annotations

import math
import numbers

__all__ = [
    "DataError",
    "OutputError",
    "ParameterError",
    "RunWarning",
    "ScenarioError",
    "SignalError",
    "UrdfError",
    "is_finite_number",
]


def is_finite_number(x) -> bool:
    """True for a finite ``int`` or ``float`` read from a file, or a NumPy scalar given in code (a
    ``bool`` is not a number)."""
    return not isinstance(x, bool) and isinstance(x, numbers.Real) and math.isfinite(x)


class ParameterError(ValueError):
    """A physical or base parameter, or a configuration value, is invalid.

    Examples
    --------
    >>> from adaptive_dd.identification.filters import design_filter_bank
    >>> design_filter_bank("M3", tau_f=0.01)
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.ParameterError: method must be 'M1' or 'M2', got 'M3'
    """


class SignalError(ValueError):
    """A state, torque or signal array has the wrong shape or non-finite values.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd import Simulation, load_scenario
    >>> Simulation(load_scenario()).step(np.zeros(2))
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.SignalError: call reset() before step()
    """


class DataError(ValueError):
    """A user's recorded experiment (CSV) cannot be read; names file, line and column.

    Examples
    --------
    >>> from adaptive_dd.io import read_recording
    >>> read_recording("missing.csv")
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.DataError: missing.csv: no such file
    """


class ScenarioError(ValueError):
    """A benchmark scenario (TOML) is invalid; names file, key and reason.

    Examples
    --------
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> parse_scenario({"payload": {"mass": 3.0}}, src="mine.toml")
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.ScenarioError: mine.toml: payload: must be an array of tables [[payload]]
    """


class OutputError(ValueError):
    """An output folder or file cannot be created or written; names the path and the reason.

    Examples
    --------
    >>> import tempfile
    >>> from adaptive_dd.outputs import check_output_dir
    >>> a_file = tempfile.mkstemp()[1]
    >>> check_output_dir(a_file + "/results")
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.OutputError: /.../results: cannot create the output folder: /... is a file
    """


class UrdfError(ValueError):
    """A robot description (URDF) cannot be used; names the file, the element and the reason.

    Examples
    --------
    >>> from adaptive_dd.plant import Arm
    >>> Arm.from_urdf("nope.urdf")
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.UrdfError: nope.urdf: no such URDF file
    """


class RunWarning(UserWarning):
    """Something a run did that its results need read with: a controller's floor that did not run
    (its ratios NaN), a trial's divergence, ... The command line prints it on one line
    (``adaptive-dd: warning: ...``); from Python it is a ``UserWarning``."""
