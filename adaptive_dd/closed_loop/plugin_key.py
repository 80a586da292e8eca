"""The key of a compiled plug-in's cached loop: a hash of what numba compiles of it.

numba's own cache (``cache=True``) is keyed by the time stamp of the file that defines the function
it compiled, not by what that function calls or reads: cached under such a key, a plug-in's loop
would outlive an edit of its helper in another file. The loop of a plug-in
(:func:`adaptive_dd.closed_loop.plugin_loop.plugin_loop`) is therefore a module of its own, named
by :func:`function_key`: a hash of the plug-in's functions as numba compiles them (bytecode,
constants, flags and argument counts, defaults, jit options), of the ``njit`` functions they reach
in any file and of the values they read from globals (recursively, through a user module's
attributes too), and of every numba extension (``@overload``, ``@overload_method``, ...) defined
outside numba, numpy and this package in the process (an attribute such as ``a.gain()`` may reach
one, which no name shows). Whatever the key cannot follow (a closure's cells, a class, a module
that serves attributes through ``__getattr__``, a typing template written by hand) gives no key:
the loop is then compiled in every process. Globals are read as they are when the key is made,
as numba freezes them when it compiles.
"""

from __future__ import annotations

import hashlib
import inspect
import sys
import types
from pathlib import Path

import numpy as np
from numba.core.dispatcher import Dispatcher

__all__ = ["function_key"]

_SAFE = frozenset({"adaptive_dd", "numba", "numpy", "math", "cmath", "builtins", "operator"})
"""Packages whose functions a plug-in may call without their code being keyed (their names are):
the cache folder is keyed by this package's kernels, and numba's cache by numba's version."""


class Unkeyable(Exception):
    """A plug-in's function reads something its key cannot follow."""


def _root(obj) -> str:
    return (getattr(obj, "__module__", None) or "").split(".")[0]


def _canonical(v) -> str:
    """A repr that is the same in every process (sets sorted: their order follows the hash seed)."""
    if isinstance(v, set | frozenset):
        return "{" + ", ".join(sorted(_canonical(x) for x in v)) + "}"
    if isinstance(v, dict):
        items = sorted(v.items(), key=repr)
        return "{" + ", ".join(f"{_canonical(k)}: {_canonical(x)}" for k, x in items) + "}"
    if isinstance(v, list | tuple):
        return type(v).__name__ + "(" + ", ".join(_canonical(x) for x in v) + ")"
    return repr(v)


def _value(h, v) -> None:
    """Hash a value numba compiles in as a constant (a global, a default, a code constant)."""
    if v is None or v is Ellipsis or isinstance(v, bool | int | float | complex | str | bytes | np.generic):
        h.update(repr((type(v).__name__, v)).encode())
    elif isinstance(v, np.ndarray):
        h.update(f"array{v.dtype}{v.shape}".encode())
        h.update(np.ascontiguousarray(v).tobytes())
    elif isinstance(v, tuple | frozenset):  # a named tuple's type and field names too
        h.update(f"{type(v).__module__}.{type(v).__qualname__}{getattr(v, '_fields', '')}".encode())
        for x in v if isinstance(v, tuple) else sorted(v, key=repr):
            _value(h, x)
    elif inspect.iscode(v):
        _code(h, v)
    else:
        raise Unkeyable(repr(v))


def _code(h, code) -> None:
    """Hash a code object: its bytecode, flags, argument counts, names, constants and place (not
    its file's other text)."""
    h.update(f"{code.co_qualname}@{code.co_filename}:{code.co_firstlineno}".encode())
    h.update(code.co_code)
    counts = (code.co_flags, code.co_argcount, code.co_posonlyargcount, code.co_kwonlyargcount)
    h.update(repr(counts).encode())
    for names in (code.co_names, code.co_varnames, code.co_freevars, code.co_cellvars):
        h.update(repr(names).encode())
    _value(h, code.co_consts)


def _names(code) -> set:
    """The global and attribute names a code object and the code nested in it read."""
    names = set(code.co_names)
    for c in code.co_consts:
        if inspect.iscode(c):
            names |= _names(c)
    return names


