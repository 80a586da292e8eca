"""Checks of one number, or of a list of numbers, read from a file: each appends ``"key: reason"``
to a list of errors and returns whether the value passed (every problem of a file is reported at
once: :mod:`adaptive_dd.benchmark.scenario_checks`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["check_number"]

_NUM = (int, float, np.integer, np.floating)


def _short(v: Any) -> str:
    s = repr(v)
    return s if len(s) <= 40 else s[:37] + "..."


def check_number(errs: list, key: str, v: Any, lo: float, hi: float, *, integer=False, lo_open=False) -> bool:
    """Check one number in ``[lo, hi]`` (``(lo, hi]`` with lo_open); False and a message if not."""
    if isinstance(v, bool) or not isinstance(v, _NUM) or (integer and not isinstance(v, int | np.integer)):
        errs.append(f"{key}: must be {'an integer' if integer else 'a number'}, got {_short(v)}")
        return False
    if not isinstance(v, int | np.integer) and not math.isfinite(v):
        errs.append(f"{key}: must be finite, got {v!r}")
        return False
    if (v <= lo if lo_open else v < lo) or v > hi:
        errs.append(
            f"{key}: must be in {'(' if lo_open else '['}{_bound(lo)}, {_bound(hi)}], got {_short(v)}"
        )
        return False
    return True


def _bound(x) -> str:
    """A range's bound as a reader gives it: an integer in full (a seed's 9223372036854775807, not
    9.22337e+18), a float in its shortest exact form up to 10 digits."""
    return str(x) if isinstance(x, int | np.integer) else f"{x:.10g}"


def _nums(errs: list, key: str, v: Any, lo: float, hi: float, *, n: int | None = None, **kw) -> bool:
    """A tuple of numbers, each in range; of length n when given."""
    if not isinstance(v, tuple) or (n is not None and len(v) != n):
        what = f"a list of {n} numbers" if n is not None else "a list of numbers"
        errs.append(f"{key}: must be {what}, got {_short(v)}")
        return False
    return all([check_number(errs, key, x, lo, hi, **kw) for x in v])
