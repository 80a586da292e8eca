"""Benchmark scenarios: TOML files read with ``tomllib`` and checked field by field.

Every key is optional; the value after ``=`` below is the default that is used
(and shown as such by ``adaptive-dd validate``) when a key is left out::

    [run]
    duration = 20.0            # s, > 0 (the run size is limited, see below)
    sample_period = 0.001      # s, T in [1e-5, 0.1] and T <= duration / 10
    seeds = 10                 # Monte-Carlo trials per controller, 1 .. 10000
    seed = 0                   # base seed, 0 <= seed < 2**63
    substeps = 2               # RK4 steps per sample, 1 .. 100
    excite = 0.0               # s of designed excitation before the task, its identification
                               # the controllers' model (N-joint arms; 0: none; <= 3600)
    controllers = ["pd", "ct_nominal", "ct_oracle", "adaptive_ct_paper", "adaptive_ct",
                   "slotine_li", "slotine_li_oracle"]
                               # names, or import paths "package.module:Class"

    [control]
    bandwidth = 40.0           # rad/s, shared by all controllers; bandwidth * T <= 0.2;
                               # an N-joint (URDF) arm also takes one value per joint
    damping = 1.0              # in (0, 10]

    [controllers.NAME]         # settings of one listed controller (NAME: its name, or the
    key = value                # class name of an import path); plain TOML values, kept as given;
                               # adaptive_ct's estimator and detector settings are derived from
                               # the arm and the scenario, not keys (scenario_settings.DERIVED)

    [reference]                # q_d(t) = offset + w(t) sum_k a_k sin(2 pi f_k t + phase_k);
                               # default: the shipped payload_swap scenario's reference
    ramp = 0.0                 # s, w rises smoothly from 0 to 1 over this time, 0 <= ramp <= 3600
    joint1 = { offset = 0.0, amplitude = [0.5, 0.2], frequency = [0.4, 1.1], phase = [0.0, 0.0] }
    joint2 = { offset = 0.0, amplitude = [0.6, 0.2], frequency = [0.5, 1.3], phase = [0.0, 0.0] }
                               # rad, Hz, rad; |offset| + sum |a_k| <= 10 rad; 0 < f_k <= 0.1 / T;
                               # |phase_k| <= 100 rad; at most 50 terms; phase defaults to zeros

    [[payload]]                # a disk at the tip of link 2 from `at` on; 0 kg before the first
    at = 5.0                   # s, required; every segment holds at least one sample
    mass = 3.0                 # kg, required, 0 .. 50
    radius = 0.05              # m, 0 .. 0.5, the same for every disk

    [plant]                    # N-joint arms: the simulated robot when it is not the [arm]
    urdf = "FILE"              # other inertials, the same joints and frames (and friction law keys)
    viscous = [...]            # per joint, the plant's only; also coulomb, armature
    [plant.uncertainty]        # a plant drawn per seed (adaptive_dd.plant.uncertainty)
    mass = 0.1                 # relative; com [m]; inertia, viscous, coulomb, armature relative
    distribution = "uniform"   # or "normal"

    [model]
    from = "FILE.urdf"         # the controllers' model: these link inertials (N-joint arms)
    uncertainty = {mass = 0.1} # how far it may be from the robot (levels as [plant.uncertainty];
                               # default: the plant's draw levels, else exact)

    [noise]                    # Tables 2 and 4 of the paper
    position_variance = [1e-8, 1e-7]   # rad^2, each in [0, 1]
    velocity_variance = [5e-5, 1e-4]   # (rad/s)^2, each in [0, 1]
    dropout = 0.0              # probability that a sample's measurement is lost (NaN), 0 .. 0.5

Why these limits: a reference component at frequency f sampled at T is seen
by the discrete controllers with ``1 / (f T)`` samples per period; the loop
tracks it only well below its bandwidth (40 rad/s ~ 6.4 Hz at 1 kHz), so we
require at least 10 samples per period (``f <= 0.1 / T``, 100 Hz at 1 kHz),
five times inside the Nyquist limit ``0.5 / T``. ``bandwidth * T <= 0.2`` keeps
the discrete PD part of every controller well inside its stability region.
Masses above 50 kg are beyond what the arm's direct-drive motors can lift.
Finally the size of the run (samples x seeds x controllers) is estimated and a
run above 4 GiB of recorded signals or 24 h of estimated wall time is refused
(:func:`run_estimate`).

All problems of a file are collected and raised at once as one
:class:`~adaptive_dd.errors.ScenarioError` whose lines read ``file: key: reason``.
Checks live in ``Scenario.__post_init__``, so ``dataclasses.replace`` cannot
bypass them.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.benchmark.scenario_base import LIMITS, Reference, RunEstimate, run_estimate
from adaptive_dd.benchmark.scenario_checks import (
    scenario_errors,
    scenario_fields,
    table_name,
    thaw,
)
from adaptive_dd.benchmark.scenario_format import format_scenario
from adaptive_dd.benchmark.scenario_settings import controller_setting_errors, derived_setting_errors
from adaptive_dd.errors import ScenarioError
from adaptive_dd.plant.arm import Arm
from adaptive_dd.plant.arm_tables import arm_from_tables
from adaptive_dd.plant.parameters import PAYLOAD_RADIUS
from adaptive_dd.plant.two_link import ClosedFormTwoLink, as_arm, as_two_link_cached, closed_form_view
from adaptive_dd.plant.uncertainty import (
    PLANT_TRUTH_KEYS,
    PlantSpec,
    Uncertainty,
    model_uncertainty,
    parse_model,
    parse_plant,
)

__all__ = [
    "LIMITS",
    "Reference",
    "RunEstimate",
    "Scenario",
    "default_scenario_path",
    "format_scenario",
    "load_scenario",
    "model_and_plant",
    "parse_scenario",
    "read_toml",
    "run_estimate",
    "scenario_closed_forms",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Scenario:
    """A checked benchmark scenario (see the module docstring for the file format).

    Made by :func:`load_scenario` or :func:`parse_scenario`. Constructing one (also through
    ``dataclasses.replace``) checks every field and raises one :class:`ScenarioError` listing
    all problems.

    ``arm`` is an :class:`~adaptive_dd.plant.arm.Arm` (default the paper's SICE arm; a
    :class:`~adaptive_dd.plant.two_link.ClosedFormTwoLink` given here becomes the arm it is the
    closed forms of, :func:`~adaptive_dd.plant.two_link.as_arm`). An arm of the paper's geometry
    runs the closed forms, chosen here automatically: :attr:`closed_forms` holds their record
    (:func:`~adaptive_dd.plant.two_link.closed_form_view`), None where the general kernels run
    (any other arm, ``Arm(general=True)``, a ``plant`` apart from the arm).

    Attributes
    ----------
    name : str
        The scenario's name (its file's stem).
    duration : float
        Length of a trial [s].
    sample_period : float
        The control and sensor period T [s].
    seeds : int
        Trials per controller.
    controllers : tuple of str
        The controllers run, by name or import path.
    reference : Reference
        The desired joint trajectory (sums of sines per joint).
    swap_times, swap_masses : tuple of float
        When the payload changes [s] and its mass after each change [kg].
    position_variance, velocity_variance : tuple of float
        The sensors' noise per joint [rad^2], [(rad/s)^2].
    bandwidth : float or tuple of float
        Every controller's closed-loop bandwidth [rad/s] (one per joint, or one for all).
    arm : Arm
        The arm the controllers are given.
    plant : PlantSpec or None
        The simulated robot when it is not ``arm`` (drawn around it per seed); None: ``arm``.
    excite : float
        Seconds of designed excitation before the task; 0: none.
    closed_forms : ClosedFormTwoLink or None
        The paper's closed forms when they run this scenario.

    Examples
    --------
    >>> from adaptive_dd import load_scenario
    >>> sc = load_scenario()
    >>> sc.duration, sc.sample_period, sc.n_samples
    (20.0, 0.001, 20000)
    >>> sc.swap_times, sc.swap_masses
    ((5.0, 10.0, 15.0), (3.0, 1.0, 0.0))
    """

    name: str
    duration: float
    sample_period: float
    seeds: int
    controllers: tuple[str, ...]
    reference: Reference
    swap_times: tuple[float, ...]
    swap_masses: tuple[float, ...]
    payload_radius: float = PAYLOAD_RADIUS
    position_variance: tuple[float, float] = (1e-8, 1e-7)
    velocity_variance: tuple[float, float] = (5e-5, 1e-4)
    dropout: float = 0.0
    seed: int = 0
    substeps: int = 2
    bandwidth: float | tuple[float, ...] = 40.0
    damping: float = 1.0
    source: str = "<memory>"
    controller_options: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...] = ()
    defaulted: frozenset[str] = field(default=frozenset(), compare=False)
    arm: Arm = field(default_factory=lambda: ClosedFormTwoLink.sice().to_arm())
    swap_com: tuple = ()
    swap_inertia: tuple = ()
    excite: float = 0.0
    """[s] of the designed excitation run on the plant before the task, the controllers' model
    identified from it (:mod:`adaptive_dd.closed_loop.excitation_phase`); 0: none."""
    plant: PlantSpec | None = None
    """What the simulated robot is when it is not ``arm`` (:mod:`adaptive_dd.plant.uncertainty`):
    ``arm`` is then the model the controllers are given. None: the plant is ``arm`` exactly."""
    model_uncertainty: Uncertainty | None = None
    """How far ``arm`` may be from the robot (``[model] uncertainty``, by default the plant's draw
    levels: :func:`~adaptive_dd.plant.uncertainty.model_uncertainty`); the controllers' settings
    follow from it. None: the plant's draw levels, the model exact without a draw."""
    origin: str | None = field(default=None, repr=False, compare=False)
    """The scenario file's folder, absolute, when it was read from a file: its plug-ins are looked
    up there whatever the working directory is when it runs (``source`` is the path as given)."""
    closed_forms: ClosedFormTwoLink | None = field(init=False, default=None, repr=False, compare=False)
    """The paper's closed forms of ``arm`` (eqs. 3-9) when the run takes that fast path: the arm is
    of the paper's geometry and ``plant`` is None (:func:`scenario_closed_forms`); None: the general
    kernels (:mod:`adaptive_dd.closed_loop`)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "arm", as_arm(self.arm))  # a closed-form record: the arm it is of
        object.__setattr__(self, "closed_forms", scenario_closed_forms(self.arm, self.plant))
        errors = scenario_errors({f.name: getattr(self, f.name) for f in fields(self) if f.init})
        if errors:  # (a file's errors are raised by parse_scenario, before: these are the code's)
            where = (
                "Scenario"
                if self.source == "<memory>"
                else f"Scenario from {self.source}, as changed in code"
            )
            raise _scenario_error(where, errors)

    @property
    def n_joints(self) -> int:
        return self.arm.n_joints

    def payload_of(self, i: int) -> dict:
        """Mass, com and inertia of the payload of swap ``i`` (keyword arguments of
        ``arm.sigma_with_payload``; com and inertia only for a URDF arm)."""
        kw: dict = {"mass": self.swap_masses[i], "radius": self.payload_radius}
        if self.swap_com and self.swap_com[i] is not None:
            kw["com"] = self.swap_com[i]
        if self.swap_inertia and self.swap_inertia[i] is not None:
            kw["inertia"] = self.swap_inertia[i]
        return kw

    def segment_sigmas(self) -> NDArray[np.float64]:
        """True base parameters of each constant-payload segment, ``(n_segments, p)``: the arm's (the
        paper's sigma, p = 7, on the closed forms' fast path, :attr:`closed_forms`), or with a
        ``[plant]`` the plant's before any draw (each seed's own: the results' ``plant``)."""
        if self.plant is not None:
            from adaptive_dd.closed_loop.types import pi_with_payload

            p = self.plant
            friction = np.concatenate([p.viscous, p.coulomb, p.armature])
            payloads = [None, *(self.payload_of(i) for i in range(len(self.swap_times)))]
            B = self.arm.base.B
            return np.array(
                [B @ np.concatenate([pi_with_payload(self.arm, x, p.pi_links), friction]) for x in payloads]
            )
        arm = self.closed_forms or self.arm  # the run's parameters: the paper's sigma on its fast path
        rows = [arm.sigma_with_payload(0.0, radius=self.payload_radius)]
        rows += [arm.sigma_with_payload(**self.payload_of(i)) for i in range(len(self.swap_times))]
        return np.array(rows)

    @property
    def n_samples(self) -> int:
        """Samples per trial, ``round(duration / sample_period)``."""
        return round(self.duration / self.sample_period)

    def segments(self) -> list[tuple[float, float, float]]:
        """``(start, end, mass)`` of each constant-payload segment."""
        edges = [0.0, *self.swap_times, self.duration]
        masses = [0.0, *self.swap_masses]
        return [(edges[i], edges[i + 1], masses[i]) for i in range(len(masses))]

    def segment_samples(self) -> list[int]:
        """Number of samples ``k T`` in each segment ``[start, end)``."""
        from adaptive_dd.plant.sampling import first_sample

        T, n = self.sample_period, self.n_samples
        edges = [0, *(first_sample(t, T) for t in self.swap_times), n]
        return [b - a for a, b in itertools.pairwise(edges)]

    def estimate(self) -> RunEstimate:
        """Memory and time estimate of this run (:func:`run_estimate`), one-time compilation included
        when numba's cache is cold, the excitation phase (``[run] excite``) when it has one."""
        from adaptive_dd._numba_cache import compile_estimate
        from adaptive_dd.controllers.registry import plugin_functions

        general = self.closed_forms is None
        return run_estimate(
            self.n_samples, self.seeds, len(self.controllers), self.n_joints if general else None,
            compile_seconds=compile_estimate(self.closed_forms or self.arm, plugin_functions(self)),
            excite_samples=round(self.excite / self.sample_period),
        )  # fmt: skip

    def options(self, name: str) -> dict[str, Any]:
        """Settings of controller ``name`` from its ``[controllers.NAME]`` table (plain values)."""
        for n, opts in self.controller_options:
            if n == name:
                return thaw(opts)
        return {}

    def with_controllers(self, names) -> Scenario:
        """This scenario running only ``names`` (some of its ``run.controllers``), the settings
        tables of the others dropped with them: a table for a controller left out of a selection
        made after the scenario was written (``benchmark --controllers``, a sweep's
        ``controllers``) is not an error, as one for a controller never listed is."""
        if isinstance(names, str):  # a string is a sequence of letters: 'a', 'd', ... as controllers
            raise ScenarioError(
                f"with_controllers: a list of names, got the string {names!r}: pass [{names!r}]"
            )
        names = tuple(names)
        keep = set(names) | {table_name(n) for n in names}
        opts = tuple(o for o in self.controller_options if o[0] in keep)
        return dataclasses.replace(self, controllers=names, controller_options=opts)


