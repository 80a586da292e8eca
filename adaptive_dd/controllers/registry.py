"""Controllers by name or import path, with settings from a scenario's ``[controllers.NAME]`` table.

A scenario lists built-in names (:data:`CONTROLLERS`) or import paths ``"package.module:Class"``
of your own classes (the protocol: ``docs/controllers.md``). Settings every controller takes:

``bandwidth``, ``damping``
    Override the scenario's ``[control]`` gains for this controller.
``label``
    The name the controller's results carry (default: the built-in name, or the class name).
``law``
    On an entry of a new name only: the built-in or import path it runs, with its own table's
    settings (one law twice with two settings, an ablation: :func:`law_of`).

A plug-in class is called with its table's settings as keyword arguments, plus ``gains``
(:class:`Gains`), ``sigma_nominal`` (the arm's base parameters), ``arm`` (the arm, two-link
or from a URDF, with the scenario's overrides) and ``scenario`` if its ``__init__`` names
them. Unknown settings are errors naming the controller and the key.

The table of built-in names and their settings: :mod:`adaptive_dd.controllers.builtins`.
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from adaptive_dd.controllers.base import DEFAULT_GAINS, Controller, Gains
from adaptive_dd.controllers.builtins import (
    ABSENT,
    CONTROLLERS,
    ONLINE_KEYS,
    Builtin,
    Setting,
    inventory,
    slotine_bounds,
)
from adaptive_dd.controllers.plugins import (
    COMMON,
    PythonForm,
    controller_label,
    floor_setting,
    load_controller_class,
    plugin_controller,
    plugin_search,
    table_name,
)
from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.kind import arm_kind
from adaptive_dd.plant.two_link import ClosedFormTwoLink, closed_form_view

__all__ = [
    "ABSENT",
    "COMMON",
    "CONTROLLERS",
    "ONLINE_KEYS",
    "Builtin",
    "Setting",
    "controller_label",
    "controllers_for",
    "gains_for",
    "inventory",
    "law_of",
    "load_controller_class",
    "make_controller",
    "scenario_controller",
    "scenario_controllers",
    "slotine_bounds",
]


IMPORT_PATH = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*:[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$")
"""The shape of a plug-in's import path, ``package.module:Class``."""