def _options(h, f) -> None:
    """Hash a dispatcher's jit options: its target options, ``locals``, its signatures when they
    were given (no other is compiled then) and its pipeline."""
    h.update(_canonical(getattr(f, "targetoptions", {})).encode())
    h.update(_canonical(getattr(f, "locals", {})).encode())
    if not getattr(f, "_can_compile", True):
        h.update(_canonical([str(s) for s in f.signatures]).encode())
    pipeline = getattr(getattr(f, "_compiler", None), "pipeline_class", None)
    h.update(f"{getattr(pipeline, '__module__', '')}.{getattr(pipeline, '__qualname__', '')}".encode())


def _function(h, f, seen: set) -> None:
    """Hash an ``njit`` function (or a plain one an extension compiles) and what it reaches from
    its globals (:func:`_globals`)."""
    py = getattr(f, "py_func", f)
    if id(py) in seen:
        return
    seen.add(id(py))
    if not inspect.isfunction(py) or py.__closure__ or py.__kwdefaults__:
        raise Unkeyable(f"{py!r} is built at run time or takes keyword-only defaults")
    _options(h, f)
    _code(h, py.__code__)
    _value(h, py.__defaults__)
    _globals(h, py.__globals__, _names(py.__code__), seen)


def _globals(h, space: dict, names: set, seen: set) -> None:
    """Hash what ``names`` find in a module's ``space``: ``njit`` functions outside :data:`_SAFE`
    (recursively; inside it, their names), a user's module's attributes of those names, plain
    values (numba compiles them in as constants), the name of a :data:`_SAFE` module, function or
    type. Anything else (a class, a plain function numba would compile through an overload) is
    :class:`Unkeyable`."""
    for name in sorted(names & space.keys()):
        v = space[name]
        h.update(name.encode())
        if isinstance(v, Dispatcher):
            if _root(v.py_func) in _SAFE:
                h.update(f"{v.py_func.__module__}.{v.py_func.__qualname__}".encode())
            else:
                _function(h, v, seen)
        elif isinstance(v, types.ModuleType):  # each function's names walked in it: each reads its own
            h.update(v.__name__.encode())
            walk = (id(v), frozenset(names))
            if v.__name__.split(".")[0] not in _SAFE and walk not in seen:
                if "__getattr__" in vars(v):  # what it serves is not in its namespace
                    raise Unkeyable(f"module {v.__name__} serves attributes through __getattr__")
                seen.add(walk)
                _globals(h, vars(v), names, seen)
        elif callable(v) and _root(v) in _SAFE:  # np.sin, math.cos, np.float64: which one
            h.update(f"{_root(v)}.{getattr(v, '__qualname__', getattr(v, '__name__', repr(v)))}".encode())
        else:
            _value(h, v)


def _extensions(h, seen: set) -> None:
    """Hash every numba typing template defined outside :data:`_SAFE` by a module loaded in this
    process (as it is now, not an earlier load of it): an ``@overload`` / ``@overload_method`` /
    ``@overload_attribute``'s function (its code and what it reaches), sorted by name. A template
    written by hand there is :class:`Unkeyable`. A process that has loaded other extensions gives
    other keys (a compilation more, never a stale loop)."""
    import numba
    from numba.core.typing.templates import builtin_registry

    found = {}
    numba_dir = Path(numba.__file__).parent
    for tmpl in (*builtin_registry.functions, *builtin_registry.attributes):
        f = getattr(tmpl, "_overload_func", None)
        if f is not None:
            code = getattr(f, "__code__", None)  # numba's own operators' have no module: their file
            inside = code is not None and Path(code.co_filename).is_relative_to(numba_dir)
            loaded = vars(sys.modules[f.__module__]) if f.__module__ in sys.modules else None
            if _root(f) not in _SAFE and not inside and loaded is getattr(f, "__globals__", None):
                found[f"{f.__module__}.{f.__qualname__}"] = f  # of a module loaded now, as it is now
        elif _root(tmpl) not in _SAFE | {"abc"}:
            raise Unkeyable(f"a typing template of {tmpl.__module__}")
    for name in sorted(found):
        h.update(name.encode())
        _function(h, found[name], seen)


def function_key(functions, salt: bytes) -> str | None:
    """The key of the loop of a plug-in's ``functions`` (``njit`` functions), ``salt`` the loop's
    own code (module docstring); None when one of them reads what the key cannot follow."""
    h = hashlib.sha1(salt)
    seen: set = set()
    try:
        for f in functions:
            h.update(f"{f.py_func.__module__}.{f.py_func.__qualname__}".encode())
            _function(h, f, seen)
        _extensions(h, seen)
    except Unkeyable:
        return None
    return h.hexdigest()[:16]