def scenario_closed_forms(arm, plant: PlantSpec | None = None) -> ClosedFormTwoLink | None:
    """The closed forms a run of ``arm`` takes (:func:`~adaptive_dd.plant.two_link.closed_form_view`),
    or None: the general kernels. A ``plant`` apart from the arm runs the general kernels; so does
    ``arm`` None (a scenario whose ``[arm]`` was wrong, while its other tables are checked)."""
    return None if arm is None or plant is not None else closed_form_view(arm)


def runtime_line(sc: Scenario) -> str:
    """Which kernels the run takes, and why, in one line for the report and ``validate``: the
    paper's closed forms of an arm of its geometry (the choice is automatic:
    :func:`scenario_closed_forms`), or the general N-joint kernels with every reason that applies."""
    if sc.closed_forms is not None:
        return (
            "runtime: the paper's two-link closed forms (eqs. 3-9): the arm has the paper's geometry and "
            "the simulated robot's parameters are the arm's (no [plant] urdf, viscous, coulomb, armature or "
            "uncertainty); "
            'add `robot = "sice_arm"` and `general = true` to [arm] to run it '
            "on the general N-joint kernels"
        )
    if sc.arm is None:
        return "runtime: the general N-joint kernels (no arm given)"
    why = []
    if as_two_link_cached(sc.arm) is None:
        why.append("the arm is not of the paper's geometry")
    elif sc.arm.general:
        why.append("[arm] general = true")
    if sc.plant is not None:
        why.append("a plant apart from the arm ([plant])")
    return f"runtime: the general N-joint kernels ({sc.arm.n_joints} joints; {'; '.join(why)})"


