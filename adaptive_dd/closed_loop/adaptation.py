"""The payload adaptation laws of the arena beyond Slotine-Li's gradient, compiled: one sample per
call, after the command (the estimate serves the next sample).

* :func:`project_payload`: the a-priori box, the centre of mass in a ball and the payload's
  pseudo-inertia kept positive semi-definite (a physically consistent payload: the estimated
  inertia ``M0(q) + M_payload(q)`` stays positive definite, Craig, Hsu and Sastry's condition for
  the inverse they use); :func:`rebuild_payload_model` the trial's model from the payload.
* :func:`chs_step`: Craig, Hsu and Sastry ("Adaptive Control of Mechanical Manipulators", IJRR
  6(2), 1987): ``theta' = Gamma W^T M_hat^-1 E1``, ``E1 = e' + lam e``, ``W = Y_j(q, qd, qd,
  qdd_f) P`` the payload's regressor at the measured velocity and the filtered measured
  acceleration ``qdd_f = rate / (s + rate) d/dt qd``.
* :func:`natural_step`: Lee, Kwon and Park ("A Natural Adaptive Control Law for Robot
  Manipulators", IROS 2018): the payload link's inertial parameters ``phi`` (link and payload
  about the joint frame) adapted along the natural gradient of the log-det divergence of their
  pseudo-inertia ``J(phi)``, ``J' = gamma J G J`` with ``G`` the 4x4 dual of ``Y_j^T s``
  (``tr(G J(x)) = (Y_j^T s) . x``), stepped on the manifold of positive definite ``J``:
  ``J+ = J^1/2 expm(T gamma J^1/2 G J^1/2) J^1/2``.

The state of :func:`chs_step` is in rows of the law's ``obs (OBS_ROWS, n)`` (the residual observer
is off for these laws): the last fresh measurement (``O_Q``, ``O_QD``), the count of fresh ones
(``O_COUNT``) and the filtered acceleration (:data:`CH_QDD`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.closed_loop.residual_observer import O_COUNT, O_Q, O_QD, O_TAU
from adaptive_dd.identification.pseudo_inertia import parameters_of, pseudo_inertia
from adaptive_dd.plant.chain import body_slotine_li_regressor_in, mass_matrix_in
from adaptive_dd.plant.chain_dynamics import _cholesky_solve

__all__ = [
    "ADAPT_CHS",
    "ADAPT_GRADIENT",
    "ADAPT_ICL",
    "ADAPT_NATURAL",
    "CH_QDD",
    "NATURAL_STEP_MAX",
    "chs_step",
    "dual_pseudo_inertia",
    "natural_link_step",
    "natural_step",
    "parameters_of",
    "payload_gradient_step",
    "project_payload",
    "pseudo_inertia",
    "rebuild_payload_model",
]

ADAPT_GRADIENT, ADAPT_CHS, ADAPT_ICL, ADAPT_NATURAL = 0, 1, 2, 3
"""``LawConfig.adapt_kind``: Slotine-Li's gradient (and composite's), Craig-Hsu-Sastry's, integral
concurrent learning's (the gradient plus :func:`~adaptive_dd.closed_loop.composite.icl_term`),
Lee-Kwon-Park's natural gradient."""

CH_QDD = 0
"""Row of ``obs`` holding Craig-Hsu-Sastry's filtered measured acceleration [rad/s^2]."""

NATURAL_STEP_MAX = 0.05
"""The natural law's step ``expm(X)`` with the eigenvalues of ``X`` clipped to +-this: the
pseudo-inertia changes by at most ``e^0.05 - 1 = 5 %`` in any direction per sample (a guard
against one wild sample; the law's own steps are far smaller)."""


@njit(cache=True)
def dual_pseudo_inertia(g, G):  # pragma: no cover - compiled
    """``G (4, 4)`` symmetric with ``tr(G J(x)) = g . x`` for every ``x (10,)`` (``J`` of
    :func:`pseudo_inertia`): the gradient ``g`` over the parameters as a 4x4 matrix."""
    G[0, 0], G[1, 1], G[2, 2] = g[6] + g[9], g[4] + g[9], g[4] + g[6]
    G[0, 1] = G[1, 0] = -0.5 * g[5]
    G[0, 2] = G[2, 0] = -0.5 * g[7]
    G[1, 2] = G[2, 1] = -0.5 * g[8]
    for r in range(3):
        G[r, 3] = G[3, r] = 0.5 * g[1 + r]
    G[3, 3] = g[0]


