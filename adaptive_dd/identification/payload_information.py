"""How fast a payload's mass can be known after a swap: a Cramér-Rao bound along a trajectory.

The model (the payload regression of :mod:`~adaptive_dd.identification.online`,
arm known, payload's ten parameters ``theta`` unknown)::

    y_k = Phi_k theta + e_k,     Phi_k = body_regressor(q_k, qd_k, qdd_k; link jp) @ payload_map

with the regressor at the true (oracle) state, and ``e_k`` the equation error that the
sensor noise causes through the M2 filters (eq. 20) of the estimator. Linearising the
inverse dynamics about the true state, with white position noise ``nu_q`` and velocity
noise ``nu_v`` (variances per joint, as :class:`~adaptive_dd.plant.devices.SensorConfig`)::

    e_k = - M_k (G1 nu_v) - D_qd,k (G0 nu_v) - D_q,k (G0 nu_q)

where ``M`` is the mass matrix (armature included) and ``D_q, D_qd`` the partial
derivatives of the inverse dynamics (viscous friction included; Coulomb friction's
derivative is zero away from zero speed, and the estimator does not use equations near
it). The filtered noises' per-sample covariance is ``sigma^2 Gamma`` with ``Gamma`` the
2 x 2 Gram matrix of the impulse responses of G0 and G1, so::

    R_k = sum_j sigma_v,j^2 [M e_j, D_qd e_j] Gamma [M e_j, D_qd e_j]^T
          + sigma_q,j^2 Gamma_00 D_q e_j e_j^T D_q^T                           (n x n)

Two noise models:

``"colored"`` (default)
    The filtered noise is correlated over about the filter's memory: the covariance of
    the stacked errors of the first ``window`` samples after the swap is built from the
    cross-correlations of the impulse responses of G0 and G1 (the noise that entered
    before the swap included), ``Sigma = L L^T`` (Cholesky), and the information after
    t samples is that of the first t whitened blocks ``L^-1 Phi`` (the whitening is
    causal, so one factorisation gives the whole curve). Exact for the linearised model.
``"white"``
    Each sample's error independent with the covariance ``R_k`` above: cheap for long
    records, but the derivative filter's output is strongly correlated from sample to
    sample (with a negative correlation at short lags: it can understate or overstate
    the information; on a UR5 record of the tests, 5 %: 9 ms white, 7 ms colored; 1 %:
    18 ms white, 25 ms colored).

**Approximations (documented):** the regressor is evaluated at the true state, not at
the filtered one, and the regression is taken to hold from the swap on (the filtered
equations that span the swap are not modelled: the bound is optimistic there); the
arm's parameters are exact; the sensor noise is white and Gaussian (encoder
quantisation ignored). The Fisher information ``F(t)`` of the ten payload parameters
gives the bound on the mass ``var(m) >= 1 / (F_mm - F_mr F_rr^+ F_rm)`` (the other nine
unknown; the pseudo-inverse drops directions the motion does not excite). The bound on the
centre of mass ``c = h / m`` (``h`` the first moments) is the delta method's,
``cov(c) >= J C_mh J^T`` with ``C_mh`` the (m, h) block of ``F^+`` and ``J = [-h/m^2, I/m]``;
:func:`payload_com_information_time` reports when ``sqrt(tr cov(c))`` falls below a tolerance.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve_triangular

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.identification.filters import design_filter_bank, filter_record
from adaptive_dd.plant.arm import Arm
from adaptive_dd.plant.chain import mass_matrix_batch, regressor_batch, rnea_batch

__all__ = [
    "filter_noise_gram",
    "payload_com_bound",
    "payload_com_information_time",
    "payload_information_time",
    "payload_information_times",
    "payload_mass_bound",
    "payload_mass_bound_colored",
    "payload_regression_covariance",
    "payload_regression_noise",
]

Array = NDArray[np.float64]


@lru_cache(maxsize=16)
def _impulse(tau_f: float, sample_period: float) -> Array:
    bank = design_filter_bank("M2", tau_f, sample_period)
    L = int(np.ceil(40 * tau_f / sample_period)) + 10
    imp = np.zeros(L)
    imp[0] = 1.0
    h = filter_record(bank, imp)  # (L, 2): impulse responses of G0, G1
    h.setflags(write=False)
    return h


def filter_noise_gram(tau_f: float, sample_period: float) -> Array:
    """``Gamma (2, 2)``: covariance of ``[G0 nu, G1 nu]`` per unit variance of white ``nu``."""
    h = _impulse(tau_f, sample_period)
    return h.T @ h


def _states(arm: Arm, q, qd, qdd) -> tuple[Array, Array, Array]:
    q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
    n = arm.n_joints
    if q.ndim != 2 or q.shape[1] != n or qd.shape != q.shape or qdd.shape != q.shape:
        raise SignalError(
            f"q, qd, qdd must share a shape (n_samples, {n}), got {q.shape}, {qd.shape}, {qdd.shape}"
        )
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(qdd))):
        raise SignalError("q, qd, qdd must be finite (an oracle trajectory)")
    return q, qd, qdd


def _variances(arm: Arm, position_variance, velocity_variance) -> tuple[Array, Array]:
    n = arm.n_joints
    sq = np.asarray(arm.sensor.position_variance if position_variance is None else position_variance, float)
    sv = np.asarray(arm.sensor.velocity_variance if velocity_variance is None else velocity_variance, float)
    if sq.shape != (n,) or sv.shape != (n,) or np.any(sq < 0) or np.any(sv < 0):
        raise ParameterError(f"noise variances must be {n} values >= 0, got {sq}, {sv}")
    return sq, sv


def _linearisation(arm: Arm, q, qd, qdd, payload) -> tuple[Array, Array, Array, Array]:
    """``Phi (N, n, 10)``, ``M (N, n, n)`` with armature, ``D_qd``, ``D_q (N, n, n)`` at the true state."""
    pay = np.asarray(payload, dtype=float)
    if pay.shape != (10,) or not np.all(np.isfinite(pay)):
        raise ParameterError(f"payload must be 10 finite parameters, got {payload!r}")
    N, n = q.shape
    ch, j = arm.chain, arm.payload_joint
    pi = arm.pi_links.copy()
    pi[10 * j : 10 * j + 10] += arm.payload_map @ pay
    M = mass_matrix_batch(ch, pi, q) + np.diag(arm.armature)
    h = 1e-6
    Dq = np.empty((N, n, n))
    Dv = np.empty((N, n, n))
    for k in range(n):
        e = np.zeros(n)
        e[k] = h
        Dq[:, :, k] = (rnea_batch(ch, pi, q + e, qd, qdd) - rnea_batch(ch, pi, q - e, qd, qdd)) / (2 * h)
        Dv[:, :, k] = (rnea_batch(ch, pi, q, qd + e, qdd) - rnea_batch(ch, pi, q, qd - e, qdd)) / (2 * h)
    Dv += np.diag(arm.viscous)
    Phi = regressor_batch(ch, q, qd, qdd)[:, :, 10 * j : 10 * j + 10] @ arm.payload_map
    return Phi, M, Dv, Dq


def payload_regression_noise(
    arm: Arm,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    payload: ArrayLike,
    *,
    sample_period: float,
    tau_f: float = 0.01,
    position_variance: ArrayLike | None = None,
    velocity_variance: ArrayLike | None = None,
) -> tuple[Array, Array]:
    """The payload regression's ``Phi (N, n, 10)`` and per-sample error covariance ``R (N, n, n)``.

    Parameters
    ----------
    arm : Arm
    q, qd, qdd : (N, n)
        The true trajectory [rad, rad/s, rad/s^2].
    payload : (10,)
        The true payload about its frame (it enters ``M`` and the derivatives).
    sample_period, tau_f : float
        [s]: the estimator's sample period and M2 filter constant.
    position_variance, velocity_variance : (n,), optional
        Sensor noise variances [rad^2, (rad/s)^2] (default ``arm.sensor``'s).
    """
    q, qd, qdd = _states(arm, q, qd, qdd)
    sq, sv = _variances(arm, position_variance, velocity_variance)
    Phi, M, Dv, Dq = _linearisation(arm, q, qd, qdd, payload)
    G = filter_noise_gram(tau_f, sample_period)
    Gs = G[[1, 0]][:, [1, 0]]  # order (G1, G0), as A's columns
    R = np.zeros(M.shape)
    for k in range(arm.n_joints):
        A = np.stack([M[:, :, k], Dv[:, :, k]], axis=-1)  # (N, n, 2): [G1 nu_v, G0 nu_v] -> torque
        R += sv[k] * np.einsum("nia,ab,njb->nij", A, Gs, A)
        R += sq[k] * G[0, 0] * Dq[:, :, k, None] * Dq[:, None, :, k]
    return Phi, R


def _white_information(Phi: ArrayLike, R: ArrayLike) -> Array:
    """Cumulative Fisher information ``(N, 10, 10)`` of independent samples ``Phi (N, n, 10)``
    with error covariances ``R (N, n, n)``."""
    Phi, R = np.asarray(Phi, dtype=float), np.asarray(R, dtype=float)
    reg = 1e-12 * np.maximum(np.trace(R, axis1=1, axis2=2), 1e-300)[:, None, None] * np.eye(R.shape[1])
    return np.cumsum(np.einsum("nia,nij,njb->nab", Phi, np.linalg.inv(R + reg), Phi), axis=0)


def _colored_information(Phi: ArrayLike, S: ArrayLike) -> Array:
    """Cumulative Fisher information ``(K, 10, 10)`` of ``Phi (K, n, 10)`` with the joint error
    covariance ``S (K, n, K, n)``: whitened by S's Cholesky factor (causal, so the first t blocks
    carry the first t samples' information)."""
    Phi, S = np.asarray(Phi, dtype=float), np.asarray(S, dtype=float)
    K, n = Phi.shape[:2]
    S = S.reshape(K * n, K * n)
    S = S + 1e-12 * np.trace(S) / (K * n) * np.eye(K * n)
    X = solve_triangular(np.linalg.cholesky(S), Phi.reshape(K * n, 10), lower=True).reshape(K, n, 10)
    return np.cumsum(np.einsum("kia,kib->kab", X, X), axis=0)


def _schur_std(F: Array, rcond: float = 1e-10) -> Array:
    """Bound on the mass's standard deviation from cumulative Fisher informations ``F (N, 10, 10)``."""
    Frr_pinv = np.linalg.pinv(F[:, 1:, 1:], rcond=rcond, hermitian=True)
    schur = F[:, 0, 0] - np.einsum("na,nab,nb->n", F[:, 0, 1:], Frr_pinv, F[:, 1:, 0])
    ok = schur > 1e-12 * np.maximum(F[:, 0, 0], 1e-300)
    return np.where(ok, 1.0 / np.sqrt(np.where(ok, schur, 1.0)), np.inf)


def payload_mass_bound(Phi: ArrayLike, R: ArrayLike) -> Array:
    """White-noise model: Cramér-Rao standard deviation [kg] of the mass after each sample, ``(N,)``.

    ``Phi (N, n, 10)``, ``R (N, n, n)``: the samples from the swap on
    (:func:`payload_regression_noise`); inf while the mass is not determined.
    """
    return _schur_std(_white_information(Phi, R))


def _com_std(F: Array, payload: Array, axes=None, rcond: float = 1e-10) -> Array:
    """Bound on the centre of mass's error [m] (``sqrt`` of the trace of its covariance over
    ``axes``, a (3,) mask, default all) from cumulative Fisher informations ``F (N, 10, 10)``
    about ``payload (10,)``; inf while the mass or those first moments are not determined."""
    m, h = payload[0], payload[1:4]
    ax = np.ones(3, bool) if axes is None else np.asarray(axes, bool)
    J = np.hstack([-h[:, None] / m**2, np.eye(3) / m])[ax]  # d(h/m) / d(m, h)
    C = np.linalg.pinv(F, rcond=rcond, hermitian=True)
    var = np.einsum("ia,nab,ib->n", J, C[:, :4, :4], J)
    # a direction the pseudo-inverse dropped carries no information, not a bound of zero: m and
    # the h's asked for are determined when their unit vectors lie in F's range (F F^+ keeps them)
    cols = np.flatnonzero(np.r_[True, ax])
    proj = np.einsum("nab,nbc->nac", F, C)[:, :, cols]
    ok = np.all(np.abs(proj - np.eye(10)[:, cols]) < 1e-6, axis=(1, 2))
    return np.where(ok, np.sqrt(np.maximum(var, 0.0)), np.inf)


def payload_com_bound(Phi: ArrayLike, R: ArrayLike, payload: ArrayLike) -> Array:
    """White-noise model: Cramér-Rao bound [m] on the centre of mass's error after each sample, ``(N,)``.

    ``sqrt(tr cov(c))`` by the delta method (module docstring); ``Phi (N, n, 10)``,
    ``R (N, n, n)`` as :func:`payload_mass_bound`, ``payload (10,)`` the true payload.
    """
    return _com_std(_white_information(Phi, R), np.asarray(payload, dtype=float))


def payload_regression_covariance(
    arm: Arm,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    payload: ArrayLike,
    *,
    sample_period: float,
    tau_f: float = 0.01,
    position_variance: ArrayLike | None = None,
    velocity_variance: ArrayLike | None = None,
) -> tuple[Array, Array]:
    """``Phi (K, n, 10)`` and the joint covariance ``S (K, n, K, n)`` of the errors of K samples.

    ``S[k, :, l, :] = E[e_k e_l^T]`` under the colored model (module docstring); the
    diagonal blocks equal :func:`payload_regression_noise`'s ``R``. Keep K in the hundreds.
    """
    q, qd, qdd = _states(arm, q, qd, qdd)
    sq, sv = _variances(arm, position_variance, velocity_variance)
    Phi, M, Dv, Dq = _linearisation(arm, q, qd, qdd, payload)
    K = q.shape[0]
    h = _impulse(tau_f, sample_period)  # (L, 2): G0, G1
    L = h.shape[0]
    # c[d, a, b] = E[(h_a * nu)_k (h_b * nu)_{k-d}] = sum_m h_a[m + d] h_b[m], d = k - l >= 0
    c = np.zeros((K, 2, 2))
    for d in range(min(K, L)):
        c[d] = h[d:].T @ h[: L - d]
    lag = np.arange(K)[:, None] - np.arange(K)[None, :]
    C = np.where((lag >= 0)[..., None, None], c[np.abs(lag)], np.swapaxes(c[np.abs(lag)], -1, -2))
    Cv = C[..., [1, 0], :][..., :, [1, 0]]  # (K, K, 2, 2) in the order (G1, G0)
    A = np.stack([M, Dv], axis=-1)  # (K, n, n_j, 2)
    S = np.einsum("j,kijb,klbc,lmjc->kilm", sv, A, Cv, A, optimize=True)
    S += np.einsum("j,kij,kl,lmj->kilm", sq, Dq, C[..., 0, 0], Dq, optimize=True)
    return Phi, S


def payload_mass_bound_colored(Phi: ArrayLike, S: ArrayLike) -> Array:
    """Colored-noise model: Cramér-Rao standard deviation [kg] of the mass after each sample, ``(K,)``.

    ``Phi (K, n, 10)``, ``S (K, n, K, n)`` (:func:`payload_regression_covariance`). The
    whitening by the Cholesky factor of S is causal, so the first t blocks of
    ``L^-1 Phi`` carry the information of the first t samples.
    """
    return _schur_std(_colored_information(Phi, S))


def _check(payload, tol, model, window) -> Array:
    pay = np.asarray(payload, dtype=float)
    if pay.shape != (10,) or not pay[0] > 0:
        raise ParameterError(f"payload must be 10 parameters with a mass > 0, got {payload!r}")
    if not (isinstance(tol, int | float) and tol > 0):
        raise ParameterError(f"tol must be a number > 0, got {tol!r}")
    if model not in ("colored", "white"):
        raise ParameterError(f"model must be 'colored' or 'white', got {model!r}")
    if not isinstance(window, int | np.integer) or window < 1:
        raise ParameterError(f"window must be an integer >= 1, got {window!r}")
    return pay


def _information(arm, q, qd, qdd, pay, swap_sample, model, window, **kw) -> Array:
    """Cumulative Fisher information ``(K, 10, 10)`` of the payload from the swap on; ``kw``: the
    sensor settings of :func:`payload_regression_noise`."""
    q, qd, qdd = _states(arm, q, qd, qdd)
    if not 0 <= swap_sample < q.shape[0]:
        raise ParameterError(f"swap_sample must be in [0, {q.shape[0]}), got {swap_sample!r}")
    end = q.shape[0] if model == "white" else min(q.shape[0], swap_sample + window)
    s = slice(swap_sample, end)
    if model == "white":
        return _white_information(*payload_regression_noise(arm, q[s], qd[s], qdd[s], pay, **kw))
    return _colored_information(*payload_regression_covariance(arm, q[s], qd[s], qdd[s], pay, **kw))


def _first_time(std: Array, bound: float, sample_period: float) -> float:
    """Seconds after the swap at which ``std`` (one per sample from the swap on) is first within ``bound``."""
    hit = np.flatnonzero(std <= bound)
    return float((hit[0] + 1) * sample_period) if len(hit) else float("inf")


def payload_information_time(
    arm: Arm,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    payload: ArrayLike,
    swap_sample: int,
    *,
    sample_period: float,
    tau_f: float = 0.01,
    position_variance: ArrayLike | None = None,
    velocity_variance: ArrayLike | None = None,
    tol: float = 0.05,
    model: str = "colored",
    window: int = 300,
) -> float:
    """Seconds after a swap at which the Cramér-Rao bound on the payload's mass falls below ``tol`` of it.

    The information limit of a payload-swap benchmark: no unbiased estimator working from
    the M2-filtered regression of the same sensors (under the model of the module
    docstring) can know the new mass to ``tol`` sooner. ``inf`` if not reached within the
    record (``"white"``) or within ``window`` samples (``"colored"``).

    Parameters
    ----------
    arm : Arm
    q, qd, qdd : (N, n)
        The oracle trajectory of the whole record [rad, rad/s, rad/s^2].
    payload : (10,)
        The payload after the swap, about its frame (its mass ``payload[0] > 0``).
    swap_sample : int
        First sample with the new payload.
    sample_period, tau_f : float
        [s].
    position_variance, velocity_variance : (n,), optional
        Sensor noise variances (default ``arm.sensor``'s).
    tol : float
        Relative standard deviation of the mass to reach, in (0, 1).
    model : {"colored", "white"}
        Noise model (module docstring).
    window : int
        Samples after the swap the colored model considers (its cost grows as ``window^3``).

    Returns
    -------
    float
        Seconds after the swap; ``inf`` if not reached.

    Examples
    --------
    The vertical three-joint arm picking up 1 kg at 0.4 s of a sine it tracks exactly (an
    oracle's trajectory is close to its reference):

    >>> import numpy as np
    >>> from adaptive_dd.identification.payload_information import payload_information_time
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> arm = Arm.from_urdf(robot_urdf("vertical3"))
    >>> T = 1e-3
    >>> t = np.arange(0.0, 0.8, T)[:, None]
    >>> q = 0.8 * np.sin([1.1, 1.7, 2.3] * t) + 0.4 * np.sin([3.1, 4.3, 5.9] * t)
    >>> qd = np.gradient(q, T, axis=0)
    >>> qdd = np.gradient(qd, T, axis=0)
    >>> payload = np.zeros(10)
    >>> payload[0] = 1.0  # 1 kg at the payload frame's origin
    >>> payload_information_time(arm, q, qd, qdd, payload, 400, sample_period=T)  # [s]
    0.04
    >>> round(payload_information_time(arm, q, qd, qdd, payload, 400, sample_period=T, tol=0.01), 3)
    0.071
    """
    pay = _check(payload, tol, model, window)
    if not 0 < tol < 1:
        raise ParameterError(f"tol must be in (0, 1), got {tol!r}")
    info = _information(
        arm, q, qd, qdd, pay, swap_sample, model, window, sample_period=sample_period, tau_f=tau_f,
        position_variance=position_variance, velocity_variance=velocity_variance,
    )  # fmt: skip
    return _first_time(_schur_std(info), tol * pay[0], sample_period)


def payload_com_information_time(
    arm: Arm,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    payload: ArrayLike,
    swap_sample: int,
    *,
    sample_period: float,
    tau_f: float = 0.01,
    position_variance: ArrayLike | None = None,
    velocity_variance: ArrayLike | None = None,
    tol: float = 0.01,
    model: str = "colored",
    window: int = 300,
    axes: ArrayLike | None = None,
) -> float:
    """Seconds after a swap at which the Cramér-Rao bound on the payload's centre of mass
    (``sqrt(tr cov(c))``, delta method) falls below ``tol`` [m].

    As :func:`payload_information_time` (same arguments, same model), for the centre of mass
    instead of the mass; ``tol`` is in metres (default 1 cm). ``axes``: a (3,) mask of the
    components to judge (default all; a planar arm sees only the in-plane ones,
    ``arm.payload_identifiable[1:4]``). ``inf`` if not reached.
    """
    pay = _check(payload, tol, model, window)
    info = _information(
        arm, q, qd, qdd, pay, swap_sample, model, window, sample_period=sample_period, tau_f=tau_f,
        position_variance=position_variance, velocity_variance=velocity_variance,
    )  # fmt: skip
    return _first_time(_com_std(info, pay, axes), tol, sample_period)


def payload_information_times(
    arm: Arm,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    payload: ArrayLike,
    swap_sample: int,
    *,
    sample_period: float,
    tau_f: float = 0.01,
    position_variance: ArrayLike | None = None,
    velocity_variance: ArrayLike | None = None,
    mass_tol: float = 0.05,
    com_tol: float = 0.01,
    model: str = "colored",
    window: int = 300,
    axes: ArrayLike | None = None,
) -> tuple[float, float]:
    """``(mass time, centre-of-mass time)`` [s] from one Fisher information: what
    :func:`payload_information_time` (``tol=mass_tol``) and :func:`payload_com_information_time`
    (``tol=com_tol``) return, at the cost of one (the colored model's Cholesky factor dominates)."""
    pay = _check(payload, com_tol, model, window)
    if not 0 < mass_tol < 1:
        raise ParameterError(f"mass_tol must be in (0, 1), got {mass_tol!r}")
    info = _information(
        arm, q, qd, qdd, pay, swap_sample, model, window, sample_period=sample_period, tau_f=tau_f,
        position_variance=position_variance, velocity_variance=velocity_variance,
    )  # fmt: skip
    mass = _first_time(_schur_std(info), mass_tol * pay[0], sample_period)
    return mass, _first_time(_com_std(info, pay, axes), com_tol, sample_period)
