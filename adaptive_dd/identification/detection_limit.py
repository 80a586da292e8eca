"""The detection limit of a payload swap on an N-joint arm: when an optimal test could know it.

The N-joint counterpart of :mod:`~adaptive_dd.identification.two_link_detection_limit` (same test,
same threshold): the generalized likelihood ratio (GLR) of a change of the payload, the arm
known, on the measurements of ``q`` and ``qd`` after the swap, the applied torques known. The
payload changes from ``before`` to ``after`` (ten parameters each, about the payload frame);
the test is on the scale ``s`` of that change, ``theta(s) = before + s (after - before)``
(``s = 1`` true). With a known onset its statistic has the non-centrality

    lambda(t) = sum_{k = k_s + 1}^{t} S_k^T R^-1 S_k,     S_k = d x_k / d s,

``x = (q, qd)`` the state, ``R = diag(position variances, velocity variances)``. ``S`` follows
the discrete dynamics linearised along the recorded trajectory::

    S_{k+1} = F_k S_k + G_k,    F_k = d Phi / d x,  G_k = d Phi / d s,  S_{k_s} = 0,

with ``Phi`` one sample of the arm's dynamics under the recorded torque (RK4 substeps over
:func:`~adaptive_dd.plant.chain_dynamics.forward_dynamics`, armature and viscous and Coulomb friction,
the sign of each joint's speed held over the sample), ``F, G`` by central differences. The GLR
detects with probability ``prob`` once ``sqrt(lambda) >= z_(1 - alpha / 2) + z_prob``,
``alpha = rate / n_tests`` (:func:`~adaptive_dd.identification.two_link_detection_limit.detection_threshold`).

**What it leaves out** (the limit is, if anything, early): the state at the swap is taken as
known (its measurement noise is ignored), and so is the rest of the arm; the plant's
stick-slip friction is replaced by friction with the recorded sign. The on-line detector also
meets friction its model lacks, does not know the onset and works on filtered equations.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.two_link_detection_limit import detection_threshold
from adaptive_dd.plant.chain import forward_dynamics

__all__ = ["detection_limit", "detection_sensitivity"]


@njit(cache=True)
def _accel(ch, pi, arm_f, q, qd, tau, sgn, out):  # pragma: no cover - compiled
    """Joint accelerations under ``tau`` less viscous and Coulomb friction (sign ``sgn`` held)."""
    n = q.shape[0]
    t = np.empty(n)
    for j in range(n):
        t[j] = tau[j] - arm_f[1, j] * qd[j] - arm_f[2, j] * sgn[j]
    return forward_dynamics(ch, pi, arm_f[0], q, qd, t, out)


@njit(cache=True)
def _stage(ch, pi, arm_f, y, src, scale, tau, sgn, tmp, acc, dst):  # pragma: no cover - compiled
    """One RK4 stage: ``dst = f(y + scale * src)``."""
    n = tau.shape[0]
    for a in range(2 * n):
        tmp[a] = y[a] + scale * src[a]
    _accel(ch, pi, arm_f, tmp[:n], tmp[n:], tau, sgn, acc)
    for j in range(n):
        dst[j] = tmp[n + j]
        dst[n + j] = acc[j]


@njit(cache=True)
def _phi(ch, pi, arm_f, x, tau, sgn, T, substeps, out):  # pragma: no cover - compiled
    """One sample of the dynamics, state ``x = (q, qd)`` (2 n,), RK4 with ``substeps``."""
    n = tau.shape[0]
    h = T / substeps
    y = x.copy()
    k1, k2, k3, k4 = np.empty(2 * n), np.empty(2 * n), np.empty(2 * n), np.empty(2 * n)
    tmp = np.empty(2 * n)
    acc = np.empty(n)
    for _ in range(substeps):
        _stage(ch, pi, arm_f, y, y, 0.0, tau, sgn, tmp, acc, k1)
        _stage(ch, pi, arm_f, y, k1, 0.5 * h, tau, sgn, tmp, acc, k2)
        _stage(ch, pi, arm_f, y, k2, 0.5 * h, tau, sgn, tmp, acc, k3)
        _stage(ch, pi, arm_f, y, k3, h, tau, sgn, tmp, acc, k4)
        for a in range(2 * n):
            y[a] += h / 6.0 * (k1[a] + 2.0 * k2[a] + 2.0 * k3[a] + k4[a])
    for a in range(2 * n):
        out[a] = y[a]


@njit(cache=True)
def _sensitivity(ch, pi_b, dpi, arm_f, q, qd, tau, T, substeps, wq, wv, need, eps):  # pragma: no cover
    """``S_k`` (N, 2 n) from sample 0 (the swap, S = 0) on, and the first k with
    ``sqrt(lambda_k) >= need`` (-1 if none; ``need <= 0``: run the whole record)."""
    N, n = q.shape
    S = np.zeros((N, 2 * n))
    x, xp, xm = np.empty(2 * n), np.empty(2 * n), np.empty(2 * n)
    fp, fm = np.empty(2 * n), np.empty(2 * n)
    F = np.empty((2 * n, 2 * n))
    G = np.empty(2 * n)
    sgn = np.empty(n)
    pi1 = pi_b + dpi
    pp, pm = pi_b + (1.0 + eps) * dpi, pi_b + (1.0 - eps) * dpi
    info = 0.0
    for k in range(N - 1):
        for j in range(n):
            x[j], x[n + j] = q[k, j], qd[k, j]
            sgn[j] = np.sign(qd[k, j])
        for a in range(2 * n):
            d = eps * max(1.0, abs(x[a]))
            for b in range(2 * n):
                xp[b] = x[b]
                xm[b] = x[b]
            xp[a] += d
            xm[a] -= d
            _phi(ch, pi1, arm_f, xp, tau[k], sgn, T, substeps, fp)
            _phi(ch, pi1, arm_f, xm, tau[k], sgn, T, substeps, fm)
            for b in range(2 * n):
                F[b, a] = (fp[b] - fm[b]) / (2.0 * d)
        _phi(ch, pp, arm_f, x, tau[k], sgn, T, substeps, fp)
        _phi(ch, pm, arm_f, x, tau[k], sgn, T, substeps, fm)
        for b in range(2 * n):
            G[b] = (fp[b] - fm[b]) / (2.0 * eps)
        for b in range(2 * n):
            acc = G[b]
            for a in range(2 * n):
                acc += F[b, a] * S[k, a]
            S[k + 1, b] = acc
        for j in range(n):
            info += wq[j] * S[k + 1, j] ** 2 + wv[j] * S[k + 1, n + j] ** 2
        if need > 0.0 and np.sqrt(info) >= need:
            return S[: k + 2], k + 1
    return S, -1


def _inputs(arm, q, qd, tau, k_swap, before, after, position_variance, velocity_variance):
    q, qd, tau = (np.ascontiguousarray(x, dtype=float) for x in (q, qd, tau))
    n = arm.n_joints
    N = q.shape[0]
    if q.ndim != 2 or q.shape[1] != n or qd.shape != q.shape or tau.shape != q.shape:
        raise ParameterError(f"q, qd, tau must be (N, {n}) each, got {q.shape}, {qd.shape}, {tau.shape}")
    if not (isinstance(k_swap, int | np.integer) and 0 <= k_swap < N - 1):
        raise ParameterError(f"k_swap must lie in [0, {N - 2}] for a record of {N} samples, got {k_swap!r}")
    for name, x in (("q", q), ("qd", qd), ("tau", tau)):
        if not np.all(np.isfinite(x[k_swap:])):
            raise ParameterError(f"{name} holds non-finite values after the swap (sample >= {k_swap})")
    b, a = (np.asarray(x, dtype=float) for x in (before, after))
    if b.shape != (10,) or a.shape != (10,) or not (np.all(np.isfinite(b)) and np.all(np.isfinite(a))):
        raise ParameterError(
            f"before and after must be 10 finite payload parameters, got {b.shape}, {a.shape}"
        )
    if np.array_equal(a, b):
        raise ParameterError("before and after are the same payload: there is no change to detect")
    pv = arm.sensor.position_variance if position_variance is None else position_variance
    vv = arm.sensor.velocity_variance if velocity_variance is None else velocity_variance
    pv, vv = (np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy() for v in (pv, vv))
    if not (np.all(pv > 0) and np.all(vv > 0) and np.all(np.isfinite(pv)) and np.all(np.isfinite(vv))):
        raise ParameterError(f"noise variances must be {n} finite values > 0 each, got {pv}, {vv}")
    jp = arm.payload_joint
    pi_b = np.ascontiguousarray(arm.pi_links, dtype=float).copy()
    pi_b[10 * jp : 10 * jp + 10] += arm.payload_map @ b
    dpi = np.zeros_like(pi_b)
    dpi[10 * jp : 10 * jp + 10] = arm.payload_map @ (a - b)
    arm_f = np.ascontiguousarray(np.stack([arm.armature, arm.viscous, arm.coulomb]), dtype=float)
    sl = slice(k_swap, None)
    return q[sl], qd[sl], tau[sl], pi_b, dpi, arm_f, 1.0 / pv, 1.0 / vv


def detection_sensitivity(
    arm,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    k_swap: int,
    sample_period: float,
    before: ArrayLike,
    after: ArrayLike,
    substeps: int = 2,
) -> np.ndarray:
    """``S_k = d x_k / d s`` (N - k_swap, 2 n) from the swap on (module docstring): how the
    state ``(q, qd)`` would move per unit of the payload change, along the recorded trajectory."""
    q, qd, tau, pi_b, dpi, arm_f, wq, wv = _inputs(arm, q, qd, tau, k_swap, before, after, None, None)
    S, _ = _sensitivity(
        arm.chain, pi_b, dpi, arm_f, q, qd, tau, float(sample_period), int(substeps), wq, wv, -1.0, 1e-6
    )
    return S


def detection_limit(
    arm,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    k_swap: int,
    sample_period: float,
    before: ArrayLike,
    after: ArrayLike,
    position_variance: ArrayLike | None = None,
    velocity_variance: ArrayLike | None = None,
    *,
    n_tests: int,
    rate: float = 0.01,
    prob: float = 0.5,
    substeps: int = 2,
) -> float | None:
    """Time [s] after a swap at which the optimal GLR detects it (module docstring).

    Parameters
    ----------
    arm : Arm
        The arm (its standard parameters, armature and friction are the known part).
    q, qd : array_like (N, n)
        Recorded *true* trajectory (e.g. ct_oracle's) [rad], [rad/s].
    tau : array_like (N, n)
        Torque applied over each sample [N m].
    k_swap : int
        First sample with the new payload.
    sample_period : float
        T [s].
    before, after : array_like (10,)
        The payload's parameters before and after the swap, about the payload frame
        (:func:`~adaptive_dd.plant.arm.payload_parameters`; zeros: no payload).
    position_variance, velocity_variance : array_like (n,), optional
        Sensor noise [rad^2], [(rad/s)^2] (default ``arm.sensor``'s).
    n_tests : int
        Tests a trial makes (its number of samples).
    rate, prob : float
        False alarms per trial; detection probability.
    substeps : int
        RK4 substeps per sample of the linearised dynamics.

    Returns
    -------
    float or None
        Seconds after the swap, None if the record ends first.

    Examples
    --------
    The three-joint arm held still by its gravity torque when a 1 kg payload appears at its tip:

    >>> import numpy as np
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.identification.detection_limit import detection_limit
    >>> from adaptive_dd.plant.arm import payload_parameters
    >>> ref = {"joint1": {"offset": 0.3, "amplitude": [0.4], "frequency": [0.3]},
    ...        "joint2": {"offset": -0.6, "amplitude": [0.5], "frequency": [0.4]},
    ...        "joint3": {"offset": 0.4, "amplitude": [0.6], "frequency": [0.5]}}
    >>> arm = parse_scenario({"arm": {"robot": "vertical3"}, "reference": ref}).arm
    >>> q, qd = np.tile([0.3, -0.6, 0.4], (300, 1)), np.zeros((300, 3))
    >>> tau = arm.regressor(q, qd, np.zeros((300, 3))) @ arm.sigma  # holds the unloaded arm
    >>> t = detection_limit(arm, q, qd, tau, 0, 1e-3, np.zeros(10), payload_parameters(1.0),
    ...                     n_tests=1000)  # compiles on a cold cache
    >>> 0 < t < 0.3  # [s] after the swap
    True
    """
    q, qd, tau, pi_b, dpi, arm_f, wq, wv = _inputs(
        arm, q, qd, tau, k_swap, before, after, position_variance, velocity_variance
    )
    if not (isinstance(substeps, int | np.integer) and substeps >= 1):
        raise ParameterError(f"substeps must be an integer >= 1, got {substeps!r}")
    need = detection_threshold(n_tests, rate, prob)
    _, k = _sensitivity(
        arm.chain, pi_b, dpi, arm_f, q, qd, tau, float(sample_period), int(substeps), wq, wv, need, 1e-6
    )
    return None if k < 0 else float(k * sample_period)
