"""The :class:`Arm`: any fixed-base serial arm from a URDF, with friction, armature and payload.

Parameters
----------
Standard parameters ``pi`` (13 n): per link the ten inertial parameters about the
joint frame (Pinocchio's order), then per joint viscous friction ``fv``, Coulomb
friction ``fc`` and armature ``Ia`` (:mod:`adaptive_dd.plant.base_parameters`).
The base parameters ``sigma = B pi`` (p of them) are found once per arm by QR
with pivoting; the base regressor is a column subset of the standard one, so

    arm.regressor(q, qd, qdd) @ arm.sigma == inverse dynamics (friction included),

batch axis first, shape ``(..., n, p)``.

Payload
-------
A rigid body fixed to the payload frame (a link of the URDF): mass ``m``, centre
of mass ``c`` in that frame, inertia about the centre of mass ``I_c`` (or a disk
of radius R, axis along the frame's z: ``I_c = m diag(R^2/4, R^2/4, R^2/2)``).
Its ten parameters about the frame's origin, ``pi_p``, enter the base parameters
linearly: ``sigma(payload) = sigma + P pi_p`` with ``P = payload_basis`` (p x 10,
rank up to 10). :meth:`Arm.payload_from_sigma` inverts that by least
squares on the identifiable part.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.arm_fields import FRICTION_LAWS, check_fields
from adaptive_dd.plant.base_parameters import BaseParameters, base_parameters, standard_names
from adaptive_dd.plant.devices import ActuatorConfig, SensorConfig
from adaptive_dd.plant.payload import PayloadEstimate, payload_parameters
from adaptive_dd.plant.urdf import read_urdf

__all__ = ["DEFAULT_GRAVITY", "Arm", "PayloadEstimate", "payload_parameters"]

Array = NDArray[np.float64]

DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
"""Gravity in the base frame [m/s^2] unless a scenario or caller gives another."""
DEFAULT_ENCODER_COUNTS = 2**20
"""Counts per revolution of a URDF arm's encoders unless given (a 20-bit encoder)."""
DEFAULT_POSITION_VARIANCE = 1e-8
"""rad^2, as the SICE arm's joint 1 (Table 2 of the paper)."""
DEFAULT_VELOCITY_VARIANCE = 5e-5
"""(rad/s)^2, as the SICE arm's joint 1 (Table 4 of the paper)."""
DEFAULT_DAC_BITS = 16
"""D/A resolution of a URDF arm's torque command unless given."""
DEFAULT_PAYLOAD_OFFSET = 0.1
"""[m] How far a payload's centre of mass may lie from the payload frame when the arm states
nothing (``Arm.payload_offset``): a tool off the flange."""


