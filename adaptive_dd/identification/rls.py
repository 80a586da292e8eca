"""Recursive least squares with a variable forgetting factor (paper eq. 14).

A pure step over an immutable state, batched over leading axes, and a thin
stateful class. For one scalar equation ``y = phi^T theta``::

    eps    = y - phi^T theta(t-1)
    lam(t) = (1 - mu) lam(t-1) + mu
    K      = P(t-1) phi / (lam(t) + phi^T P(t-1) phi)
    theta  = theta(t-1) + K eps
    P(t)   = (P(t-1) - K phi^T P(t-1)) / lam(t)

Safeguards (off the paper's path, each documented): a non-finite sample is
skipped and counted, leaving theta, P and lambda as they were; P is kept
symmetric; its trace is capped at ``max_trace`` so that forgetting without
excitation cannot wind it up without bound.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError

__all__ = [
    "RLSConfig",
    "RLSState",
    "RecursiveLeastSquares",
    "batch_least_squares",
    "rls_init",
    "rls_step",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class RLSConfig:
    """Settings of eq. (14).

    Attributes
    ----------
    lam0 : float
        Initial forgetting factor lambda(0), in (0, 1].
    mu : float
        Rate of the forgetting factor towards 1, in [0, 1] (0: constant lambda).
    p0 : float
        Initial covariance ``P(0) = p0 I``, > 0.
    max_trace : float or None
        Cap on ``trace(P)``; ``None`` means ``n * p0`` (never above its start).

    Examples
    --------
    >>> from adaptive_dd.identification.rls import RLSConfig
    >>> RLSConfig(lam0=0.995, mu=0.0)
    RLSConfig(lam0=0.995, mu=0.0, p0=100.0, max_trace=None)
    """

    lam0: float = 0.99
    mu: float = 0.002
    p0: float = 100.0
    max_trace: float | None = None

    def __post_init__(self) -> None:
        if not (0.0 < self.lam0 <= 1.0):
            raise ParameterError(f"lam0 (initial forgetting factor) must be in (0, 1], got {self.lam0}")
        if not (0.0 <= self.mu <= 1.0):
            raise ParameterError(f"mu must be in [0, 1], got {self.mu}")
        if not (np.isfinite(self.p0) and self.p0 > 0):
            raise ParameterError(f"p0 (initial covariance) must be > 0, got {self.p0}")
        if self.max_trace is not None and not (self.max_trace > 0):
            raise ParameterError(f"max_trace must be > 0 or None, got {self.max_trace}")


class RLSState(NamedTuple):
    """Immutable estimator state; arrays carry the batch axes first.

    theta : (..., n); P : (..., n, n); lam : (...); n_skipped : (...) int
    """

    theta: Array
    P: Array
    lam: Array
    n_skipped: NDArray[np.int_]


def rls_init(
    n_params: int,
    cfg: RLSConfig = RLSConfig(),
    batch_shape: tuple = (),
    theta0: ArrayLike | None = None,
) -> RLSState:
    """Initial state: ``theta0`` (default 0), ``P = p0 I``, ``lambda = lam0``.

    Parameters
    ----------
    n_params : int
        Parameters estimated.
    cfg : RLSConfig
        Forgetting and start-up covariance.
    batch_shape : tuple of int
        Leading axes (trials), broadcast over.
    theta0 : array_like, shape (..., n_params), optional
        The start estimate.

    Returns
    -------
    RLSState
        ``theta``, ``P`` and ``lam`` with the batch axes first.

    Examples
    --------
    >>> from adaptive_dd.identification.rls import RLSConfig, rls_init
    >>> state = rls_init(2, RLSConfig(p0=100.0), batch_shape=(3,))  # 3 trials, 2 parameters
    >>> state.theta.shape, state.P.shape, float(state.lam[0])
    ((3, 2), (3, 2, 2), 0.99)
    """
    th = np.zeros((*batch_shape, n_params)) if theta0 is None else np.asarray(theta0, dtype=float)
    th = np.broadcast_to(th, (*batch_shape, n_params)).copy()
    if not np.all(np.isfinite(th)):
        raise ParameterError(f"theta0 must be finite, got {theta0}")
    p = np.broadcast_to(cfg.p0 * np.eye(n_params), (*batch_shape, n_params, n_params)).copy()
    return RLSState(th, p, np.full(batch_shape, cfg.lam0), np.zeros(batch_shape, dtype=int))


def rls_step(
    state: RLSState,
    phi: Array,
    y: Array,
    cfg: RLSConfig = RLSConfig(),
    *,
    forget: bool = True,
    active: NDArray[np.bool_] | None = None,
) -> tuple[RLSState, dict]:
    """One update of eq. (14) (pure function).

    Parameters
    ----------
    state : RLSState
    phi : ndarray, shape (..., n)
        Regressor of the scalar equation.
    y : ndarray, shape (...)
        Its output.
    forget : bool
        Advance and apply lambda(t); ``False`` applies lambda = 1 (a second
        equation of the same sample).
    active : ndarray of bool, shape (...), optional
        Where False, the state is left unchanged (data selection).

    Returns
    -------
    state : RLSState
    info : dict
        ``eps`` (prior error), ``gain`` (K), ``skipped`` (non-finite sample).

    Examples
    --------
    With no forgetting, recursive least squares converges to the batch solution:

    >>> import numpy as np
    >>> from adaptive_dd.identification.rls import RLSConfig, batch_least_squares, rls_init, rls_step
    >>> rng = np.random.default_rng(0)
    >>> phi = rng.standard_normal((200, 2))
    >>> y = phi @ np.array([2.0, -1.0])
    >>> cfg = RLSConfig(lam0=1.0, mu=0.0, p0=1e6)
    >>> state = rls_init(2, cfg)
    >>> for k in range(200):
    ...     state, info = rls_step(state, phi[k], y[k], cfg)
    >>> state.theta.round(6), batch_least_squares(phi, y).round(6)
    (array([ 2., -1.]), array([ 2., -1.]))
    """
    theta, P, lam_prev, n_skipped = state
    finite = np.isfinite(y) & np.isfinite(phi).all(axis=-1)
    clean = bool(finite.all())
    if not clean:
        phi = np.where(finite[..., None], phi, 0.0)
        y = np.where(finite, y, 0.0)
    lam = (1.0 - cfg.mu) * lam_prev + cfg.mu if forget else lam_prev
    lam_eff = lam if forget else np.ones_like(lam_prev)
    pphi = (P @ phi[..., None])[..., 0]
    den = lam_eff + (phi * pphi).sum(axis=-1)
    eps = y - (phi * theta).sum(axis=-1)
    gain = pphi / den[..., None]
    th_new = theta + gain * eps[..., None]
    p_new = (P - gain[..., :, None] * pphi[..., None, :]) / lam_eff[..., None, None]
    p_new = 0.5 * (p_new + np.swapaxes(p_new, -1, -2))
    cap = cfg.max_trace if cfg.max_trace is not None else cfg.p0 * theta.shape[-1]
    tr = np.trace(p_new, axis1=-2, axis2=-1)
    if np.any(tr > cap):
        p_new = p_new * np.minimum(1.0, cap / np.maximum(tr, 1e-300))[..., None, None]
    bad = ~finite | ~(den > 0)  # den is NaN or inf only if P went bad: skip too
    keep = bad if active is None else bad | ~active
    if keep.any():
        th_new = np.where(keep[..., None], theta, th_new)
        p_new = np.where(keep[..., None, None], P, p_new)
        lam = np.where(keep, lam_prev, lam)
    out = RLSState(th_new, p_new, lam, n_skipped + bad if not clean or bad.any() else n_skipped)
    return out, {"eps": np.where(bad, np.nan, eps) if not clean else eps, "gain": gain, "skipped": bad}


class RecursiveLeastSquares:
    """Stateful wrapper of :func:`rls_step` (eq. 14), batched.

    ``state`` holds the current :class:`RLSState`; ``last_info`` the ``info`` dict of
    the last update (prior error ``eps``, ``gain``, ``skipped``).

    Examples
    --------
    >>> est = RecursiveLeastSquares(3)
    >>> est.update(np.array([1.0, 0.0, 2.0]), 3.0)  # doctest: +ELLIPSIS
    array([...])
    """

    def __init__(
        self,
        n_params: int,
        cfg: RLSConfig = RLSConfig(),
        batch_shape: tuple = (),
        theta0: ArrayLike | None = None,
    ) -> None:
        self.cfg = cfg
        self.state = rls_init(n_params, cfg, batch_shape, theta0)

    @property
    def theta(self) -> Array:
        return self.state.theta

    @property
    def P(self) -> Array:
        return self.state.P

    def update(self, phi: ArrayLike, y: ArrayLike, *, forget: bool = True, active=None) -> Array:
        """Feed one sample; return the new estimate."""
        self.state, self.last_info = rls_step(
            self.state,
            np.asarray(phi, dtype=float),
            np.asarray(y, dtype=float),
            self.cfg,
            forget=forget,
            active=active,
        )
        return self.state.theta


def batch_least_squares(
    phi: ArrayLike,
    y: ArrayLike,
    active: ArrayLike | None = None,
    ridge: float = 0.0,
    theta0: ArrayLike | None = None,
) -> Array:
    """Least squares over a whole record.

    Parameters
    ----------
    phi : array_like, shape (..., K, n)
        One row per scalar equation (stack samples and outputs into K; a record
        ``(..., N, 2, n)`` becomes ``reshape(..., 2 N, n)``).
    y : array_like, shape (..., K)
    active : array_like of bool, shape (..., K), optional
        Equations to use (non-finite ones are always left out).
    ridge : float
        Adds ``ridge * |theta - theta0|^2`` to the cost; ``ridge = 1/p0`` with
        ``lambda = 1`` is exactly what RLS computes from ``P(0) = p0 I``.
    theta0 : array_like, shape (..., n), optional

    Returns
    -------
    ndarray, shape (..., n)

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.identification.rls import batch_least_squares
    >>> phi = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    >>> batch_least_squares(phi, np.array([1.0, 2.0, 3.0])).round(6)
    array([1., 2.])
    """
    phi = np.asarray(phi, dtype=float)
    y = np.asarray(y, dtype=float)
    if phi.ndim < 2 or phi.shape[:-1] != y.shape:
        raise SignalError(f"phi must be (..., K, n) and y (..., K); got {phi.shape} and {y.shape}")
    n = phi.shape[-1]
    ok = np.isfinite(y) & np.all(np.isfinite(phi), axis=-1)
    if active is not None:
        ok &= np.asarray(active, dtype=bool)
    a = np.where(ok[..., None], phi, 0.0)
    b = np.where(ok, y, 0.0)
    ata = np.einsum("...ki,...kj->...ij", a, a)
    atb = np.einsum("...ki,...k->...i", a, b)
    if ridge > 0:
        t0 = np.zeros(n) if theta0 is None else np.asarray(theta0, dtype=float)
        ata = ata + ridge * np.eye(n)
        atb = atb + ridge * t0
    return np.linalg.solve(ata, atb[..., None])[..., 0]
