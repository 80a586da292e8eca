"""Controllers by name or import path, with settings from a scenario's ``[controllers.NAME]`` table.

A scenario lists built-in names (:data:`CONTROLLERS`) or import paths ``"package.module:Class"``
of your own classes (the protocol: ``docs/controllers.md``). Settings every controller takes:

``bandwidth``, ``damping``
    Override the scenario's ``[control]`` gains for this controller.
``label``
    The name the controller's results carry (default: the built-in name, or the class name).

Built-in settings:

``adaptive_ct``
    ``boost_bandwidth``, ``boost_duration``, ``estimator = {...}`` (fields of
    :class:`~adaptive_dd.identification.two_link_online.TwoLinkOnlineConfig`: ``tau_f``, ``split``,
    ``construction``, ``p0_payload``, ``p0_j2``, ``project``, ``align``), ``detector = {...}``
    (fields of :class:`~adaptive_dd.identification.two_link_online.ChangeDetector`; also accepted inside
    ``estimator``, as on an N-joint arm), or ``detector = false`` for none.
``slotine_li``
    ``gamma`` (seven adaptation gains).
``ct_nominal``, ``pd``
    ``sigma`` (the fixed model, seven base parameters).

A plug-in class is called with its table's settings as keyword arguments, plus ``gains``
(:class:`Gains`), ``sigma_nominal`` (the arm's base parameters), ``arm`` (the arm, two-link
or from a URDF, with the scenario's overrides) and ``scenario`` if its ``__init__`` names
them. Unknown settings are errors naming the controller and the key.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import sys
from collections.abc import Callable
from typing import Any

import numpy as np

from adaptive_dd.controllers.adaptive import ADAPTIVE_ONLINE, AdaptiveCT
from adaptive_dd.controllers.base import DEFAULT_GAINS, Controller, Gains
from adaptive_dd.controllers.feedback import PD, ComputedTorque
from adaptive_dd.controllers.slotine_li import DEFAULT_GAMMA, SlotineLi, default_bounds
from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.two_link_online import ChangeDetector, TwoLinkOnlineConfig
from adaptive_dd.plant.two_link import TwoLinkArm

__all__ = ["CONTROLLERS", "Builtin", "controller_label", "load_controller_class", "make_controller"]

COMMON = {"bandwidth", "damping", "label"}

ONLINE_KEYS = {"tau_f", "split", "construction", "p0_payload", "p0_j2", "project", "align"}


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


def _unknown(spec: str, options: dict, allowed: set) -> None:
    bad = sorted(set(options) - allowed)
    if bad:
        raise ParameterError(f"controllers.{spec}: unknown setting(s) {bad}; allowed: {sorted(allowed)}")


def _sigma(spec: str, options: dict) -> np.ndarray:
    from adaptive_dd.plant.parameters import validate_sigma

    return validate_sigma(options["sigma"], f"controllers.{spec}.sigma")


def _online(spec: str, options: dict) -> TwoLinkOnlineConfig:
    est = dict(options.get("estimator", {}))
    det = options.get("detector", {})
    if "detector" in est:  # also accepted inside ``estimator``, as on an N-joint arm
        if "detector" in options:
            raise ParameterError(
                f"controllers.{spec}: 'detector' given twice (at the top and in 'estimator'); keep one"
            )
        det = est.pop("detector")
    _unknown(f"{spec}.estimator", est, ONLINE_KEYS)
    kw: dict[str, Any] = dict(est)
    if det is False:
        kw["detector"] = None
    elif isinstance(det, dict):
        fields = {f.name for f in dataclasses.fields(ChangeDetector)}
        _unknown(f"{spec}.detector", det, fields)
        kw["detector"] = ChangeDetector(**det)
    else:
        raise ParameterError(
            f"controllers.{spec}.detector: a table of detector settings or false, got {det!r}"
        )
    return dataclasses.replace(ADAPTIVE_ONLINE, **kw)


@dataclasses.dataclass(frozen=True)
class Builtin:
    """A built-in controller: ``make(gains, settings, arm)`` builds it (the settings without the
    common ones, checked against ``settings`` first)."""

    make: Callable[[Gains, dict, Any], Controller]
    settings: frozenset[str] = frozenset()


def _model(spec: str, o: dict, arm) -> np.ndarray:
    """The fixed model: the ``sigma`` setting, else the arm's base parameters."""
    return _sigma(spec, o) if "sigma" in o else arm.sigma


def _adaptive_ct_paper(g: Gains, o: dict, arm) -> Controller:
    from adaptive_dd.controllers.adaptive import adaptive_ct_paper

    ctrl = adaptive_ct_paper(g, arm.sigma)
    ctrl.online = dataclasses.replace(
        ctrl.online, payload_direction=tuple(float(x) for x in arm.payload_direction(0.0))
    )
    return ctrl


