"""Plug-in controllers: a class named by its import path ``"package.module:Class"``, built with its
``[controllers.NAME]`` table's settings and what the runner hands it (:data:`PLUGIN_GIVEN`).

The protocol (``reset``, ``command``, ``observe``) and a worked example on each kind of arm:
``docs/controllers.md``. :func:`~adaptive_dd.controllers.registry.make_controller` calls
:func:`plugin_controller` for any name with a ``:``.

A plug-in whose ``reset``, ``command`` and ``observe`` are ``numba.njit`` functions is a compiled
plug-in (:func:`is_compiled`): it runs inside the compiled closed loop
(:mod:`adaptive_dd.closed_loop.plugin_loop`; what the loop hands it: :func:`compiled_form`), on
an N-joint arm and, through ``run_benchmark``, on the paper's arm's closed forms. Any other runs
on the Python path, and the run says so once (:func:`slow_path_note`).
"""

from __future__ import annotations

import importlib
import inspect
import sys

import numpy as np

from adaptive_dd.controllers.base import Controller, Gains, declared
from adaptive_dd.errors import ParameterError

__all__ = [
    "BOUNDS_HINT",
    "COMMON",
    "PLUGIN_GIVEN",
    "PluginForm",
    "PythonForm",
    "check_controller_object",
    "compiled_form",
    "controller_label",
    "floor_of",
    "floor_setting",
    "is_compiled",
    "load_controller_class",
    "plugin_controller",
    "slow_path_note",
    "table_name",
    "unknown_settings",
]

COMMON = {"bandwidth", "damping", "label", "floor"}
"""Settings every controller takes, built-in or plug-in (``docs/controllers.md``)."""


def floor_setting(table: str, value) -> str | None:
    """A ``floor`` setting checked: the name of the controller the report divides this one's error
    by (one of the run's), or ``false`` for none; a :class:`ParameterError` naming the table else."""
    if value is False:
        return None
    if not isinstance(value, str) or not value.strip():
        raise ParameterError(
            f"controllers.{table}.floor: the name of one of the run's controllers (its error divides "
            f"this one's in the report), or false for none; got {value!r}"
        )
    return value


def floor_of(ctrl) -> str | None:
    """The floor a controller object declares: its ``floor`` (a class attribute or the table's
    setting), the documented default (``base.DECLARED``: ``ct_oracle``) when it has none, None for
    ``None`` or ``False``; anything else is a :class:`ParameterError` naming the class."""
    value = declared(ctrl, "floor")  # the documented default; False read as None there
    if value is None:
        return None
    if not isinstance(value, str) or not value.strip():
        raise ParameterError(
            f"{type(ctrl).__name__}.floor = {value!r}: the name of one of the run's controllers (its "
            "error divides this one's in the report), or None (False) for none"
        )
    return value


def controller_label(spec: str, options: dict | None = None) -> str:
    """The name results carry: the ``label`` setting, the built-in name, or the class name."""
    if options and "label" in options:
        return str(options["label"])
    return spec.rsplit(":", 1)[-1].rsplit(".", 1)[-1] if ":" in spec else spec


def plugin_search(source, origin: str | None = None) -> tuple:
    """The folders a scenario's plug-ins are looked up in after the Python path: the folder of the
    scenario file (``origin``, absolute, as it was read; else ``source``'s when it is a file from
    here), then the working directory."""
    from pathlib import Path

    src = Path(str(source))
    first = Path(origin) if origin is not None else src.parent if src.is_file() else None
    if first is None or first.resolve() == Path.cwd().resolve():  # the same folder named once
        return (Path.cwd(),)
    return (first, Path.cwd())


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
        looked = ", ".join(str(p) for p in search) if search else "none"
        hint = (
            f" (looked on the Python path and in: {looked}); put {mod_name.replace('.', '/')}.py beside the "
            "scenario file or in the working directory, or add its folder to PYTHONPATH"
            if isinstance(exc, ModuleNotFoundError) and exc.name == mod_name.split(".")[0]
            else ""
        )
        raise ParameterError(f"controller {path!r}: cannot import module {mod_name!r}: {exc}{hint}") from None
    finally:
        for p in extra:
            sys.path.remove(p)
    module = obj
    _check_not_shadowed(path, module, mod_name, search)
    for part in attr.split("."):
        if not hasattr(obj, part):
            from adaptive_dd.benchmark.key_hints import did_you_mean

            named, hint = _module_named(module, mod_name, search)
            hint = hint or did_you_mean(part, [n for n in dir(obj) if not n.startswith("_")])
            raise ParameterError(f"controller {path!r}: {named} has no {attr!r}{hint}")
        obj = getattr(obj, part)
    missing = [m for m in ("reset", "command", "observe") if not callable(getattr(obj, m, None))]
    if not inspect.isclass(obj) or missing:
        raise ParameterError(
            f"controller {path!r}: not a controller class (needs reset, command, observe; missing {missing})"
        )
    return obj