def law_of(entry: str, table: dict | None = None) -> str:
    """The law an entry of ``run.controllers`` runs: the entry itself (a built-in name or an import
    path), or the ``law`` its ``[controllers.NAME]`` table names: a variant, one law run a second
    time under a name of its own with its own settings (an ablation).

    Raises
    ------
    ParameterError
        A ``law`` on an entry that is a law already, or a ``law`` that is neither a built-in name nor
        an import path, naming the table and the value.

    Examples
    --------
    >>> from adaptive_dd.controllers.registry import law_of
    >>> law_of("no_observer", {"law": "adaptive_ct", "observer": False})
    'adaptive_ct'
    >>> law_of("adaptive_ct", {"observer": False})
    'adaptive_ct'
    """
    if "law" not in (table or {}):
        return entry
    law = table["law"]
    if entry in CONTROLLERS or ":" in entry:
        raise ParameterError(
            f"controllers.{table_name(entry)}.law: {entry!r} is a law already; `law` gives a new entry "
            f'of run.controllers its law (e.g. run.controllers = [..., "{table_name(entry)}_b"] and '
            f'[controllers.{table_name(entry)}_b] law = "{entry}")'
        )
    if not isinstance(law, str) or not (law in CONTROLLERS or IMPORT_PATH.match(law)):
        import difflib

        near = difflib.get_close_matches(str(law).strip().lower(), list(CONTROLLERS), n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise ParameterError(
            f"controllers.{entry}.law: must be a built-in name ({', '.join(CONTROLLERS)}) or an import "
            f"path 'package.module:Class' (not another variant), got {law!r}{hint}"
        )
    return law


def _variant(spec: str, gains, options: dict, arm, search: tuple, scenario) -> Controller:
    """The entry ``spec`` whose table names its ``law`` (:func:`law_of`): that law built with the
    rest of the table, its results carrying ``spec`` (or the table's ``label``); errors name
    ``spec``'s table, where the setting is."""
    law = law_of(spec, options)
    rest = {k: v for k, v in options.items() if k != "law"}
    rest.setdefault("label", spec)
    try:
        return make_controller(law, gains, rest, arm, search, scenario)
    except ParameterError as exc:
        msg = str(exc).replace(f"controllers.{table_name(law)}", f"controllers.{spec}")
        msg = msg.replace(f"controller {law!r}", f"controller {spec!r} (law {law!r})")
        raise ParameterError(msg) from None


def gains_for(arm, bandwidth=40.0, damping: float = 1.0):
    """The ``[control]`` gains in the form ``arm``'s controllers take.

    Parameters
    ----------
    arm : Arm
        The arm controlled.
    bandwidth : float or sequence of float
        Closed-loop bandwidth [rad/s]: one for every joint, or one per joint (N-joint arms).
    damping : float
        Damping ratio, > 0.

    Returns
    -------
    Gains or JointGains
        :class:`Gains` on the two-link arm, :class:`~adaptive_dd.closed_loop.controllers.JointGains`
        (one bandwidth per joint, a single value broadcast) on an N-joint arm.

    Raises
    ------
    ParameterError
        A bandwidth or damping that is not > 0.

    Examples
    --------
    >>> from adaptive_dd.controllers import gains_for
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> gains_for(Arm.from_urdf(robot_urdf("ur5")), 40.0).bandwidth
    array([40., 40., 40., 40., 40., 40.])
    """
    if closed_form_view(arm) is not None:  # the arm's fast path, as make_controller chooses
        return Gains(bandwidth, damping)
    from adaptive_dd.closed_loop.controllers import JointGains

    return JointGains.of(bandwidth, damping, arm.n_joints)


def scenario_controller(scenario, spec: str) -> tuple[str, Controller]:
    """``(label, controller)`` of one entry of a scenario's controller list, on either arm, as the run
    builds it: its ``[controllers.NAME]`` settings (``adaptive_ct``'s estimator told the scenario's
    ``[plant.uncertainty]``: :func:`~adaptive_dd.closed_loop.controllers.with_stated_uncertainty`),
    the ``[control]`` gains in the arm's form (a plug-in gets :class:`Gains` with the largest
    per-joint bandwidth), plug-ins imported from the scenario's folder or the working directory.

    Raises
    ------
    ParameterError
        An unknown name, a plug-in that does not import, an unknown or invalid setting.
    """
    from pathlib import Path

    src = Path(scenario.source)
    search = plugin_search(src, getattr(scenario, "origin", None))
    opts = scenario.options(controller_label(spec)) or scenario.options(spec)
    in_file = bool(opts)  # the plug-in's table is the file's (not settings handed in code)
    label = controller_label(spec, opts)
    law = law_of(spec, opts)  # a variant's law: what it is built as
    if ":" in law:
        bw = opts.get("bandwidth", scenario.bandwidth)
        g = Gains(float(np.max(bw)), opts.get("damping", scenario.damping))
        opts = {**opts, "bandwidth": g.bandwidth}
    else:
        g = gains_for(scenario.closed_forms or scenario.arm, scenario.bandwidth, scenario.damping)
    arm = scenario.closed_forms or scenario.arm  # the arm the run simulates: its closed forms or its own
    try:
        ctrl = make_controller(spec, g, opts, arm=arm, search=search, scenario=scenario)
    except ParameterError as exc:  # a plug-in's table is checked here, not when the file is read: name it
        if ":" not in law or not in_file or str(exc).startswith(str(src)) or not src.is_file():
            raise
        raise ParameterError(f"{src}: {exc}") from None
    if ":" in spec and "label" not in opts:
        label = str(ctrl.name)  # what the plug-in declares (its class name if nothing)
    return label, ctrl


def scenario_controllers(scenario, specs=None) -> dict[str, Controller]:
    """The controllers of ``specs`` (default the scenario's list) by the name their results carry
    (:func:`scenario_controller`).

    Raises
    ------
    ParameterError
        Two controllers whose results would carry the same name (a plug-in's ``name`` or a
        ``label`` equal to another's), naming both.
    """
    out: dict[str, Controller] = {}
    spec_of: dict[str, str] = {}
    for spec in scenario.controllers if specs is None else specs:
        label, ctrl = scenario_controller(scenario, spec)
        if label in out:
            raise ParameterError(
                f"{scenario.source}: controllers {spec_of[label]!r} and {spec!r} both carry the name "
                f'{label!r} in the results; give one a label = "..." in its [controllers.NAME] table'
            )
        out[label], spec_of[label] = ctrl, spec
    return out


def controllers_for(arm) -> tuple[str, ...]:
    """The built-in names that run on ``arm``.

    Parameters
    ----------
    arm : Arm
        The arm.

    Returns
    -------
    tuple of str
        Every built-in name but the two-link-only ones on an N-joint arm (an arm of the paper's
        geometry runs its closed forms, :func:`make_controller`).

    Examples
    --------
    >>> from adaptive_dd.controllers import controllers_for
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> names = controllers_for(Arm.from_urdf(robot_urdf("ur5")))
    >>> "adaptive_ct" in names, "adaptive_ct_paper" in names  # the paper's estimator: two-link only
    (True, False)
    """
    kind = arm_kind(arm)
    return tuple(n for n, e in CONTROLLERS.items() if e.applies_to(kind))


def _check_settings(spec: str, o: dict, entry: Builtin, kind: str, arm) -> None:
    """Unknown settings, and settings the other arm alone takes, are errors naming controller and key."""
    here = entry.settings_on(kind)
    elsewhere = sorted(k for k in o if k in entry.settings and k not in here)
    if elsewhere:
        k = elsewhere[0]
        raise ParameterError(
            f"controllers.{spec}.{k}: not a setting on {_arm_words(arm)}: {entry.settings[k].rule}"
        )
    bad = sorted(set(o) - set(here))
    if bad:
        takes = [name for name, e in CONTROLLERS.items() if bad[0] in e.settings and name != spec]
        hint = f"; '{bad[0]}' is a setting of {', '.join(takes)}" if takes else ""
        derived = sorted(k for k in here if not entry.settings[k].scenario_key)
        allowed = sorted((set(here) | COMMON) - set(derived))
        if derived:  # settings of make_controller that a scenario file may not set
            hint += f" ({derived}: derived from the scenario, set in code only: make_controller's options)"
        raise ParameterError(f"controllers.{spec}: unknown setting(s) {bad}; allowed: {allowed}{hint}")


def _detector_at_the_top(spec: str, o: dict) -> dict:
    """``estimator.detector`` moved to the top of the table (its one documented place, on both arms),
    with a FutureWarning; both at once is an error."""
    est = o.get("estimator")
    if not (isinstance(est, dict) and "detector" in est):
        return o
    if "detector" in o:
        raise ParameterError(
            f"controllers.{spec}: 'detector' given twice (at the top and in 'estimator'); keep one"
        )
    warnings.warn(
        f"controllers.{spec}.estimator.detector: write the detector's table at the top of "
        f"[controllers.{spec}] (detector = {{...}} or false); inside 'estimator' is accepted for now",
        FutureWarning,
        stacklevel=2,  # one place: shown once per run, not once per caller
    )
    return {**o, "estimator": {k: v for k, v in est.items() if k != "detector"}, "detector": est["detector"]}


def _arm_words(arm) -> str:
    return "the two-link arm" if arm_kind(arm) == "two_link" else f"this {arm.n_joints}-joint arm"


def _chain_controller(spec: str, entry: Builtin, gains, options: dict, o: dict, arm) -> Controller:
    """The N-joint form (:mod:`adaptive_dd.closed_loop.controllers`), the table's defaults filled in."""
    from adaptive_dd.closed_loop.arena_laws import ARM_LAWS

    filled = {k: v for k, v in entry.settings_on("chain").items() if v is not None}
    bw = options.get("bandwidth", gains.bandwidth)
    dmp = options.get("damping", gains.damping)
    try:
        return ARM_LAWS[entry.chain](arm, bw, dmp, **{**filled, **o})
    except ParameterError:
        raise
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"controllers.{spec}: {exc}") from None