def _scenario_error(src: str, errors: list[str]) -> ScenarioError:
    lines = [f"{src}: {e}" for e in errors]
    if len(lines) == 1:
        return ScenarioError(lines[0])
    return ScenarioError(f"{src}: {len(lines)} errors\n" + "\n".join("  " + ln for ln in lines))


def default_scenario_path() -> Path:
    """The ``payload_swap`` scenario shipped with the package.

    Returns
    -------
    Path
        The TOML file inside the installed package.

    Examples
    --------
    >>> from adaptive_dd.benchmark.scenario import default_scenario_path
    >>> default_scenario_path().name
    'payload_swap.toml'
    """
    return packaged_scenarios()["payload_swap"]


def read_toml(path: Path) -> dict:
    """Parse a TOML file read as UTF-8 (a BOM is allowed); errors name the file and position
    (:func:`adaptive_dd.io.read_toml` raising ``ScenarioError``)."""
    from adaptive_dd.io import read_toml as _read

    return _read(path, ScenarioError)


def packaged_scenarios() -> dict[str, Path]:
    """The scenario files inside the package, by name (``ur5_tool_swap``, ...; the arena's choice of
    them: :func:`adaptive_dd.arena.leaderboard.shipped_scenarios`)."""
    folder = Path(str(resources.files("adaptive_dd.scenarios")))
    return {p.stem: p for p in sorted(folder.glob("*.toml"))}


