"""The compiled online estimator's filters, regression and RLS row update.

The M2 filter bank on the momentum form's sums (:func:`_filtered_signals`,
:func:`_momentum_channels`, :func:`_arm_momentum_channels`), the regression rows of payload mode
(:func:`_regression`) and eq. (14) for one scalar equation (:func:`_rls_row`).
Called by the per-sample step :func:`~adaptive_dd.identification.online_kernel.est_step_trial_in`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.identification.online_slots import (
    BIG,
    C_RESTART,
    C_SINCE_BAD,
    C_SKIPPED,
    C_STARTED,
    MODE_ARM,
    MOMENTUM_CHANNELS,
)
from adaptive_dd.plant.chain_regressor import momentum_columns_in, momentum_form_in


@njit(cache=True, inline="always")
def _filtered_signals(c, s, i, q, qd, tau, w):  # pragma: no cover - compiled
    """Filter sample (q, qd, tau) of trial i into ``w`` (:class:`EstWork`); return True if the
    filtered equations are usable.

    Payload mode: ``w.tf = G0 tau``, ``w.ym = G1 p + G0 wv`` (n,) of the known links and
    ``w.phim = G1 py + G0 wy`` (n, 10) of the payload's link (:func:`momentum_form_in`), at the
    held channels; mode "arm": the whole regression ``w.phi, w.y``
    (:func:`_arm_momentum_channels`). The filters (re)start on the first sample and on the
    sample after an alarm (``C_RESTART``).
    """
    n = q.shape[0]
    cnt = s.cnt[i]
    start = cnt[C_STARTED] == 0
    u = w.u
    for j in range(n):
        t = tau[j]
        if c.align:
            prev = tau[j] if cnt[C_STARTED] == 0 else s.tau_prev[i, j]
            t = 0.5 * (tau[j] + prev)
        u[j] = q[j]
        u[n + j] = qd[j]
        u[2 * n + j] = t
        u[3 * n + j] = np.sign(qd[j])
    bad = False
    for k in range(4 * n):
        if not np.isfinite(u[k]):
            bad = True
    if c.align:
        for j in range(n):
            if np.isfinite(tau[j]):
                s.tau_prev[i, j] = tau[j]
    if cnt[C_STARTED] == 0:  # the filters start in the steady state of the first sample
        for k in range(4 * n):
            s.u_last[i, k] = u[k] if np.isfinite(u[k]) else 0.0
        cnt[C_SINCE_BAD] = BIG
        cnt[C_STARTED] = 1
    if bad:  # hold the last finite sample of every channel
        for k in range(4 * n):
            u[k] = s.u_last[i, k]
        cnt[C_SINCE_BAD] = 0
        cnt[C_SKIPPED] += 1
    else:
        for k in range(4 * n):
            s.u_last[i, k] = u[k]
        cnt[C_SINCE_BAD] = min(cnt[C_SINCE_BAD] + 1, BIG)
    if c.mode == MODE_ARM:
        _arm_momentum_channels(c, s, i, start or cnt[C_RESTART] == 1, w)
    else:
        _momentum_channels(c, s, i, start or cnt[C_RESTART] == 1, w)
    cnt[C_RESTART] = 0
    return cnt[C_SINCE_BAD] > c.taint


@njit(cache=True)
def _summed_channels(Am, Bm, Cm, Dm, xf, u1, u0, y, tmp):  # pragma: no cover - compiled
    """One sample of the summing realisation (``Am, Bm, Cm, Dm``) on every channel of ``xf``:
    ``y = G1 u1 + G0 u0``, the states advanced in place (order 2 written out, its matrices in
    scalars: a call per channel would cost more than its arithmetic); ``tmp`` (at least the
    order,) scratch of the other orders."""
    order = Am.shape[0]
    if order == 2:
        a00, a01, a10, a11 = Am[0, 0], Am[0, 1], Am[1, 0], Am[1, 1]
        b00, b01, b10, b11 = Bm[0, 0], Bm[0, 1], Bm[1, 0], Bm[1, 1]
        c0, c1, d0, d1 = Cm[0], Cm[1], Dm[0], Dm[1]
        for ch in range(y.shape[0]):
            z0, z1, v1, v0 = xf[ch, 0], xf[ch, 1], u1[ch], u0[ch]
            y[ch] = d1 * v1 + d0 * v0 + c0 * z0 + c1 * z1
            xf[ch, 0] = a00 * z0 + a01 * z1 + b01 * v1 + b00 * v0
            xf[ch, 1] = a10 * z0 + a11 * z1 + b11 * v1 + b10 * v0
        return
    for ch in range(y.shape[0]):
        acc = Dm[1] * u1[ch] + Dm[0] * u0[ch]
        for m in range(order):
            acc += Cm[m] * xf[ch, m]
        y[ch] = acc
        for m in range(order):
            acc = Bm[m, 1] * u1[ch] + Bm[m, 0] * u0[ch]
            for k in range(order):
                acc += Am[m, k] * xf[ch, k]
            tmp[m] = acc
        for m in range(order):
            xf[ch, m] = tmp[m]


@njit(cache=True, inline="always")
def _momentum_channels(c, s, i, restart, w):  # pragma: no cover - compiled
    """The momentum form at the held channels ``w.u`` (q, qd, tau, sgn), filtered.

    The known arm's momentum ``p = M qd + ia qd`` and rest ``wv = g - C^T qd + fv qd +
    fc sgn(qd)``, the payload link's ``py, wy`` (n, 10) (:func:`momentum_form_in`). Out:
    ``tf = G0 tau``, ``ym = G1 p + G0 wv``, ``phim = G1 py + G0 wy``, each sum one channel of
    the summing realisation (``MOMENTUM_CHANNELS`` n channels in ``s.xf[i]``: tau, (p, wv),
    (py, wy) row-major).

    On ``restart`` (the first sample, and the sample after an alarm) the filters start
    afresh: momentum channels in the steady state of this sample, the others at rest (the
    state ``p xm1``, ``py xm1``; 0 for tau). The equation ``G0 tau = G1 p + G0 wv`` then holds
    exactly for the signals continued before this sample (momentum constant, torque and rest
    zero), so the filters carry no memory of a payload that has gone: the equations after an
    alarm are exact from the first sample on.
    """
    tf, ym, phim, u = w.tf, w.ym, w.phim, w.u
    n = ym.shape[0]
    nch = MOMENTUM_CHANNELS * n
    u1, u0, y, p, wv, py, wy = w.u1, w.u0, w.yf, w.p, w.wv, w.py, w.wy  # inputs (G1, G0), outputs
    # the whole pi0 (its first 10 n entries are read), not a view of it
    momentum_form_in(c.ch, c.pi0, c.jp, u[:n], u[n : 2 * n], w.chain, w.a2, p, wv, py, wy)
    for r in range(n):
        qd = u[n + r]
        u1[r] = 0.0
        u0[r] = u[2 * n + r]
        p[r] += c.pi0[12 * n + r] * qd
        wv[r] += c.pi0[10 * n + r] * qd + c.pi0[11 * n + r] * u[3 * n + r]
    xf = s.xf[i]
    if restart:  # the G1 inputs (momentum) in steady state, the G0 inputs at rest
        for ch in range(nch):
            for m in range(c.xm1.shape[0]):
                xf[ch, m] = u1[ch] * c.xm1[m]
    _summed_channels(c.Am, c.Bm, c.Cm, c.Dm, xf, u1, u0, y, w.ftmp)
    for r in range(n):
        tf[r] = y[r]
        ym[r] = y[n + r]
        for k in range(10):
            phim[r, k] = y[2 * n + 10 * r + k]


def arm_momentum_channels(n: int) -> int:
    """Filter channels of mode "arm" in momentum form, n joints: torque (n), every link's
    ``G1 py + G0 wy`` (10 n per link), viscous, Coulomb and armature columns (n each)."""
    return 4 * n + 10 * n * n


@njit(cache=True)
def _arm_momentum_channels(c, s, i, restart, w):  # pragma: no cover - compiled
    """Mode "arm" in momentum form: the whole base regression ``w.phi (n, p)``, ``w.y (n,)``.

    ``G0 tau = G1 (Y_p sigma) + G0 (Y_w sigma)`` for the momentum form of every link
    (:func:`momentum_form_in` once per link), viscous ``G0 qd``, Coulomb ``G0 sgn(qd)`` and
    armature ``G1 qd`` columns, the payload's ten columns those of link ``jp`` through ``pmap``.
    Exact for any parameters and any tau_f; on ``restart`` the filters start afresh as in
    :func:`_momentum_channels` (momentum channels in steady state, the others at rest).
    """
    u = w.u
    n = w.ym.shape[0]
    nch = 4 * n + 10 * n * n
    # views of the scratch w.arm, no allocation a sample (zeros when made: the entries of u1 and
    # u0 not written below stay 0, as in arrays made afresh)
    a = w.arm
    u1, u0, y = a[:nch], a[nch : 2 * nch], a[2 * nch : 3 * nch]
    o = 3 * nch
    pm, wv = a[o : o + n], a[o + n : o + 2 * n]
    py, wy = a[o + 2 * n : o + 12 * n].reshape((n, 10)), a[o + 12 * n : o + 22 * n].reshape((n, 10))
    q, qd = u[:n], u[n : 2 * n]
    for r in range(n):
        u0[r] = u[2 * n + r]
    for j in range(n):
        if j == 0:  # the kinematics once; every link's columns from them (the same numbers)
            momentum_form_in(c.ch, c.pi0, j, q, qd, w.chain, w.a2, pm, wv, py, wy)
        else:
            momentum_columns_in(j, w.chain, w.a2, py, wy)
        for r in range(n):
            for k in range(10):
                ch = n + (j * n + r) * 10 + k
                u1[ch] = py[r, k]
                u0[ch] = wy[r, k]
    f0 = n + 10 * n * n
    for r in range(n):
        u0[f0 + r] = qd[r]
        u0[f0 + n + r] = u[3 * n + r]
        u1[f0 + 2 * n + r] = qd[r]
    xf = s.xf[i]
    if restart:
        for ch in range(nch):
            for m in range(c.xm1.shape[0]):
                xf[ch, m] = u1[ch] * c.xm1[m]
    _summed_channels(c.Am, c.Bm, c.Cm, c.Dm, xf, u1, u0, y, w.ftmp)
    phi, yy = w.phi, w.y
    pb = c.indep.shape[0]
    p = phi.shape[1]
    for r in range(n):
        yy[r] = y[r]
        for a in range(pb):
            col = c.indep[a]
            if col < 10 * n:
                phi[r, a] = y[n + ((col // 10) * n + r) * 10 + col % 10]
            else:
                kind = (col - 10 * n) // n
                jj = (col - 10 * n) % n
                phi[r, a] = y[f0 + kind * n + r] if jj == r else 0.0
        for k in range(p - pb):
            acc = 0.0
            for m in range(10):
                acc += y[n + (c.jp * n + r) * 10 + m] * c.pmap[m, k]
            phi[r, pb + k] = acc


@njit(cache=True, inline="always")
def _payload_rows(c, link, known, phi, y):  # pragma: no cover - compiled
    """Payload mode: ``phi = link @ pmap`` (the link's columns in the payload's parameters) and
    ``y -= known`` (the known arm's part), row by row."""
    for r in range(link.shape[0]):
        y[r] -= known[r]
        for k in range(10):
            acc = 0.0
            for m in range(10):
                acc += link[r, m] * c.pmap[m, k]
            phi[r, k] = acc


@njit(cache=True, inline="always")
def _regression(c, tf, ym, phim, phi, y):  # pragma: no cover - compiled
    """Payload mode: the regression ``y = phi theta`` (n x p) of the filtered momentum form
    (:func:`_momentum_channels`); mode "arm" has it already (:func:`_arm_momentum_channels`)."""
    if c.mode == MODE_ARM:
        return
    for r in range(tf.shape[0]):
        y[r] = tf[r]
    _payload_rows(c, phim, ym, phi, y)


@njit(cache=True)
def _rls_row(theta, P, phi, y, lam_eff, pphi, nz):  # pragma: no cover - compiled
    """Eq. (14) for one scalar equation; returns the prior error (NaN: nothing changed).

    ``P phi`` is accumulated over the nonzero entries of phi only (rows of P, P being
    symmetric), and the update ``P - g g^T`` with ``g = P phi / sqrt(den)`` keeps P
    symmetric to the last bit (a product of two floats does not depend on their order).
    """
    p = theta.shape[0]
    m = 0
    for a in range(p):
        if phi[a] != 0.0:
            nz[m] = a
            m += 1
    eps = y
    for a in range(p):
        pphi[a] = 0.0
    for t in range(m):
        b = nz[t]
        f = phi[b]
        eps -= f * theta[b]
        for a in range(p):
            pphi[a] += P[b, a] * f
    den = lam_eff
    for t in range(m):
        den += phi[nz[t]] * pphi[nz[t]]
    if not (np.isfinite(eps) and np.isfinite(den) and den > 0.0):
        return np.nan
    inv = 1.0 / den
    root = np.sqrt(inv)
    for a in range(p):
        theta[a] += pphi[a] * inv * eps
        pphi[a] *= root
    if lam_eff != 1.0:  # the forgetting's division in the same pass (the same two roundings)
        il = 1.0 / lam_eff
        for a in range(p):
            ga = pphi[a]
            for b in range(p):
                P[a, b] = (P[a, b] - ga * pphi[b]) * il
        return eps
    for a in range(p):
        ga = pphi[a]
        for b in range(p):
            P[a, b] -= ga * pphi[b]
    return eps