def _builtin(spec: str, gains, options: dict, arm) -> Controller:
    entry = CONTROLLERS[spec]
    kind = arm_kind(arm)
    if not entry.applies_to(kind) and kind == "two_link":
        raise ParameterError(
            f"controller {spec!r} runs on N-joint arms only, not on the two-link arm's closed-form "
            f"runtime: it is {entry.only}"
        )
    if not entry.applies_to(kind):
        raise ParameterError(
            f"controller {spec!r} is for the two-link arm only, not for {_arm_words(arm)}: {entry.only}"
        )
    o = _detector_at_the_top(spec, {k: v for k, v in options.items() if k not in COMMON})
    _check_settings(spec, o, entry, kind, arm)
    if kind == "chain":
        return _chain_controller(spec, entry, gains, options, o, arm)
    try:
        g = Gains(options.get("bandwidth", gains.bandwidth), options.get("damping", gains.damping))
    except ParameterError as exc:
        raise ParameterError(f"controllers.{spec}: {exc}") from None
    filled = {k: v for k, v in entry.settings_on("two_link").items() if v is not None}
    try:
        return entry.make(g, {**filled, **o}, arm)
    except (TypeError, ValueError) as exc:
        if str(exc).startswith(f"controllers.{spec}"):  # it names the setting already
            raise ParameterError(str(exc)) from None
        raise ParameterError(f"controllers.{spec}: {exc}") from None


