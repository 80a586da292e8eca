"""Physical consistency of a rigid body's ten inertial parameters, and fits constrained to it.

A body's parameters ``pi = [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` (about a
frame's origin, Pinocchio's order) are those of a real mass distribution iff its
**pseudo-inertia**

    J = [[Sigma, h], [h^T, m]],   Sigma = tr(I)/2 * 1 - I,   h = m c,

is positive semidefinite (Wensing, Kim and Slotine, RA-L 2018): it is then the second
moment ``int [x; 1][x; 1]^T dm``. A constrained fit parameterises ``J = L L^T`` with ``L``
lower triangular and an exponential on its diagonal (the log-Cholesky parameters of
Rucker and Wensing, RA-L 2022: 10 unconstrained numbers, every value a physical body)
and minimises the Mahalanobis distance to the unconstrained estimate,
``(pi - pi_hat)^T F (pi - pi_hat)`` with ``F`` its information, by
``scipy.optimize.least_squares``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from adaptive_dd.errors import ParameterError

__all__ = [
    "ConsistentArmFit",
    "ConsistentFit",
    "consistent_arm_fit",
    "consistent_fit",
    "is_physical",
    "params_from_pseudo_inertia",
    "pseudo_inertia",
]

Array = NDArray[np.float64]
_TRIL = np.tril_indices(4)


def pseudo_inertia(pi: ArrayLike) -> Array:
    """The 4 x 4 pseudo-inertia of ten parameters ``(..., 10)`` -> ``(..., 4, 4)``."""
    p = np.asarray(pi, dtype=float)
    if p.shape[-1] != 10:
        raise ParameterError(f"a body has 10 inertial parameters, got shape {p.shape}")
    m, h = p[..., 0], p[..., 1:4]
    ixx, ixy, iyy, ixz, iyz, izz = (p[..., k] for k in range(4, 10))
    inertia = np.stack(
        [np.stack([ixx, ixy, ixz], -1), np.stack([ixy, iyy, iyz], -1), np.stack([ixz, iyz, izz], -1)], -2
    )
    tr = ixx + iyy + izz
    J = np.zeros((*p.shape[:-1], 4, 4))
    J[..., :3, :3] = 0.5 * tr[..., None, None] * np.eye(3) - inertia
    J[..., :3, 3] = h
    J[..., 3, :3] = h
    J[..., 3, 3] = m
    return J


def params_from_pseudo_inertia(J: ArrayLike) -> Array:
    """Inverse of :func:`pseudo_inertia`: ``(..., 4, 4)`` -> ``(..., 10)``."""
    J = np.asarray(J, dtype=float)
    S = 0.5 * (J[..., :3, :3] + np.swapaxes(J[..., :3, :3], -1, -2))
    inertia = np.trace(S, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - S
    return np.concatenate(
        [
            J[..., 3, 3, None],
            J[..., :3, 3],
            np.stack([inertia[..., i, j] for i, j in ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))], -1),
        ],
        axis=-1,
    )


def is_physical(pi: ArrayLike, atol: float = 0.0) -> bool:
    """True when the pseudo-inertia of ``pi (10,)`` is positive semidefinite (eigenvalues >= -atol)."""
    return bool(np.linalg.eigvalsh(pseudo_inertia(pi))[0] >= -atol)


def _from_log_cholesky(theta: Array) -> Array:
    """``(..., 10)`` log-Cholesky coordinates -> ``(..., 10)`` parameters (a batch of bodies)."""
    theta = np.asarray(theta, dtype=float)
    L = np.zeros((*theta.shape[:-1], 4, 4))
    L[..., _TRIL[0], _TRIL[1]] = theta
    d = np.arange(4)
    L[..., d, d] = np.exp(np.clip(L[..., d, d], -40.0, 40.0))
    return params_from_pseudo_inertia(L @ np.swapaxes(L, -1, -2))


def _to_log_cholesky(J: Array, floor: float) -> Array:
    lam, V = np.linalg.eigh(0.5 * (J + J.T))
    Jp = (V * np.maximum(lam, floor)) @ V.T
    L = np.linalg.cholesky(Jp)
    L[np.diag_indices(4)] = np.log(np.diag(L))
    return L[_TRIL]


@dataclass(frozen=True)
class ConsistentFit:
    """A body's parameters constrained to be physical.

    Attributes
    ----------
    params : ndarray (10,)
        The constrained estimate (its pseudo-inertia positive definite).
    unconstrained : ndarray (10,)
    min_eigenvalue : float
        Smallest eigenvalue of the unconstrained estimate's pseudo-inertia [kg m^2]; < 0:
        no rigid body has those parameters.
    distance : float
        Mahalanobis distance from the unconstrained estimate to the constrained one,
        ``sqrt((pi - pi_hat)^T F (pi - pi_hat))``: in units of the estimate's std; 0 if
        it was physical.
    was_physical : bool
    """

    params: Array
    unconstrained: Array
    min_eigenvalue: float
    distance: float
    was_physical: bool


def consistent_fit(pi_hat: ArrayLike, information: ArrayLike) -> ConsistentFit:
    """The physical body nearest to ``pi_hat (10,)`` in the metric of its information ``(10, 10)``.

    Raises
    ------
    ParameterError
        Non-finite inputs or an information matrix that is not positive definite.
    """
    pi_hat = np.asarray(pi_hat, dtype=float)
    F = np.asarray(information, dtype=float)
    if (
        pi_hat.shape != (10,)
        or F.shape != (10, 10)
        or not (np.all(np.isfinite(pi_hat)) and np.all(np.isfinite(F)))
    ):
        raise ParameterError(
            f"need 10 finite parameters and a (10, 10) information, got {pi_hat.shape}, {F.shape}"
        )
    try:
        Lf = np.linalg.cholesky(0.5 * (F + F.T))
    except np.linalg.LinAlgError:
        raise ParameterError("the information matrix of the payload is not positive definite") from None
    J = pseudo_inertia(pi_hat)
    lam = np.linalg.eigvalsh(J)
    lam_min = float(lam[0])
    scale = max(float(np.abs(lam).max()), 1e-12)
    if lam_min >= -1e-12 * scale:  # semidefinite to rounding: a thin disk, a point mass
        return ConsistentFit(pi_hat.copy(), pi_hat.copy(), lam_min, 0.0, True)

    def residual(theta):
        return Lf.T @ (_from_log_cholesky(theta) - pi_hat)

    sol = least_squares(residual, _to_log_cholesky(J, 1e-6 * scale), method="lm", xtol=1e-12, ftol=1e-12)
    params = _from_log_cholesky(sol.x)
    return ConsistentFit(params, pi_hat.copy(), lam_min, float(np.linalg.norm(sol.fun)), False)


@dataclass(frozen=True)
class ConsistentArmFit:
    """All links' standard parameters, each link physical, whose base parameters fit an estimate.

    Attributes
    ----------
    pi : ndarray (13 n,)
        Links (each pseudo-inertia positive definite), then fv, fc, Ia (>= 0).
    sigma : ndarray (p,)
        ``B pi``: the nearest physically consistent base parameters.
    distance : float
        Mahalanobis distance from the unconstrained estimate to ``sigma`` (in its std):
        about 0 when the estimate is consistent, large when no physical arm has it.
    """

    pi: Array
    sigma: Array
    distance: float


def consistent_arm_fit(
    model, sigma_hat: ArrayLike, information: ArrayLike, prior_weight: float = 1e-6
) -> ConsistentArmFit:
    """Physically consistent standard parameters nearest (Mahalanobis) to base parameters ``sigma_hat``.

    The base parameters do not fix the standard ones; among those that fit, the fit keeps
    close to the URDF's (a penalty ``prior_weight`` on the relative change of each). Links
    by log-Cholesky, friction and armature bounded below by 0; solved by
    ``scipy.optimize.least_squares`` (trust-region reflective).
    """
    sigma_hat = np.asarray(sigma_hat, float)
    F = np.asarray(information, float)
    if F.shape != (model.p, model.p) or sigma_hat.shape != (model.p,):
        raise ParameterError(f"need {model.p} base parameters and a ({model.p}, {model.p}) information")
    if not (np.all(np.isfinite(F)) and np.all(np.isfinite(sigma_hat))):
        raise ParameterError("the estimate or its information matrix is not finite")
    Lf = _information_factor(F)
    n = model.n
    ref = model.pi_ref
    x0 = _log_cholesky_coordinates(ref, n)
    scale = np.maximum(np.abs(ref), 1e-3 * np.abs(ref).max())

    def residual(x):
        pi = _pi_of(x, n)
        return np.concatenate([Lf.T @ (model.B @ pi - sigma_hat), np.sqrt(prior_weight) * (pi - ref) / scale])

    LB = Lf.T @ model.B

    def jac(x):
        D = _pi_jacobian(x, n)
        return np.vstack([LB @ D, np.sqrt(prior_weight) * D / scale[:, None]])

    lo = np.concatenate([np.full(10 * n, -np.inf), np.zeros(3 * n)])
    sol = least_squares(
        residual,
        np.maximum(x0, lo),
        jac=jac,
        bounds=(lo, np.inf),
        method="trf",
        max_nfev=200,
        tr_solver="lsmr",
    )
    pi = _pi_of(sol.x, n)
    sig = model.B @ pi
    return ConsistentArmFit(pi, sig, float(np.linalg.norm(Lf.T @ (sig - sigma_hat))))


def _information_factor(F: Array) -> Array:
    """``Lf`` with ``F = Lf Lf^T``, through the eigen-decomposition: a semidefinite F (some
    direction not seen) is allowed (those directions are then left to the prior) where a
    Cholesky factor would fail."""
    lam, V = np.linalg.eigh(0.5 * (F + F.T))
    return V * np.sqrt(np.maximum(lam, 1e-12 * max(lam.max(), 0.0)))


def _log_cholesky_coordinates(pi: Array, n: int) -> Array:
    """Standard parameters ``pi (13 n,)`` as the fit's unknowns: each link's 10 in log-Cholesky
    coordinates of its pseudo-inertia, then friction and armature as they are."""
    links = pi[: 10 * n].reshape(n, 10)
    return np.concatenate(
        [
            np.concatenate([_to_log_cholesky(pseudo_inertia(links[j]), 1e-8) for j in range(n)]),
            pi[10 * n :],
        ]
    )


def _pi_of(x: Array, n: int) -> Array:
    """Standard parameters ``(13 n,)`` of the fit's unknowns (:func:`_log_cholesky_coordinates`)."""
    return np.concatenate([_from_log_cholesky(x[: 10 * n].reshape(n, 10)).reshape(-1), x[10 * n :]])


def _pi_jacobian(x: Array, n: int) -> Array:
    """``d pi / d x`` ``(13 n, 13 n)``: block diagonal, each link's 10 x 10 block by central
    differences, the identity on friction and armature."""
    h = 1e-6
    X = x[: 10 * n].reshape(n, 1, 10) + h * np.eye(10)
    blocks = (_from_log_cholesky(X) - _from_log_cholesky(X - 2 * h * np.eye(10))) / (2 * h)  # (n, k, out)
    D = np.eye(13 * n)
    for j in range(n):
        D[10 * j : 10 * j + 10, 10 * j : 10 * j + 10] = blocks[j].T
    return D
