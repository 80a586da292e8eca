"""Offline output-error (maximum-likelihood) identification of sigma by multiple shooting.

Model: the arm simulated by the compiled stick-slip step
(:func:`adaptive_dd.plant.two_link_integrator.two_link_plant_step`) under the measured applied torque;
measurements ``y_k = [q_k, qd_k] + e_k`` with white Gaussian ``e_k`` of known variances.
Then maximum likelihood is nonlinear least squares on the output errors weighted by the
noise standard deviations, and attains the Cramér-Rao bound of
:mod:`adaptive_dd.identification.fisher` asymptotically.

Open-loop drift
---------------
A simulation over the whole 10 s record from a wrong sigma drifts away from the data
(positions integrate velocity errors), which makes the cost very non-convex. Multiple
shooting cuts the record into segments of ``segment_length`` samples, each started from
its own free initial state ``s_j`` (4 unknowns per segment); continuity
``x_end(s_j, sigma) = s_{j+1}`` enters as residuals with weight ``continuity_weight``
times that of a measurement (a penalty that tends to the constraint), so the optimum is
that of one long simulation while every segment stays close to the data throughout.

Solver: ``scipy.optimize.least_squares`` (trust-region reflective, sigma kept
non-negative) with the Jacobian from the forward sensitivity equations of
:mod:`adaptive_dd.identification.sensitivity` chained over each segment.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.experiments import TABLE2
from adaptive_dd.identification.fisher import SIGNALS, output_variances
from adaptive_dd.identification.sensitivity import chain_sensitivities, local_sensitivities
from adaptive_dd.plant.parameters import project_sigma, validate_sigma
from adaptive_dd.plant.two_link_integrator import two_link_plant_step

__all__ = ["TwoLinkOutputErrorResult", "output_error_fit"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class TwoLinkOutputErrorResult:
    """Result of :func:`output_error_fit`.

    Attributes
    ----------
    sigma : ndarray (7,)
        Estimate.
    std : ndarray (7,)
        Standard deviations from the Gauss-Newton covariance ``(J^T J)^-1`` (residuals
        are in units of the noise std, so this is the Cramér-Rao bound at the estimate
        with the segment states unknown too).
    nodes : ndarray (n_segments, 4)
        Estimated states ``[q1 q2 qd1 qd2]`` at the segment starts.
    cost : float
        Half the sum of squared normalised residuals.
    n_residuals : int
    nfev : int
    success : bool
    message : str
    segment_length : int
    """

    sigma: Array
    std: Array
    nodes: Array
    cost: float
    n_residuals: int
    nfev: int
    success: bool
    message: str
    segment_length: int


class _Problem:
    """Residuals and Jacobian of the multiple-shooting problem (one record)."""

    def __init__(self, y, tau, var, var_state, seg, T, substeps, weight, x0):
        n = y.shape[0]
        self.x0 = x0  # known initial state (4,), or None: the first node is free
        self.n, self.seg, self.T, self.substeps = n, seg, T, substeps
        self.nseg = -(-n // seg)
        pad = self.nseg * seg + 1 - n
        self.tau = np.concatenate((tau, np.zeros((pad, 2)))).reshape(-1, 2)
        self.tau_seg = np.stack([self.tau[j * seg : j * seg + seg + 1] for j in range(self.nseg)])
        self.rows = np.flatnonzero(np.isfinite(var))
        self.w = 1.0 / np.sqrt(var[self.rows])
        self.y = y
        self.valid = (np.arange(self.nseg * seg) < n).reshape(self.nseg, seg)
        # a defect counts `weight` times a measurement of each state component
        self.wd = weight / np.sqrt(var_state)
        self._cache = (None, None)

    def split(self, p):
        nodes = p[7:].reshape(-1, 4)
        if self.x0 is not None:
            nodes = np.concatenate((self.x0[None], nodes))
        return p[:7], nodes

    def simulate(self, p):
        if self._cache[0] is not None and np.array_equal(self._cache[0], p):
            return self._cache[1]
        sg, nodes = self.split(p)
        sg = project_sigma(sg)  # the solver may step outside; the cost is flat there
        q, qd = nodes[:, :2].copy(), nodes[:, 2:].copy()
        stuck, slip = qd == 0.0, np.ones_like(qd)
        xs = np.empty((self.nseg, self.seg + 1, 4))
        for i in range(self.seg + 1):
            xs[:, i, :2], xs[:, i, 2:] = q, qd
            if i < self.seg:
                q, qd, stuck, slip = two_link_plant_step(
                    q, qd, stuck, slip, self.tau_seg[:, i], sg, self.T, self.substeps
                )
        self._cache = (p.copy(), xs)
        return xs

    def residuals(self, p):
        xs = self.simulate(p)
        pred = xs[:, :-1].reshape(-1, 4)[: self.n]
        r_meas = ((self.y - pred)[:, self.rows] * self.w).ravel()
        defect = (xs[:-1, -1] - self.split(p)[1][1:]) * self.wd
        return np.concatenate((r_meas, defect.ravel()))

    def jacobian(self, p):
        xs = self.simulate(p)
        sg = project_sigma(p[:7])
        a, _, ps = local_sensitivities(xs[..., :2], xs[..., 2:], self.tau_seg, sg, self.T, self.substeps)
        ext = np.concatenate((np.zeros((*ps.shape[:-1], 4)), ps), axis=-1)
        s0 = np.concatenate((np.eye(4), np.zeros((4, 7))), axis=-1)
        z = chain_sensitivities(a, ext, np.broadcast_to(s0, (self.nseg, 4, 11)))  # (nseg, L+1, 4, 11)
        nr, npar = len(self.rows), 7 + 4 * self.nseg
        jm = np.zeros((self.nseg, self.seg, nr, npar))
        zr = -z[:, :-1][:, :, self.rows] * self.w[:, None]  # (nseg, L, nr, 11)
        jm[..., :7] = zr[..., 4:]
        for j in range(self.nseg):
            jm[j, :, :, 7 + 4 * j : 11 + 4 * j] = zr[j, :, :, :4]
        jm = jm[self.valid].reshape(-1, npar)
        jd = np.zeros((self.nseg - 1, 4, npar))
        for j in range(self.nseg - 1):
            zend = z[j, -1] * self.wd[:, None]
            jd[j, :, :7] = zend[:, 4:]
            jd[j, :, 7 + 4 * j : 11 + 4 * j] = zend[:, :4]
            jd[j, :, 11 + 4 * j : 15 + 4 * j] = -np.diag(self.wd)
        jac = np.concatenate((jm, jd.reshape(-1, npar)))
        return jac if self.x0 is None else np.delete(jac, np.s_[7:11], axis=1)


def output_error_fit(
    q_meas: ArrayLike,
    qd_meas: ArrayLike,
    tau: ArrayLike,
    sigma0: ArrayLike,
    sample_period: float = TABLE2["sample_period"],
    position_variance: ArrayLike = TABLE2["position_variance"],
    velocity_variance: ArrayLike = TABLE2["velocity_variance"],
    *,
    measured: tuple[str, ...] = SIGNALS,
    segment_length: int = 500,
    continuity_weight: float = 1e4,
    substeps: int = 2,
    max_nfev: int = 50,
    x0: ArrayLike | None = None,
) -> TwoLinkOutputErrorResult:
    """Output-error (maximum-likelihood) estimate of sigma from one record, by multiple shooting.

    Parameters
    ----------
    q_meas, qd_meas : array_like (N, 2)
        Measured angles [rad] and velocities [rad/s] at the sample instants.
    tau : array_like (N, 2)
        Applied torque held over each sample [N m] (known).
    sigma0 : array_like (7,)
        Start, e.g. the recursive estimate ``estimate(..., estimator="exact").final``.
    sample_period : float
        T [s].
    position_variance, velocity_variance : array_like (2,)
        Noise variances: the weights of the residuals (Table 2 / 4 by default).
    measured : tuple of {"q", "qd"}
        Signals fitted.
    segment_length : int
        Samples per shooting segment.
    continuity_weight : float
        Weight of a continuity defect relative to a measurement residual.
    substeps : int
        RK4 steps per sample of the model (as the simulator).
    max_nfev : int
        Most function evaluations of the solver.
    x0 : array_like (4,), optional
        Known initial state ``[q1 q2 qd1 qd2]`` (e.g. at rest, as in Table 2): the first
        segment then starts there. Knowing that the arm starts at rest is worth a lot:
        on Table 2 the bound on d2 is 0.008 % with x0 known, 0.025 % without.
    """
    y, tau = _checked_inputs(q_meas, qd_meas, tau, segment_length, continuity_weight)
    var = output_variances(position_variance, velocity_variance, measured)
    var_state = output_variances(position_variance, velocity_variance)
    x0_ = None if x0 is None else np.asarray(x0, dtype=float).reshape(4)
    T, L = float(sample_period), int(segment_length)
    prob = _Problem(y, tau, var, var_state, L, T, int(substeps), continuity_weight, x0_)
    nodes0 = y[:: prob.seg][: prob.nseg]
    p0 = np.concatenate((validate_sigma(sigma0), (nodes0 if x0_ is None else nodes0[1:]).ravel()))
    # Levenberg-Marquardt (MINPACK, QR): the dense Jacobian has ~4 N rows and 7 + 4 N / L columns
    sol = least_squares(prob.residuals, p0, jac=prob.jacobian, x_scale="jac", max_nfev=max_nfev, method="lm")
    return _result(prob, sol, int(segment_length))


def _result(prob: _Problem, sol, segment_length: int) -> TwoLinkOutputErrorResult:
    """The solver's solution as the estimate, its standard deviations and the segment states."""
    sg, nodes = prob.split(sol.x)
    return TwoLinkOutputErrorResult(
        sg.copy(),
        _gauss_newton_std(sol.jac),
        nodes.copy(),
        float(sol.cost),
        int(sol.fun.size),
        int(sol.nfev),
        bool(sol.success),
        str(sol.message),
        segment_length,
    )


