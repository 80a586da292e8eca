"""Output sensitivities of the arm to sigma: forward sensitivity equations and finite differences.

Both answer the same question: how does the sampled state ``x_k = [q_k, qd_k]`` of the
arm driven by a known torque record change with the base parameters sigma?

Forward sensitivity equations (:func:`local_sensitivities`, :func:`chain_sensitivities`)
    Over each sample the smooth model of eq. (7), ``M(q) qdd + C qd + B qd + D s = tau``
    with ``s`` the sign of the motion held fixed, is integrated with RK4 together with its
    variational equation. Differentiating eq. (8), ``Phi(q, qd, qdd) sigma = tau``, gives
    ``M dqdd/dsigma = -Phi(q, qd, qdd)``, ``M dqdd/dtau = I`` and
    ``M dqdd/dx = -d(M qdd + C qd + B qd)/dx`` at fixed ``qdd``. Each sample starts
    from the recorded state, so all samples are computed at once (vectorised), giving the
    per-sample Jacobians ``A_k = dx_{k+1}/dx_k``, ``G_k = dx_{k+1}/dtau_k`` and
    ``P_k = dx_{k+1}/dsigma``; the chain ``S_{k+1} = A_k S_k + P_k`` gives ``dx_k/dsigma``.

    *Sticking and reversals.* A joint whose velocity is exactly zero at both ends of a
    sample is held by Coulomb friction over it: its acceleration and all its derivatives
    are zero and the other joint moves with the reduced dynamics
    ``M_jj qdd_j = tau_j - ...``. Where a moving joint's velocity reaches zero inside a
    sample (it passes through zero, or stops and sticks), the sample is split at the
    crossing and the sensitivity jumps by the saltation term ``(f- - f+) dt_c/dsigma``,
    ``dt_c/dsigma = -(dqd_i/dsigma) / qdd_i-``: the Coulomb torque ``d_i sgn(qd_i)``
    flips, or the joint sticks (which sets its velocity sensitivity to zero: a slightly
    different arm sticks too). Left out: the jump at *breakaway* from rest, which is
    zero in continuous time (the net torque grows from zero) but not in the sampled
    kernel, which decides breakaway at substep starts; and a second crossing in one
    sample. The finite differences below contain both; on Table 2 the bounds agree
    within 0.7 % (tests/test_fisher.py).

Finite differences (:func:`finite_difference_sensitivities`)
    Central differences ``(x(sigma + h_j e_j) - x(sigma - h_j e_j)) / (2 h_j)`` of whole
    trajectories through the compiled stick-slip step
    :func:`adaptive_dd.plant.two_link_integrator.two_link_plant_step`, all 14 perturbed arms in one batch.
    Step ``h_j = rel_step * |sigma_j|`` with ``rel_step = 1e-6`` by default. The kernel
    decides breakaway from rest at substep starts, so a breakaway time moves by whole
    substeps (T / substeps) when a parameter changes: a difference that straddles such a
    jump is a spike of size ``qdd T / (substeps h)``. The smaller the step, the rarer the
    spikes; truncation error is O(h^2) and round-off ``eps |x| / h`` stays near 1e-10.
    On the Table 2 experiment the bounds from steps 1e-8 .. 1e-6 agree with each other
    to 4 digits and with the forward sensitivities within 0.7 % (per-sample sensitivities
    within 1.3 % at the 99th percentile); steps of 1e-5 and more hit the spikes (bounds
    off by up to 40 %).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant.dynamics import regressor
from adaptive_dd.plant.parameters import validate_sigma
from adaptive_dd.plant.two_link_integrator import two_link_plant_step

__all__ = [
    "chain_sensitivities",
    "finite_difference_sensitivities",
    "local_sensitivities",
    "simulate_trajectory",
]

Array = NDArray[np.float64]


def simulate_trajectory(
    sigma: ArrayLike,
    tau: ArrayLike,
    sample_period: float,
    q0: ArrayLike = (0.0, 0.0),
    qd0: ArrayLike = (0.0, 0.0),
    substeps: int = 2,
) -> tuple[Array, Array]:
    """Noise-free sampled trajectory of the arm under a held torque record.

    Parameters
    ----------
    sigma : array_like, shape (..., 7)
    tau : array_like, shape (..., N, 2)
        Torque held over ``[t_k, t_k + T)`` [N m] (the applied torque: no actuator model).
    sample_period : float
        T [s].
    q0, qd0 : array_like, shape (..., 2)
        State at sample 0; a joint with ``qd0 == 0`` starts stuck.

    Returns
    -------
    q, qd : ndarray, shape (..., N, 2)
        State at the sample instants, ``q[..., 0, :] == q0``.
    """
    tau = np.asarray(tau, dtype=float)
    sg = np.asarray(sigma, dtype=float)
    n = tau.shape[-2]
    shape = np.broadcast_shapes(tau.shape[:-2], sg.shape[:-1], np.shape(q0)[:-1], np.shape(qd0)[:-1])
    q = np.broadcast_to(np.asarray(q0, float), (*shape, 2)).copy()
    qd = np.broadcast_to(np.asarray(qd0, float), (*shape, 2)).copy()
    stuck, slip = qd == 0.0, np.ones_like(qd)
    qs, qds = np.empty((*shape, n, 2)), np.empty((*shape, n, 2))
    tau_b = np.broadcast_to(tau, (*shape, n, 2))
    sg_b = np.broadcast_to(sg, (*shape, 7))
    for k in range(n):
        qs[..., k, :], qds[..., k, :] = q, qd
        q, qd, stuck, slip = two_link_plant_step(
            q, qd, stuck, slip, tau_b[..., k, :], sg_b, sample_period, substeps
        )
    return qs, qds


def _accel_jacobians(x: Array, tau: Array, sg: Array, sgn: Array, free: NDArray[np.bool_]):
    """Accelerations and their derivatives for fixed friction modes.

    Returns ``a (..., 2)``, ``da/dx (..., 2, 4)``, ``da/dtau (..., 2, 2)``,
    ``da/dsigma (..., 2, 7)``; a joint not ``free`` (stuck) has zero rows.
    """
    q2, v1, v2 = x[..., 1], x[..., 2], x[..., 3]
    j1, j2, r, b1, b2, d1, d2 = (sg[..., i] for i in range(7))
    c2, s2 = np.cos(q2), np.sin(q2)
    f1, f2 = free[..., 0], free[..., 1]
    m11, m12 = j1 + j2 + 2.0 * r * c2, j2 + r * c2
    h1 = -r * s2 * v2 * (2.0 * v1 + v2) + b1 * v1 + d1 * sgn[..., 0]
    h2 = r * s2 * v1 * v1 + b2 * v2 + d2 * sgn[..., 1]
    # masked mass matrix: identity rows/columns for stuck joints, so their accelerations are 0
    a11, a22 = np.where(f1, m11, 1.0), np.where(f2, j2, 1.0)
    a12 = np.where(f1 & f2, m12, 0.0)
    det = a11 * a22 - a12 * a12
    inv = np.stack((np.stack((a22, -a12), -1), np.stack((-a12, a11), -1)), -2) / det[..., None, None]
    mask = np.stack((f1, f2), -1).astype(float)
    acc = np.einsum("...ij,...j->...i", inv, mask * (tau - np.stack((h1, h2), -1)))
    ac1, ac2 = acc[..., 0], acc[..., 1]
    # d(M qdd + C qd + B qd + D s)/dx at fixed qdd, rows = joints, columns = q1 q2 v1 v2
    g = np.zeros((*acc.shape[:-1], 2, 4))
    g[..., 0, 1] = -r * s2 * (2.0 * ac1 + ac2) - r * c2 * v2 * (2.0 * v1 + v2)
    g[..., 1, 1] = -r * s2 * ac1 + r * c2 * v1 * v1
    g[..., 0, 2] = -2.0 * r * s2 * v2 + b1
    g[..., 0, 3] = -2.0 * r * s2 * (v1 + v2)
    g[..., 1, 2] = 2.0 * r * s2 * v1
    g[..., 1, 3] = b2
    phi = regressor(x[..., :2], x[..., 2:], acc, sgn)
    minv = inv * mask[..., :, None]
    return (
        acc,
        -minv @ g,
        minv,
        -minv @ phi,
    )


def _rhs(x, z, tau, sg, sgn, free):
    """Time derivative of the state (..., 4) and of its sensitivity z (..., 4, 13)."""
    acc, ax, at, asg = _accel_jacobians(x, tau, sg, sgn, free)
    dx = np.concatenate((x[..., 2:], acc), axis=-1)
    dz = np.empty_like(z)
    dz[..., :2, :] = z[..., 2:, :]
    dz[..., 2:, :] = ax @ z
    dz[..., 2:, 4:6] += at
    dz[..., 2:, 6:] += asg
    return dx, dz


def _integrate(x, z, u, sg, sgn, free, dt, substeps):
    """RK4 of the state and sensitivity over per-sample durations ``dt (..., N)``."""
    hx = (dt / substeps)[..., None]
    hz = hx[..., None]
    for _ in range(substeps):
        k1x, k1z = _rhs(x, z, u, sg, sgn, free)
        k2x, k2z = _rhs(x + 0.5 * hx * k1x, z + 0.5 * hz * k1z, u, sg, sgn, free)
        k3x, k3z = _rhs(x + 0.5 * hx * k2x, z + 0.5 * hz * k2z, u, sg, sgn, free)
        k4x, k4z = _rhs(x + hx * k3x, z + hz * k3z, u, sg, sgn, free)
        x = x + (hx / 6.0) * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
        z = z + (hz / 6.0) * (k1z + 2.0 * k2z + 2.0 * k3z + k4z)
    return x, z


def _crossings(x, v0, v1, u, sg, sgn, free, coulomb, T):
    """The first velocity zero-crossing in each sample: time, joint, and modes after it.

    A moving joint whose velocity changes sign (passes through zero) or ends the sample
    at exactly zero (stops and sticks) crosses; the time is interpolated linearly for a
    passage and from the initial deceleration for a stop.
    """
    acc = _accel_jacobians(x, u, sg, sgn, free)[0]
    moving = (v0 != 0.0) & coulomb
    passes = moving & (v1 != 0.0) & (np.sign(v1) != np.sign(v0))
    stops = moving & (v1 == 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_pass = T * v0 / (v0 - v1)
        t_stop = np.where(acc * v0 < 0.0, -v0 / acc, T)
    tc = np.where(passes, t_pass, np.where(stops, t_stop, np.inf))
    tc = np.clip(tc, 0.0, np.where(passes | stops, T, np.inf))
    joint = np.argmin(tc, axis=-1)
    t1 = np.take_along_axis(tc, joint[..., None], -1)[..., 0]
    cross = np.isfinite(t1)
    onehot = (np.arange(2) == joint[..., None]) & cross[..., None]
    sgn_after = np.where(onehot & passes, -sgn, sgn)
    free_after = free & ~(onehot & stops)
    return np.where(cross, t1, T), joint, cross, sgn_after, free_after


def _saltation(x, z, u, sg, sgn, free, sgn_after, free_after, joint, cross):
    """Jump of the sensitivity where a velocity crosses zero: ``Z+ = Z- + (f- - f+) dt_c/d.``

    ``dt_c/d. = -Z-[qd_i] / qdd_i-`` (the crossing time moves with the parameters);
    ``f-`` and ``f+`` are the accelerations with the friction modes before and after.
    For a joint that sticks this sets its velocity sensitivity to zero.
    """
    a_m = _accel_jacobians(x, u, sg, sgn, free)[0]
    a_p = _accel_jacobians(x, u, sg, sgn_after, free_after)[0]
    ai = np.take_along_axis(a_m, joint[..., None], -1)[..., 0]
    zi = np.take_along_axis(z, (2 + joint)[..., None, None], -2)[..., 0, :]
    ok = cross & (np.abs(ai) > 1e-12)
    grad = np.where(ok[..., None], -zi / np.where(ok, ai, 1.0)[..., None], 0.0)
    z = z.copy()
    z[..., 2:, :] += (a_m - a_p)[..., :, None] * grad[..., None, :]
    return z


def local_sensitivities(
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    sigma: ArrayLike,
    sample_period: float,
    substeps: int = 2,
) -> tuple[Array, Array, Array]:
    """Per-sample Jacobians of the sampled arm along a recorded trajectory.

    Each sample is integrated from the recorded state with the friction modes of the
    record; a velocity zero-crossing inside a sample splits it, with the saltation jump
    of the sensitivity at the crossing (module docstring).

    Parameters
    ----------
    q, qd : array_like, shape (..., N, 2)
        State at the sample instants (true or simulated; stuck joints have qd exactly 0).
    tau : array_like, shape (..., N, 2)
        Torque held over each sample [N m].
    sigma : array_like, shape (..., 7)
    sample_period : float
        T [s].
    substeps : int
        RK4 steps per sample (per part of a split sample).

    Returns
    -------
    A : ndarray (..., N-1, 4, 4)
        ``dx_{k+1}/dx_k``.
    G : ndarray (..., N-1, 4, 2)
        ``dx_{k+1}/dtau_k``.
    P : ndarray (..., N-1, 4, 7)
        ``dx_{k+1}/dsigma`` with ``x_k`` held.
    """
    q, qd, tau = (np.asarray(a, dtype=float) for a in (q, qd, tau))
    if q.shape[-2] < 2 or q.shape != qd.shape or q.shape[-1] != 2:
        raise SignalError(f"q and qd must have equal shapes (..., N >= 2, 2), got {q.shape}, {qd.shape}")
    sg = validate_sigma(sigma)[..., None, :]
    x = np.concatenate((q[..., :-1, :], qd[..., :-1, :]), axis=-1)
    v0, v1 = qd[..., :-1, :], qd[..., 1:, :]
    coulomb = np.broadcast_to(sg[..., 5:7] > 0.0, v0.shape)
    free = ~((v0 == 0.0) & (v1 == 0.0) & coulomb)
    sgn = np.sign(np.where(v0 != 0.0, v0, v1))
    u = tau[..., :-1, :]
    z = np.zeros((*x.shape, 13))
    z[..., :, :4] = np.eye(4)
    t1, joint, cross, sgn2, free2 = _crossings(x, v0, v1, u, sg, sgn, free, coulomb, sample_period)
    x, z = _integrate(x, z, u, sg, sgn, free, t1, substeps)
    if np.any(cross):
        z = _saltation(x, z, u, sg, sgn, free, sgn2, free2, joint, cross)
        x, z = _integrate(x, z, u, sg, sgn2, free2, sample_period - t1, substeps)
    stopped = (v1 == 0.0) & coulomb  # stuck at the end of the sample: velocity pinned at 0
    z[..., 2:, :] = np.where(stopped[..., :, None], 0.0, z[..., 2:, :])
    return z[..., :4], z[..., 4:6], z[..., 6:]


def chain_sensitivities(a: Array, p: Array, s0: Array | None = None) -> Array:
    """``S_0 = s0`` (default 0), ``S_{k+1} = A_k S_k + P_k``: ``(..., N, 4, n)`` from ``(..., N-1, ...)``."""
    n = a.shape[-3] + 1
    s = np.zeros((*p.shape[:-3], 4, p.shape[-1])) if s0 is None else np.asarray(s0, float)
    out = np.empty((*s.shape[:-2], n, *s.shape[-2:]))
    out[..., 0, :, :] = s
    for k in range(n - 1):
        s = a[..., k, :, :] @ s + p[..., k, :, :]
        out[..., k + 1, :, :] = s
    return out


def finite_difference_sensitivities(
    sigma: ArrayLike,
    tau: ArrayLike,
    sample_period: float,
    q0: ArrayLike = (0.0, 0.0),
    qd0: ArrayLike = (0.0, 0.0),
    substeps: int = 2,
    rel_step: float = 1e-6,
    direction: ArrayLike | None = None,
) -> Array:
    """``dx_k/dsigma`` by central differences through the compiled stick-slip step.

    Parameters
    ----------
    sigma : array_like (7,)
    tau : array_like (N, 2)
    rel_step : float
        ``h_j = rel_step * |sigma_j|`` (module docstring: why 1e-6); a ``sigma_j`` of 0 steps on
        ``1e-3 max |sigma|``.
    direction : array_like (m, 7), optional
        Differentiate along these directions of sigma instead of its 7 axes (per unit
        of each direction; step ``rel_step * ||sigma|| / ||direction||``).

    Returns
    -------
    S : ndarray (N, 4, m)
        Rows ``q1 q2 qd1 qd2``; ``m = 7`` by default.
    """
    sg = validate_sigma(sigma)
    if sg.ndim != 1:
        raise ParameterError(f"finite_difference_sensitivities takes one sigma (7,), got {sg.shape}")
    if not rel_step > 0:
        raise ParameterError(f"rel_step must be > 0, got {rel_step}")
    if direction is None:
        # a parameter that is 0 (friction may be) steps on a thousandth of the largest's scale
        dirs, eps = np.eye(7), rel_step * np.maximum(np.abs(sg), 1e-3 * np.abs(sg).max())
    else:
        dirs = np.atleast_2d(np.asarray(direction, dtype=float))
        eps = rel_step * np.linalg.norm(sg) / np.linalg.norm(dirs, axis=-1)
    steps = eps[:, None] * dirs
    sig = np.concatenate((sg + steps, sg - steps))
    q, qd = simulate_trajectory(sig, np.asarray(tau, float)[None], sample_period, q0, qd0, substeps)
    x = np.concatenate((q, qd), axis=-1)  # (2m, N, 4)
    m = steps.shape[0]
    ds = (x[:m] - x[m:]) / (2.0 * eps[:, None, None])
    return np.moveaxis(ds, 0, -1)