def _check_not_shadowed(path: str, module, mod_name: str, search: tuple) -> None:
    """A :class:`ParameterError` when ``module``, found first on the Python path (an installed
    package or a standard module of that name) or imported earlier in this process from another
    folder, is another file than the first of ``search`` that holds it (the scenario's folder
    before the working directory): the run would take the wrong one without a word."""
    from pathlib import Path

    where = getattr(module, "__file__", None)
    rel = mod_name.replace(".", "/")
    mine = [
        f.resolve()
        for d in search
        for f in (Path(d) / f"{rel}.py", Path(d) / rel / "__init__.py")
        if f.is_file()
    ]
    if mine and where is not None and Path(where).resolve() != mine[0]:
        raise ParameterError(
            f"controller {path!r}: module {mod_name!r} ({where}) is found before your {mine[0]} (an "
            "installed package or a standard module of the same name, or a file of that name imported "
            f"earlier in this process): rename your file, e.g. my_{mod_name.rsplit('.', 1)[-1]}.py"
        )


def _module_named(module, mod_name: str, search: tuple) -> tuple[str, str]:
    """``("module 'NAME' (its file)", hint)``, the hint naming the file of ``search`` the module
    shadows: a plug-in's file named as an installed package or a standard module (``control.py``,
    ``glob.py``) is found after them on the Python path."""
    from pathlib import Path

    where = getattr(module, "__file__", None)
    text = f"module {mod_name!r}" + (f" ({where})" if where else "")
    rel = mod_name.replace(".", "/") + ".py"
    mine = [(Path(p) / rel).resolve() for p in search if (Path(p) / rel).is_file()]
    if mine and (where is None or Path(where).resolve() != mine[0]):
        return text, (
            f"; that module is found on the Python path before your {mine[0]} (an installed package or "
            f"a standard module of the same name): rename your file, e.g. my_{mod_name.rsplit('.', 1)[-1]}.py"
        )
    return text, ""


def check_controller_object(where: str, what: str, obj) -> None:
    """A :class:`ParameterError` unless ``obj`` is a controller object (an instance with callable
    ``reset``, ``command`` and ``observe``), naming ``where`` (the function) and ``what`` (the
    argument: ``controllers['a']``, ``controller``)."""
    if isinstance(obj, str):
        raise ParameterError(
            f"{where}: {what} is the name {obj!r}, not a controller object; build a built-in with "
            f"adaptive_dd.make_controller({obj!r}), or run the scenario's own by name with "
            "scenario.with_controllers([...]) and run_benchmark"
        )
    if inspect.isclass(obj):
        raise ParameterError(
            f"{where}: {what} is the class {obj.__name__}, not a controller object; pass an instance "
            f"({obj.__name__}(...))"
        )
    missing = [m for m in ("reset", "command", "observe") if not callable(getattr(obj, m, None))]
    if missing:
        raise ParameterError(
            f"{where}: {what} ({type(obj).__name__}) is not a controller: it needs reset, command and "
            f"observe; missing {missing} (docs: controllers, 'Your own controller: the protocol')"
        )
    try:
        floor_of(obj)
    except ParameterError as exc:
        raise ParameterError(f"{where}: {what}: {exc}") from None


def table_name(name: str) -> str:
    """The ``[controllers.NAME]`` a controller's settings table is named by: a built-in's name, a
    plug-in's class name (``"package.module:Class"`` -> ``"Class"``)."""
    return name.rsplit(":", 1)[-1].rsplit(".", 1)[-1] if ":" in name else name