def no_scenario_file(path: str | Path) -> ScenarioError:
    """The error for a scenario path that is no file: a folder, or nothing there."""
    what = "is a folder, not a scenario file" if Path(path).is_dir() else "no such scenario file"
    names = ", ".join(packaged_scenarios())
    return ScenarioError(f"{path}: {what} (give a scenario's .toml file, or a shipped one's name: {names})")


def scenario_file(path: str | Path) -> Path:
    """``path`` as a file: itself, or a shipped scenario's file when ``path`` is a bare name (or
    ``name.toml``) that is not a file in this folder (:func:`packaged_scenarios`); a
    :class:`ScenarioError` (:func:`no_scenario_file`) when neither is a file."""
    path = Path(path)
    if not path.exists() and path.name == str(path):
        path = packaged_scenarios().get(path.stem, path)
    if not path.is_file():
        raise no_scenario_file(path)
    return path


def load_scenario(path: str | Path | None = None) -> Scenario:
    """Read and check a scenario file (default: the shipped ``payload_swap``).

    Parameters
    ----------
    path : str or Path, optional
        A scenario TOML file (every key: the guide's *Scenario keys*), or the name of one shipped
        with the package (``"ur5_tool_swap"``: :func:`packaged_scenarios`, found from any folder);
        None: the shipped default, the paper's arm with payloads 0 -> 3 -> 1 -> 0 kg.

    Returns
    -------
    Scenario
        The checked scenario.

    Raises
    ------
    ScenarioError
        Listing every problem as ``file: key: reason``: unknown table or key, wrong
        type, non-finite or out-of-range value, unknown controller, frequency above
        ``0.1 / T``, a payload segment without samples, a run too large, ...

    Examples
    --------
    >>> from adaptive_dd import load_scenario
    >>> sc = load_scenario()
    >>> sc.name, sc.n_joints, sc.seeds
    ('payload_swap', 2, 10)
    >>> sc.segments()  # (start [s], end [s], payload [kg])
    [(0.0, 5.0, 0.0), (5.0, 10.0, 3.0), (10.0, 15.0, 1.0), (15.0, 20.0, 0.0)]
    >>> load_scenario("ur5_tool_swap").n_joints  # a shipped scenario by name
    6
    >>> load_scenario("no_such_file.toml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.ScenarioError: no_such_file.toml: no such scenario file (give a scenario's ...)
    """
    path = scenario_file(path) if path is not None else default_scenario_path()
    data = read_toml(path)
    if not data:
        raise ScenarioError(
            f"{path}: empty scenario (no table, no key): nothing to run; for the default scenario "
            "give no file (`adaptive-dd benchmark`), or start from `adaptive-dd validate`'s output"
        )
    return parse_scenario(data, str(path), name=path.stem)