@njit(cache=True)
def _sym_fn(A, f_sqrt, clip):  # pragma: no cover - compiled
    """``V diag(f(d)) V^T`` of the symmetric ``A = V diag(d) V^T``: ``sqrt(max(d, clip))`` when
    ``f_sqrt``, else ``exp(clip(d, -clip, clip))``."""
    d, V = np.linalg.eigh(A)
    out = np.zeros_like(A)
    for k in range(d.shape[0]):
        f = np.sqrt(max(d[k], clip)) if f_sqrt else np.exp(min(max(d[k], -clip), clip))
        for r in range(A.shape[0]):
            for c in range(A.shape[0]):
                out[r, c] += V[r, k] * f * V[c, k]
    return out


@njit(cache=True)
def project_payload(cfg, theta):  # pragma: no cover - compiled
    """``theta (10,)`` clipped to ``[cfg.lo, cfg.hi]``, ``m >= 0``, ``|c| <= cfg.com_radius``, then
    (``cfg.adapt_kind == ADAPT_CHS``) its pseudo-inertia's negative eigenvalues set to zero."""
    for k in range(10):
        theta[k] = min(max(theta[k], cfg.lo[k]), cfg.hi[k])
    theta[0] = max(theta[0], 0.0)
    mc = np.sqrt(theta[1] ** 2 + theta[2] ** 2 + theta[3] ** 2)
    lim = cfg.com_radius * theta[0]
    if mc > lim:
        f = lim / mc
        theta[1], theta[2], theta[3] = f * theta[1], f * theta[2], f * theta[3]
    if cfg.adapt_kind == ADAPT_CHS:
        _physical_payload(theta)


@njit(cache=True, _nrt=True)
def _physical_payload(theta):  # pragma: no cover - compiled
    """``theta (10,)`` with its pseudo-inertia's negative eigenvalues set to zero, in place. It
    allocates, so it is compiled with reference counting whoever calls it (the gradient laws' step,
    :func:`~adaptive_dd.closed_loop.laws._adapt_payload`, is compiled without)."""
    J = np.empty((4, 4))
    pseudo_inertia(theta, J)
    d, V = np.linalg.eigh(J)
    if d[0] >= 0.0:
        return
    P = np.zeros((4, 4))
    for k in range(4):
        dk = max(d[k], 0.0)
        for r in range(4):
            for c in range(4):
                P[r, c] += V[r, k] * dk * V[c, k]
    parameters_of(P, theta)


@njit(cache=True)
def rebuild_payload_model(cfg, theta, pi_model):  # pragma: no cover - compiled
    """``pi_model = pi_fixed`` plus the payload ``theta`` (about its frame) on the payload's link."""
    j = cfg.payload_joint
    for c in range(pi_model.shape[0]):
        pi_model[c] = cfg.pi_fixed[c]
    for c in range(10):
        acc = 0.0
        for k in range(10):
            acc += cfg.payload_map[c, k] * theta[k]
        pi_model[10 * j + c] += acc


@njit(cache=True)
def _chs_acceleration(cfg, q, qd, obs):  # pragma: no cover - compiled
    """Update the filtered measured acceleration at a fresh measurement; False at a held one
    (a lost sample: nothing new to learn from)."""
    n = q.shape[0]
    held = obs[O_COUNT, 0] >= 1.0
    for r in range(n):
        held = held and q[r] == obs[O_Q, r] and qd[r] == obs[O_QD, r]
    if held:
        return False
    m = obs[O_COUNT, 1]
    if obs[O_COUNT, 0] >= 1.0 and m >= 1.0:
        dt = m * cfg.T
        a = np.exp(-cfg.comp_rate * dt)
        for r in range(n):
            raw = (qd[r] - obs[O_QD, r]) / dt
            if np.isfinite(raw):
                obs[CH_QDD, r] = a * obs[CH_QDD, r] + (1.0 - a) * raw
    for r in range(n):
        obs[O_Q, r], obs[O_QD, r], obs[O_TAU, r] = q[r], qd[r], 0.0
    obs[O_COUNT, 0] += 1.0
    obs[O_COUNT, 1] = 0.0
    return True


@njit(cache=True)
def chs_step(ch, cfg, q, qd, e, ed, theta, pi_model, obs, work):  # pragma: no cover - compiled
    """One step of Craig, Hsu and Sastry's law (module docstring) on the payload ``theta (10,)``,
    then :func:`project_payload` and the trial's model rebuilt. ``e, ed (n,)`` the tracking error
    and its rate; scratch ``work`` of :func:`~adaptive_dd.closed_loop.laws.law_work`."""
    n = q.shape[0]
    if not _chs_acceleration(cfg, q, qd, obs) or obs[O_COUNT, 0] < 3.0:
        return  # held, or no filtered acceleration yet
    m, x = work[2], work[7][0]
    mass_matrix_in(ch, pi_model[: 10 * n], q, work[0], m)
    for r in range(n):
        m[r, r] += pi_model[12 * n + r]
        x[r] = ed[r] + cfg.lam[r] * e[r]
    if not _cholesky_solve(m, x):  # x = M^-1 (e' + lam e) in place
        return
    body_slotine_li_regressor_in(ch, cfg.payload_joint, q, qd, qd, obs[CH_QDD], work[0], work[4], work[3])
    payload_gradient_step(cfg, work[3], x, work[5], work[9], False, theta, pi_model)