def make_controller(
    spec: str,
    gains=None,
    options: dict | None = None,
    arm=None,
    search: tuple = (),
    scenario=None,
) -> Controller:
    """A controller by built-in name (:data:`CONTROLLERS`) or import path, with its settings, for any arm.

    The one entry point for every arm: on the two-link closed-form arm a built-in is its two-link
    class (:mod:`adaptive_dd.controllers`), on an N-joint :class:`~adaptive_dd.plant.arm.Arm` its
    class in :mod:`adaptive_dd.closed_loop.controllers`; the same name takes the same settings
    with the defaults :data:`CONTROLLERS` states for that arm.

    Parameters
    ----------
    spec : str
        A built-in name or ``"package.module:Class"``.
    gains : Gains, optional
        The scenario's ``[control]`` gains (default 40 rad/s, critically damped); on an N-joint
        arm anything with ``bandwidth`` (one value or one per joint) and ``damping``
        (:class:`~adaptive_dd.closed_loop.controllers.JointGains`). The table's ``bandwidth`` and
        ``damping`` override them.
    options : dict, optional
        The ``[controllers.NAME]`` table.
    arm : Arm, optional
        The arm it controls (default the SICE arm). An arm of the paper's geometry gets the
        two-link class, as a :class:`~adaptive_dd.benchmark.scenario.Scenario` of it runs
        (:func:`~adaptive_dd.plant.two_link.closed_form_view`; ``Arm(general=True)``: the N-joint
        class); a plug-in is handed that arm.
    search : tuple
        Folders to import a plug-in from.
    scenario : Scenario, optional
        The scenario it runs in: a built-in is then built as the scenario runs it (on its arm
        unless ``arm`` is another, its ``[control]`` gains unless ``gains`` are given,
        ``adaptive_ct`` told the model's stated uncertainty and the task's room: what
        :func:`scenario_controller` builds from the scenario's own table); handed to a plug-in
        that asks for it (see :func:`_plugin`).

    Returns
    -------
    Controller
        The controller object, reset by the run before its first trial.

    Raises
    ------
    ParameterError
        Unknown name, a two-link-only name on an N-joint arm, an import path that does not load,
        an unknown or invalid setting, or a setting of the other arm only (naming the controller,
        the key and why).

    Examples
    --------
    >>> from adaptive_dd.controllers import make_controller
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> oracle = make_controller("ct_oracle", arm=Arm.from_urdf(robot_urdf("ur5")))
    >>> oracle.name, oracle.needs_true_model
    ('ct_oracle', True)
    >>> make_controller("adaptive_ct", options={"boost_duration": 0.5}).boost_duration
    0.5
    >>> make_controller("nope")
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.ParameterError: unknown controller 'nope'; ...
    """
    options = dict(options or {})
    own = scenario is not None and (arm is None or arm is scenario.arm)  # the scenario's own arm
    law = law_of(spec, options)
    if own and ":" not in law:  # a built-in as the scenario runs it (the gains too)
        from adaptive_dd.closed_loop.controllers import with_stated_uncertainty

        arm = scenario.closed_forms or scenario.arm
        gains = gains if gains is not None else gains_for(arm, scenario.bandwidth, scenario.damping)
        options = with_stated_uncertainty(law, options, scenario)
    arm = ClosedFormTwoLink.sice() if arm is None else (closed_form_view(arm) or arm)
    base = gains or DEFAULT_GAINS
    if "law" in options:
        return _variant(spec, base, options, arm, search, scenario)
    if spec in CONTROLLERS:
        ctrl = _builtin(spec, base, options, arm)
    elif ":" in spec:
        ctrl = plugin_controller(spec, base, options, arm, scenario, search)
    else:
        raise ParameterError(
            f"unknown controller {spec!r}; built-ins for {_arm_words(arm)}: {controllers_for(arm)}, "
            "or 'package.module:Class', or a name of your own with a law (options={'law': 'adaptive_ct'})"
        )
    if "label" in options:
        if not isinstance(options["label"], str) or not options["label"].strip():
            raise ParameterError(
                f"controllers.{table_name(spec)}.label: the name its results carry, a non-empty string; "
                f"got {options['label']!r}"
            )
        ctrl.name = options["label"]
    if "floor" in options:  # the scenario's choice over the class's own (a wrapped plug-in's too)
        floor = floor_setting(table_name(spec), options["floor"])
        for c in (ctrl, ctrl.ctrl if isinstance(ctrl, PythonForm) else None):
            if c is not None:
                c.floor = floor
    if own and scenario.closed_forms is None and hasattr(ctrl, "state_task"):  # adaptive_ct: the task's room
        ctrl.state_task(scenario)
    return ctrl