def unknown_settings(spec: str, options: dict, allowed: set) -> None:
    """A :class:`ParameterError` naming the controller, the settings not in ``allowed`` and those allowed."""
    # a plug-in takes the COMMON settings (taken out before); a built-in's sub-table (its estimator) none
    common = COMMON if ":" in spec else set()
    bad = sorted(set(options) - allowed - common)
    if bad:
        from adaptive_dd.benchmark.key_hints import nearest_keys

        near = {b: nearest_keys(b, allowed | common) for b in bad}
        hint = "; ".join(f"{b!r}: did you mean {' or '.join(map(repr, n))}?" for b, n in near.items() if n)
        raise ParameterError(
            f"controllers.{table_name(spec)}: unknown setting(s) {bad}"
            + (f" ({hint})" if hint else "")
            + f"; allowed: {sorted(allowed | common)}"
        )


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
        raise ParameterError(f"controllers.{table_name(spec)}: {exc}") from None
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
            f"controllers.{table_name(spec)}: {clash} are given by the runner, not settings (remove them "
            "from the table)"
        )
    if not takes_any:
        unknown_settings(spec, kw, set(params) - set(PLUGIN_GIVEN))
    _check_setting_types(spec, params, kw)
    if "gains" in params or takes_any:
        kw["gains"] = g
    kw.update({k: v for k, v in given.items() if k in params})
    try:
        ctrl = cls(**kw)
    except Exception as exc:  # the user's code: its error, named by its table, not an internal one
        hint = ""
        arm = given.get("arm")
        if isinstance(exc, AttributeError) and arm is not None and getattr(arm, "chain", None) is None:
            hint = (
                f" (on the paper's arm a plug-in is handed {CLOSED_FORMS}'s record: sigma, regressor, "
                "mass_matrix, nominal_inertia; an arm from a URDF has the rest: "
                "benchmarks/scenarios/sice_general.toml)"
            )
        raise ParameterError(f"controllers.{table_name(spec)}: {type(exc).__name__}: {exc}{hint}") from None
    if not getattr(ctrl, "name", None) or ctrl.name == Controller.name:  # none declared: the class name
        ctrl.name = controller_label(spec)
    try:
        floor_of(ctrl)
    except ParameterError as exc:
        raise ParameterError(f"controllers.{table_name(spec)}: {exc}") from None
    if given.get("arm") is not None and is_compiled(ctrl):
        if getattr(given["arm"], "chain", None) is None:  # the closed forms' record: no compiled loop for it
            return PythonForm(ctrl.name, ctrl, given["arm"], CLOSED_FORMS)
    return ctrl


def _check_setting_types(spec: str, params, kw: dict) -> None:
    """A setting of another kind than its ``__init__`` default (a number given as text or as
    true/false, true/false as a number): a :class:`ParameterError` naming the table, the key, the value
    and the default (the class's own error named neither, and ``kp = true`` ran as 1.0)."""
    for key, value in kw.items():
        p = params.get(key)
        if p is None or p.default is inspect.Parameter.empty or p.default is None:
            continue
        d = p.default
        flag = isinstance(d, bool | np.bool_)
        listed = isinstance(d, list | tuple | np.ndarray) and np.size(d) > 0  # a per-joint default
        number = not flag and (isinstance(d, int | float | np.number) or (listed and _is_number_like(d)))
        wrong = (number and not _is_number_like(value)) or (flag and not isinstance(value, bool | np.bool_))
        if wrong:
            kind = "true or false" if flag else "a number (or a list of numbers)"
            raise ParameterError(
                f"controllers.{table_name(spec)}.{key} = {value!r}: {kind} (the class's default is {d!r})"
            )


def _is_number_like(value) -> bool:
    """A number, or a (nested) list of numbers (a per-joint setting)."""
    if isinstance(value, bool | np.bool_ | str):
        return False
    if isinstance(value, list | tuple | np.ndarray):
        return all(_is_number_like(v) for v in np.ravel(np.asarray(value, dtype=object)))
    return isinstance(value, int | float | np.number)