def _with_stated_noise(arm, position_variance, velocity_variance):
    """The arm with the scenario's ``[noise]`` as its sensors' variances, so that whatever reads
    ``arm.sensor`` (the detector's noise rise, identification on the arm) reads the
    noise the run draws, not the URDF arm's defaults."""
    arm = as_arm(arm)  # a closed-form record: the arm it is of (as Scenario does)
    pv = tuple(float(x) for x in position_variance)
    vv = tuple(float(x) for x in velocity_variance)
    s = arm.sensor
    if (pv, vv) == (tuple(s.position_variance), tuple(s.velocity_variance)):
        return arm
    return arm.with_(sensor=dataclasses.replace(s, position_variance=pv, velocity_variance=vv))


def parse_scenario(data: dict, src: str = "<memory>", name: str = "scenario") -> Scenario:
    """Check a scenario given as a dict (the parsed TOML); all problems are raised at once.

    Parameters
    ----------
    data : dict
        The scenario's tables and keys, as :func:`load_scenario` reads them from TOML; a key left
        out takes its default.
    src : str
        Where the data came from, named in error messages.
    name : str
        The scenario's name (a file's stem).

    Returns
    -------
    Scenario
        The checked scenario.

    Raises
    ------
    ScenarioError
        Listing every problem as ``src: key: reason``.

    Examples
    --------
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> sc = parse_scenario({"run": {"duration": 4.0, "seeds": 2},
    ...                      "payload": [{"at": 2.0, "mass": 1.5}]})
    >>> sc.segments()
    [(0.0, 2.0, 0.0), (2.0, 4.0, 1.5)]
    >>> parse_scenario({"run": {"seeds": 0}}, src="mine.toml")
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.ScenarioError: mine.toml: run.seeds: ...
    """
    from adaptive_dd.robots.random_arm import with_random_arm

    if not isinstance(data, Mapping):
        raise ScenarioError(
            f"{src}: a scenario is a dict of tables ({{'run': {{...}}, 'arm': {{...}}, ...}}, as a TOML file "
            f"reads), got {type(data).__name__} {data!r:.60}"
        )
    arm, errors, plant, stated = None, [], None, None
    data = with_random_arm(dict(data), src)  # robot = "random:SEED": its capacity, armature, reference
    errors += derived_setting_errors(data)  # adaptive_ct's estimator and detector: from the scenario
    table = data
    plant_table = table.get("plant")
    law_table = plant_table
    if isinstance(plant_table, dict):
        law_table = {k: v for k, v in plant_table.items() if k not in PLANT_TRUTH_KEYS}
    try:
        arm = arm_from_tables(table.get("arm"), law_table, src)
        arm, plant = model_and_plant(src, arm, plant_table, table.get("model"))
        closed = closed_form_view(arm) is not None
        unread = [k for k in ("payload_capacity", "payload_offset") if k in (table.get("arm") or {})]
        if closed and unread:
            raise ScenarioError(
                f"{src}: {', '.join(f'arm.{k}' for k in unread)}: the paper's closed forms take every "
                "payload as a disk centred on the tip (eq. 9) with their own prior and do not read it; "
                "remove it, or add `general = true` to [arm] to run the arm on the general kernels, "
                "whose estimator it sizes"
            )
        if not closed:  # the model's stated uncertainty (URDF arms)
            stated = model_uncertainty(src, table.get("model"), plant)
    except ScenarioError as exc:
        errors.append(str(exc).removeprefix(f"{src}: "))
    values, more = scenario_fields(
        data, src == str(default_scenario_path()), arm, default_reference=lambda: load_scenario().reference
    )
    if errors:  # the arm is wrong: the number of joints, hence per-joint lists, cannot be judged
        more = [e for e in more if not e.startswith(("reference.", "noise.position", "noise.velocity"))]
    errors += more
    values.update(
        name=name, source=src, origin=str(Path(src).resolve().parent) if Path(src).is_file() else None
    )
    if arm is not None:
        values["arm"] = arm
        values["plant"] = plant
        values["model_uncertainty"] = stated
        if "payload.radius" in values.get("defaulted", ()):
            values["payload_radius"] = arm.payload_radius
    errors += [e for e in scenario_errors(values) if e.split(":")[0] not in _bad_keys(errors)]
    if not errors:
        errors += controller_setting_errors(values)
    if errors:
        raise _scenario_error(src, errors)
    noise = values["position_variance"], values["velocity_variance"]
    values["arm"] = _with_stated_noise(values["arm"], *noise)
    sc = Scenario(**values)
    model_file = (table.get("model") or {}).get("from")
    if isinstance(model_file, str) and model_file.lower().endswith(".json") and not sc.excite:
        # adaptive_ct's arm prior: what the file's identification knows (an excitation phase re-identifies)
        from adaptive_dd.closed_loop.model_prior import model_file_prior
        from adaptive_dd.plant.arm_tables import scenario_file

        prior = model_file_prior(sc, scenario_file(src, "model.from", model_file))
        sc = dataclasses.replace(sc, controller_options=prior)
    return sc


def model_and_plant(src: str, arm, plant_table, model_table) -> tuple[Any, PlantSpec | None]:
    """The controllers' model (``[model]``) and the plant (``[plant]``'s truth keys) around ``arm`` (the
    ``[arm]``); raises :class:`ScenarioError` for these tables on the two-link closed-form arm."""
    if closed_form_view(arm) is not None:
        given = sorted(k for k in (plant_table or {}) if k in PLANT_TRUTH_KEYS)
        given = [f"plant.{k}" for k in given] + (["[model]"] if model_table is not None else [])
        if given:
            raise ScenarioError(
                f"{src}: {', '.join(given)}: a plant apart from the model is not supported on the two-link "
                "arm's closed-form path; give the arm as a URDF with `general = true` in [arm] (the paper's "
                'arm: `robot = "sice_arm"`, `general = true`) to run it on the N-joint path, where it is '
                "supported"
            )
        return arm, None
    model = parse_model(src, model_table, arm)
    return model, parse_plant(src, plant_table, arm, model_from=model is not arm)


def _bad_keys(errors: list[str]) -> set[str]:
    return {e.split(":")[0] for e in errors}