def _adaptive_ct(g: Gains, o: dict, arm) -> Controller:
    boost = {k: o[k] for k in ("boost_bandwidth", "boost_duration") if k in o}
    online = dataclasses.replace(
        _online("adaptive_ct", o), payload_direction=tuple(float(x) for x in arm.payload_direction(0.0))
    )
    return AdaptiveCT(online, g, arm.sigma, **boost)


CONTROLLERS: dict[str, Builtin] = {
    "pd": Builtin(lambda g, o, arm: PD(g, _model("pd", o, arm)), frozenset({"sigma"})),
    "ct_nominal": Builtin(
        lambda g, o, arm: ComputedTorque(g, _model("ct_nominal", o, arm)), frozenset({"sigma"})
    ),
    "ct_oracle": Builtin(lambda g, o, arm: ComputedTorque(g, arm.sigma, oracle=True)),
    "ct_oracle_textbook": Builtin(
        lambda g, o, arm: ComputedTorque(g, arm.sigma, oracle=True, reference_velocity=False)
    ),
    "adaptive_ct_paper": Builtin(_adaptive_ct_paper),
    "adaptive_ct": Builtin(
        _adaptive_ct, frozenset({"boost_bandwidth", "boost_duration", "estimator", "detector"})
    ),
    "slotine_li": Builtin(
        lambda g, o, arm: SlotineLi(g, o.get("gamma", DEFAULT_GAMMA), arm.sigma, bounds=slotine_bounds(arm)),
        frozenset({"gamma"}),
    ),
    "slotine_li_oracle": Builtin(
        lambda g, o, arm: SlotineLi(g, theta0=arm.sigma, bounds=slotine_bounds(arm), oracle=True)
    ),
}
"""Names a scenario may list, each with its factory and settings (a new built-in: one entry)."""


def _builtin(spec: str, g: Gains, options: dict, arm) -> Controller:
    o = {k: v for k, v in options.items() if k not in COMMON}
    entry = CONTROLLERS[spec]
    _unknown(spec, o, set(entry.settings))
    return entry.make(g, o, arm)


def slotine_bounds(arm) -> tuple:
    """Slotine-Li's a-priori box for an arm (:func:`~adaptive_dd.controllers.slotine_li.default_bounds`)."""
    return default_bounds(arm.sigma, arm)


def make_controller(
    spec: str,
    gains: Gains | None = None,
    options: dict | None = None,
    arm=None,
    search: tuple = (),
    scenario=None,
) -> Controller:
    """A controller by built-in name or import path, with its settings.

    ``arm`` (default the SICE arm) is the arm it controls; ``scenario`` (optional) is handed to a
    plug-in that asks for it (see :func:`_plugin`).

    Raises
    ------
    ParameterError
        Unknown name, an import path that does not load, an unknown or invalid setting
        (naming the controller and the key).
    """
    options = dict(options or {})
    arm = arm or TwoLinkArm.sice()
    base = gains or DEFAULT_GAINS
    try:
        g = Gains(options.get("bandwidth", base.bandwidth), options.get("damping", base.damping))
    except ParameterError as exc:
        raise ParameterError(f"controllers.{spec}: {exc}") from None
    if spec in CONTROLLERS:
        try:
            ctrl = _builtin(spec, g, options, arm)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"controllers.{spec}: {exc}") from None
    elif ":" in spec:
        given = {"sigma_nominal": arm.sigma, "arm": arm, "scenario": scenario}
        ctrl = _plugin(spec, g, options, given, search)
    else:
        raise ParameterError(
            f"unknown controller {spec!r}; choose from {tuple(CONTROLLERS)} or 'package.module:Class'"
        )
    if "label" in options:
        ctrl.name = str(options["label"])
    return ctrl


PLUGIN_GIVEN = ("gains", "sigma_nominal", "arm", "scenario")
"""What the runner hands a plug-in whose ``__init__`` names it: the gains, the arm's base
parameters without payload, the arm itself, the scenario (None when run outside one)."""


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
        _unknown(spec, kw, set(params) - set(PLUGIN_GIVEN))
    if "gains" in params or takes_any:
        kw["gains"] = g
    kw.update({k: v for k, v in given.items() if k in params})
    try:
        ctrl = cls(**kw)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"controllers.{spec}: {type(exc).__name__}: {exc}") from None
    if not hasattr(ctrl, "name") or ctrl.name == Controller.name:
        ctrl.name = controller_label(spec)
    return ctrl
