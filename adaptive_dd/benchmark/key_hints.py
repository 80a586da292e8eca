"""What a misspelt or repeated key of a scenario meant: the hints its errors give."""

from __future__ import annotations

import difflib
from collections import Counter
from collections.abc import Callable, Iterable

__all__ = ["did_you_mean", "nearest_keys", "repeated_entries"]


def nearest_keys(key: str, allowed: Iterable[str]) -> list[str]:
    """The allowed keys nearest ``key``, all as near as the nearest (``seedz``: ``seed`` and
    ``seeds``, the count, which the nearest alone left out); at most three.

    >>> nearest_keys("seedz", ["controllers", "duration", "seed", "seeds"])
    ['seed', 'seeds']
    """
    scored = sorted(((difflib.SequenceMatcher(None, key, a).ratio(), a) for a in allowed), reverse=True)
    best = scored[0][0] if scored else 0.0
    return [a for r, a in scored if r >= 0.6 and r >= best - 0.1][:3]


def did_you_mean(key: str, allowed: Iterable[str], show=repr) -> str:
    """`` (did you mean 'a' or 'b'?)`` of :func:`nearest_keys`, each shown by ``show``; empty when
    none is near.

    >>> did_you_mean("seedz", ["duration", "seed", "seeds"])
    " (did you mean 'seed' or 'seeds'?)"
    """
    near = nearest_keys(key, allowed)
    return f" (did you mean {' or '.join(map(show, near))}?)" if near else ""


def repeated_entries(entries: Iterable[str], table_name: Callable[[str], str]) -> str:
    """What a list repeats: each entry given twice, and the distinct entries that share a settings
    table (``table_name(entry)``: two plug-ins of one class name from two files).

    >>> repeated_entries(["pd", "a:Law", "b:Law", "pd"], lambda x: x.rsplit(":", 1)[-1])
    "'pd' twice; 'a:Law' and 'b:Law' share the settings table [controllers.Law]"
    """
    entries = list(entries)
    said = [f"{x!r} twice" for x, k in Counter(entries).items() if k > 1]
    distinct = list(dict.fromkeys(entries))
    for t, k in Counter(table_name(x) for x in distinct).items():
        if k > 1:
            xs = " and ".join(repr(x) for x in distinct if table_name(x) == t)
            said.append(f"{xs} share the settings table [controllers.{t}]")
    return "; ".join(said)
