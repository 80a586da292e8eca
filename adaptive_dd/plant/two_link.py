"""The paper's closed forms as a fast path of :class:`~adaptive_dd.plant.arm.Arm` (issue 27: one arm type).

The public arm is :class:`~adaptive_dd.plant.arm.Arm` (a URDF, or :meth:`Arm.sice()
<adaptive_dd.plant.arm.Arm.sice>`). An arm of the paper's geometry (two revolute joints about
parallel vertical axes, centres of mass on the links' axes, no armature: :func:`as_two_link`) also
has the closed forms of eqs. (3-9); :func:`closed_form_view` is the one function that says whether
an arm has them and returns their record, a :class:`ClosedFormTwoLink`;
:func:`~adaptive_dd.plant.two_link_view.paper_sigma` maps the arm's base parameters onto the
paper's ``sigma = [J1 J2 r b1 b2 d1 d2]``. ``ClosedFormTwoLink`` was called
``TwoLinkArm`` (deprecated, a FutureWarning).

A :class:`ClosedFormTwoLink` holds the base parameters ``sigma`` (eq. 9, without payload), the
physical parameters of eq. (10) when they are known, the link lengths (``l2`` is
where the payload disk mounts), the default payload disk radius, the actuator and
sensor models, and the friction law of the *simulated plant*. Controllers and
estimators keep the paper's friction model (viscous plus Coulomb, eqs. 5-6);
only the simulated plant changes with :attr:`ClosedFormTwoLink.friction`.

Plant friction laws
-------------------
Per joint i, ``b_i``, ``d_i`` from sigma (integration: :mod:`adaptive_dd.plant.two_link_integrator`).

``"stick-slip"`` (default)
    ``b_i qd_i + d_i sgn(qd_i)`` with true sticking at rest (hybrid integrator).
``"tanh"``
    ``b_i qd_i + d_i tanh(qd_i / v)``, ``v = friction_velocity`` [rad/s]: smooth; a joint at
    rest under a torque below ``d_i`` creeps at about ``v atanh(tau / d_i)``.
``"stribeck"``
    ``b_i qd_i + d_i (1 + (k - 1) exp(-(qd_i / v_s)^2)) tanh(qd_i / v)``, ``k = stribeck_ratio``
    (static over Coulomb friction, >= 1), ``v_s = stribeck_velocity`` [rad/s]: friction peaks at
    ``k d_i`` near rest and falls to ``d_i`` for ``|qd_i| >> v_s``.
``"lugre"``
    The dynamic LuGre model (Canudas de Wit, Olsson, Astrom, Lischinsky, IEEE TAC 40(3), 1995): a
    bristle deflection ``z_i`` per joint, ``dz/dt = v - sigma0 |v| z / g(v)``, ``g(v) = d_i (1 +
    (k - 1) exp(-(v / v_s)^2))``, torque ``sigma0 z + sigma1 dz/dt + b_i v`` (the paper's ``Fc``
    is ``d_i``, ``Fs = k d_i``, its ``sigma2`` is ``b_i``): pre-sliding, the Stribeck effect,
    hysteresis at reversals, a friction lag. Defaults from the paper's simulation values:
    ``lugre_stiffness`` sigma0 = 1e5 N m/rad per joint (a breakaway deflection d_i / sigma0 of 32
    and 7 urad on the SICE arm); ``lugre_damping`` sigma1 = sqrt(sigma0 J_i), ``J_i = M_ii(q2 =
    0)`` (its rule sigma1 = sqrt(sigma0 m): damped at 0.5 of critical); ``k = stribeck_ratio`` =
    1.5 (its Fs / Fc); ``v_s = stribeck_velocity`` 0.1 rad/s by default (its 0.001 m/s belongs to
    a 1 kg slider; ``benchmarks/scenarios/lugre_friction.toml`` says the value it uses).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant import dynamics
from adaptive_dd.plant.devices import SICE_SENSOR, ActuatorConfig, SensorConfig
from adaptive_dd.plant.paper_geometry import (
    equivalent_physical,
    is_paper_geometry,
    physical_parameters,
)
from adaptive_dd.plant.parameters import (
    PAYLOAD_RADIUS,
    SIGMA_NAMES,
    PhysicalParameters,
    payload_mass_from_sigma,
    payload_sigma_delta,
    validate_sigma,
)

__all__ = ["FRICTION_LAWS", "ClosedFormTwoLink", "as_arm", "as_two_link", "closed_form_view"]

Array = NDArray[np.float64]

FRICTION_LAWS = ("stick-slip", "tanh", "stribeck", "lugre")
"""Plant friction laws; the index is the integer code the compiled integrator takes."""

GEOMETRY_FACTOR = 1.5
"""A centre of mass ``a_i`` must lie within ``[0, GEOMETRY_FACTOR * l_i]``."""


def _finite(name: str, v) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float | np.floating | np.integer):
        raise ParameterError(f"ClosedFormTwoLink.{name} must be a number, got {v!r}")
    if not math.isfinite(v):
        raise ParameterError(f"ClosedFormTwoLink.{name} must be finite, got {v!r}")
    return float(v)


@dataclass(frozen=True, eq=False)
class ClosedFormTwoLink:
    """A two-link horizontal arm: parameters, geometry, actuators, sensors, plant friction.

    Build it with :meth:`sice`, :meth:`from_physical` or :meth:`from_sigma` rather than directly.
    Immutable; :func:`dataclasses.replace` makes variants (validation runs again).

    Attributes
    ----------
    sigma : ndarray (7,)
        Base parameters ``[J1 J2 r b1 b2 d1 d2]`` (eq. 9) without payload
        [kg m^2, kg m^2, kg m^2, N m s, N m s, N m, N m]; read-only.
    l1, l2 : float
        Length of link 1 (joint 1 to joint 2) and distance from joint 2 to the
        payload mount [m].
    payload_radius : float
        Default radius [m] of the payload disk (its own inertia ``m R^2 / 2``).
    physical : PhysicalParameters or None
        The eq. (10) parameters when known; ``physical.to_sigma() == sigma``.
    actuator : ActuatorConfig
        Torque limits and D/A (default: the SICE arm's).
    sensor : SensorConfig
        Encoder counts and noise variances (default: the SICE arm's).
    friction : {"stick-slip", "tanh", "stribeck", "lugre"}
        The simulated plant's friction law (module docstring).
    friction_velocity : float
        ``v`` [rad/s] of the tanh and stribeck laws, > 0.
    stribeck_ratio : float
        Static over Coulomb friction ``k`` (stribeck law), >= 1.
    stribeck_velocity : float
        ``v_s`` [rad/s] of the stribeck and lugre laws, > 0.
    lugre_stiffness : (float, float)
        Bristle stiffness sigma0 per joint [N m/rad] (lugre law).
    lugre_damping : (float, float) or None
        Bristle damping sigma1 per joint [N m s/rad]; None: ``sqrt(sigma0_i M_ii(q2 = 0))``.
    source : Arm or None
        The arm this record is the closed forms of, when it was read from one (:meth:`to_arm`).

    Raises
    ------
    ParameterError
        Naming the field and the value: non-finite numbers, non-positive
        inertias, masses or lengths, ``J1 J2 <= r^2``, a centre of mass outside
        ``[0, 1.5 l_i]``, physical and base parameters that disagree, an unknown
        friction law, non-positive friction velocities.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.plant import ClosedFormTwoLink
    >>> sice = ClosedFormTwoLink.sice()  # Table 1 of the paper
    >>> sice.sigma.round(4)  # J1 J2 r b1 b2 d1 d2
    array([0.429, 0.071, 0.162, 5.236, 1.116, 3.208, 0.743])
    >>> ClosedFormTwoLink.from_sigma([0.1, 0.07, 0.2, 5, 1, 3, 0.7], 0.2, 0.2)
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.ParameterError: ClosedFormTwoLink.sigma: J1*J2 - r^2 = ... must be > 0, ...
    """

    sigma: Array
    l1: float
    l2: float
    payload_radius: float = PAYLOAD_RADIUS
    physical: PhysicalParameters | None = None
    actuator: ActuatorConfig = field(default_factory=lambda: ClosedFormTwoLink.sice().actuator)
    sensor: SensorConfig = field(default_factory=lambda: ClosedFormTwoLink.sice().sensor)
    friction: str = "stick-slip"
    friction_velocity: float = 0.02
    stribeck_ratio: float = 1.5
    stribeck_velocity: float = 0.1
    lugre_stiffness: tuple[float, float] = (1e5, 1e5)
    lugre_damping: tuple[float, float] | None = None
    source: object = field(default=None, repr=False, compare=False)
    """The :class:`~adaptive_dd.plant.arm.Arm` this record was read from (:func:`as_two_link`), or
    None; :meth:`to_arm` returns it while the record is still its closed forms."""
    closed_form: ClassVar[bool] = True
    """True: the paper's closed forms (eqs. 3-9), the two-link fast path (False on the general
    :class:`~adaptive_dd.plant.arm.Arm`); what the command line asks to choose the paper's experiments."""

    def __post_init__(self) -> None:
        s = np.array(validate_sigma(self.sigma, "ClosedFormTwoLink.sigma"), dtype=float, copy=True)
        if s.shape != (7,):
            raise ParameterError(f"ClosedFormTwoLink.sigma must have shape (7,), got {s.shape}")
        s.setflags(write=False)
        object.__setattr__(self, "sigma", s)
        for name in ("l1", "l2"):
            v = _finite(name, getattr(self, name))
            if v <= 0:
                raise ParameterError(f"ClosedFormTwoLink.{name} must be > 0 m, got {v!r}")
            object.__setattr__(self, name, v)
        rad = _finite("payload_radius", self.payload_radius)
        if rad < 0:
            raise ParameterError(f"ClosedFormTwoLink.payload_radius must be >= 0 m, got {rad!r}")
        object.__setattr__(self, "payload_radius", rad)
        if self.physical is not None:
            self._check_physical()
        if not isinstance(self.actuator, ActuatorConfig):
            raise ParameterError(
                f"ClosedFormTwoLink.actuator must be an ActuatorConfig, got {self.actuator!r}"
            )
        if not isinstance(self.sensor, SensorConfig):
            raise ParameterError(f"ClosedFormTwoLink.sensor must be a SensorConfig, got {self.sensor!r}")
        if self.friction not in FRICTION_LAWS:
            raise ParameterError(
                f"ClosedFormTwoLink.friction must be one of {FRICTION_LAWS}, got {self.friction!r}"
            )
        for name in ("friction_velocity", "stribeck_velocity"):
            v = _finite(name, getattr(self, name))
            if v <= 0:
                raise ParameterError(f"ClosedFormTwoLink.{name} must be > 0 rad/s, got {v!r}")
            object.__setattr__(self, name, v)
        k = _finite("stribeck_ratio", self.stribeck_ratio)
        if k < 1:
            raise ParameterError(
                f"ClosedFormTwoLink.stribeck_ratio (static / Coulomb friction) must be >= 1, got {k!r}"
            )
        object.__setattr__(self, "stribeck_ratio", k)
        self._check_lugre()

    def _check_lugre(self) -> None:
        for name in ("lugre_stiffness", "lugre_damping"):
            v = getattr(self, name)
            if v is None and name == "lugre_damping":
                continue
            if not isinstance(v, tuple | list | np.ndarray) or len(v) != 2:
                raise ParameterError(
                    f"ClosedFormTwoLink.{name} must be two values (one per joint), got {v!r}"
                )
            vals = tuple(_finite(f"{name}[{i}]", x) for i, x in enumerate(v))
            if min(vals) <= 0:
                raise ParameterError(f"ClosedFormTwoLink.{name} must be > 0 per joint, got {v!r}")
            object.__setattr__(self, name, vals)

    def _check_physical(self) -> None:
        p = self.physical
        if not isinstance(p, PhysicalParameters):
            raise ParameterError(f"ClosedFormTwoLink.physical must be PhysicalParameters or None, got {p!r}")
        for name, a, length in (("a1", p.a1, p.l1), ("a2", p.a2, p.l2)):
            if not 0 <= a <= GEOMETRY_FACTOR * length:
                raise ParameterError(
                    f"ClosedFormTwoLink.physical.{name} = {a!r} m: the centre of mass must lie within "
                    f"[0, {GEOMETRY_FACTOR} * l{name[1]}] = [0, {GEOMETRY_FACTOR * length:g}] m"
                )
        for name in ("l1", "l2"):
            mine, theirs = getattr(self, name), getattr(p, name)
            if mine != theirs:
                raise ParameterError(
                    f"ClosedFormTwoLink.{name} = {mine!r} differs from physical.{name} = {theirs!r}"
                )
        ref = p.to_sigma()
        bad = ~np.isclose(self.sigma, ref, rtol=1e-9, atol=1e-12)
        if bad.any():
            k = int(np.argmax(bad))
            raise ParameterError(
                f"ClosedFormTwoLink.sigma[{k}] ({SIGMA_NAMES[k]}) = {self.sigma[k]!r} differs from "
                f"physical.to_sigma() = {ref[k]!r}"
            )

    # ----------------------------------------------------------------- factories
    @classmethod
    def sice(cls, **overrides) -> ClosedFormTwoLink:
        """The SICE arm of the paper: Table 1, l1 = l2 = 0.2 m, 0.05 m disk, (70, 15) N m, 12-bit D/A.

        ``overrides`` replace fields (e.g. ``friction="tanh"``).
        """
        from adaptive_dd.plant.parameters import L1, L2, TABLE1_PHYSICAL, TABLE1_SIGMA, TORQUE_LIMITS

        arm = cls(
            sigma=TABLE1_SIGMA,
            l1=L1,
            l2=L2,
            payload_radius=PAYLOAD_RADIUS,
            physical=TABLE1_PHYSICAL,
            actuator=ActuatorConfig(TORQUE_LIMITS, dac_bits=12),
            sensor=SICE_SENSOR,
        )
        return replace(arm, **overrides) if overrides else arm

    @classmethod
    def from_urdf(cls, path, payload_frame: str | None = None, gravity=(0.0, 0.0, -9.81), **overrides):
        """Deprecated: :meth:`Arm.from_urdf <adaptive_dd.plant.arm.Arm.from_urdf>` (the fast path
        is then chosen where it runs, :func:`closed_form_view`).

        Returns a :class:`ClosedFormTwoLink` when the URDF is the paper's kind of two-link arm
        (:func:`as_two_link`: the closed-form fast path),
        else the general :class:`~adaptive_dd.plant.arm.Arm`.
        """
        import warnings

        from adaptive_dd.plant.arm import Arm

        warnings.warn(
            "ClosedFormTwoLink.from_urdf (was TwoLinkArm.from_urdf) is deprecated: use Arm.from_urdf; "
            "the closed forms are chosen automatically where they apply (closed_form_view)",
            FutureWarning,
            stacklevel=2,
        )

        general = Arm.from_urdf(path, payload_frame, gravity, **overrides)
        two = as_two_link(general)
        return general if two is None else two

    @classmethod
    def from_physical(cls, physical: PhysicalParameters, **kwargs) -> ClosedFormTwoLink:
        """An arm from the physical parameters of eq. (10) (link lengths included).

        ``kwargs``: the other fields (``payload_radius``, ``actuator``, ``friction``, ...).
        """
        if not isinstance(physical, PhysicalParameters):
            raise ParameterError(f"from_physical needs PhysicalParameters, got {physical!r}")
        return cls(sigma=physical.to_sigma(), l1=physical.l1, l2=physical.l2, physical=physical, **kwargs)

    @classmethod
    def from_sigma(cls, sigma: ArrayLike, l1: float, l2: float, **kwargs) -> ClosedFormTwoLink:
        """An arm known by its base parameters (eq. 9) and geometry only.

        ``kwargs``: the other fields (``payload_radius``, ``actuator``, ``friction``, ...).
        """
        return cls(sigma=np.asarray(sigma, dtype=float), l1=l1, l2=l2, **kwargs)

    # ------------------------------------------------------------------ interface
    @property
    def n_joints(self) -> int:
        """Number of joints (2)."""
        return 2

    @property
    def friction_code(self) -> int:
        """Integer code of :attr:`friction` for the compiled integrator."""
        return FRICTION_LAWS.index(self.friction)

    @property
    def lugre_sigma1(self) -> tuple[float, float]:
        """Bristle damping per joint [N m s/rad]: :attr:`lugre_damping` or ``sqrt(sigma0_i M_ii(q2 = 0))``."""
        if self.lugre_damping is not None:
            return self.lugre_damping
        j1, j2, r = self.sigma[0], self.sigma[1], self.sigma[2]
        inertia = (j1 + j2 + 2.0 * r, j2)
        return tuple(float(np.sqrt(s0 * m)) for s0, m in zip(self.lugre_stiffness, inertia, strict=True))

    @property
    def friction_params(self) -> tuple[float, ...]:
        """``(friction_velocity, stribeck_ratio, stribeck_velocity, sigma0_1, sigma0_2, sigma1_1,
        sigma1_2)`` for the integrator (:data:`adaptive_dd.plant.two_link_integrator.N_FRICTION_PARAMS`)."""
        return (
            self.friction_velocity,
            self.stribeck_ratio,
            self.stribeck_velocity,
            *self.lugre_stiffness,
            *self.lugre_sigma1,
        )

    def _radius(self, radius: ArrayLike | None) -> Array:
        rad = np.asarray(self.payload_radius if radius is None else radius, dtype=float)
        if np.any(~np.isfinite(rad)) or np.any(rad < 0):
            raise ParameterError(f"payload radius must be finite and >= 0 m, got {rad}")
        return rad

    def payload_direction(self, radius: ArrayLike | None = None) -> Array:
        """``d sigma / d m`` of a tip disk, shape ``(..., 7)`` [m^2].

        ``[l1^2, l2^2 + R^2 / 2, l1 l2, 0, 0, 0, 0]``; ``R`` defaults to
        :attr:`payload_radius`.
        """
        rad = self._radius(radius)
        out = np.zeros((*rad.shape, 7))
        out[..., 0] = self.l1**2
        out[..., 1] = self.l2**2 + 0.5 * rad**2
        out[..., 2] = self.l1 * self.l2
        return out

    def sigma_with_payload(
        self, mass: ArrayLike, radius: ArrayLike | None = None, sigma0: ArrayLike | None = None
    ) -> Array:
        """Base parameters with a tip disk of mass ``mass`` [kg], shape ``(..., 7)``.

        Adds ``m l1^2`` to J1, ``m l2^2 + m R^2 / 2`` to J2 and ``m l1 l2`` to r
        (parallel-axis theorem; docs/paper_reading.md); friction is unchanged. ``sigma0``
        (``(..., 7)``) replaces :attr:`sigma` as the unloaded arm.
        """
        base = self.sigma if sigma0 is None else np.asarray(sigma0, dtype=float)
        return base + payload_sigma_delta(mass, self._radius(radius), self.l1, self.l2)

    def payload_mass_from_sigma(self, sigma_hat: ArrayLike) -> Array:
        """Tip mass [kg] implied by estimated base parameters ``(..., 7)``, shape ``(...)``.

        Least squares on the changes of J1 and r from :attr:`sigma` (J2 also holds
        the disk's own inertia, whose radius is unknown).
        """
        return payload_mass_from_sigma(sigma_hat, self.sigma, self.l1, self.l2)

    def mass_matrix(self, q: ArrayLike, sigma: ArrayLike | None = None) -> Array:
        """Inertia matrix M(q) of eq. (3), ``(..., 2, 2)``; ``sigma`` defaults to :attr:`sigma`."""
        return dynamics.mass_matrix(q, self.sigma if sigma is None else sigma)

    def inverse_dynamics(self, q, qd, qdd, sigma: ArrayLike | None = None) -> Array:
        """Joint torques ``Phi @ sigma`` of eq. (7), ``(..., 2)``; ``sigma`` defaults to :attr:`sigma`."""
        return dynamics.inverse_dynamics(q, qd, qdd, self.sigma if sigma is None else sigma)

    def regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Array:
        """Regressor Phi(q, qd, qdd) of eq. (8), ``(..., 2, 7)``: ``Phi @ sigma`` is the torque."""
        return dynamics.regressor(q, qd, qdd)

    def nominal_inertia(self) -> Array:
        """Diagonal of M(q = 0) without payload, ``(2,)`` [kg m^2]: ``[J1 + J2 + 2 r, J2]``."""
        s = self.sigma
        return np.array([s[0] + s[1] + 2.0 * s[2], s[1]])

    def equivalent_physical(self) -> PhysicalParameters:
        """Physical parameters (eq. 10) that map onto :attr:`sigma`: :attr:`physical` when known,
        otherwise one consistent set (:func:`~adaptive_dd.plant.paper_geometry.equivalent_physical`;
        rigid-body dynamics depend on sigma only, so any such set is equivalent)."""
        return (
            self.physical if self.physical is not None else equivalent_physical(self.sigma, self.l1, self.l2)
        )

    def to_arm(self):
        """The :class:`~adaptive_dd.plant.arm.Arm` this record is the closed forms of.

        The arm it was read from (:attr:`source`, e.g. a scenario's ``[arm] robot = "sice_arm"``)
        while this record is still that arm's closed forms; otherwise an arm whose URDF is the
        shipped ``sice_arm.urdf`` for the paper's Table 1 arm, else written from
        :meth:`equivalent_physical` (joint axes along z, link 2 at ``l1``, the payload frame ``tip``
        at ``l2``; position limits +-pi, velocity limits 2 pi rad/s, as the shipped
        ``sice_arm.urdf``) into the user's cache folder, named by a hash of its text; actuator,
        sensor, payload radius and plant friction (LuGre's too) are the record's.
        :func:`closed_form_view` of the result is this record exactly (held on the arm, pickled with
        it), so that a scenario given a record runs the same numbers as before.
        """
        from adaptive_dd.plant.arm import Arm
        from adaptive_dd.plant.parameters import TABLE1_PHYSICAL

        if self.source is not None and as_two_link_cached(self.source) == self:
            return self.source
        if self.physical == TABLE1_PHYSICAL:
            from adaptive_dd.robots import robot_urdf

            path = robot_urdf("sice_arm")
        else:
            from adaptive_dd.plant.two_link_urdf import cached_urdf, two_link_urdf

            path = cached_urdf(two_link_urdf(self.equivalent_physical(), self.actuator.torque_limit))
        arm = Arm.from_urdf(
            path,
            "tip",
            actuator=self.actuator,
            sensor=self.sensor,
            payload_radius=self.payload_radius,
            friction=self.friction,
            friction_velocity=self.friction_velocity,
            stribeck_ratio=self.stribeck_ratio,
            stribeck_velocity=self.stribeck_velocity,
            lugre_stiffness=self.lugre_stiffness,
            lugre_damping=self.lugre_damping,
        )
        arm._cache["as_two_link"] = replace(self, source=arm)  # exactly this record, not read back
        return arm

    def to_dict(self) -> dict:
        """JSON-able description (for results metadata)."""
        return {
            "sigma": [float(x) for x in self.sigma],
            "sigma_names": list(SIGMA_NAMES),
            "l1": self.l1,
            "l2": self.l2,
            "payload_radius": self.payload_radius,
            "physical": None if self.physical is None else asdict(self.physical),
            "actuator": _jsonable(asdict(self.actuator)),
            "sensor": _jsonable(asdict(self.sensor)),
            "friction": self.friction,
            "friction_velocity": self.friction_velocity,
            "stribeck_ratio": self.stribeck_ratio,
            "stribeck_velocity": self.stribeck_velocity,
            "lugre_stiffness": list(self.lugre_stiffness),
            "lugre_damping": list(self.lugre_sigma1),
        }

    def _key(self) -> tuple:
        return (
            tuple(self.sigma.tolist()),
            self.l1,
            self.l2,
            self.payload_radius,
            self.physical,
            self.actuator,
            self.sensor,
            self.friction,
            self.friction_params,
        )

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ClosedFormTwoLink) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