CLOSED_FORMS = "the paper's closed-form two-link runtime"
"""Why a compiled plug-in on the paper's arm's closed forms is wrapped in a :class:`PythonForm`:
other users of the closed forms (the stepping API, the Gymnasium face) call it trial by trial;
``run_benchmark`` unwraps it into the two-link compiled loop
(:func:`adaptive_dd.benchmark.drivers.run_plugin`)."""

# ------------------------------------------------------------------ the compiled protocol
_PER_SAMPLE = ("reset", "command", "observe")


def is_compiled(ctrl) -> bool:
    """Whether ``ctrl`` is a compiled plug-in: its ``reset``, ``command`` and ``observe`` are all
    ``numba.njit`` functions (a :class:`ParameterError` when only some are: say which)."""
    from numba.core.dispatcher import Dispatcher

    jitted = [m for m in _PER_SAMPLE if isinstance(getattr(ctrl, m, None), Dispatcher)]
    if jitted and len(jitted) < len(_PER_SAMPLE):
        plain = [m for m in _PER_SAMPLE if m not in jitted]
        raise ParameterError(
            f"controller {type(ctrl).__name__}: {jitted} are numba.njit functions but {plain} are not; "
            "a compiled plug-in compiles all three (docs/own_controller.md), a plain one none"
        )
    return bool(jitted)


class PluginForm:
    """What the compiled loop runs for a compiled plug-in (:func:`compiled_form`).

    Attributes
    ----------
    params : object
        The plug-in's ``parameters(sample_period)`` (any value numba compiles).
    need : int
        Bits of :data:`~adaptive_dd.closed_loop.plugin_loop.NEEDS`: the model terms the loop computes.
    state : ndarray (S, m)
        Per-trial state, ``m = state_size`` (0: none), zeros (``reset`` fills trial i's row).
    reset, command, observe, estimate : numba dispatchers
        The per-sample functions (``estimate`` a no-op when the plug-in reports no estimate).
    estimates : bool
        Whether the loop records ``estimate``'s base parameters.
    true_model : bool
        The terms are of each trial's true model (``needs_true_model``), else of the controllers'.
    """

    def __init__(self, params, need, state, functions, estimates, true_model) -> None:
        self.params, self.need, self.state = params, need, state
        self.reset, self.command, self.observe, self.estimate = functions
        self.estimates, self.true_model = estimates, true_model


def compiled_form(name: str, ctrl, n_trials: int, sample_period: float) -> PluginForm:
    """The :class:`PluginForm` of compiled plug-in ``ctrl`` (results name ``name``) for ``n_trials``.

    Reads its declarations: ``needs`` (names of
    :data:`~adaptive_dd.closed_loop.plugin_loop.NEEDS`, default none), ``state_size`` (floats per
    trial, default 0), ``parameters(sample_period)`` (default ``()``), ``estimate`` (an ``njit``
    function ``estimate(p, x, out)``, or none) and ``needs_true_model``.

    Raises
    ------
    ParameterError
        An unknown need, a ``state_size`` that is not an integer >= 0, an ``estimate`` that is
        not compiled, ``parameters`` that raise.
    """
    from numba import typeof
    from numba.core.dispatcher import Dispatcher

    from adaptive_dd.closed_loop.plugin_loop import NEEDS, no_estimate

    where = f"controllers.{name}"
    needs = declared_needs(ctrl)
    bad = [x for x in needs if x not in NEEDS]
    if bad:
        raise ParameterError(
            f"{where}: needs {bad} are not terms the compiled loop hands over; allowed: {sorted(NEEDS)}"
        )
    size = getattr(ctrl, "state_size", 0)
    if isinstance(size, bool) or not isinstance(size, int | np.integer) or size < 0:
        raise ParameterError(f"{where}: state_size must be an integer >= 0 (floats per trial), got {size!r}")
    est = getattr(ctrl, "estimate", None)
    if est is not None and not isinstance(est, Dispatcher):
        raise ParameterError(
            f"{where}: estimate must be a numba.njit function estimate(p, x, out), got {est!r}"
        )
    make = getattr(ctrl, "parameters", None)
    try:
        params = () if make is None else make(float(sample_period))
    except Exception as exc:
        raise ParameterError(
            f"{where}: parameters({sample_period}) raised {type(exc).__name__}: {exc}"
        ) from None
    try:
        typeof(params)
    except (ValueError, TypeError) as exc:  # numba would fail every trial with a page of typing errors
        raise ParameterError(
            f"{where}: parameters({sample_period}) returned a {type(params).__name__}, which numba "
            f"cannot compile ({exc}); return a tuple of arrays and numbers (docs/controllers.md, "
            "'Compiled plug-ins')"
        ) from None
    need = 0
    for x in needs:
        need |= NEEDS[x]
    state = np.zeros((int(n_trials), int(size)))  # none with state_size 0: x[0] is an IndexError
    checked = tuple(_bounds_checked(f) for f in (ctrl.reset, ctrl.command, ctrl.observe))
    functions = (*checked, _bounds_checked(est) if est is not None else no_estimate)
    return PluginForm(
        params, need, state, functions, est is not None, bool(getattr(ctrl, "needs_true_model", False))
    )