def _checked_inputs(
    q_meas, qd_meas, tau, segment_length: int, continuity_weight: float
) -> tuple[Array, Array]:
    """The measurements ``y = [q qd] (N, 4)`` and ``tau (N, 2)``, checked with the segment settings."""
    q_meas, qd_meas, tau = (np.asarray(a, dtype=float) for a in (q_meas, qd_meas, tau))
    if not (q_meas.shape == qd_meas.shape == tau.shape and tau.ndim == 2 and tau.shape[-1] == 2):
        raise SignalError(
            f"q_meas, qd_meas, tau must be (N, 2) records of one length, got "
            f"{q_meas.shape}, {qd_meas.shape}, {tau.shape}"
        )
    y = np.column_stack((q_meas, qd_meas))
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(tau))):
        raise SignalError("q_meas, qd_meas, tau records must be finite")
    if segment_length < 2 or continuity_weight <= 0:
        raise ParameterError(
            f"need segment_length >= 2 and continuity_weight > 0, got {segment_length}, {continuity_weight}"
        )
    return y, tau


def _gauss_newton_std(jac: Array) -> Array:
    """Standard deviations of sigma from ``(J^T J)^-1`` (NaN where J^T J is singular)."""
    jtj = jac.T @ jac
    try:
        cov = np.linalg.inv(jtj)
        return np.sqrt(np.abs(np.diag(cov)[:7]))
    except np.linalg.LinAlgError:
        return np.full(7, np.nan)