def _jsonable(d: dict) -> dict:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}


# ------------------------------------------------------------------ the fast path
def as_two_link(arm, atol: float = 1e-12) -> ClosedFormTwoLink | None:
    """The two-link :class:`ClosedFormTwoLink` equal to ``arm`` (an :class:`~adaptive_dd.plant.arm.Arm`),
    or None if it is not one.

    The closed forms of the paper (eqs. 3-8) hold for two revolute joints about
    parallel z axes, joint 2 at ``(l1, 0, 0)`` of joint 1's frame, centres of mass
    on the links' x axes, gravity along z (no gravity torque), no armature, and the
    payload frame at ``(l2, 0, z)`` of link 2 with its axes aligned. Such an arm is
    exactly a :class:`ClosedFormTwoLink` (physical parameters of eq. 10); the benchmark then runs
    the two-link kernels, held equal to the general ones by a test.
    """
    if not is_paper_geometry(arm, atol):
        return None
    # the two-link ClosedFormTwoLink has no position limits; the scenario's reference keeps within them
    phys = physical_parameters(arm)
    return ClosedFormTwoLink.from_physical(
        phys,
        payload_radius=arm.payload_radius,
        actuator=arm.actuator,
        sensor=arm.sensor,
        friction=arm.friction,
        friction_velocity=arm.friction_velocity,
        stribeck_ratio=arm.stribeck_ratio,
        stribeck_velocity=arm.stribeck_velocity,
        lugre_stiffness=arm.lugre_stiffness,
        lugre_damping=arm.lugre_damping,
        source=arm,
    )