@njit(cache=True)
def payload_gradient_step(cfg, yb, v, g, extra, with_extra, theta, pi_model):  # pragma: no cover - compiled
    """``theta += T gamma (P^T Y_j^T v [+ extra])`` per parameter (a non-finite step skipped), then
    :func:`project_payload` and the trial's model rebuilt: the payload step of every gradient law.
    ``yb (n, 10)`` the payload link's regressor ``Y_j``, ``v (n,)`` the vector it is driven by,
    ``g (10,)`` scratch; ``extra (10,)`` added when ``with_extra`` (the composite or ICL term)."""
    n = v.shape[0]
    for c in range(10):  # g = Y_j^T v
        acc = 0.0
        for r in range(n):
            acc += yb[r, c] * v[r]
        g[c] = acc
    for k in range(10):
        upd = 0.0
        for c in range(10):
            upd += cfg.payload_map[c, k] * g[c]
        if with_extra:
            upd += extra[k]
        upd *= cfg.T * cfg.gamma[k]
        theta[k] += upd if np.isfinite(upd) else 0.0
    project_payload(cfg, theta)
    rebuild_payload_model(cfg, theta, pi_model)


@njit(cache=True)
def natural_link_step(phi, g, step, m_max):  # pragma: no cover - compiled
    """One link's step of Lee, Kwon and Park's law (their eq. for the discrete update, ``J+ =
    J^1/2 expm(step J^1/2 G J^1/2) J^1/2``) on its parameters ``phi (10,)`` about its joint frame,
    in place; ``g (10,)`` the gradient ``Y_j^T s`` [N m s / unit], ``step`` the sample period
    times the gain ``gamma`` [s], ``m_max`` [kg] the largest mass (the pseudo-inertia scaled down
    to it: still definite). A singular ``J`` is floored at ``1e-9 tr``; the eigenvalues of the
    exponent clipped to :data:`NATURAL_STEP_MAX`. False (``phi`` untouched) if the step is not
    finite. :func:`natural_step` applies it to the payload's link; the same step on every link is
    the authors' whole-arm adaptation (``benchmarks/natural_adaptive_reproduction.py``)."""
    J, G = np.empty((4, 4)), np.empty((4, 4))
    pseudo_inertia(phi, J)
    dual_pseudo_inertia(g, G)
    S = _sym_fn(J, True, 1e-9 * max(J[0, 0] + J[1, 1] + J[2, 2] + J[3, 3], 1e-12))
    X = step * (S @ G @ S)
    if not np.all(np.isfinite(X)):
        return False
    Jn = S @ _sym_fn(0.5 * (X + X.T), False, NATURAL_STEP_MAX) @ S
    if Jn[3, 3] > m_max:
        Jn *= m_max / Jn[3, 3]
    parameters_of(Jn, phi)
    return True


@njit(cache=True)
def natural_step(ch, cfg, q, qd, qdr, a, s, theta, pi_model, work):  # pragma: no cover - compiled
    """One step of Lee, Kwon and Park's law (module docstring). Here ``theta (10,)`` is the change
    of the payload link's parameters about its joint frame (``phi = phi0 + theta``, ``phi0`` the
    nominal link's, its pseudo-inertia floored at ``1e-9 tr`` if singular); ``s = e' + lam e``;
    the mass added kept within ``cfg.hi[0]``: :func:`natural_link_step` on that link."""
    n = q.shape[0]
    j = cfg.payload_joint
    yb = work[3]
    body_slotine_li_regressor_in(ch, j, q, qd, qdr, a, work[0], work[4], yb)
    g, phi = work[5], work[9]
    for c in range(10):
        acc = 0.0
        for r in range(n):
            acc += yb[r, c] * s[r]
        g[c] = acc
        phi[c] = cfg.pi_fixed[10 * j + c] + theta[c]
    if not natural_link_step(phi, g, cfg.T * cfg.nat_gain, cfg.pi_fixed[10 * j] + cfg.hi[0]):
        return
    for c in range(10):
        theta[c] = phi[c] - cfg.pi_fixed[10 * j + c]
    for c in range(pi_model.shape[0]):
        pi_model[c] = cfg.pi_fixed[c]
    for c in range(10):
        pi_model[10 * j + c] += theta[c]