def built_controllers(scenario, specs=None):
    """Per controller of ``scenario`` (or of ``specs``, some of them), built as the run builds it:
    ``(spec, form, exception)``, the :func:`~adaptive_dd.controllers.plugins.compiled_form` of a
    compiled plug-in (else None; its declarations and parameters() read as the run reads them), or
    what building it raised."""
    from adaptive_dd.controllers.plugins import compiled_form, is_compiled

    for spec in scenario.controllers if specs is None else specs:
        try:
            label, ctrl = scenario_controller(scenario, spec)
            form = compiled_form(label, ctrl, 1, scenario.sample_period) if is_compiled(ctrl) else None
        except Exception as exc:  # a plug-in may raise anything: reported, not a traceback
            yield spec, None, exc
        else:
            yield spec, form, None


def plugin_functions(scenario) -> list[tuple]:
    """The per-sample functions ``(reset, command, observe, estimate)`` of each compiled plug-in
    of ``scenario`` that can be built (``validate`` says why another cannot): what the run compiles
    into a loop of its own (``validate``'s estimate of the compilation). Only the plug-ins are built:
    the built-ins compile no loop of their own."""
    plugins = [s for s in scenario.controllers if ":" in law_of(s, scenario.options(s))]
    return [
        (f.reset, f.command, f.observe, f.estimate)
        for _, f, _ in built_controllers(scenario, plugins)
        if f is not None
    ]