def declared_needs(ctrl) -> tuple:
    """A compiled plug-in's ``needs`` as a tuple of names (one name alone allowed)."""
    needs = getattr(ctrl, "needs", ())
    return (needs,) if isinstance(needs, str) else tuple(needs)


def no_kernels(name: str, where: str) -> ParameterError:
    """The error of plug-in ``name`` that needs ``regressor`` where (``where``) no arm kernels are."""
    return ParameterError(
        f"controllers.{name}: needs 'regressor', the kernels of an arm from a URDF; {where} has none: "
        "run the paper's arm on the general kernels (its URDF with general = true: "
        "benchmarks/scenarios/sice_general.toml)"
    )


BOUNDS_HINT = (
    "an index beyond an array the loop hands the plug-in: its state x has state_size floats per trial "
    "(declare state_size as large as reset, command and observe use), q, qd, tau and the reference n, "
    "sigma p, and p is what parameters() returns (an index or an unpacking beyond its items) "
    "(docs/controllers.md, 'Compiled plug-ins')"
)
"""What an ``IndexError`` inside a compiled plug-in's functions most likely means (the run's message)."""


def _bounds_checked(f):
    """A plug-in's ``njit`` function compiled again with numba's bounds checking on (its other
    options kept, its cache off): numba checks no index by default, so a plug-in that writes past
    its state (a ``state_size`` too small) would write into the next trial's state, and its
    results would change from run to run without an error. Checked, such an index raises an
    ``IndexError``, which fails the plug-in's trials with :data:`BOUNDS_HINT`. A function that
    already checks its bounds is kept as it is; the checked one is made once per function and kept
    on it (the loop compiled for it is found again: numba keys it by the function object)."""
    from numba import njit

    options = {k: v for k, v in f.targetoptions.items() if k not in ("cache", "nopython")}
    if options.get("boundscheck"):
        return f
    checked = getattr(f, "_adaptive_dd_bounds_checked", None)
    if checked is None:
        checked = njit(**{**options, "boundscheck": True}, locals=dict(f.locals))(f.py_func)
        f._adaptive_dd_bounds_checked = checked
    return checked


def slow_path_note(name: str, ctrl) -> str:
    """The one line a run prints for a controller on the Python path: that it is slow, and why."""
    return (
        f"{name}: a plain-Python controller ({type(ctrl).__module__}.{type(ctrl).__qualname__}) runs on "
        "the slow Python path, one command per sample for the batch of trials; write its reset, command and "
        "observe as numba.njit functions to run it in the compiled loop (docs/own_controller.md)"
    )


