"""Output error (maximum likelihood) for any serial arm, and its Cramér-Rao bound.

Noise model
-----------
The applied torque is known (held over each sample). The measured signals are
``y_k = [q_k, qd_k] + e_k``, ``e_k`` white Gaussian with the sensor's variances (plus the
encoder's ``Delta^2 / 12`` on q). The record is cut into segments of ``L`` samples and each
segment's initial state ``x_j = [q, qd]`` is an unknown (a nuisance parameter) besides the
parameters ``theta`` of ``sigma = sigma0 + E theta`` (``E = I``: all base parameters; ``E`` =
:attr:`Arm.payload_basis`: the payload alone, the arm known).

The Fisher information of theta with the segment states unknown is

    F = sum_j (A_j^T A_j - A_j^T C_j (C_j^T C_j)^-1 C_j^T A_j),

``A_j`` and ``C_j`` the output sensitivities of segment j to theta and to ``x_j`` divided by
the noise std (the Schur complement eliminates the states), and ``sqrt(diag(F^-1))`` is
the **Cramér-Rao bound of this segmented experiment**: the smallest std of any unbiased
estimator that does not use the continuity of the state across segment boundaries.
Continuity would add information; on a record replayed open loop through a gravity-loaded
arm the sensitivities grow without bound over a long record and no estimator we know
reaches that larger information, so the bound we state and the estimator we hold to it
are both the segmented ones (``L`` is printed with them).

Sensitivities
-------------
Along the simulated trajectory, ``dx/dt = f(x, tau, sigma)`` is linearised at each sample:
``F_k = df/dx`` (forward differences of the compiled forward dynamics) and
``G_k = df/dsigma = [0; -M^-1 Y_base(q, qd, qdd)]``; the sensitivities obey
``Z_{k+1} = Phi_k Z_k + Gamma_k`` with ``Phi_k = exp(T F)`` and ``Gamma_k = int_0^T
exp(s F) ds G``, ``F, G`` the means of the Jacobians at both ends of the sample (trapezoid;
fourth-order series of the exponential over ``T / 2^s`` and ``s`` doublings, so that a stiff
step, a light joint at a standstill under a steep smooth Coulomb law, contracts as it should).
Measured against finite differences through the
RK4 model: ~1e-3 relative where the dynamics are smooth,
but up to a few % of the sensitivities after a velocity reversal of a light joint, where
the smooth Coulomb law's slope ``fc / v_f`` over the joint's inertia reaches ~500 1/s; the
test holds them to finite differences through the RK4 model where the law is mild, and the
benchmark measures what is left as the ratio of the estimator's error to the bound). The
estimator's residuals use
the same RK4 model that simulates the records
(:func:`adaptive_dd.identification.model.rk4_step`); its optimum does not depend on
the Jacobian's approximation.

Estimator
---------
Levenberg-Marquardt on the normalised output errors, the segment states eliminated in
each step by the same Schur complement (as in bundle adjustment): the normal equations
have ``p + 2 n`` times the number of segments unknowns, but each state block touches one
segment only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.identification.model import Model, pi_from_sigma, rk4_step, state_jacobian

__all__ = [
    "OutputErrorResult",
    "cramer_rao_bound",
    "fit_output_error",
    "measurement_std",
    "schur_information",
    "segment_sensitivities",
    "simulate_segments",
]

Array = NDArray[np.float64]


def measurement_std(arm, quantize: bool = True) -> Array:
    """Noise std of ``[q_1..q_n, qd_1..qd_n]`` (encoder step ``Delta^2/12`` added to q), ``(2 n,)``."""
    var = np.concatenate([arm.sensor.position_variance, arm.sensor.velocity_variance]).astype(float)
    if quantize and arm.sensor.quantize:
        var[: arm.n_joints] += arm.sensor.resolution**2 / 12.0
    if np.any(var <= 0):
        raise ParameterError(f"the noise variances must be > 0 for a likelihood, got {var.tolist()}")
    return np.sqrt(var)


def _segments(x: Array, L: int) -> tuple[Array, int]:
    """(N, m) -> (nseg, L, m) with the tail that does not fill a segment dropped."""
    nseg = x.shape[0] // L
    if nseg < 1:
        raise SignalError(f"the record ({x.shape[0]} samples) is shorter than one segment of {L}")
    return x[: nseg * L].reshape(nseg, L, *x.shape[1:]), nseg


def simulate_segments(model: Model, pi: Array, x0: Array, tau: Array, T: float, substeps: int = 2) -> Array:
    """States ``(nseg, L, 2 n)`` from initial states ``x0 (nseg, 2 n)`` under ``tau (nseg, L, n)``."""
    n = model.n
    nseg, L = tau.shape[:2]
    xs = np.empty((nseg, L, 2 * n))
    q, qd = x0[:, :n].copy(), x0[:, n:].copy()
    for k in range(L):
        xs[:, k, :n], xs[:, k, n:] = q, qd
        if k + 1 < L:
            q, qd = rk4_step(model, pi, q, qd, tau[:, k], T, substeps)
    return xs


def _expm_terms(F: Array, T: float) -> tuple[Array, Array]:
    """``exp(T F)`` and ``int_0^T exp(sF) ds``, batch ``(..., m, m)``: their series to fourth order
    over ``T / 2^s``, then ``s`` doublings (``exp(2hF) = exp(hF)^2``, ``int_0^2h = (I + exp(hF))
    int_0^h``), ``s`` the fewest that bring ``|T F| / 2^s`` (the largest row sum over the batch)
    to 0.5. Unscaled, the series of a stiff step diverges: at ``T F = -16`` (a light joint's smooth
    Coulomb slope at a standstill) it gives 2161 for ``exp(-16)``."""
    m = F.shape[-1]
    eye = np.broadcast_to(np.eye(m), F.shape)
    norm = float(np.abs(T * F).sum(axis=-1).max()) if F.size else 0.0
    if not np.isfinite(norm):
        raise SignalError("the output error's sensitivities: the state's Jacobian is not finite")
    s = int(np.ceil(np.log2(norm / 0.5))) if norm > 0.5 else 0
    h = T / 2.0**s
    TF = h * F
    TF2 = TF @ TF
    TF3 = TF2 @ TF
    phi = eye + TF + TF2 / 2 + TF3 / 6 + TF3 @ TF / 24
    gam = h * (eye + TF / 2 + TF2 / 6 + TF3 / 24)
    for _ in range(s):
        gam = gam + phi @ gam
        phi = phi @ phi
    return phi, gam


def segment_sensitivities(
    model: Model, pi: Array, xs: Array, tau: Array, T: float, E: Array | None = None
) -> Array:
    """``d x_k / d [x_j, theta]`` along each segment, ``(nseg, L, 2 n, 2 n + r)`` (module docstring).

    ``E (p, r)``: the parameters are ``sigma = sigma0 + E theta`` (default the identity).
    """
    n = model.n
    nseg, L = xs.shape[:2]
    E = np.eye(model.p) if E is None else E
    r = E.shape[1]
    Z = np.zeros((nseg, L, 2 * n, 2 * n + r))
    Z[:, 0, :, : 2 * n] = np.eye(2 * n)
    F0, G0, _ = state_jacobian(model, pi, xs[:, 0, :n], xs[:, 0, n:], tau[:, 0])
    for k in range(L - 1):
        # the Jacobians at both ends of the sample under the torque held over it (trapezoid)
        F1, G1, _ = state_jacobian(model, pi, xs[:, k + 1, :n], xs[:, k + 1, n:], tau[:, k])
        phi, gam = _expm_terms(0.5 * (F0 + F1), T)
        Z[:, k + 1] = phi @ Z[:, k]
        Z[:, k + 1, :, 2 * n :] += gam @ (0.5 * (G0 + G1) @ E)
        if k + 1 < L - 1:
            F0, G0, _ = state_jacobian(model, pi, xs[:, k + 1, :n], xs[:, k + 1, n:], tau[:, k + 1])
    return Z


def schur_information(
    A: Array, C: Array, r: Array | None = None, damping: float = 0.0
) -> tuple[Array, Array | None, Array, Array]:
    """Information of theta with the segment states eliminated.

    Parameters
    ----------
    A : ndarray (nseg, R, m)
        Normalised residual Jacobian of each segment to theta.
    C : ndarray (nseg, R, s)
        ... to the segment's own state.
    r : ndarray (nseg, R), optional
        Residuals: then the reduced gradient is returned too.
    damping : float
        Levenberg-Marquardt factor on the diagonals of the state blocks.

    Returns
    -------
    S : ndarray (m, m)
        ``sum_j A_j^T A_j - W_j^T U_j^-1 W_j`` (the Fisher information when A, C are the
        sensitivities over the noise std).
    b : ndarray (m,) or None
        ``sum_j A_j^T r_j - W_j^T U_j^-1 C_j^T r_j``.
    U_inv : ndarray (nseg, s, s)
    W : ndarray (nseg, s, m)
        ``C_j^T A_j``.
    """
    U = np.einsum("jks,jkt->jst", C, C)
    if damping:
        U = U + damping * np.einsum("jss->js", U)[..., None] * np.eye(U.shape[-1])
    U_inv = np.linalg.inv(U)
    W = np.einsum("jks,jkm->jsm", C, A)
    m = A.shape[-1]
    Af = A.reshape(-1, m)
    S = Af.T @ Af - np.einsum("jsm,jst,jtl->ml", W, U_inv, W)
    b = None
    if r is not None:
        gc = np.einsum("jks,jk->js", C, r)
        b = Af.T @ r.reshape(-1) - np.einsum("jsm,jst,jt->m", W, U_inv, gc)
    return S, b, U_inv, W


def _jacobians(model, pi, xs, tau, T, E, w):
    n = model.n
    Z = segment_sensitivities(model, pi, xs, tau, T, E)
    Zw = -Z * w[None, None, :, None]  # d residual = -(d model output) / std
    nseg, L = xs.shape[:2]
    C = Zw[..., : 2 * n].reshape(nseg, L * 2 * n, 2 * n)
    A = Zw[..., 2 * n :].reshape(nseg, L * 2 * n, -1)
    return A, C


def cramer_rao_bound(
    model: Model,
    sigma: ArrayLike,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    std: ArrayLike,
    *,
    sample_period: float = 1e-3,
    segment_length: int = 200,
    substeps: int = 2,
    E: Array | None = None,
) -> tuple[Array, Array]:
    """Cramér-Rao bound of theta for one record (module docstring), the states at the segment starts given.

    Parameters
    ----------
    sigma : array_like (p,)
        Where the bound is evaluated (the truth, or an estimate).
    q, qd : array_like (N, n)
        States from which each segment starts (the true states; only the first of each
        segment is used, the rest is simulated).
    tau : array_like (N, n)
        Applied torque [N m].
    std : array_like (2 n,)
        Measurement noise std (:func:`measurement_std`).

    Returns
    -------
    crb_std : ndarray (r,)
        ``sqrt(diag(F^-1))``.
    information : ndarray (r, r)
        F.
    """
    pi = pi_from_sigma(model, sigma)
    x = np.concatenate([np.asarray(q, float), np.asarray(qd, float)], axis=1)
    tau_s, _ = _segments(np.asarray(tau, float), segment_length)
    xs0, _ = _segments(x, segment_length)
    xs = simulate_segments(model, pi, xs0[:, 0], tau_s, sample_period, substeps)
    A, C = _jacobians(model, pi, xs, tau_s, sample_period, E, 1.0 / np.asarray(std, float))
    S, _, _, _ = schur_information(A, C)
    cov = np.linalg.inv(S)
    return np.sqrt(np.abs(np.diag(cov))), S


@dataclass(frozen=True)
class OutputErrorResult:
    """Result of :func:`fit_output_error`.

    Attributes
    ----------
    sigma : ndarray (p,)
        Estimated base parameters (``sigma0 + E theta``).
    theta : ndarray (r,)
    std : ndarray (r,)
        Cramér-Rao bound of theta at the estimate (segment states unknown).
    information : ndarray (r, r)
    nodes : ndarray (nseg, 2 n)
        Estimated states at the segment starts.
    cost : float
        Half the sum of squared normalised residuals.
    n_residuals : int
    iterations : int
    converged : bool
    segment_length : int

    Examples
    --------
    Made by :func:`fit_output_error`, here on one second of a noisy record of the three-joint arm:

    >>> import numpy as np
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.identification.model import arm_model
    >>> from adaptive_dd.identification.output_error import fit_output_error, measurement_std
    >>> from adaptive_dd.identification.records import simulate_record
    >>> ref = {"joint1": {"offset": 0.3, "amplitude": [0.4], "frequency": [0.3]},
    ...        "joint2": {"offset": -0.6, "amplitude": [0.5], "frequency": [0.4]},
    ...        "joint3": {"offset": 0.4, "amplitude": [0.6], "frequency": [0.5]}}
    >>> sc = parse_scenario({"arm": {"robot": "vertical3"}, "reference": ref})
    >>> rec = simulate_record(sc.arm, sc.reference, 1.0, [np.random.default_rng(0)])
    >>> start = 1.05 * rec.sigma_true
    >>> fit = fit_output_error(arm_model(sc.arm), rec.q[0], rec.qd[0], rec.tau[0], start,
    ...                        measurement_std(sc.arm), max_iter=5)
    >>> fit.sigma.shape, fit.std.shape  # the arm's 17 base parameters and their bound
    ((17,), (17,))
    >>> fit.information.shape, fit.iterations <= 5  # Fisher information; LM iterations
    ((17, 17), True)
    """

    sigma: Array
    theta: Array
    std: Array
    information: Array
    nodes: Array
    cost: float
    n_residuals: int
    iterations: int
    converged: bool
    segment_length: int


def fit_output_error(
    model: Model,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    sigma0: ArrayLike,
    std: ArrayLike,
    *,
    sample_period: float = 1e-3,
    segment_length: int = 200,
    substeps: int = 2,
    E: Array | None = None,
    max_iter: int = 30,
    rtol: float = 1e-9,
) -> OutputErrorResult:
    """Output-error estimate from one record by Levenberg-Marquardt over segments (module docstring).

    Parameters
    ----------
    q, qd, tau : array_like (N, n)
        Measured positions [rad], velocities [rad/s] and the applied torque [N m].
    sigma0 : array_like (p,)
        Start (e.g. :func:`~adaptive_dd.identification.regression.weighted_least_squares`'s
        estimate); with ``E`` given, the fixed part ``sigma0`` and theta starts at 0.
    std : array_like (2 n,)
        Measurement noise std (:func:`measurement_std`).
    segment_length : int
        L, samples per segment (>= 2).
    E : ndarray (p, r), optional
        ``sigma = sigma0 + E theta``; default: all base parameters free.
    max_iter : int
        Most Levenberg-Marquardt iterations.
    rtol : float
        Stop when the cost decreases by less than this fraction.

    Returns
    -------
    OutputErrorResult
        The estimate, its Cramér-Rao bound, the fit's residuals and whether it converged.

    Examples
    --------
    One second of a noisy record of the three-joint arm, the fit started 5 % off the truth:

    >>> import numpy as np
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.identification.model import arm_model
    >>> from adaptive_dd.identification.output_error import fit_output_error, measurement_std
    >>> from adaptive_dd.identification.records import simulate_record
    >>> ref = {"joint1": {"offset": 0.3, "amplitude": [0.4], "frequency": [0.3]},
    ...        "joint2": {"offset": -0.6, "amplitude": [0.5], "frequency": [0.4]},
    ...        "joint3": {"offset": 0.4, "amplitude": [0.6], "frequency": [0.5]}}
    >>> sc = parse_scenario({"arm": {"robot": "vertical3"}, "reference": ref})
    >>> rec = simulate_record(sc.arm, sc.reference, 1.0, [np.random.default_rng(0)])
    >>> start = 1.05 * rec.sigma_true
    >>> fit = fit_output_error(arm_model(sc.arm), rec.q[0], rec.qd[0], rec.tau[0], start,
    ...                        measurement_std(sc.arm), max_iter=5)
    >>> fit.sigma.shape, fit.std.shape  # the arm's 17 base parameters and their bound
    ((17,), (17,))
    >>> bool(np.linalg.norm(fit.sigma - rec.sigma_true) < np.linalg.norm(start - rec.sigma_true))
    True
    """
    q, qd, tau = (np.asarray(a, dtype=float) for a in (q, qd, tau))
    if not (q.shape == qd.shape == tau.shape and q.ndim == 2 and q.shape[1] == model.n):
        raise SignalError(f"q, qd, tau must be (N, {model.n}), got {q.shape}, {qd.shape}, {tau.shape}")
    for name, a in (("q", q), ("qd", qd), ("tau", tau)):
        if not np.all(np.isfinite(a)):
            r, c = np.argwhere(~np.isfinite(a))[0]
            raise SignalError(
                f"{name} must be finite: {a[r, c]} at sample {r}, joint {c + 1} (leave such samples out of "
                "the record, or bridge them, before the fit)"
            )
    if segment_length < 2:
        raise ParameterError(f"segment_length must be >= 2, got {segment_length}")
    if np.shape(sigma0) != (model.p,):
        raise ParameterError(f"sigma0 must be ({model.p},) base parameters, got shape {np.shape(sigma0)}")
    s0, E, theta = _parametrisation(model, sigma0, E)
    w = 1.0 / np.asarray(std, dtype=float)
    if w.shape not in ((), (2 * model.n,)):
        raise ParameterError(
            f"std must be one number or ({2 * model.n},): q's then qd's per joint, got shape {w.shape}"
        )
    T, L = float(sample_period), int(segment_length)
    y, nseg = _segments(np.concatenate([q, qd], axis=1), L)
    tau_s, _ = _segments(tau, L)

    def residuals(th, x0):
        pi = pi_from_sigma(model, s0 + E @ th)
        xs = simulate_segments(model, pi, x0, tau_s, T, substeps)
        return pi, xs, ((y - xs) * w).reshape(nseg, -1)

    def jacobians(pi, xs):
        return _jacobians(model, pi, xs, tau_s, T, E, w)

    fit = _levenberg_marquardt(residuals, jacobians, theta, y[:, 0].copy(), max_iter, rtol)
    return _result(fit, s0, E, jacobians, L)


def _result(fit: _Fit, s0: Array, E: Array, jacobians, L: int) -> OutputErrorResult:
    """The estimate where the iterations stopped, with its Cramér-Rao bound (segment states unknown)."""
    S, _, _, _ = schur_information(*jacobians(fit.pi, fit.xs))
    std_theta = np.sqrt(np.abs(np.diag(np.linalg.inv(S))))
    return OutputErrorResult(
        sigma=s0 + E @ fit.theta,
        theta=fit.theta,
        std=std_theta,
        information=S,
        nodes=fit.nodes,
        cost=fit.cost,
        n_residuals=int(fit.r.size),
        iterations=fit.iterations,
        converged=fit.converged,
        segment_length=L,
    )


def _parametrisation(model: Model, sigma0: ArrayLike, E: Array | None) -> tuple[Array, Array, Array]:
    """``s0, E, theta`` with ``sigma = s0 + E theta`` and theta's start: ``sigma0`` itself with
    ``E`` the identity when no ``E`` is given (all base parameters free), else 0."""
    s0 = np.asarray(sigma0, dtype=float)
    if E is None:  # all base parameters free: theta is sigma itself
        return np.zeros(model.p), np.eye(model.p), s0.copy()
    return s0, np.asarray(E, dtype=float), np.zeros(np.shape(E)[1])


class _Fit(NamedTuple):
    """Where :func:`_levenberg_marquardt` stopped: the estimate, its simulation and residuals."""

    theta: Array
    nodes: Array
    pi: Array
    xs: Array
    r: Array
    cost: float
    iterations: int
    converged: bool


def _levenberg_marquardt(
    residuals, jacobians, theta: Array, nodes: Array, max_iter: int, rtol: float
) -> _Fit:
    """Levenberg-Marquardt over theta and the segment-start states ``nodes``.

    ``residuals(theta, nodes) -> (pi, xs, r)`` simulates the segments and returns the
    normalised residuals ``r (nseg, L 2n)``; ``jacobians(pi, xs) -> (A, C)`` their derivatives
    in theta and in the nodes. Converged when no step lowers the cost or the cost decreases
    by less than the fraction ``rtol``.
    """
    pi, xs, r = residuals(theta, nodes)
    cost = 0.5 * float(np.sum(r**2))
    lam, it, converged = 1e-3, 0, False
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        A, C = jacobians(pi, xs)
        d_th, d_x, trial, new_cost, lam = _damped_step(residuals, A, C, r, theta, nodes, cost, lam)
        if trial is None or not np.isfinite(new_cost) or new_cost > cost:
            converged = True  # no step lowers the cost: a minimum to machine precision
            break
        decrease = (cost - new_cost) / max(cost, 1e-300)
        theta, nodes = theta + d_th, nodes + d_x
        pi, xs, r = trial
        cost = new_cost
        lam = max(lam / 10.0, 1e-9)
        if decrease < rtol:
            converged = True
            break
    return _Fit(theta, nodes, pi, xs, r, cost, it, converged)


def _damped_step(
    residuals, A: Array, C: Array, r: Array, theta: Array, nodes: Array, cost: float, lam: float
):
    """One Levenberg-Marquardt step from ``(theta, nodes)``: the damping ``lam`` grows tenfold
    (up to 1e10) until the step lowers ``cost``; the node increments are eliminated through
    the Schur complement (:func:`schur_information`).

    Returns ``d_theta, d_nodes``, the trial's ``residuals(...)`` (None where the simulation
    failed), its cost (inf where it failed) and the damping used.
    """
    while True:
        S, b, U_inv, W = schur_information(A, C, r, damping=lam)
        Sd = S + lam * np.diag(np.diag(S))
        d_th = -np.linalg.solve(Sd, b)
        gc = np.einsum("jks,jk->js", C, r)
        d_x = -np.einsum("jst,jt->js", U_inv, gc + np.einsum("jsm,m->js", W, d_th))
        try:
            trial = residuals(theta + d_th, nodes + d_x)
        except (SignalError, ParameterError):
            trial = None
        new_cost = np.inf if trial is None else 0.5 * float(np.sum(trial[2] ** 2))
        if new_cost <= cost:
            break
        lam *= 10.0
        if lam > 1e10:
            break
    return d_th, d_x, trial, new_cost, lam
