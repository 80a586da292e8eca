"""The plant is not the model: what the simulated robot is, apart from what the controllers are given.

A scenario's ``[arm]`` is the model every controller (and every plug-in) is given. The
simulated robot, the *plant*, is that arm unless the scenario's ``[plant]`` table says
otherwise:

* ``urdf = "FILE"``: the plant's links from another URDF with the same joints and frames
  (other inertial values; checked by :func:`kinematics_mismatch`);
* ``viscous``, ``coulomb``, ``armature``: per-joint values of the plant only;
* ``[plant.uncertainty]``: a plant drawn per seed around that (:class:`Uncertainty`).

Oracles (``ct_oracle``, ``ct_oracle_textbook``, ``slotine_li_oracle``, any controller that
declares ``needs_true_model``) get the plant of their trial; the others get the model.

How far the model may be from the robot is the model's, not the plant's
(:func:`model_uncertainty`): ``[model] uncertainty = {...}`` (the levels of
``[plant.uncertainty]``), by default the levels the plant is drawn with, and without either the
model taken as exact, whatever the plant is: drawn, a URDF of its own, the ``[arm]`` itself, a
real robot. The controllers' settings follow from it (:func:`stated_uncertainty`).

The draw (:func:`draw_plant`), per link, with the link's mass ``m``, centre of mass ``c``
and rotational inertia about it ``I_c`` (from its ten parameters about the joint frame)::

    m' = m (1 + l_mass u)        c' = c + l_com u_xyz        I_c' = I_c (1 + l_inertia u)

and per joint ``fv' = fv (1 + l_viscous u)``, ``fc' = fc (1 + l_coulomb u)``,
``Ia' = Ia (1 + l_armature u)``, every ``u`` independent: uniform in ``[-1, 1]``
(``distribution = "uniform"``, the default) or standard normal clipped to ``[-3, 3]``
(``"normal"``: the level is one standard deviation). Relative levels are below 1 (uniform)
or 1/3 (normal), so every factor is positive: masses stay positive, and a positive factor
on the whole of ``I_c`` keeps it positive definite and within the triangle inequality (the
COM shift moves the parallel-axis term only). Each drawn link is checked again
(:func:`check_link`). The draw of seed index ``i`` uses the generator
``numpy.random.default_rng([scenario.seed, i, 2])`` (:func:`plant_rng`): reproducible, apart
from the sensor noise's ``(seed, i)`` and the dropouts' ``(seed, i, 1)``, and the same for
every controller of the run (common random numbers).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError, ScenarioError

__all__ = [
    "DISTRIBUTIONS",
    "MODEL_KEYS",
    "PLANT_TRUTH_KEYS",
    "UNCERTAINTY_KEYS",
    "PlantDraw",
    "PlantSpec",
    "Uncertainty",
    "check_link",
    "draw_plant",
    "exact_plant",
    "kinematics_mismatch",
    "link_params",
    "link_parts",
    "model_uncertainty",
    "parse_model",
    "parse_plant",
    "plant_draws",
    "plant_rng",
    "stated_uncertainty",
]

Array = NDArray[np.float64]

DISTRIBUTIONS = ("uniform", "normal")
UNCERTAINTY_KEYS = ("mass", "com", "inertia", "viscous", "coulomb", "armature", "distribution")
"""Keys of ``[plant.uncertainty]``: levels (relative, ``com`` in m) and the distribution."""
PLANT_TRUTH_KEYS = ("urdf", "viscous", "coulomb", "armature", "uncertainty")
"""Keys of ``[plant]`` that say what the plant is (the others choose its friction law)."""
_RELATIVE = ("mass", "inertia", "viscous", "coulomb", "armature")
_MAX_COM = 0.5  # m: a centre of mass off by more than this is another robot
_NORMAL_CLIP = 3.0


@dataclass(frozen=True)
class Uncertainty:
    """Levels of the plant's draw around its nominal values (module docstring).

    Attributes
    ----------
    mass, inertia, viscous, coulomb, armature : float
        Relative levels (0.1: 10 %).
    com : float
        [m], per axis.
    distribution : {"uniform", "normal"}
        ``u`` uniform in [-1, 1], or standard normal clipped to [-3, 3].
    """

    mass: float = 0.0
    com: float = 0.0
    inertia: float = 0.0
    viscous: float = 0.0
    coulomb: float = 0.0
    armature: float = 0.0
    distribution: str = "uniform"

    def __post_init__(self) -> None:
        if self.distribution not in DISTRIBUTIONS:
            raise ParameterError(f"distribution must be one of {DISTRIBUTIONS}, got {self.distribution!r}")
        top = 1.0 if self.distribution == "uniform" else 1.0 / _NORMAL_CLIP
        for key in _RELATIVE:
            v = getattr(self, key)
            if not (math.isfinite(v) and 0.0 <= v < top):
                raise ParameterError(
                    f"{key}: a relative level in [0, {top:.3g}) ({self.distribution}: every factor "
                    f"1 + level u stays positive), got {v!r}"
                )
        if not (math.isfinite(self.com) and 0.0 <= self.com <= _MAX_COM):
            raise ParameterError(f"com: a level in [0, {_MAX_COM}] m, got {self.com!r}")


@dataclass(frozen=True)
class PlantSpec:
    """The plant of a scenario before any draw, and the draw's levels.

    Attributes
    ----------
    pi_links : tuple of float (10 n,)
        The plant's links (standard parameters about the joint frames, Pinocchio's order).
    viscous, coulomb, armature : tuple of float (n,)
        The plant's joints [N m s, N m, kg m^2].
    uncertainty : Uncertainty or None
        None: every seed meets this plant exactly.
    urdf : str or None
        The ``[plant] urdf`` file the links come from (None: the ``[arm]``'s).
    notes : tuple of str
        What reading the plant's URDF noted (a massless frame, a repaired inertia, ...:
        :attr:`~adaptive_dd.plant.arm.Arm.urdf_notes`) when it is not the controllers' model's URDF
        (``[plant] urdf``, or the ``[arm]``'s under ``[model] from``); printed by ``validate``.
    """

    pi_links: tuple[float, ...]
    viscous: tuple[float, ...]
    coulomb: tuple[float, ...]
    armature: tuple[float, ...]
    uncertainty: Uncertainty | None = None
    urdf: str | None = None
    notes: tuple[str, ...] = field(default=(), compare=False)

    def nominal(self) -> PlantDraw:
        """The plant without a draw."""
        a = np.array
        return PlantDraw(a(self.pi_links), a(self.viscous), a(self.coulomb), a(self.armature))


class PlantDraw(NamedTuple):
    """One trial's plant: ``pi_links (10 n,)``, ``viscous, coulomb, armature (n,)``."""

    pi_links: Array
    viscous: Array
    coulomb: Array
    armature: Array

    @property
    def pi(self) -> Array:
        """``(13 n,)`` ``[links, fv, fc, Ia]`` (the layout of ``Arm.pi``)."""
        return np.concatenate([self.pi_links, self.viscous, self.coulomb, self.armature])

    def to_dict(self) -> dict:
        """Per link mass [kg], centre of mass [m] and inertia about it ``[ixx, iyy, izz, ixy, ixz,
        iyz]`` [kg m^2]; per joint friction and armature (JSON-ready)."""
        links = []
        for j in range(self.viscous.size):
            m, c, Ic = link_parts(self.pi_links[10 * j : 10 * j + 10])
            I6 = [Ic[0, 0], Ic[1, 1], Ic[2, 2], Ic[0, 1], Ic[0, 2], Ic[1, 2]]
            links.append({"mass": float(m), "com": c.tolist(), "inertia": [float(x) for x in I6]})
        return {
            "links": links,
            "viscous": self.viscous.tolist(),
            "coulomb": self.coulomb.tolist(),
            "armature": self.armature.tolist(),
        }


# ------------------------------------------------------------------------- one link
def link_parts(pi10) -> tuple[float, Array, Array]:
    """``(m, c (3,), I_c (3, 3))``: mass, centre of mass and inertia about it of ten parameters
    about a frame's origin (``c = 0`` for a massless link)."""
    p = np.asarray(pi10, dtype=float)
    m = float(p[0])
    c = p[1:4] / m if m > 0 else np.zeros(3)
    ixx, ixy, iyy, ixz, iyz, izz = p[4:10]
    Io = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return m, c, Io - m * (c @ c * np.eye(3) - np.outer(c, c))


def link_params(m: float, c, Ic) -> Array:
    """Inverse of :func:`link_parts`: the ten parameters about the frame's origin ``(10,)``."""
    c = np.asarray(c, dtype=float)
    Io = np.asarray(Ic, dtype=float) + m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.array([m, *(m * c), Io[0, 0], Io[0, 1], Io[1, 1], Io[0, 2], Io[1, 2], Io[2, 2]])


def check_link(pi10, where: str = "link") -> None:
    """Raise :class:`~adaptive_dd.errors.ParameterError` unless ``pi10`` is a rigid body's: mass
    > 0 with the inertia about the centre of mass positive definite and within the triangle
    inequality (or all ten zero: a massless link)."""
    p = np.asarray(pi10, dtype=float)
    if not np.all(np.isfinite(p)):
        raise ParameterError(f"{where}: non-finite inertial parameters {p.tolist()}")
    if np.all(p == 0.0):
        return
    m, _, Ic = link_parts(p)
    if m <= 0:
        raise ParameterError(f"{where}: mass {m} kg must be > 0")
    lam = np.linalg.eigvalsh(0.5 * (Ic + Ic.T))
    tol = 1e-9 * max(abs(lam).max(), 1e-300)
    if lam[0] <= 0 or lam[2] > lam[0] + lam[1] + tol:
        raise ParameterError(
            f"{where}: the inertia about the centre of mass (principal moments {lam.tolist()}) is not a "
            "rigid body's (positive definite, each at most the sum of the other two)"
        )


# ------------------------------------------------------------------------- the draw
def plant_rng(seed: int, index: int) -> np.random.Generator:
    """The generator of seed index ``index``'s plant: ``default_rng([seed, index, 2])``."""
    return np.random.default_rng([int(seed), int(index), 2])


def _u(rng: np.random.Generator, distribution: str, shape) -> Array:
    if distribution == "uniform":
        return rng.uniform(-1.0, 1.0, shape)
    return np.clip(rng.standard_normal(shape), -_NORMAL_CLIP, _NORMAL_CLIP)


def draw_plant(spec: PlantSpec, rng: np.random.Generator) -> PlantDraw:
    """One plant drawn around ``spec`` (the module docstring's rule); ``spec.nominal()`` without
    an uncertainty. Raises :class:`~adaptive_dd.errors.ParameterError` if a drawn link is not a
    rigid body's (it cannot happen from a consistent nominal; checked all the same)."""
    base = spec.nominal()
    unc = spec.uncertainty
    if unc is None:
        return base
    n = base.viscous.size
    ul = _u(rng, unc.distribution, (n, 5))  # per link: mass, com x y z, inertia
    uj = _u(rng, unc.distribution, (n, 3))  # per joint: viscous, coulomb, armature
    pi = base.pi_links.copy()
    for j in range(n):
        m, c, Ic = link_parts(base.pi_links[10 * j : 10 * j + 10])
        if m <= 0:
            continue
        pi[10 * j : 10 * j + 10] = link_params(
            m * (1.0 + unc.mass * ul[j, 0]), c + unc.com * ul[j, 1:4], Ic * (1.0 + unc.inertia * ul[j, 4])
        )
        check_link(pi[10 * j : 10 * j + 10], f"drawn plant link {j + 1}")
    return PlantDraw(
        pi,
        base.viscous * (1.0 + unc.viscous * uj[:, 0]),
        base.coulomb * (1.0 + unc.coulomb * uj[:, 1]),
        base.armature * (1.0 + unc.armature * uj[:, 2]),
    )


def exact_plant(arm) -> PlantSpec:
    """The plant equal to ``arm`` (an :class:`~adaptive_dd.plant.arm.Arm`)."""
    t = lambda x: tuple(float(v) for v in x)  # noqa: E731
    return PlantSpec(t(arm.pi_links), t(arm.viscous), t(arm.coulomb), t(arm.armature))


def plant_draws(scenario, seed_indices) -> list[PlantDraw]:
    """Each trial's plant: seed index ``i`` drawn with :func:`plant_rng` ``(scenario.seed, i)``
    around ``scenario.plant`` (the ``[arm]`` itself when the scenario has no ``[plant]``)."""
    spec = scenario.plant if scenario.plant is not None else exact_plant(scenario.arm)
    if spec.uncertainty is None:
        d = spec.nominal()
        return [d for _ in seed_indices]
    return [draw_plant(spec, plant_rng(scenario.seed, i)) for i in seed_indices]


# --------------------------------------------------------------------- the [plant] table
def kinematics_mismatch(model_arm, other) -> str | None:
    """Why two Arms do not have the same joints and frames (None: they have)."""
    if tuple(model_arm.joint_names) != tuple(other.joint_names):
        return f"joints {list(other.joint_names)} differ from the [arm]'s {list(model_arm.joint_names)}"
    a, b = model_arm.chain, other.chain
    for name in ("jtype", "axis", "rot", "trans"):
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        if x.shape != y.shape or not np.allclose(x, y, rtol=0.0, atol=1e-9):
            return f"the joints' {name} (placements and axes) differ from the [arm]'s"
    if not np.allclose(model_arm.payload_map, other.payload_map, rtol=0.0, atol=1e-9):
        return f"the payload frame {other.payload_frame!r} sits elsewhere than the [arm]'s"
    return None


def _number(src: str, key: str, v, lo: float, hi: float, hi_open: bool = False, what: str = "") -> float:
    """``v`` as a float in ``[lo, hi]`` (``hi`` open), else an error naming ``key`` (and ``what``
    the number is, after a value beyond the range)."""
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ScenarioError(f"{src}: key '{key}' must be a finite number, got {v!r}")
    if v < lo or (v >= hi if hi_open else v > hi):
        raise ScenarioError(
            f"{src}: key '{key}' must be in [{lo:g}, {hi:.3g}{')' if hi_open else ']'}, got {v!r}"
            + (f" ({what})" if what and v > hi else "")
        )
    return float(v)


def _uncertainty(src: str, table, at: str = "plant.uncertainty") -> Uncertainty:
    """The levels of the table ``at`` (``[plant.uncertainty]`` or ``[model] uncertainty``); a level
    left out is 0."""
    if not isinstance(table, dict):
        raise ScenarioError(
            f"{src}: [{at}] must be a table of levels {list(UNCERTAINTY_KEYS)}, got {table!r}"
        )
    for key in table:
        if key not in UNCERTAINTY_KEYS:
            from adaptive_dd.benchmark.key_hints import did_you_mean

            hint = did_you_mean(key, UNCERTAINTY_KEYS)
            raise ScenarioError(f"{src}: unknown key '{at}.{key}'{hint}; allowed: {sorted(UNCERTAINTY_KEYS)}")
    dist = table.get("distribution", "uniform")
    if dist not in DISTRIBUTIONS:
        raise ScenarioError(
            f"{src}: key '{at}.distribution' must be one of {list(DISTRIBUTIONS)}, got {dist!r}"
        )
    top = 1.0 if dist == "uniform" else 1.0 / _NORMAL_CLIP
    kw = {"distribution": dist}
    for key in _RELATIVE:
        if key in table:
            kw[key] = _number(
                src, f"{at}.{key}", table[key], 0.0, top, hi_open=True, what="a fraction: 0.1 for 10 %"
            )
    if "com" in table:
        kw["com"] = _number(src, f"{at}.com", table["com"], 0.0, _MAX_COM)
    return Uncertainty(**kw)


def parse_plant(src: str, table: dict | None, arm, model_from: bool = False) -> PlantSpec | None:
    """The plant of a ``[plant]`` table around ``arm`` (the ``[arm]``: an Arm).

    Only the keys of :data:`PLANT_TRUTH_KEYS` are read here (the friction law's keys are the
    arm's, :func:`~adaptive_dd.plant.arm_tables.arm_from_tables`). Returns None when the plant is the
    arm exactly and the controllers' model is the arm too (``model_from`` False).

    Raises
    ------
    ScenarioError
        Naming ``src``, the key and the value: a URDF with other joints or frames, a list of the
        wrong length, a negative or too large level, an unknown key of ``[plant.uncertainty]``.
    """
    from adaptive_dd.plant.arm_tables import (
        URDF_TABLE_BOUNDS,
        _table_vector,
        inertialess_joints,
        scenario_file,
    )

    table = {} if table is None else {k: v for k, v in table.items() if k in PLANT_TRUTH_KEYS}
    if not table and not model_from:
        return None
    spec = exact_plant(arm)
    n = arm.n_joints
    urdf = None
    notes = tuple(arm.urdf_notes) if model_from and arm.urdf is not None else ()  # the model is another file
    if "urdf" in table:
        u = table["urdf"]
        if not isinstance(u, str) or not u:
            raise ScenarioError(f"{src}: key 'plant.urdf' must be a file path, got {u!r}")
        path = scenario_file(src, "plant.urdf", u)
        other = _same_arm_urdf(
            src, "plant.urdf", u, path, arm, "the plant's URDF must have the same joints and frames as the "
            "[arm] (other inertial values only)"
        )  # fmt: skip
        urdf, notes = str(path), tuple(other.urdf_notes)
        spec = PlantSpec(tuple(float(x) for x in other.pi_links), spec.viscous, spec.coulomb, spec.armature)
    vals = {}
    for key in ("viscous", "coulomb", "armature"):
        if key in table:
            try:
                v = _table_vector(src, key, table[key], n, 0.0, strict=False, hi=URDF_TABLE_BOUNDS[key])
            except ScenarioError as exc:
                raise ScenarioError(str(exc).replace(f"'arm.{key}'", f"'plant.{key}'")) from None
            vals[key] = tuple(float(x) for x in v)
    unc = _uncertainty(src, table["uncertainty"]) if "uncertainty" in table else None
    armature = vals.get("armature", spec.armature)
    for j, d in inertialess_joints(arm, spec.pi_links, armature):  # the arm's were checked
        raise ScenarioError(
            f"{src}: [plant]: joint {arm.joint_names[j]!r} of the plant moves no inertia about its axis "
            f"(mass matrix diagonal {d:.3g}: in {urdf or 'the [arm] URDF'} the links beyond it have no "
            "<inertial>, or point masses on its axis): the plant cannot be simulated. Give those links "
            "their <inertial> in plant.urdf, or state the drive's rotor inertia in plant.armature"
        )
    return PlantSpec(
        spec.pi_links,
        vals.get("viscous", spec.viscous),
        vals.get("coulomb", spec.coulomb),
        armature,
        unc,
        urdf,
        notes,
    )


MODEL_KEYS = ("from", "uncertainty")
"""Keys of ``[model]``: ``from``, a file the controllers' model is read from; ``uncertainty``, how
far that model may be from the robot (:func:`model_uncertainty`)."""


def model_uncertainty(src: str, table, plant: PlantSpec | None) -> Uncertainty | None:
    """How far the controllers' model may be from the robot: ``[model] uncertainty`` (a table of
    the keys of ``[plant.uncertainty]``, a level left out 0; every level 0: the model is exact),
    else the levels ``plant`` is drawn with (``[plant.uncertainty]``), else None (exact). A
    CAD-level default was measured and not kept: on exact URDFs it costs the unloaded first
    segment (``docs/plant_and_model.md``).

    Raises
    ------
    ScenarioError
        Naming ``src``, ``model.uncertainty.KEY`` and the value: not a table, an unknown key, a
        level out of its range (:func:`_uncertainty`).
    """
    if isinstance(table, dict) and "uncertainty" in table:
        return _uncertainty(src, table["uncertainty"], "model.uncertainty")
    return plant.uncertainty if plant is not None else None


def stated_uncertainty(scenario) -> Uncertainty | None:
    """The levels the scenario states for its model (``scenario.model_uncertainty``; for a scenario
    built without it, its plant's draw), None when the model is stated exact (every level 0) or
    nothing is stated."""
    unc = getattr(scenario, "model_uncertainty", None)
    if unc is None:
        unc = getattr(getattr(scenario, "plant", None), "uncertainty", None)
    levels = ("mass", "com", "inertia", "viscous", "coulomb", "armature")
    return None if unc is None or not any(getattr(unc, k) for k in levels) else unc


def parse_model(src: str, table, arm):
    """The controllers' model of a ``[model]`` table: ``arm`` (the ``[arm]``) when there is none.

    ``from = "FILE.urdf"``: a URDF with the same joints and frames as the ``[arm]``, whose links'
    inertial values replace the ``[arm]``'s in the model every non-oracle controller gets (the
    joints' friction and armature, actuators and sensors stay the ``[arm]``'s). The plant stays
    the ``[arm]`` (with the ``[plant]`` table's changes).

    ``from = "DIR/model.json"`` (what ``adaptive-dd identify --out DIR`` writes): the links of its
    physically consistent fit (``model.urdf`` beside it) and its identified viscous, Coulomb and
    armature values; the ``[arm]``'s friction law, actuators and sensors stay.

    Raises
    ------
    ScenarioError
        Naming ``src``, the key and the value: an unknown key, a missing file, other joints or
        frames, a model.json that is not one or has no consistent fit, another kind of file.
    """

    if table is None:
        return arm
    if not isinstance(table, dict):
        raise ScenarioError(f"{src}: [model] must be a table, got {table!r}")
    for key in table:
        if key not in MODEL_KEYS:
            raise ScenarioError(f"{src}: unknown key 'model.{key}'; allowed: {list(MODEL_KEYS)}")
    if "from" not in table:
        return arm
    u = table["from"]
    if not isinstance(u, str) or not u:
        raise ScenarioError(f"{src}: key 'model.from' must be a file path, got {u!r}")
    from adaptive_dd.plant.arm_tables import scenario_file

    path = scenario_file(src, "model.from", u)
    rule = "the model must have the same joints and frames as the [arm]"
    if path.suffix.lower() == ".json":
        return _identified_arm(src, u, path, arm, rule)
    if path.suffix.lower() != ".urdf":
        raise ScenarioError(
            f"{src}: key 'model.from' = {u!r}: expected a .urdf file or the model.json that "
            "`adaptive-dd identify --out DIR` writes"
        )
    _same_arm_urdf(src, "model.from", u, path, arm, rule)
    return arm.with_(urdf=path)


def _identified_arm(src: str, u: str, path: Path, arm, rule: str):
    """The arm of an identified ``model.json``: its physically consistent fit's links (``model.urdf``)
    and its viscous, Coulomb and armature values; the [arm]'s friction law is kept."""
    from adaptive_dd.errors import DataError
    from adaptive_dd.identification.identified_model import load_identified_model

    try:
        m = load_identified_model(path)
    except DataError as exc:
        raise ScenarioError(f"{src}: key 'model.from' = {u!r}: {exc}") from None
    if m.fitted_urdf is None:
        raise ScenarioError(
            f"{src}: key 'model.from' = {u!r}: this model has no physically consistent fit (no model.urdf "
            "beside it), so it has no link inertials a controller can use; identify on a longer or richer "
            "record, or give a URDF"
        )
    if list(m.joint_names) != list(arm.joint_names):
        raise ScenarioError(
            f"{src}: key 'model.from' = {u!r}: identified on joints {list(m.joint_names)}, the [arm] has "
            f"{list(arm.joint_names)}"
        )
    fitted = Path(m.fitted_urdf)
    _same_arm_urdf(src, "model.from", u, fitted, arm, rule)
    return arm.with_(
        urdf=fitted,
        viscous=np.asarray(m.viscous, dtype=float),
        coulomb=np.asarray(m.coulomb, dtype=float),
        armature=np.asarray(m.armature, dtype=float),
    )


def _same_arm_urdf(src: str, key: str, u: str, path: Path, arm, rule: str):
    """The arm of the URDF at ``path`` (the scenario's ``key = u``), checked to have ``arm``'s joints
    and frames; a :class:`ScenarioError` naming the key, the value and ``rule`` otherwise."""
    from adaptive_dd.errors import UrdfError
    from adaptive_dd.plant.arm import Arm

    try:
        other = Arm.from_urdf(path, arm.payload_frame, gravity=arm.gravity)
        _ = other.chain, other.pi_links
    except (UrdfError, ParameterError) as exc:
        raise ScenarioError(f"{src}: key '{key}' = {u!r}: {exc}") from None
    why = kinematics_mismatch(arm, other)
    if why is not None:
        raise ScenarioError(f"{src}: key '{key}' = {u!r}: {why}; {rule}")
    return other
