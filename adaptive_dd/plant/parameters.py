"""Parameters of the SICE two-link direct-drive arm.

Base parameters ``sigma = [J1, J2, r, b1, b2, d1, d2]`` (paper eq. 9), the
physical parameters of eq. (10) and their map onto sigma (eq. 3), and a payload
disk at the tip of link 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError

__all__ = [
    "L1",
    "L2",
    "PAYLOAD_RADIUS",
    "SIGMA_NAMES",
    "TABLE1_PHYSICAL",
    "TABLE1_SIGMA",
    "TORQUE_LIMITS",
    "Payload",
    "PhysicalParameters",
    "payload_mass_from_sigma",
    "payload_sigma_delta",
    "project_sigma",
    "validate_sigma",
]

L1 = 0.2
"""Length of link 1 [m] (SICE standard arm)."""
L2 = 0.2
"""Length of link 2 [m]."""
TORQUE_LIMITS = (70.0, 15.0)
"""Maximum actuator torques [N m] of joints 1 and 2 (Section 1)."""
PAYLOAD_RADIUS = 0.05
"""Default radius [m] of the payload disk (the one place this default is written)."""

SIGMA_NAMES = ("J1", "J2", "r", "b1", "b2", "d1", "d2")
"""Names of the base parameters, in the order of eq. (9)."""

TABLE1_SIGMA = np.array([0.429, 0.071, 0.162, 5.236, 1.116, 3.208, 0.743])
"""Base parameters of Table 1: J1, J2, r [kg m^2], b1, b2 [N m s], d1, d2 [N m]."""
TABLE1_SIGMA.setflags(write=False)


def validate_sigma(sigma: ArrayLike, name: str = "sigma") -> NDArray[np.float64]:
    """Check base parameters and return them as a float array of shape ``(..., 7)``.

    Raises
    ------
    ParameterError
        Wrong last axis, non-finite entries, ``J1``, ``J2`` or ``r`` not positive,
        negative friction, or ``J1 * J2 <= r**2`` (the inertia matrix of eq. 3 is
        then indefinite for some ``q2``).
    """
    s = np.asarray(sigma, dtype=float)
    if s.ndim == 0 or s.shape[-1] != 7:
        raise ParameterError(f"{name} must have shape (..., 7) [J1 J2 r b1 b2 d1 d2], got {s.shape}")
    if not np.all(np.isfinite(s)):
        raise ParameterError(f"{name} has non-finite entries: {s}")
    for k in range(3):
        if np.any(s[..., k] <= 0):
            raise ParameterError(f"{name}: {SIGMA_NAMES[k]} must be > 0, got {s[..., k]}")
    for k in range(3, 7):
        if np.any(s[..., k] < 0):
            raise ParameterError(f"{name}: {SIGMA_NAMES[k]} must be >= 0, got {s[..., k]}")
    det = s[..., 0] * s[..., 1] - s[..., 2] ** 2
    if np.any(det <= 0):
        raise ParameterError(
            f"{name}: J1*J2 - r^2 = {det} must be > 0, or the inertia matrix M(q) of eq. (3) "
            f"is not positive definite for all q2"
        )
    return s


@dataclass(frozen=True)
class Payload:
    """A uniform steel disk fixed at the tip of link 2, centred on the tip.

    Parameters
    ----------
    mass : float
        Mass [kg], >= 0.
    radius : float
        Radius [m], >= 0; the disk turns about its own axis with the link, adding
        ``mass * radius**2 / 2`` to the inertia of link 2.
    """

    mass: float
    radius: float = PAYLOAD_RADIUS

    def __post_init__(self) -> None:
        for f in ("mass", "radius"):
            v = getattr(self, f)
            if not math.isfinite(v) or v < 0:
                raise ParameterError(f"Payload.{f} must be finite and >= 0, got {v!r}")

    @property
    def inertia(self) -> float:
        """Inertia of the disk about its own centre [kg m^2]."""
        return 0.5 * self.mass * self.radius**2


def payload_sigma_delta(
    mass: ArrayLike, radius: ArrayLike = PAYLOAD_RADIUS, l1: float = L1, l2: float = L2
) -> NDArray[np.float64]:
    """Change of sigma caused by a tip disk: ``(..., 7)``.

    A tip mass ``m`` adds ``m l1^2`` to J1, ``m l2^2 + m R^2/2`` to J2 and
    ``m l1 l2`` to r (docs/paper_reading.md); friction is unchanged.
    """
    m = np.asarray(mass, dtype=float)
    rad = np.asarray(radius, dtype=float)
    if np.any(~np.isfinite(m)) or np.any(m < 0):
        raise ParameterError(f"payload mass must be finite and >= 0, got {m}")
    if np.any(~np.isfinite(rad)) or np.any(rad < 0):
        raise ParameterError(f"payload radius must be finite and >= 0, got {rad}")
    m, rad = np.broadcast_arrays(m, rad)
    out = np.zeros((*m.shape, 7))
    out[..., 0] = m * l1**2
    out[..., 1] = m * l2**2 + 0.5 * m * rad**2
    out[..., 2] = m * l1 * l2
    return out


@dataclass(frozen=True)
class PhysicalParameters:
    """Physical parameters of eq. (10) plus the (known) link lengths.

    Attributes
    ----------
    I1, I2 : float
        Inertia of links 1 and 2 about their centres of mass [kg m^2].
    m1, m2 : float
        Masses [kg]; ``m2`` includes everything carried by link 2.
    a1, a2 : float
        Distances from joint i to the centre of mass of link i [m].
    b1, b2 : float
        Viscous friction [N m s/rad].
    d1, d2 : float
        Coulomb friction [N m].
    l1, l2 : float
        Link lengths [m].
    """

    I1: float
    I2: float
    m1: float
    m2: float
    a1: float
    a2: float
    b1: float
    b2: float
    d1: float
    d2: float
    l1: float = L1
    l2: float = L2

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not isinstance(v, int | float) or not math.isfinite(v):
                raise ParameterError(f"PhysicalParameters.{f.name} must be a finite number, got {v!r}")
            strict = f.name in ("m1", "m2", "l1", "l2", "I1", "I2")
            if (strict and v <= 0) or v < 0:
                bound = "> 0" if strict else ">= 0"
                raise ParameterError(f"PhysicalParameters.{f.name} must be {bound}, got {v!r}")

    def to_sigma(self) -> NDArray[np.float64]:
        """Base parameters (eq. 3 and 9): ``[J1, J2, r, b1, b2, d1, d2]``."""
        j1 = self.I1 + self.m1 * self.a1**2 + self.m2 * self.l1**2
        j2 = self.I2 + self.m2 * self.a2**2
        r = self.m2 * self.l1 * self.a2
        return np.array([j1, j2, r, self.b1, self.b2, self.d1, self.d2])

    def with_payload(self, payload: Payload) -> PhysicalParameters:
        """Link 2 with the disk rigidly added at its tip (parallel-axis theorem)."""
        m = payload.mass
        if m == 0:
            return self
        m2 = self.m2 + m
        a2 = (self.m2 * self.a2 + m * self.l2) / m2
        i2 = self.I2 + self.m2 * (self.a2 - a2) ** 2 + payload.inertia + m * (self.l2 - a2) ** 2
        return PhysicalParameters(
            self.I1,
            i2,
            self.m1,
            m2,
            self.a1,
            a2,
            self.b1,
            self.b2,
            self.d1,
            self.d2,
            self.l1,
            self.l2,
        )


TABLE1_PHYSICAL = PhysicalParameters(
    I1=0.014,
    I2=0.071 - 10.125 * 0.08**2,
    m1=1.0,
    m2=10.125,
    a1=0.1,
    a2=0.08,
    b1=5.236,
    b2=1.116,
    d1=3.208,
    d2=0.743,
)
"""A physical set that maps exactly onto Table 1 (docs/paper_reading.md: a2 = 0.08 m, m2 = r/(l1 a2)).

