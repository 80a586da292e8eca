"""Scenario tables frozen (hashable, for the frozen :class:`~adaptive_dd.benchmark.scenario.Scenario`)
and thawed back to plain values."""

from __future__ import annotations

from typing import Any

__all__ = ["freeze", "thaw"]


class _Table(tuple):
    """A TOML table frozen as a tuple of ``(key, value)`` pairs (hashable)."""

    __slots__ = ()


def freeze(value: Any) -> Any:
    """Lists -> tuples and tables -> sorted ``(key, value)`` tuples, recursively (hashable)."""
    if isinstance(value, dict):
        return _Table(sorted((str(k), freeze(v)) for k, v in value.items()))
    if isinstance(value, list | tuple):
        return tuple(freeze(v) for v in value)
    return value


def thaw(value: Any) -> Any:
    """The inverse of :func:`freeze`: plain dicts and lists again."""
    if isinstance(value, _Table):
        return {k: thaw(v) for k, v in value}
    if isinstance(value, tuple):
        return [thaw(v) for v in value]
    return value