class PythonForm:
    """A compiled plug-in on the Python path (``engine="python"``; one built on the paper's
    closed forms, :data:`CLOSED_FORMS`, for their users other than ``run_benchmark``, which runs
    it in the two-link compiled loop unless it needs the arm's kernels): its ``njit`` functions called
    trial by trial, the model terms it declares from the arm's regressor and mass matrix (of the
    true model given to an oracle, ``sigma_true``). Says once per run that it is on the slow path.

    Parameters
    ----------
    name : str
        The name its results carry.
    ctrl : object
        The compiled plug-in (:func:`is_compiled`).
    arm : Arm or closed forms' record
        ``regressor(q, qd, qdd)``, ``mass_matrix(q, sigma)``, ``sigma``.
    why : str
        Why it is not in the compiled loop (printed).
    """

    def __init__(self, name: str, ctrl, arm, why: str) -> None:
        self.name, self.ctrl, self.arm, self.why = name, ctrl, arm, why
        self.floor = floor_of(ctrl)
        self.needs_true_model = bool(getattr(ctrl, "needs_true_model", False))
        self.form: PluginForm | None = None

    takes_pi_true = True
    """The Python path gives ``pi_true`` (each trial's plant): the arm's kernels of an oracle's model."""

    def reset(self, n_trials: int, sample_period: float) -> None:
        from adaptive_dd.closed_loop.plugin_loop import NEED_REGRESSOR

        f = compiled_form(self.name, self.ctrl, n_trials, sample_period)
        self.kin = None
        if getattr(self.arm, "chain", None) is not None:
            from adaptive_dd.controllers.kernels import arm_kernels

            pj, pmap = int(self.arm.payload_joint), np.ascontiguousarray(self.arm.payload_map, dtype=float)
            self.kin = arm_kernels(self.arm.chain, np.ascontiguousarray(self.arm.pi, dtype=float), pj, pmap)
        elif f.need & NEED_REGRESSOR:
            raise no_kernels(self.name, self.why)
        print(
            f"{self.name}: a compiled plug-in on the slow Python path ({self.why}): its functions are "
            "called trial by trial, sample by sample",
            file=sys.stderr,
            flush=True,
        )
        self.form = f
        self.T, self._k = float(sample_period), 0
        self._alarms: list[list[float]] = [[] for _ in range(int(n_trials))]
        for i in range(int(n_trials)):
            f.reset(f.params, f.state[i])

    def _terms(self, q, qd, sigma):
        """``(g, M, bias)`` per trial as the compiled loop gives them (NaN where not declared)."""
        from adaptive_dd.closed_loop.plugin_loop import NEED_BIAS, NEED_GRAVITY, NEED_MASS_MATRIX

        S, n = q.shape
        need, zero = self.form.need, np.zeros_like(q)
        g, m, c = np.full((S, n), np.nan), np.full((S, n, n), np.nan), np.full((S, n), np.nan)
        if need & NEED_GRAVITY:
            g = np.einsum("tip,tp->ti", self.arm.regressor(q, zero, zero), sigma)
        if need & NEED_MASS_MATRIX:
            m = np.stack([self.arm.mass_matrix(q[i], sigma[i]) for i in range(S)])
        if need & NEED_BIAS:
            c = np.einsum("tip,tp->ti", self.arm.regressor(q, qd, zero), sigma)
        return np.ascontiguousarray(g), np.ascontiguousarray(m), np.ascontiguousarray(c)

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None, pi_true=None):
        from adaptive_dd.controllers.kernels import with_model

        f = self.form
        q, qd = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float)
        sigma = sigma_true if self.needs_true_model and sigma_true is not None else self.arm.sigma
        sigma = np.broadcast_to(np.asarray(sigma, dtype=float), (q.shape[0], np.shape(sigma)[-1]))
        g, m, c = self._terms(q, qd, sigma)
        ref = [np.ascontiguousarray(r, dtype=float) for r in (q_d, qd_d, qdd_d)]
        out = np.empty_like(q)
        kin = self.kin
        for i in range(q.shape[0]):
            if kin is not None and self.needs_true_model and pi_true is not None:
                kin = with_model(kin, np.ascontiguousarray(pi_true[i], dtype=float))
            f.command(f.params, f.state[i], q[i], qd[i], *ref, (g[i], m[i], c[i], kin), out[i])
        return out

    def observe(self, q, qd, tau) -> None:
        f = self.form
        q, qd = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float)
        tau = np.ascontiguousarray(tau, dtype=float)
        for i in range(q.shape[0]):
            if f.observe(f.params, f.state[i], q[i], qd[i], tau[i]) == 1:
                self._alarms[i].append(self._k * self.T)
        self._k += 1

    @property
    def sigma_hat(self):
        f = self.form
        if f is None or not f.estimates:
            return None
        out = np.empty((f.state.shape[0], np.shape(self.arm.sigma)[-1]))
        for i in range(out.shape[0]):
            f.estimate(f.params, f.state[i], out[i])
        return out

    @property
    def alarm_times(self):
        return self._alarms if getattr(self.ctrl, "has_detector", False) and self.form is not None else None