@dataclass(frozen=True, eq=False)
class Arm:
    """A fixed-base serial arm of n revolute/prismatic joints described by a URDF.

    Build it with :meth:`from_urdf`. Immutable; :func:`dataclasses.replace` makes
    variants (other friction, limits, sensors, plant friction law).

    Attributes
    ----------
    urdf : Path
        The description.
    payload_frame : str
        The link that carries the payload.
    gravity : ndarray (3,)
        [m/s^2] in the base frame.
    viscous, coulomb, armature : ndarray (n,)
        Per joint [N m s, N m, kg m^2] (URDF ``<dynamics damping friction>``; armature 0
        unless given).
    position_limits : ndarray (n, 2)
        [rad or m]; ``+-inf`` for continuous joints.
    velocity_limits : ndarray (n,)
        [rad/s or m/s].
    actuator : ActuatorConfig
        Torque limits (URDF ``effort``) and D/A.
    sensor : SensorConfig
        Encoders and noise.
    payload_radius : float
        Default disk radius [m] of a payload given by mass alone; the shape the estimator's payload
        prior gives a payload of unknown mass (its inertia a disk's of this radius per kg).
    payload_offset : float
        How far [m] a payload's centre of mass may lie from the payload frame's origin (a data
        sheet's; ``[arm] payload_offset``): the length scale of the estimator's payload prior
        (:func:`~adaptive_dd.identification.online_config.payload_prior`); 0: centred (eq. 9).
    friction, friction_velocity, stribeck_ratio, stribeck_velocity
        The simulated plant's friction law, as on :class:`adaptive_dd.plant.two_link.ClosedFormTwoLink`.
    lugre_stiffness, lugre_damping
        The LuGre law's bristle stiffness ``sigma0`` [N m/rad] and damping ``sigma1`` [N m s/rad]
        (``friction = "lugre"``), one value for every joint or one per joint; the damping's default
        (None) is ``sqrt(sigma0_i M_ii(0))`` (:attr:`lugre_sigma1`), as on ``ClosedFormTwoLink``.
    payload_capacity : float or None
        Rated payload [kg] (``[arm] payload_capacity``); sizes the estimator's re-opening on a
        change alarm (None: the detector's generic size).
    repair_inertia : bool
        Repair links whose URDF inertia is not a rigid body's (:func:`~adaptive_dd.plant.urdf.read_urdf`).
    general : bool
        Keep the general kernels even where the paper's closed forms apply (the arm's geometry is
        the paper's: :func:`~adaptive_dd.plant.two_link.closed_form_view`); ``[arm] general = true``.
        False (default): a scenario of such an arm runs the closed forms, its fast path.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> ur5 = Arm.from_urdf(robot_urdf("ur5"))
    >>> ur5.n_joints, ur5.base.count  # joints, base parameters
    (6, 52)
    >>> ur5.mass_matrix(np.zeros(6)).shape
    (6, 6)
    >>> ur5.with_(payload_capacity=5.0).payload_capacity
    5.0
    """

    urdf: Path
    payload_frame: str
    gravity: Array
    viscous: Array
    coulomb: Array
    armature: Array
    position_limits: Array
    velocity_limits: Array
    actuator: ActuatorConfig
    sensor: SensorConfig
    joint_names: tuple[str, ...] = ()
    locked: tuple[str, ...] = ()
    payload_radius: float = 0.05
    friction: str = "stick-slip"
    friction_velocity: float = 0.02
    stribeck_ratio: float = 1.5
    stribeck_velocity: float = 0.1
    repair_inertia: bool = False
    payload_capacity: float | None = None
    payload_offset: float = DEFAULT_PAYLOAD_OFFSET
    general: bool = False
    lugre_stiffness: float | tuple[float, ...] = 1e5
    lugre_damping: float | tuple[float, ...] | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)
    closed_form: ClassVar[bool] = False
    """False: an :class:`Arm` (True on the closed forms' record,
    :class:`~adaptive_dd.plant.two_link.ClosedFormTwoLink`); whether an arm has the closed forms is
    :func:`~adaptive_dd.plant.two_link.closed_form_view`'s to say."""

    def __post_init__(self) -> None:
        check_fields(self)

    # ----------------------------------------------------------------- factories
    @classmethod
    def sice(cls, **overrides) -> Arm:
        """The paper's SICE two-link arm: the shipped ``sice_arm.urdf`` (payload at ``tip``) with its
        data sheet (``ROBOTS["sice_arm"]``: the 12-bit D/A, encoders and noise of Tables 2 and 4,
        payloads centred on the tip, eq. 9), as :class:`~adaptive_dd.plant.two_link.ClosedFormTwoLink`.

        Its closed forms (eqs. 3-9) are its fast path:
        :func:`~adaptive_dd.plant.two_link.closed_form_view` of it is
        :meth:`ClosedFormTwoLink.sice() <adaptive_dd.plant.two_link.ClosedFormTwoLink.sice>` (to
        1 ulp: the URDF's numbers read back through Pinocchio), chosen automatically by a
        :class:`~adaptive_dd.benchmark.scenario.Scenario` of it; ``general=True`` keeps the general
        kernels. :func:`~adaptive_dd.plant.two_link_view.paper_sigma` maps its base parameters onto the
        paper's ``[J1 J2 r b1 b2 d1 d2]``."""
        from adaptive_dd.robots import ROBOTS, robot_urdf

        info = ROBOTS["sice_arm"]
        arm = cls.from_urdf(robot_urdf("sice_arm"), info.payload_frame)
        return replace(arm, **{**info.stated(arm), **overrides})

    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        payload_frame: str | None = None,
        gravity: ArrayLike = DEFAULT_GRAVITY,
        **overrides,
    ) -> Arm:
        """An arm from a URDF file (checked by :func:`adaptive_dd.plant.urdf.read_urdf`).

        ``overrides`` replace fields (``viscous``, ``coulomb``, ``armature``, ``sensor``,
        ``actuator``, ``friction``, ...). Friction comes from ``<dynamics>``, torque
        limits from ``<limit effort>``.
        """
        robot = read_urdf(path, payload_frame, repair=bool(overrides.get("repair_inertia", False)))
        n = len(robot.joints)
        kw = dict(
            urdf=Path(path),
            payload_frame=robot.payload_frame,
            gravity=np.asarray(gravity, dtype=float),
            viscous=[j.damping for j in robot.joints],
            coulomb=[j.friction for j in robot.joints],
            armature=np.zeros(n),
            position_limits=[[j.lower, j.upper] for j in robot.joints],
            velocity_limits=[j.velocity for j in robot.joints],
            actuator=ActuatorConfig(tuple(j.effort for j in robot.joints), dac_bits=DEFAULT_DAC_BITS),
            sensor=SensorConfig(
                encoder_counts=(DEFAULT_ENCODER_COUNTS,) * n,
                position_variance=(DEFAULT_POSITION_VARIANCE,) * n,
                velocity_variance=(DEFAULT_VELOCITY_VARIANCE,) * n,
            ),
            joint_names=robot.joint_names,
            locked=robot.locked,
        )
        kw.update(overrides)
        return cls(**kw)

    # ------------------------------------------------------------ derived, cached
    def _cached(self, key: str, make):
        return self._cache[key] if key in self._cache else self._cache.setdefault(key, make())

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        # the closed forms' record is kept: an arm made from one (ClosedFormTwoLink.to_arm) holds it exactly
        state["_cache"] = {k: v for k, v in self._cache.items() if k == "as_two_link"}
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)

    n_joints = property(lambda self: len(self.joint_names))

    @property
    def model(self):
        """The Pinocchio model (gravity set; off-chain joints locked)."""
        return self._cached("model", lambda: self._robot.model(self.gravity))

    @property
    def _robot(self):
        return self._cached(
            "robot", lambda: read_urdf(self.urdf, self.payload_frame, repair=self.repair_inertia)
        )

    @property
    def joint_kinds(self) -> tuple[str, ...]:
        """URDF type of each joint (``revolute``, ``continuous``, ``prismatic``)."""
        return tuple(j.kind for j in self._robot.joints)

    @property
    def urdf_notes(self) -> tuple[str, ...]:
        """What reading the URDF did not check, or repaired (:attr:`.urdf.UrdfRobot.notes`)."""
        return self._robot.notes

    @property
    def chain(self):
        """The arrays the compiled kernels take (:class:`adaptive_dd.plant.chain.Chain`)."""
        from adaptive_dd.plant.chain import chain_from_model

        return self._cached("chain", lambda: chain_from_model(self.model))

    @property
    def pi_links(self) -> Array:
        """Standard inertial parameters of the links, ``(10 n,)``."""

        def make():
            m = self.model
            return np.concatenate([m.inertias[i].toDynamicParameters() for i in range(1, m.njoints)])

        return self._cached("pi_links", make)

    @property
    def pi(self) -> Array:
        """All standard parameters ``[links, fv, fc, Ia]``, ``(13 n,)``."""
        return np.concatenate([self.pi_links, self.viscous, self.coulomb, self.armature])

    @property
    def base(self) -> BaseParameters:
        """The base parameter structure (QR on 60 random states, seed 0: deterministic)."""
        lim = self.position_limits
        return self._cached(
            "base",
            lambda: base_parameters(
                self.standard_regressor, self.n_joints, lim[:, 0], lim[:, 1], np.random.default_rng(0)
            ),
        )

    @property
    def sigma(self) -> Array:
        """Base parameters of the arm without payload, ``(p,)``."""
        return self.base.B @ self.pi

    @property
    def sigma_names(self) -> tuple[str, ...]:
        return self.base.names

    @property
    def standard_names(self) -> tuple[str, ...]:
        return standard_names(self.n_joints)

    @property
    def payload_joint(self) -> int:
        """Index (0-based) of the link that carries the payload frame."""
        return self._payload_frame[0]

    @property
    def _payload_frame(self):
        def make():
            m = self.model
            if not m.existFrame(self.payload_frame):
                raise ParameterError(f"{self.urdf}: payload frame {self.payload_frame!r} not in the model")
            from adaptive_dd.plant.urdf import frame_id

            f = m.frames[frame_id(m, self.payload_frame)]
            return int(f.parentJoint) - 1, f.placement

        return self._cached("payload_frame", make)

    @property
    def payload_map(self) -> Array:
        """``(10, 10)``: payload parameters about the payload frame -> about its link's joint frame."""

        def make():
            import pinocchio as pin

            _, placement = self._payload_frame
            p0 = payload_parameters(1.0, [0.01, 0.02, 0.03], radius=0.1)

            def moved(p):
                return placement.act(pin.Inertia.FromDynamicParameters(p)).toDynamicParameters()

            base = moved(p0)
            return np.stack([moved(p0 + np.eye(10)[k]) - base for k in range(10)], axis=1)

        return self._cached("payload_map", make)

    @property
    def payload_basis(self) -> Array:
        """``(p, 10)``: how the payload's ten parameters (about its frame) move sigma."""
        j = self.payload_joint
        return self.base.B[:, 10 * j : 10 * j + 10] @ self.payload_map

    # ------------------------------------------------------------------ dynamics
    def standard_regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Array:
        """``W(q, qd, qdd)`` of the standard parameters, ``(..., n, 13 n)``."""
        q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
        n = self.n_joints
        shape = np.broadcast_shapes(q.shape, qd.shape, qdd.shape)
        if shape[-1:] != (n,):
            raise ParameterError(f"states must have shape (..., {n}), got {shape}")
        q, qd, qdd = (np.broadcast_to(x, shape).reshape(-1, n) for x in (q, qd, qdd))
        Y = self._rigid_regressor(q, qd, qdd)
        eye = np.eye(n)
        W = np.concatenate(
            [Y, eye * qd[:, None, :], eye * np.sign(qd)[:, None, :], eye * qdd[:, None, :]], axis=2
        )
        return W.reshape(*shape[:-1], n, 13 * n)

    def _rigid_regressor(self, q: Array, qd: Array, qdd: Array) -> Array:
        from adaptive_dd.plant.chain import regressor_batch

        return regressor_batch(self.chain, q, qd, qdd)

    def pin_configuration(self, q: ArrayLike) -> Array:
        """Pinocchio's configuration of joint positions ``q (n,)`` (continuous joints as cos, sin;
        :func:`adaptive_dd.plant.chain.pin_configuration`)."""
        from adaptive_dd.plant.chain import pin_configuration

        return pin_configuration(self.model, q)

    def regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Array:
        """Base regressor ``(..., n, p)``: ``regressor @ sigma`` is the joint torque."""
        return self.standard_regressor(q, qd, qdd)[..., self.base.independent]

    def _standard_of(self, sigma: ArrayLike | None) -> Array | None:
        """A standard vector ``(13 n,)`` whose base image is ``sigma (p,)``: ``sigma`` on the
        independent columns, 0 elsewhere (``W @ it == regressor @ sigma``); None for a batch."""
        s = self.sigma if sigma is None else np.asarray(sigma, dtype=float)
        if s.ndim != 1:
            return None
        if s.shape != self.sigma.shape:
            raise ParameterError(f"sigma has {s.size} base parameters, this arm has {self.sigma.size}")
        pe = np.zeros(13 * self.n_joints)
        pe[self.base.independent] = s
        return pe

    def inverse_dynamics(self, q, qd, qdd, sigma: ArrayLike | None = None) -> Array:
        """Joint torques ``(..., n)`` (friction and armature included): ``regressor @ sigma``, by
        the compiled RNEA on the standard vector of :meth:`_standard_of` (linear in it)."""
        from adaptive_dd.plant.chain import rnea_batch

        pe = self._standard_of(sigma)
        q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
        n = self.n_joints
        shape = np.broadcast_shapes(q.shape, qd.shape, qdd.shape)
        if pe is None or shape[-1:] != (n,):  # a batch of sigmas; the shape error
            return np.einsum("...ij,...j->...i", self.regressor(q, qd, qdd), np.asarray(sigma, dtype=float))
        fv, fc, ia = pe[10 * n : 11 * n], pe[11 * n : 12 * n], pe[12 * n :]
        return rnea_batch(self.chain, pe[: 10 * n], q, qd, qdd) + fv * qd + fc * np.sign(qd) + ia * qdd

    def mass_matrix(self, q: ArrayLike, sigma: ArrayLike | None = None) -> Array:
        """M(q) with armature, ``(..., n, n)``, from base parameters ``(..., p)`` (default :attr:`sigma`)."""
        from adaptive_dd.plant.chain import mass_matrix_batch

        pe, q, n = self._standard_of(sigma), np.asarray(q, dtype=float), self.n_joints
        if pe is not None:
            return mass_matrix_batch(self.chain, pe[: 10 * n], q) + np.diag(pe[12 * n :])
        z, s, e = np.zeros_like(q), np.asarray(sigma, dtype=float), np.eye(n)  # a batch: by the columns
        cols = [self.inverse_dynamics(q, z, np.broadcast_to(e[k], q.shape), s) for k in range(n)]
        return np.stack(cols, -1) - self.inverse_dynamics(q, z, z, s)[..., None]

    def nominal_inertia(self) -> Array:
        """Diagonal of M at the middle of the position limits (0 for unbounded joints), ``(n,)``."""
        lim = self.position_limits
        bounded = np.isfinite(lim).all(axis=1)
        mid = np.where(bounded, np.where(bounded[:, None], lim, 0.0).mean(axis=1), 0.0)  # no inf - inf
        return np.diag(self.mass_matrix(mid)).copy()

    # ------------------------------------------------------------------- payload
    def sigma_with_payload(
        self,
        mass: ArrayLike,
        com: ArrayLike | None = None,
        inertia: ArrayLike | None = None,
        radius: float | None = None,
        sigma0: ArrayLike | None = None,
    ) -> Array:
        """Base parameters with a rigid body on the payload frame, ``(..., p)``: ``mass`` [kg] may
        be an array (one disk per entry, the same com and inertia); ``radius`` (default
        :attr:`payload_radius`) when ``inertia`` is not given. A mass < 0 or not finite is refused."""
        base = self.sigma if sigma0 is None else np.asarray(sigma0, dtype=float)
        rad = self.payload_radius if radius is None else radius
        m = np.asarray(mass, dtype=float)
        if not np.all(np.isfinite(m) & (m >= 0)):
            raise ParameterError(f"sigma_with_payload: mass must be finite and >= 0 kg, got {mass!r}")
        if inertia is None:  # a disk: every parameter scales with the mass
            pp = m[..., None] * payload_parameters(1.0, com, radius=rad)
        else:
            flat = [payload_parameters(float(x), com, inertia) for x in m.reshape(-1)]
            pp = np.reshape(flat, (*m.shape, 10))
        return base + pp @ self.payload_basis.T

    def payload_direction(self, radius: ArrayLike | None = None) -> Array:
        """``d sigma / d m`` of a disk at the payload frame's origin, ``(p,)``."""
        rad = self.payload_radius if radius is None else float(radius)
        return self.payload_basis @ payload_parameters(1.0, radius=rad)

    def payload_from_sigma(self, sigma_hat: ArrayLike, sigma0: ArrayLike | None = None) -> PayloadEstimate:
        """The payload implied by base parameters ``(..., p)`` (least squares on :attr:`payload_basis`).

        Parameters not determined by the base parameters (a null direction of the
        basis) are reported in ``identifiable``; the com of an unidentifiable axis is nan.
        """
        s0 = self.sigma if sigma0 is None else np.asarray(sigma0, dtype=float)
        d = np.asarray(sigma_hat, dtype=float) - s0
        P = self.payload_basis
        pinv = np.linalg.pinv(P, rcond=1e-9)
        params = d @ pinv.T
        ident = self.payload_identifiable
        m = params[..., 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            com = params[..., 1:4] / m[..., None]
        com = np.where(ident[1:4], com, np.nan)
        return PayloadEstimate(m, com, params, ident)

    @property
    def payload_identifiable(self) -> NDArray[np.bool_]:
        """Which of the payload's ten parameters the base parameters determine, ``(10,)``."""

        def make():
            P = self.payload_basis
            _, s, vt = np.linalg.svd(P)
            null = vt[np.sum(s > 1e-9 * s[0]) :]
            return np.all(np.abs(null) < 1e-8, axis=0) if len(null) else np.ones(10, dtype=bool)

        return self._cached("payload_ident", make)

    def payload_mass_from_sigma(self, sigma_hat: ArrayLike) -> Array:
        return self.payload_from_sigma(sigma_hat).mass  # [kg] (...) of base parameters (..., p)

    @property
    def payload_rank(self) -> int:
        """Rank of :attr:`payload_basis` (how many payload directions the base parameters see)."""
        s = np.linalg.svd(self.payload_basis, compute_uv=False)
        return int(np.sum(s > 1e-9 * s[0]))

    # -------------------------------------------------------------------- misc
    @property
    def friction_code(self) -> int:
        return FRICTION_LAWS.index(self.friction)

    @property
    def friction_params(self) -> tuple[float, ...]:
        """What the plant's friction law reads: ``friction_velocity, stribeck_ratio,
        stribeck_velocity``, then under LuGre :attr:`lugre_stiffness` and :attr:`lugre_sigma1`."""
        base = (self.friction_velocity, self.stribeck_ratio, self.stribeck_velocity)
        return (*base, *self.lugre_stiffness, *self.lugre_sigma1) if self.friction == "lugre" else base

    @property
    def lugre_sigma1(self) -> tuple[float, ...]:
        """LuGre bristle damping per joint [N m s/rad]: :attr:`lugre_damping` or
        ``sqrt(sigma0_i M_ii(0))`` (``M`` with the armature, at q = 0)."""
        if self.lugre_damping is not None:
            return self.lugre_damping
        m = np.diag(self.mass_matrix(np.zeros(self.n_joints)))
        return tuple(float(np.sqrt(s0 * mi)) for s0, mi in zip(self.lugre_stiffness, m, strict=True))

    def with_(self, **changes) -> Arm:
        """:func:`dataclasses.replace`, keeping nothing cached that depends on what changed (a new
        ``sensor`` alone keeps the dynamics: model, chain, payload maps)."""
        out = replace(self, **changes)
        if set(changes) == {"sensor"}:
            out._cache.update({k: v for k, v in self._cache.items() if k != "as_two_link"})
        return out

    def to_dict(self) -> dict:
        """JSON-able description (for results metadata)."""
        return {
            "urdf": str(self.urdf),
            "joints": list(self.joint_names),
            "locked": list(self.locked),
            "payload_frame": self.payload_frame,
            "gravity": self.gravity.tolist(),
            "viscous": self.viscous.tolist(),
            "coulomb": self.coulomb.tolist(),
            "armature": self.armature.tolist(),
            "position_limits": self.position_limits.tolist(),
            "velocity_limits": self.velocity_limits.tolist(),
            "torque_limit": list(self.actuator.torque_limit),
            "sigma": self.sigma.tolist(),
            "sigma_names": list(self.sigma_names),
            "payload_radius": self.payload_radius,
            "payload_capacity": self.payload_capacity,
            "payload_offset": self.payload_offset,
            "friction": self.friction,
            "friction_velocity": self.friction_velocity,
            "stribeck_ratio": self.stribeck_ratio,
            "stribeck_velocity": self.stribeck_velocity,
            "repair_inertia": self.repair_inertia,
            "general": self.general,
            **(
                {"lugre_stiffness": list(self.lugre_stiffness), "lugre_damping": list(self.lugre_sigma1)}
                if self.friction == "lugre"
                else {}
            ),
        }

    def _key(self) -> tuple:
        """Every compared field, arrays as (nested) tuples: equal arms describe the same arm."""

        def plain(v):
            return tuple(map(plain, v)) if isinstance(v, (np.ndarray, list, tuple)) else v

        return tuple(plain(getattr(self, f.name)) for f in fields(self) if f.compare)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Arm) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())
