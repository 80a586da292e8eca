"""Base parameters of a serial arm by numerical QR on sampled regressors (Gautier's method).

The standard parameters of an n-joint arm are, per link, the ten inertial
parameters of Pinocchio's ordering about the joint frame (``m, m cx, m cy, m cz,
Ixx, Ixy, Iyy, Ixz, Iyz, Izz``), then per joint the viscous friction ``fv``, the
Coulomb friction ``fc`` and the armature (rotor inertia) ``Ia``::

    pi = [link 1 (10), ..., link n (10), fv (n), fc (n), Ia (n)]        (13 n,)

and the joint torque is ``W(q, qd, qdd) pi`` with ``W = [Y | diag(qd) |
diag(sgn qd) | diag(qdd)]``, ``Y`` Pinocchio's joint-torque regressor. Many
columns of ``W`` are zero or linear combinations of others for every motion; the
*base parameters* are the independent combinations. Stacking ``W`` over random
states and factorising it by QR (columns in the standard order) splits them into
independent ``b`` and dependent ``d`` ones with ``W_d = W_b K``,
``K = R_bb^-1 R_bd``; then ``W pi = W_b (pi_b + K pi_d)`` and

    sigma = pi_b + K pi_d = B pi,    W_base = W[:, b].

The base regressor is a column subset of the standard one, and ``B`` maps any
standard parameter vector (a payload's, a link's) onto the base parameters.
Gautier, "Numerical calculation of the base inertial parameters of robots",
J. Robotic Systems 8(4), 1991.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

__all__ = ["LINK_PARAMETER_NAMES", "BaseParameters", "base_parameters", "standard_names"]

Array = NDArray[np.float64]

LINK_PARAMETER_NAMES = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
"""Names of the ten inertial parameters of a link (Pinocchio's order; ``mx = m c_x``)."""


def standard_names(n: int) -> tuple[str, ...]:
    """Names of the ``13 n`` standard parameters, e.g. ``Izz2``, ``fv3``, ``Ia1``."""
    names = [f"{p}{j + 1}" for j in range(n) for p in LINK_PARAMETER_NAMES]
    for p in ("fv", "fc", "Ia"):
        names += [f"{p}{j + 1}" for j in range(n)]
    return tuple(names)


@dataclass(frozen=True, eq=False)
class BaseParameters:
    """The base parameter structure of an arm.

    Attributes
    ----------
    independent : ndarray of int (p,)
        Columns of the standard regressor kept as base columns, ascending.
    B : ndarray (p, 13 n)
        ``sigma = B @ pi``.
    names : tuple of str (p,)
        What each base parameter regroups, e.g. ``"Izz2 + 0.425*mx3 + ..."``.
    unidentifiable : tuple of str
        Standard parameters that no torque depends on (a zero column).
    """

    independent: NDArray[np.int64]
    B: Array
    names: tuple[str, ...]
    unidentifiable: tuple[str, ...]

    @property
    def count(self) -> int:
        return len(self.independent)

    def __repr__(self) -> str:
        return f"BaseParameters({self.count} of {self.B.shape[1]})"


def _term(c: float, name: str) -> str:
    if abs(c - 1.0) < 1e-12:
        return name
    if abs(c + 1.0) < 1e-12:
        return f"-{name}"
    return f"{c:.6g}*{name}"


def base_parameters(
    regressor: Callable[[Array, Array, Array], Array],
    n: int,
    lower: Array,
    upper: Array,
    rng: np.random.Generator,
    n_samples: int = 60,
    rtol: float = 1e-9,
) -> BaseParameters:
    """Base parameters from the standard regressor sampled at random states.

    Parameters
    ----------
    regressor : callable
        ``regressor(q, qd, qdd) -> (m, n, 13 n)`` for states of shape ``(m, n)``.
    n : int
        Number of joints.
    lower, upper : ndarray (n,)
        Position range to sample (infinite bounds are replaced by ``-pi, pi``).
    rng : numpy.random.Generator
        Source of the random states.
    n_samples : int
        Number of random states (each gives n rows).
    rtol : float
        A diagonal entry of R below ``rtol * |R[0, 0]|`` ends the rank.
    """
    lo = np.where(np.isfinite(lower), lower, -np.pi)
    hi = np.where(np.isfinite(upper), upper, np.pi)
    q = rng.uniform(lo, hi, (n_samples, n))
    qd = rng.uniform(-2.0, 2.0, (n_samples, n))
    qdd = rng.uniform(-5.0, 5.0, (n_samples, n))
    W = np.asarray(regressor(q, qd, qdd)).reshape(n_samples * n, 13 * n)
    names = standard_names(n)
    norms = np.linalg.norm(W, axis=0)
    zero = norms <= rtol * max(norms.max(), 1e-300)
    cols = np.flatnonzero(~zero)
    # Columns in the standard order (link 1 first, armature last): a column is kept when it is
    # independent of the kept columns before it (unpivoted QR: |R_jj| of the scaled columns),
    # so a parameter is regrouped onto those of the links nearer the base, as in Khalil and
    # Gautier's closed-form grouping (e.g. Izz1 + l1^2 m2 + Ia1), and the names read naturally.
    Ws = W[:, cols] / norms[cols]
    R = scipy.linalg.qr(Ws, mode="r")[0]
    keep = np.abs(np.diag(R)) > rtol * np.sqrt(Ws.shape[0])
    b_idx, d_idx = cols[keep], cols[~keep]
    K = np.linalg.lstsq(W[:, b_idx], W[:, d_idx], rcond=None)[0]
    K[np.abs(K) < 1e-10] = 0.0
    rank = len(b_idx)
    B = np.zeros((rank, 13 * n))
    B[np.arange(rank), b_idx] = 1.0
    B[:, d_idx] = K
    labels = []
    for i, col in enumerate(b_idx):
        terms = [names[col]] + [_term(K[i, k], names[dc]) for k, dc in enumerate(d_idx) if K[i, k] != 0.0]
        labels.append(" + ".join(terms).replace("+ -", "- "))
    return BaseParameters(b_idx, B, tuple(labels), tuple(names[i] for i in np.flatnonzero(zero)))