The paper gives only base parameters; this is one consistent choice, used for the
Pinocchio model. ``TABLE1_PHYSICAL.to_sigma()`` equals ``TABLE1_SIGMA`` to rounding.
"""


R_MIN = 1e-9
"""Smallest r [kg m^2] that :func:`project_sigma` returns."""


PROJECTION_J_MIN = 1e-3
"""Smallest J1, J2 [kg m^2] of a projected model."""
PROJECTION_MARGIN = 0.05
"""Projected models keep ``r^2 <= (1 - margin) J1 J2``."""


def project_sigma(
    sigma: ArrayLike, j_min: float = PROJECTION_J_MIN, margin: float = PROJECTION_MARGIN
) -> NDArray[np.float64]:
    """Nearest physically consistent base parameters (cheap projection), ``(..., 7)``.

    ``J1, J2 >= j_min``, ``r >= R_MIN`` (validate_sigma needs r > 0), friction ``>= 0``,
    and ``r^2 <= (1 - margin) J1 J2`` so that M(q) stays positive definite for every q2.
    Non-finite entries are left for the caller to catch.
    """
    s = np.array(sigma, dtype=float, copy=True)
    s[..., 0:2] = np.maximum(s[..., 0:2], j_min)
    s[..., 3:7] = np.maximum(s[..., 3:7], 0.0)
    r_max = np.sqrt((1.0 - margin) * s[..., 0] * s[..., 1])
    s[..., 2] = np.clip(s[..., 2], R_MIN, r_max)
    return s


def payload_mass_from_sigma(
    sigma_hat: ArrayLike, sigma0: ArrayLike = TABLE1_SIGMA, l1: float = L1, l2: float = L2
) -> NDArray[np.float64]:
    """Tip mass [kg] implied by estimated base parameters, ``(...)``.

    Least squares on the changes of J1 (``m l1^2``) and r (``m l1 l2``) from the
    unloaded arm ``sigma0``; J2 is left out because it also holds the disk's own
    inertia, whose radius is unknown.
    """
    d = np.asarray(sigma_hat, dtype=float) - np.asarray(sigma0, dtype=float)
    a1, a2 = l1**2, l1 * l2
    return (a1 * d[..., 0] + a2 * d[..., 2]) / (a1**2 + a2**2)
