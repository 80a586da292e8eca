"""Online estimators of sigma from filtered regressions, and the named pipelines.

Splits (Section 3.1, cascaded as in docs/paper_reading.md)
----------------------------------------------------------
``"15"``: equation 2 estimates ``[J2 r b2 d2]`` from ``y2`` exactly; equation 1
estimates ``[J1 b1 d1]`` from ``y1 - (qdd1 + qdd2) J2_hat - phi13 r_hat`` with
J2_hat, r_hat just updated by equation 2.
``"16"``: the mirror: equation 1 estimates ``[J1 J2 r b1 d1]`` from ``y1``,
equation 2 estimates ``[b2 d2]`` from ``y2 - (qdd1 + qdd2) J2_hat - phi23 r_hat``.
``"full"``: one RLS on all seven parameters with both equations of each sample
(two scalar updates; the forgetting factor is applied once per sample).

Estimators (the names used by ``adaptive-dd reproduce`` and ``identify``)
-------------------------------------------------------------------------
``paper``
    The paper as written: construction "paper" (eqs. 17/19), RLS of eq. (14)
    with the variable forgetting factor, on the chosen split.
``batch_ls``, ``kalman``
    Batch least squares, and filterpy's Kalman filter, on the paper's data.
``exact``
    Ours, online: construction "exact" (G0 applied to the whole equation, no
    nonlinear-filtering error), the torque aligned to the sample instants
    (``(tau(t-1) + tau(t)) / 2``, since the zero-order-hold torque over
    ``[t, t+T)`` drives the motion after t), data selection (an equation is used
    only when its joint's measured velocity stayed above a threshold over the
    filter's memory: no sticking, no noisy sign), and the full 7-parameter RLS.
``exact_batch_ls``
    Batch least squares on the same data as ``exact``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.kalman import KalmanParameterEstimator
from adaptive_dd.identification.regressors import two_link_filtered_regression
from adaptive_dd.identification.rls import RLSConfig, batch_least_squares, rls_init, rls_step

__all__ = [
    "ESTIMATORS",
    "EXACT_RLS",
    "PAPER_RLS",
    "SPLITS",
    "EstimationResult",
    "SplitRLS",
    "align_torque",
    "estimate",
    "excitation_mask",
    "prepare_regression",
    "solve_regression",
]

Array = NDArray[np.float64]

SPLITS = {
    "15": ((1, (1, 2, 4, 6)), (0, (0, 3, 5))),
    "16": ((0, (0, 1, 2, 3, 5)), (1, (4, 6))),
    "full": None,
}
"""Cascaded splits as (row, parameter indices) of the exact stage, then the dependent stage."""

ESTIMATORS = ("paper", "batch_ls", "kalman", "exact", "exact_batch_ls")


class SplitRLS:
    """Recursive estimation of sigma (7) on a split, batched (eq. 14 per scalar equation).

    Parameters
    ----------
    split : {"15", "16", "full"}
    cfg : RLSConfig
    batch_shape : tuple
    theta0 : array_like (7,) or (..., 7), optional
    """

    def __init__(
        self,
        split: str = "full",
        cfg: RLSConfig = RLSConfig(),  # noqa: B008
        batch_shape: tuple = (),
        theta0: ArrayLike | None = None,
    ) -> None:
        if split not in SPLITS:
            raise ParameterError(f"split must be one of {list(SPLITS)}, got {split!r}")
        self.split, self.cfg = split, cfg
        th0 = np.broadcast_to(
            np.zeros(7) if theta0 is None else np.asarray(theta0, float), (*batch_shape, 7)
        ).copy()
        if split == "full":
            self.states = [rls_init(7, cfg, batch_shape, th0)]
        else:
            (_, ia), (_, ib) = SPLITS[split]
            self.states = [
                rls_init(len(ia), cfg, batch_shape, th0[..., list(ia)]),
                rls_init(len(ib), cfg, batch_shape, th0[..., list(ib)]),
            ]
        self.last_eps = np.full((*batch_shape, 2), np.nan)

    @property
    def theta(self) -> Array:
        """Current estimate of sigma, ``(..., 7)``."""
        if self.split == "full":
            return self.states[0].theta
        (_, ia), (_, ib) = SPLITS[self.split]
        th = np.empty((*self.states[0].theta.shape[:-1], 7))
        th[..., list(ia)] = self.states[0].theta
        th[..., list(ib)] = self.states[1].theta
        return th

    @property
    def P(self) -> Array:
        """Covariance ``(..., 7, 7)`` (block diagonal for a cascade)."""
        if self.split == "full":
            return self.states[0].P
        (_, ia), (_, ib) = SPLITS[self.split]
        p = np.zeros((*self.states[0].P.shape[:-2], 7, 7))
        p[..., np.ix_(ia, ia)[0], np.ix_(ia, ia)[1]] = self.states[0].P
        p[..., np.ix_(ib, ib)[0], np.ix_(ib, ib)[1]] = self.states[1].P
        return p

    @property
    def n_skipped(self) -> Array:
        return sum(s.n_skipped for s in self.states)

    def step(self, phi: Array, y: Array, active: NDArray[np.bool_] | None = None) -> Array:
        """Feed one sample ``phi (..., 2, 7)``, ``y (..., 2)``; return sigma_hat ``(..., 7)``.

        ``active (..., 2)`` marks the equations to use (data selection).
        """
        act = (lambda r: None) if active is None else (lambda r: active[..., r])
        if self.split == "full":
            s, i0 = rls_step(self.states[0], phi[..., 0, :], y[..., 0], self.cfg, active=act(0))
            s, i1 = rls_step(s, phi[..., 1, :], y[..., 1], self.cfg, forget=False, active=act(1))
            self.states[0] = s
            self.last_eps = np.stack((i0["eps"], i1["eps"]), axis=-1)
            return s.theta
        (ra, ia), (rb, ib) = SPLITS[self.split]
        sa, info_a = rls_step(self.states[0], phi[..., ra, list(ia)], y[..., ra], self.cfg, active=act(ra))
        other = [j for j in range(7) if j not in ib]
        th_a = np.zeros((*sa.theta.shape[:-1], 7))
        th_a[..., list(ia)] = sa.theta
        yb = y[..., rb] - np.einsum("...j,...j->...", phi[..., rb, other], th_a[..., other])
        sb, info_b = rls_step(self.states[1], phi[..., rb, list(ib)], yb, self.cfg, active=act(rb))
        self.states = [sa, sb]
        eps = np.empty((*sa.theta.shape[:-1], 2))
        eps[..., ra], eps[..., rb] = info_a["eps"], info_b["eps"]
        self.last_eps = eps
        return self.theta

    def run(self, phi: Array, y: Array, active: NDArray[np.bool_] | None = None) -> Array:
        """Feed a record ``phi (..., N, 2, 7)``; return the estimates ``(..., N, 7)``."""
        n = phi.shape[-3]
        out = np.empty((*phi.shape[:-3], n, 7))
        for k in range(n):
            out[..., k, :] = self.step(
                phi[..., k, :, :], y[..., k, :], None if active is None else active[..., k, :]
            )
        return out


def align_torque(tau: ArrayLike, axis: int = -2) -> Array:
    """``(tau(t-1) + tau(t)) / 2`` along the time axis (``tau(0)`` at the first sample).

    The torque held over ``[t, t+T)`` drives the motion after t; the motion at the
    instant t is driven by the mean of the torques on either side.
    """
    tau = np.asarray(tau, dtype=float)
    prev = np.concatenate((np.take(tau, [0], axis=axis), np.delete(tau, -1, axis=axis)), axis=axis)
    return 0.5 * (tau + prev)


def excitation_mask(qd: ArrayLike, threshold: float, memory: int, axis: int = -2) -> NDArray[np.bool_]:
    """Equations whose joint moved with ``|qd| > threshold`` over the last ``memory`` samples.

    Parameters
    ----------
    qd : array_like, shape (..., n_samples, 2)
        Measured velocity [rad/s].
    threshold : float
        Velocity below which friction may stick or its sign is uncertain [rad/s].
    memory : int
        Samples a sticking or sign error lingers in the filtered equation (about
        ``8 tau_f / T``).
    """
    qd = np.moveaxis(np.asarray(qd, dtype=float), axis, -2)
    n = qd.shape[-2]
    k = np.arange(n)[:, None]
    near = np.abs(qd) <= threshold
    last = np.maximum.accumulate(np.where(near, k, -(10**9)), axis=-2)
    return np.moveaxis((k - last) > memory, -2, axis)


@dataclass(frozen=True)
class EstimationResult:
    """Estimates of sigma over a record.

    Attributes
    ----------
    theta : ndarray (..., n_samples, 7)
        Estimate after each sample (batch estimators: the final value repeated).
    final : ndarray (..., 7)
    std : ndarray (..., 7)
        Standard deviations from the covariance scaled by the residual variance
        (``sqrt(diag(P) * s^2)``, s^2 the mean squared residual of the used equations).
    n_used : ndarray (...)
        Equations used.
    estimator, split, method : str
    tau_f : float
    """

    theta: Array
    final: Array
    std: Array
    n_used: Array
    estimator: str
    split: str
    method: str
    tau_f: float


PAPER_RLS = RLSConfig(lam0=0.99, mu=0.002, p0=100.0)
"""RLS settings of the ``paper`` estimator. The paper gives none; lambda(0) = 0.99 lies
in its range 0.98 < lambda <= 1 and mu = 0.002 brings lambda to 1 within ~2 s."""
EXACT_RLS = RLSConfig(lam0=1.0, mu=0.0, p0=1e4)
"""RLS settings of ``exact``: no forgetting (the parameters are constant in Table 2)."""


def prepare_regression(
    q: ArrayLike,
    tau: ArrayLike,
    qd: ArrayLike | None = None,
    *,
    estimator: str = "paper",
    method: str = "M2",
    tau_f: float = 0.006,
    sample_period: float = 1e-3,
    threshold: float = 0.05,
    memory_factor: float = 6.0,
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """Filtered regression and data selection an estimator works on.

    Returns ``phi (..., N, 2, 7)``, ``y (..., N, 2)`` and ``active (..., N, 2)``
    (all True but for the ``exact*`` estimators).
    """
    if estimator not in ESTIMATORS:
        raise ParameterError(f"estimator must be one of {ESTIMATORS}, got {estimator!r}")
    if threshold < 0 or memory_factor < 0:
        raise ParameterError(f"threshold and memory_factor must be >= 0, got {threshold}, {memory_factor}")
    exact = estimator.startswith("exact")
    tau = np.asarray(tau, dtype=float)
    fr = two_link_filtered_regression(
        q,
        align_torque(tau) if exact else tau,
        qd,
        method=method,
        construction="exact" if exact else "paper",
        tau_f=tau_f,
        sample_period=sample_period,
    )
    if exact:
        qd_sel = qd if method == "M2" else np.gradient(np.asarray(q, float), sample_period, axis=-2)
        active = excitation_mask(qd_sel, threshold, int(np.ceil(memory_factor * tau_f / sample_period)))
    else:
        active = np.ones(fr.y.shape, dtype=bool)
    return fr.phi, fr.y, active


def solve_regression(
    phi: Array,
    y: Array,
    active: NDArray[np.bool_],
    *,
    estimator: str = "paper",
    split: str = "15",
    rls: RLSConfig | None = None,
    theta0: ArrayLike | None = None,
    kalman_q: float = 0.0,
    progress=None,
    max_lag: int = 0,
) -> tuple[Array, Array, Array]:
    """Run an estimator on prepared data.

    Returns ``theta (..., N, 7)``, the covariance-like ``P (..., 7, 7)`` and
    standard deviations ``(..., 7)``: ``sqrt(diag(P) s^2)`` with ``s^2`` the residual
    variance inflated by the residuals' autocorrelation up to ``max_lag`` samples.
    """
    split = split if estimator == "paper" else "full"
    if split not in SPLITS:
        raise ParameterError(f"split must be one of {list(SPLITS)}, got {split!r}")
    rls = rls or (EXACT_RLS if estimator.startswith("exact") else PAPER_RLS)
    batch, n = phi.shape[:-3], phi.shape[-3]
    if estimator in ("batch_ls", "exact_batch_ls"):
        a = phi.reshape(*batch, -1, 7)
        b = y.reshape(*batch, -1)
        act = active.reshape(*batch, -1) & np.isfinite(b) & np.isfinite(a).all(axis=-1)
        final = batch_least_squares(a, b, act)
        theta = np.broadcast_to(final[..., None, :], (*batch, n, 7))
        a0 = np.where(act[..., None], a, 0.0)
        pmat = np.linalg.inv(np.einsum("...ki,...kj->...ij", a0, a0))
    elif estimator == "kalman":
        flat_phi, flat_y = phi.reshape(-1, n, 2, 7), y.reshape(-1, n, 2)
        runs, ps = [], []
        for i in range(flat_phi.shape[0]):
            kf = KalmanParameterEstimator(7, 2, q=kalman_q, p0=rls.p0, theta0=theta0)
            runs.append(kf.run(flat_phi[i], flat_y[i]))
            ps.append(kf.P)
            if progress is not None:
                progress(1 / flat_phi.shape[0])
        theta = np.stack(runs).reshape(*batch, n, 7)
        final, pmat = theta[..., -1, :], np.stack(ps).reshape(*batch, 7, 7)
    else:
        est = SplitRLS(split, rls, batch, theta0)
        theta = est.run(phi, y, active)
        final, pmat = theta[..., -1, :], est.P
    used = active & np.isfinite(y) & np.isfinite(phi).all(axis=-1)  # skipped samples do not count
    resid = np.where(
        used, y - np.einsum("...nij,...j->...ni", np.where(used[..., None], phi, 0.0), final), 0.0
    )
    if estimator in ("exact", "exact_batch_ls", "batch_ls") and max_lag > 0:
        return theta, pmat, _newey_west_std(phi, resid, used, max_lag)  # rows differ in noise, coloured
    n_used = used.sum(axis=(-2, -1))
    s2 = (resid**2).sum(axis=(-2, -1)) / np.maximum(n_used - 7, 1)
    s2 = s2 * _autocorrelation_inflation(resid, max_lag)
    std = np.sqrt(np.abs(np.diagonal(pmat, axis1=-2, axis2=-1)) * s2[..., None])
    return theta, pmat, std


def _newey_west_std(phi: Array, resid: Array, used: NDArray[np.bool_], max_lag: int) -> Array:
    """Sandwich ``A^-1 S A^-1`` per record (``S`` the scores' Bartlett sum up to ``max_lag``,
    :func:`~adaptive_dd.identification.log_covariance._bartlett_sum`): each joint's own residual
    level and the filters' colouring, where one pooled ``s^2`` understates joint 1's parameters."""
    from adaptive_dd.identification.log_covariance import _bartlett_sum

    a = np.where(used[..., None], phi, 0.0)
    A = np.einsum("...nri,...nrj->...ij", a, a)
    g = np.einsum("...nri,...nr->...ni", a, resid)  # each sample's score (..., N, 7)
    flat = g.reshape(-1, *g.shape[-2:])
    S = np.stack([_bartlett_sum(x, int(max_lag), [(0, x.shape[0])]) for x in flat]).reshape(A.shape)
    ai = np.linalg.inv(A)
    return np.sqrt(np.abs(np.diagonal(ai @ S @ ai, axis1=-2, axis2=-1)))


def _autocorrelation_inflation(resid: Array, max_lag: int) -> Array:
    """``1 + 2 sum_k rho_k`` (lags 1..max_lag) of the residuals, >= 1.

    The filtered equation errors are coloured (correlated over about tau_f), so
    ``s^2 (Phi^T Phi)^-1`` alone would understate the variance of the estimate.
    """
    r = resid.reshape(-1, *resid.shape[-2:])  # (B, N, 2)
    var = (r**2).sum(axis=1)
    acc = np.zeros_like(var)
    for k in range(1, max(int(max_lag), 0) + 1):
        acc += (r[:, k:] * r[:, :-k]).sum(axis=1)
    rho_sum = np.where(var > 0, acc / np.maximum(var, 1e-300), 0.0)
    infl = np.maximum(1.0, 1.0 + 2.0 * rho_sum).mean(axis=-1)
    return infl.reshape(resid.shape[:-2])


def estimate(
    q: ArrayLike,
    tau: ArrayLike,
    qd: ArrayLike | None = None,
    *,
    estimator: str = "paper",
    method: str = "M2",
    split: str = "15",
    tau_f: float = 0.006,
    sample_period: float = 1e-3,
    rls: RLSConfig | None = None,
    theta0: ArrayLike | None = None,
    threshold: float = 0.05,
    memory_factor: float = 6.0,
    kalman_q: float = 0.0,
) -> EstimationResult:
    """Estimate sigma from measured records ``q, tau, qd (..., n_samples, 2)``.

    Parameters
    ----------
    estimator : {"paper", "batch_ls", "kalman", "exact", "exact_batch_ls"}
        See the module docstring.
    method : {"M1", "M2"}
    split : {"15", "16", "full"}
        Used by ``paper``; the others use the full regression.
    tau_f, sample_period : float
        Filter time constant and sample period [s].
    rls : RLSConfig, optional
        Default :data:`PAPER_RLS` or :data:`EXACT_RLS`.
    theta0 : array_like (7,), optional
        Initial estimate (default 0).
    threshold, memory_factor : float
        Data selection of ``exact*``: velocity threshold [rad/s] and memory in units of tau_f.
    kalman_q : float
        Random-walk variance of ``kalman``.
    """
    phi, y, active = prepare_regression(
        q,
        tau,
        qd,
        estimator=estimator,
        method=method,
        tau_f=tau_f,
        sample_period=sample_period,
        threshold=threshold,
        memory_factor=memory_factor,
    )
    theta, _, std = solve_regression(
        phi,
        y,
        active,
        estimator=estimator,
        split=split,
        rls=rls,
        theta0=theta0,
        kalman_q=kalman_q,
        max_lag=int(np.ceil(10 * tau_f / sample_period)),
    )
    split = split if estimator == "paper" else "full"
    n_used = (active & np.isfinite(y) & np.isfinite(phi).all(axis=-1)).sum(axis=(-2, -1))
    return EstimationResult(theta, theta[..., -1, :], std, n_used, estimator, split, method, float(tau_f))