def closed_form_view(arm) -> ClosedFormTwoLink | None:
    """The closed-form record the fast path runs for ``arm``, or None: the general kernels.

    The one place that decides whether the paper's closed forms (eqs. 3-9) apply: an
    :class:`~adaptive_dd.plant.arm.Arm` of the paper's geometry (:func:`as_two_link`) unless built
    with ``general=True``; a :class:`ClosedFormTwoLink` is its own record. Cached on the arm (the
    geometry test reads the Pinocchio model once). The record and the general kernels give the same
    dynamics (``tests/test_one_arm.py``: mass matrix, torque, a closed-loop trial).
    """
    if getattr(arm, "closed_form", None) is True:
        return arm
    if getattr(arm, "closed_form", None) is not False or arm.general:
        return None
    return as_two_link_cached(arm)


def as_arm(arm):
    """``arm`` as an :class:`~adaptive_dd.plant.arm.Arm`: itself, or the arm a closed-form record is of
    (:meth:`ClosedFormTwoLink.to_arm`, whose :func:`closed_form_view` is that record exactly).

    With :func:`closed_form_view`, the one place that asks an arm's class (``closed_form``): a
    :class:`~adaptive_dd.benchmark.scenario.Scenario` holds ``as_arm`` of what it is given, and code
    that needs the closed forms asks :func:`closed_form_view`."""
    return arm.to_arm() if getattr(arm, "closed_form", None) is True else arm


def as_two_link_cached(arm) -> ClosedFormTwoLink | None:
    """:func:`as_two_link` of an :class:`~adaptive_dd.plant.arm.Arm`, cached, ``general`` ignored."""
    return arm._cached("as_two_link", lambda: as_two_link(arm))


def __getattr__(name: str):
    """``TwoLinkArm``, the old name of :class:`ClosedFormTwoLink` (a FutureWarning)."""
    if name == "TwoLinkArm":
        import warnings

        warnings.warn(
            "adaptive_dd.plant.two_link.TwoLinkArm is deprecated: the one arm type is "
            "adaptive_dd.plant.Arm (Arm.sice() for the paper's arm; its closed forms are chosen "
            "automatically); the closed-form record is ClosedFormTwoLink",
            FutureWarning,
            stacklevel=2,
        )
        return ClosedFormTwoLink
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
