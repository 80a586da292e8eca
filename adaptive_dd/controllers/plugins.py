"""Plug-in controllers: a class named by its import path ``"package.module:Class"``, built with its
``[controllers.NAME]`` table's settings and what the runner hands it (:data:`PLUGIN_GIVEN`).

The protocol (``reset``, ``command``, ``observe``) and a worked example on each kind of arm:
``docs/controllers.md``. :func:`~adaptive_dd.controllers.registry.make_controller` calls
:func:`plugin_controller` for any name with a ``:``.
"""

from __future__ import annotations

import importlib
import inspect
import sys

from adaptive_dd.controllers.base import Controller, Gains
from adaptive_dd.errors import ParameterError

__all__ = [
    "COMMON",
    "PLUGIN_GIVEN",
    "controller_label",
    "load_controller_class",
    "plugin_controller",
    "unknown_settings",
]

COMMON = {"bandwidth", "damping", "label"}
"""Settings every controller takes, built-in or plug-in (``docs/controllers.md``)."""


def controller_label(spec: str, options: dict | None = None) -> str:
    """The name results carry: the ``label`` setting, the built-in name, or the class name."""
    if options and "label" in options:
        return str(options["label"])
    return spec.rsplit(":", 1)[-1].rsplit(".", 1)[-1] if ":" in spec else spec


def load_controller_class(path: str, search: tuple = ()) -> type:
    """Import ``"package.module:Class"``; clear errors for a missing module, class or protocol.

    The module is looked up on the Python path, then in the folders ``search`` (the
    scenario file's folder and the working directory, when a scenario names it).
    """
    if ":" not in path:
        raise ParameterError(f"controller {path!r}: an import path is 'package.module:Class'")
    mod_name, _, attr = path.partition(":")
    extra = [str(p) for p in search if str(p) not in sys.path]
    sys.path[len(sys.path) :] = extra
    try:
        obj = importlib.import_module(mod_name)
    except ImportError as exc:
        raise ParameterError(f"controller {path!r}: cannot import module {mod_name!r}: {exc}") from None
    finally:
        for p in extra:
            sys.path.remove(p)
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ParameterError(f"controller {path!r}: module {mod_name!r} has no {attr!r}")
        obj = getattr(obj, part)
    missing = [m for m in ("reset", "command", "observe") if not callable(getattr(obj, m, None))]
    if not inspect.isclass(obj) or missing:
        raise ParameterError(
            f"controller {path!r}: not a controller class (needs reset, command, observe; missing {missing})"
        )
    return obj


def unknown_settings(spec: str, options: dict, allowed: set) -> None:
    """A :class:`ParameterError` naming the controller, the settings not in ``allowed`` and those allowed."""
    bad = sorted(set(options) - allowed)
    if bad:
        raise ParameterError(f"controllers.{spec}: unknown setting(s) {bad}; allowed: {sorted(allowed)}")


PLUGIN_GIVEN = ("gains", "sigma_nominal", "arm", "scenario")
"""What the runner hands a plug-in whose ``__init__`` names it: the gains, the arm's base
parameters without payload, the arm itself, the scenario (None when run outside one)."""


def plugin_controller(spec: str, gains, options: dict, arm, scenario=None, search: tuple = ()) -> Controller:
    """The plug-in ``spec`` built with its ``options`` (its table; ``bandwidth`` and ``damping``
    override ``gains``) and the :data:`PLUGIN_GIVEN` its ``__init__`` names: ``arm`` (what the run
    simulates: the :class:`~adaptive_dd.plant.arm.Arm`, or on the paper's arm its closed forms'
    record), its base parameters ``sigma_nominal``, ``scenario``.

    Raises
    ------
    ParameterError
        An import path that does not load, a class that is not a controller, an unknown setting,
        a setting the runner gives, a bad bandwidth or damping.
    """
    try:
        g = Gains(options.get("bandwidth", gains.bandwidth), options.get("damping", gains.damping))
    except ParameterError as exc:
        raise ParameterError(f"controllers.{spec}: {exc}") from None
    given = {"sigma_nominal": arm.sigma, "arm": arm, "scenario": scenario}
    return _plugin(spec, g, options, given, search)


def _plugin(spec: str, g: Gains, options: dict, given: dict, search: tuple) -> Controller:
    """A plug-in class called with its settings and the :data:`PLUGIN_GIVEN` it names
    (``gains`` also to a ``**kwargs``)."""
    cls = load_controller_class(spec, search)
    kw = {k: v for k, v in options.items() if k not in COMMON}
    params = inspect.signature(cls).parameters
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    clash = sorted(set(kw) & set(PLUGIN_GIVEN))
    if clash:
        raise ParameterError(
            f"controllers.{spec}: {clash} are given by the runner, not settings (remove them from the table)"
        )
    if not takes_any:
        unknown_settings(spec, kw, set(params) - set(PLUGIN_GIVEN))
    if "gains" in params or takes_any:
        kw["gains"] = g
    kw.update({k: v for k, v in given.items() if k in params})
    try:
        ctrl = cls(**kw)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"controllers.{spec}: {type(exc).__name__}: {exc}") from None
    if not getattr(ctrl, "name", None) or ctrl.name == Controller.name:  # none declared: the class name
        ctrl.name = controller_label(spec)
    return ctrl
