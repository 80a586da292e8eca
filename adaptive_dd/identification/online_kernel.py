"""Compiled per-trial step of the N-joint online estimator (:mod:`~adaptive_dd.identification.online`).

:func:`est_step_trial` advances trial ``i`` of an :class:`EstState` by one sample, in
place; :func:`est_model_trial` writes the model that control uses (standard
parameters, projected). The Python path and any compiled closed loop call these
same functions. Configuration travels as one :class:`EstCfg` NamedTuple of arrays
and scalars (built by :func:`~adaptive_dd.identification.online.est_init`).

One sample, per trial:

1. non-finite input: the last finite channels are held, the sample is counted as
   skipped, and the filtered equations are not used for ``taint`` samples (the
   filters' memory);
2. M2 filter bank (eq. 20, Tustin; the same matrices as
   :func:`~adaptive_dd.identification.filters.design_filter_bank`) on the channels
   ``q, qd, tau, sgn(qd)`` (outputs G0, G1); the regressor is evaluated at the filtered
   signals ``qf = G0 q, qdf = G0 qd, qddf = G1 qd``, friction columns at ``G0 qd``,
   ``G0 sgn(qd)`` (the paper's M2 construction generalised to n joints). The momentum
   form filters ``G0 tau``, ``G1 p + G0 wv`` and ``G1 py + G0 wy`` instead, each sum as
   one state of the bank's transposed realisation
   (:func:`~adaptive_dd.identification.filters.summing_realisation`);
3. data selection: equation j is used once joint j has been faster than the
   threshold for the filters' memory;
4. RLS of eq. (14), one scalar update per used joint equation (row weights ``w``);
   the forgetting factor advances once per sample, at the first used row;
5. the change detector on the rows' prior errors (:func:`_detect`); on an alarm the
   covariance is re-opened along the payload subspace (and once more when the
   filters' memory has passed the alarm).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from adaptive_dd.identification.pseudo_inertia import project_payload
from adaptive_dd.plant.chain import (
    Chain,
    mass_matrix_in,
    momentum_form_in,
    regressor,
    rnea_body_regressor_in,
    workspace,
)

# columns of the per-trial integer state `cnt`
C_K = 0  # samples stepped
C_STARTED = 1
C_SINCE_BAD = 2  # samples since the last non-finite input
C_SKIPPED = 3  # samples with a non-finite input
C_ALARMS = 4
C_SINCE_ALARM = 5
C_LAST_ALARM = 6  # sample index of the last alarm (-1: none)
C_REOPEN_AT = 7  # sample at which the covariance is re-opened again (-1: none)
C_RESTART = 8  # 1: the momentum channels restart at the next sample (set by an alarm)
C_FOLLOWS = 9  # 1: the model control uses follows the estimate (0: it keeps the starting payload)
N_CNT = 10

BIG = 1 << 40
SIGNAL_CHANNELS = 4  # per joint: q, qd, tau, sgn(qd) (the signals form)
MOMENTUM_CHANNELS = 12  # per joint: G0 tau, G1 p + G0 wv and the payload link's G1 py + G0 wy (10)
MODE_PAYLOAD = 0
MODE_ARM = 1


class EstCfg(NamedTuple):
    """Everything the compiled step needs (built by ``est_init``; read-only).

    Attributes
    ----------
    ch : Chain
        Kinematics of the arm.
    mode : int
        0 payload (10 parameters of the payload, arm known), 1 mode "arm" (the arm's base
        parameters, then the payload's ten: ``p = indep.size + 10``; the
        payload's columns are link ``jp``'s through ``pmap``, ``pbasis`` selects the last ten).
    pi0 : (13 n,)
        Standard parameters of the known (nominal) arm, without payload.
    jp : int
        Link (0-based) that carries the payload frame.
    pmap : (10, 10)
        Payload parameters about the payload frame -> about link jp's joint frame.
    indep : (p,) int64
        Base columns of the standard regressor (mode "arm").
    Bpinv : (13 n, p)
        Mode "arm": the pseudo-inverse of the base map B (``B @ Bpinv == I``) followed
        by ``pinv(B) @ payload_basis``, so the payload block enters the model through B.
    sigma0 : (p,)
        ``B pi0`` and ten zeros (mode "arm"; zeros(10) in payload mode).
    pbasis : (p, 10)
        How the payload's ten parameters move theta (identity in payload mode).
    pbasis_pinv : (10, p)
        Pseudo-inverse of ``pbasis``.
    U : (p, r)
        Orthonormal basis of the payload subspace of theta (re-opened on an alarm).
    P_reopen : (p, p)
        Covariance put along U on an alarm.
    A, Bf, C, D : filter bank matrices (order x order, order, 2 x order, 2)
    xs0 : (order,)
        Filter state of a unit constant input.
    Am, Bm, Cm, Dm : the bank's summing realisation (order x order, order x 2, order, 2)
        One state, inputs ``u0, u1``, output ``G0 u0 + G1 u1``
        (:func:`~adaptive_dd.identification.filters.summing_realisation`; the momentum form).
    xm1 : (order,)
        Its state of a unit constant ``u1`` and ``u0 = 0``.
    w : (n,)
        Row weights: equation j is divided by ``w[j]`` (the rows' updates and the detector's
        prior errors).
    ints : (N_I,) int64, floats : (N_F,) float64
        Scalar settings, slots ``I_*`` and ``F_*`` of this module.
    vdet : (n,)
        The sensor's velocity noise variance per joint [(rad/s)^2] (the detector's
        :func:`_ref_rise`: how much a payload raises each row's noise).
    """

    ch: Chain
    mode: int
    pi0: np.ndarray
    jp: int
    pmap: np.ndarray
    indep: np.ndarray
    Bpinv: np.ndarray
    sigma0: np.ndarray
    pbasis: np.ndarray
    pbasis_pinv: np.ndarray
    U: np.ndarray
    P_reopen: np.ndarray
    A: np.ndarray
    Bf: np.ndarray
    C: np.ndarray
    D: np.ndarray
    xs0: np.ndarray
    Am: np.ndarray
    Bm: np.ndarray
    Cm: np.ndarray
    Dm: np.ndarray
    xm1: np.ndarray
    w: np.ndarray
    ints: np.ndarray
    floats: np.ndarray
    vdet: np.ndarray


# integer slots of EstCfg.ints
I_ALIGN = 0
I_SELECT = 1
I_SEL_MEMORY = 2  # samples
I_TAINT = 3  # samples
I_DETECT = 4
I_WARMUP = 5  # samples
I_MIN_LEARNED = 6
I_HOLDOFF = 7
I_RESUME = 8
I_FREEZE = 9
I_REOPEN_AGAIN = 10
I_PROJECT = 11
I_GATE_AFTER = 12  # learned samples before the learning gate applies
I_N_ROWS = 13  # rows (joints 0 .. n_rows-1) that carry information
I_MOMENTUM = 14  # 1: the regression in momentum form (payload mode)
I_MIN_ROWS = 15  # rows whose short average must exceed (threshold / 2)^2 times their level for an alarm
I_FAST = 16  # 1: the fast average may also raise an alarm
I_RESET_PAYLOAD = 17  # mode "arm": an alarm sets the payload block (theta's last ten) to zero
I_FAST_LEARNED = 18  # samples a row's own level must have learned before its fast average may alarm
I_HOLD = 19  # samples a risen row is judged against the level it had when it rose (0: no hold)
I_KEEP_START = 20  # 1: control keeps the starting payload until the first alarm (_keep_start)
N_I = 21

# float slots of EstCfg.floats
F_LAM0 = 0
F_MU = 1
F_CAP = 2  # trace cap of P (<= 0: none)
F_SEL_THRESHOLD = 3
F_ALPHA_SHORT = 4
F_ALPHA_LONG = 5
F_THRESHOLD2 = 6
F_SLOW2 = 7
F_GATE2 = 8
F_EIG_MIN = 9  # smallest eigenvalue kept in the projected pseudo-inertia
F_FLOOR2 = 10  # floor of the detector's level (squared weighted error)
F_RADIUS = 11  # radius [m] of the ball about the payload frame the projected payload lies in (0: none)
F_PRIOR_RADIUS = 12  # radius [m] of the compact-payload prior on the model control uses (0: none)
F_ALPHA_FAST = 13  # the fast average's weight of a sample
F_FAST2 = 14  # the fast average's threshold (squared RMS ratio)
F_DET_SPEED = 15  # [rad/s] a joint no faster within the selection memory creeps
F_CREEP_MARGIN = 16  # a creeping joint's row alarms only beyond this times its Coulomb friction
F_HOLD_ABOVE2 = 17  # a row rises when its short average exceeds this x the threshold x its level
F_PRESENT2 = 18  # payload mode: the variance [kg^2] of a payload's mass when one is carried (0: no weight)
N_F = 19


class EstState(NamedTuple):
    """State of a batch of estimators; every array has the trial axis first.

    Attributes
    ----------
    xf : (m, SIGNAL_CHANNELS n, order) or (m, MOMENTUM_CHANNELS n, order)
        Filter states: signals form, of the channels ``q, qd, tau, sgn(qd)`` (n each);
        momentum form, of ``G0 tau``, ``G1 p + G0 wv`` (n each) and ``G1 py + G0 wy`` (10 n,
        row-major (n, 10)).
    u_last : (m, 4 n)
        Last finite channel sample (held over a dropout).
    tau_prev : (m, n)
        Torque of the previous sample (alignment).
    cnt : (m, N_CNT) int64
        Counters, columns ``C_*`` (samples, skipped, alarms, last alarm, ...).
    since_slow : (m, n) int64
        Samples since joint j was last slow (data selection).
    seen, learned : (m, n) int64
        Detector: rows seen and rows learned by the long-run level since the last alarm.
    theta : (m, p)
        The estimator's estimate (unprojected).
    P : (m, p, p)
        Its covariance.
    lam : (m,)
        Forgetting factor.
    short, long : (m, n)
        Detector averages of the squared weighted prior errors.
    ref : (m, n)
        Level each row had established before the last alarm (0: none), without the floor
        (applied where it serves, after :func:`_ref_rise`'s factor).
    eps : (m, n)
        Weighted prior errors of the last sample (NaN where a row was not used).
    fast : (m, n)
        Detector: the fast average of the squared weighted prior errors (``fast_window``).
    since_crawl : (m, n) int64
        Detector: samples since joint j was last no faster than the detector's speed
        (``F_DET_SPEED``; its row raises alarms only past the selection memory).
    hold : (m, n)
        Detector: the level row j had when its short average rose (> 0: judged against it),
        -1 once the hold has run out while the row is still raised, 0: no hold.
    held : (m, n) int64
        Detector: samples since row j's hold began.
    ref_pay : (m, 10)
        Detector: the payload the model held (as control uses it) when ``ref`` was set, at the
        last alarm (:func:`_ref_rise`).
    ref_rise : (m, n)
        Detector: how much the payload the estimate holds raises row j's noise variance over
        ``ref_pay`` (at least 1; 1 where ``ref`` does not serve), :func:`_ref_rise`.
    start_pay : (m, 10)
        The payload the model control uses at the start (kept until the estimate follows:
        :func:`_keep_start`).
    start_mass : (m,)
        The estimate's payload mass at the start [kg].
    """

    xf: np.ndarray
    u_last: np.ndarray
    tau_prev: np.ndarray
    cnt: np.ndarray
    since_slow: np.ndarray
    seen: np.ndarray
    learned: np.ndarray
    theta: np.ndarray
    P: np.ndarray
    lam: np.ndarray
    short: np.ndarray
    long: np.ndarray
    ref: np.ndarray
    eps: np.ndarray
    fast: np.ndarray
    since_crawl: np.ndarray
    hold: np.ndarray
    held: np.ndarray
    ref_pay: np.ndarray
    ref_rise: np.ndarray
    start_pay: np.ndarray
    start_mass: np.ndarray


class EstWork(NamedTuple):
    """Scratch of one trial's step and model (:func:`est_work`): allocated once per run of
    trials, not at every sample (:func:`est_step_trial_in`, :func:`est_model_trial_in`).

    Attributes
    ----------
    chain : tuple
        ``workspace(n)`` of :mod:`adaptive_dd.plant.chain`.
    a2 : (2, 6, 10); a1 : (6, 10)
        Scratch of ``momentum_form_in`` and ``rnea_body_regressor_in``.
    u : (4 n,)
        The channels ``q, qd, tau, sgn(qd)`` of this sample.
    qf, qdf, qddf, sf, tf, ym : (n,)
        Filtered signals (see :func:`_filtered_signals`).
    phim : (n, 10)
    act : (n,) bool
        Rows used at this sample.
    phi : (n, p); y : (n,)
        The regression.
    pphi, row : (p,); nz : (p,) int64
        Scratch of :func:`_rls_row`.
    u1, u0, yf : (MOMENTUM_CHANNELS n,)
        The momentum form's inputs (G1, G0) and outputs; ``p, wv (n,)`` and ``py, wy (n, 10)``
        are views into ``u1, u0``.
    known : (n,); yb : (n, 10); W : (n, 10 n)
        Scratch of the signals form's regression.
    raw, raw_est, pay : (10,); Pc : (10, 10); d : (p,)
        Scratch of the model control uses.
    Mr, Mr0 : (n, n); pir : (10 n,)
        Scratch of the detector's :func:`_ref_rise`.
    """

    chain: tuple
    a2: np.ndarray
    a1: np.ndarray
    u: np.ndarray
    qf: np.ndarray
    qdf: np.ndarray
    qddf: np.ndarray
    sf: np.ndarray
    tf: np.ndarray
    ym: np.ndarray
    phim: np.ndarray
    act: np.ndarray
    phi: np.ndarray
    y: np.ndarray
    pphi: np.ndarray
    row: np.ndarray
    nz: np.ndarray
    u1: np.ndarray
    u0: np.ndarray
    yf: np.ndarray
    p: np.ndarray
    wv: np.ndarray
    py: np.ndarray
    wy: np.ndarray
    known: np.ndarray
    yb: np.ndarray
    W: np.ndarray
    raw: np.ndarray
    raw_est: np.ndarray
    pay: np.ndarray
    Pc: np.ndarray
    d: np.ndarray
    Mr: np.ndarray
    Mr0: np.ndarray
    pir: np.ndarray


@njit(cache=True)
def est_work(n, p):  # pragma: no cover - compiled
    """Scratch (:class:`EstWork`) of a trial's step and model, n joints, p parameters."""
    nch = MOMENTUM_CHANNELS * n
    u1, u0 = np.zeros(nch), np.zeros(nch)
    return EstWork(
        workspace(n), np.empty((2, 6, 10)), np.empty((6, 10)), np.empty(4 * n),
        np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty((n, 10)),
        np.zeros(n, dtype=np.bool_), np.empty((n, p)), np.empty(n),
        np.empty(p), np.empty(p), np.empty(p, dtype=np.int64),
        u1, u0, np.empty(nch), u1[n : 2 * n], u0[n : 2 * n],
        u1[2 * n :].reshape((n, 10)), u0[2 * n :].reshape((n, 10)),
        np.empty(n), np.empty((n, 10)), np.empty((n, 10 * n)),
        np.empty(10), np.empty(10), np.empty(10), np.empty((10, 10)), np.empty(p),
        np.empty((n, n)), np.empty((n, n)), np.empty(10 * n),
    )  # fmt: skip


@njit(cache=True)
def _filter_channels(c, s, i, u, f, ch0):  # pragma: no cover - compiled
    """One sample of the bank on channels ``ch0 ...`` of trial i: ``f[ch] = [G0 u, G1 u]``."""
    A, Bf, C, D = c.A, c.Bf, c.C, c.D
    order = A.shape[0]
    xf = s.xf[i, ch0:]
    tmp = np.empty(order)
    for ch in range(u.shape[0]):
        for o in range(2):
            acc = D[o] * u[ch]
            for m in range(order):
                acc += C[o, m] * xf[ch, m]
            f[ch, o] = acc
        for m in range(order):
            acc = Bf[m] * u[ch]
            for k in range(order):
                acc += A[m, k] * xf[ch, k]
            tmp[m] = acc
        for m in range(order):
            xf[ch, m] = tmp[m]


@njit(cache=True, inline="always")
def _filtered_signals(c, s, i, q, qd, tau, w):  # pragma: no cover - compiled
    """Filter sample (q, qd, tau) of trial i into ``w`` (:class:`EstWork`); return True if the
    filtered equations are usable.

    Signals form: ``w.qf, w.qdf, w.qddf, w.sf, w.tf``. Momentum form (``I_MOMENTUM``): ``w.tf``,
    ``w.ym = G1 p + G0 wv`` (n,) of the known links and ``w.phim = G1 py + G0 wy`` (n, 10) of
    the payload's link (:func:`momentum_form_in`), at the held channels.
    """
    n = q.shape[0]
    cnt = s.cnt[i]
    start = cnt[C_STARTED] == 0
    u = w.u
    for j in range(n):
        t = tau[j]
        if c.ints[I_ALIGN] == 1:
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
    if c.ints[I_ALIGN] == 1:
        for j in range(n):
            if np.isfinite(tau[j]):
                s.tau_prev[i, j] = tau[j]
    if cnt[C_STARTED] == 0:  # the filters start in the steady state of the first sample
        for k in range(4 * n):
            s.u_last[i, k] = u[k] if np.isfinite(u[k]) else 0.0
            if c.ints[I_MOMENTUM] == 0:  # (the momentum form starts its own, _momentum_channels)
                for m in range(c.xs0.shape[0]):
                    s.xf[i, k, m] = s.u_last[i, k] * c.xs0[m]
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
    if c.ints[I_MOMENTUM] == 1 and c.mode == MODE_ARM:
        _arm_momentum_channels(c, s, i, start or cnt[C_RESTART] == 1, w)
        cnt[C_RESTART] = 0
        return cnt[C_SINCE_BAD] > c.ints[I_TAINT]
    if c.ints[I_MOMENTUM] == 1:
        _momentum_channels(c, s, i, start or cnt[C_RESTART] == 1, w)
        cnt[C_RESTART] = 0
        return cnt[C_SINCE_BAD] > c.ints[I_TAINT]
    f = np.empty((4 * n, 2))
    _filter_channels(c, s, i, u, f, 0)
    qf, qdf, qddf, tf, sf = w.qf, w.qdf, w.qddf, w.tf, w.sf
    for j in range(n):
        qf[j] = f[j, 0]
        qdf[j] = f[n + j, 0]
        qddf[j] = f[n + j, 1]
        tf[j] = f[2 * n + j, 0]
        sf[j] = f[3 * n + j, 0]
    return cnt[C_SINCE_BAD] > c.ints[I_TAINT]


@njit(cache=True)
def _summed_channels(Am, Bm, Cm, Dm, xf, u1, u0, y):  # pragma: no cover - compiled
    """One sample of the summing realisation (``Am, Bm, Cm, Dm``) on every channel of ``xf``:
    ``y = G1 u1 + G0 u0``, the states advanced in place (order 2 written out, its matrices in
    scalars: a call per channel would cost more than its arithmetic)."""
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
    tmp = np.empty(order)
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
    momentum_form_in(c.ch, c.pi0[: 10 * n], c.jp, u[:n], u[n : 2 * n], w.chain, w.a2, p, wv, py, wy)
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
    _summed_channels(c.Am, c.Bm, c.Cm, c.Dm, xf, u1, u0, y)
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
    u1 = np.zeros(nch)
    u0 = np.zeros(nch)
    y = np.empty(nch)
    pm, wv = np.empty(n), np.empty(n)
    py, wy = np.empty((n, 10)), np.empty((n, 10))
    q, qd = u[:n], u[n : 2 * n]
    for r in range(n):
        u0[r] = u[2 * n + r]
    for j in range(n):
        momentum_form_in(c.ch, c.pi0[: 10 * n], j, q, qd, w.chain, w.a2, pm, wv, py, wy)
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
    _summed_channels(c.Am, c.Bm, c.Cm, c.Dm, xf, u1, u0, y)
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
def _regression(c, qf, qdf, qddf, sf, tf, ym, phim, phi, y, w):  # pragma: no cover - compiled
    """The regression ``y = phi theta`` (n x p) at the filtered signals (or in momentum form);
    ``w`` (:class:`EstWork`) its scratch."""
    n = qf.shape[0]
    p = phi.shape[1]
    if c.mode == MODE_ARM and c.ints[I_MOMENTUM] == 1:  # written by _arm_momentum_channels
        return
    if c.mode == MODE_PAYLOAD and c.ints[I_MOMENTUM] == 1:
        for r in range(n):
            y[r] = tf[r]
        _payload_rows(c, phim, ym, phi, y)
        return
    if c.mode == MODE_PAYLOAD:
        known, yb = w.known, w.yb
        # rnea and the payload link's regressor at one state: its kinematics computed once
        rnea_body_regressor_in(c.ch, c.pi0[: 10 * n], c.jp, qf, qdf, qddf, w.chain, w.a1, known, yb)
        for r in range(n):
            fv, fc, ia = c.pi0[10 * n + r], c.pi0[11 * n + r], c.pi0[12 * n + r]
            y[r] = tf[r]
            known[r] += fv * qdf[r] + fc * sf[r] + ia * qddf[r]
        _payload_rows(c, yb, known, phi, y)
        return
    W = w.W
    regressor(c.ch, qf, qdf, qddf, W)
    pb = c.indep.shape[0]
    base = 10 * c.jp
    for r in range(n):
        y[r] = tf[r]
        for k in range(pb):
            col = c.indep[k]
            if col < 10 * n:
                phi[r, k] = W[r, col]
            else:
                kind = (col - 10 * n) // n
                jj = (col - 10 * n) % n
                if jj != r:
                    phi[r, k] = 0.0
                elif kind == 0:
                    phi[r, k] = qdf[r]
                elif kind == 1:
                    phi[r, k] = sf[r]
                else:
                    phi[r, k] = qddf[r]
        # mode "arm": the payload's ten columns after the arm's base ones (the payload link's
        # columns through pmap, as in payload mode)
        for k in range(p - pb):
            acc = 0.0
            for m in range(10):
                acc += W[r, base + m] * c.pmap[m, k]
            phi[r, pb + k] = acc


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
    for a in range(p):
        ga = pphi[a]
        for b in range(p):
            P[a, b] -= ga * pphi[b]
    if lam_eff != 1.0:
        il = 1.0 / lam_eff
        for a in range(p):
            for b in range(p):
                P[a, b] *= il
    return eps


@njit(cache=True)
def _reopen(c, P):  # pragma: no cover - compiled
    """``P <- (I - U U^T) P (I - U U^T) + P_reopen``: forget what was known along the payload subspace."""
    U = c.U
    p, r = U.shape
    # Q = P U (p x r), S = U^T P U (r x r)
    Q = np.zeros((p, r))
    for a in range(p):
        for k in range(r):
            acc = 0.0
            for b in range(p):
                acc += P[a, b] * U[b, k]
            Q[a, k] = acc
    S = np.zeros((r, r))
    for k in range(r):
        for m in range(r):
            acc = 0.0
            for a in range(p):
                acc += U[a, k] * Q[a, m]
            S[k, m] = acc
    # (I-UU^T)P(I-UU^T) = P - U Q^T - Q U^T + U S U^T
    for a in range(p):
        for b in range(p):
            acc = P[a, b]
            for k in range(r):
                acc -= U[a, k] * Q[b, k] + Q[a, k] * U[b, k]
                for m in range(r):
                    acc += U[a, k] * S[k, m] * U[b, m]
            P[a, b] = acc + c.P_reopen[a, b]


@njit(cache=True)
def _ref_rise(c, s, i, q, w):  # pragma: no cover - compiled
    """``s.ref_rise[i]``: per row, how much the payload the estimate now holds raises the row's
    noise variance over the payload it held at the last alarm (``s.ref_pay[i]``), at least 1;
    1 outside the window in which a row is judged against its level of before that alarm.

    The rows' noise is the measured velocity's through the inertia (``G1 (M qd)`` in momentum
    form, ``M qdd`` at the filtered signals): row j's variance ``(M diag(vn^2) M^T)_jj``, ``M``
    the model's inertia (armature included) at the measured q with the payload folded into its
    link, ``vn^2`` the sensor's velocity noise (``c.vdet``). A payload picked up raises it, and
    the level kept from before the pick-up (``ref``) is then too low for the re-learning window:
    the Kinova Gen3 with 2 kg, the wrist rows' noise 5x, a second alarm 0.3-0.45 s after the
    pick-up in 5 of 50 trials (``docs/change_detection.md``, "The level kept over a pick-up").
    Computed only in that window (two inertia matrices a sample).
    """
    n = q.shape[0]
    ints = c.ints
    k = s.cnt[i, C_SINCE_ALARM]
    live = ints[I_HOLDOFF] <= k < ints[I_RESUME] + ints[I_MIN_LEARNED]
    if live:
        live = False
        for j in range(n):
            live = live or s.ref[i, j] > 0.0
    for j in range(n):
        s.ref_rise[i, j] = 1.0
    if not live:
        return
    raw, pay, pi = w.raw, w.pay, w.pir
    _payload_raw(c, s.theta[i], raw)
    _control_payload(c, s, i, raw, pay, w.Pc)
    for t in range(2):
        M = w.Mr if t == 0 else w.Mr0
        src = pay if t == 0 else s.ref_pay[i]
        for a in range(10 * n):
            pi[a] = c.pi0[a]
        base = 10 * c.jp
        for a in range(10):
            acc = 0.0
            for b in range(10):
                acc += c.pmap[a, b] * src[b]
            pi[base + a] += acc
        mass_matrix_in(c.ch, pi, q, w.chain, M)
        for j in range(n):
            M[j, j] += c.pi0[12 * n + j]
    for j in range(n):
        v1, v0 = 0.0, 0.0
        for k2 in range(n):
            v1 += w.Mr[j, k2] * w.Mr[j, k2] * c.vdet[k2]
            v0 += w.Mr0[j, k2] * w.Mr0[j, k2] * c.vdet[k2]
        if v0 > 0.0 and v1 > v0 and np.isfinite(v1):
            s.ref_rise[i, j] = v1 / v0


@njit(cache=True, inline="always")
def _detect(c, s, i, eps, act):  # pragma: no cover - compiled
    """Update the detector of trial i with the rows' prior errors; return True on an alarm.

    Per row j: a short average of ``eps_j^2`` against a long-run level, the
    bias-corrected average ``long / (1 - (1 - a)^learned)`` of what it learned. The
    level learns from ``resume`` samples after the last alarm on, and not from a
    sample whose ``eps^2`` exceeds ``gate^2`` times the level (once ``gate_after``
    samples are learned), so that a change during the learning is not absorbed.
    A row may alarm once it has been *seen* ``min_learned`` times since the last alarm
    (seen, not learned: gated samples count, so the re-arm time is bounded), outside
    the warm-up and the hold-off. Until then, and for at most ``resume + min_learned``
    samples after the alarm (the re-arm bound of a row in use throughout), a row that had
    established its level
    before the last alarm is compared with that level (``ref``, raised by the noise the
    estimate's new payload adds to the row, :func:`_ref_rise`, with the threshold
    times ``slow``, as the estimate may still be converging): a change that
    follows a false alarm within the re-learning time is detected after the hold-off.
    Past that bound such a row, not yet seen ``min_learned`` times (it was out of use), is
    compared with what it has learned since, once that is ``gate_after`` samples (the count
    after which the level is trusted to gate its own learning), with the same stricter
    threshold.
    ``ref`` is set only from an established level, so this adds at most one alarm
    (a swap that raises the noise level cannot chain alarms through it). Its time is bounded
    because a swap changes the noise level itself (the measured velocity's noise enters the
    regression times the inertia each row carries): a row out of use after a swap's alarm
    (slow, reversing) saw nothing of the new noise, and kept comparing it with the stale
    level for as long as it stayed out of use (iiwa 14, 3 kg picked up: joint 6's prior error
    0.09 -> 0.5 RMS, 0.03 of it without sensor noise; 17 of 50 trials with a false alarm 0.5-0.8 s
    after the swap before the bound, 1 of 50 after it, ``docs/learning_the_arm.md``). The level is at
    least ``floor^2``: a row that is nearly noise-free (a wrist joint) would otherwise
    alarm on the regression's own modelling error, which varies with the motion. The
    threshold is ``slow^2`` times higher while another row is out of use (a joint that
    is slow or reversing disturbs the others).
    """
    n = eps.shape[0]
    ints, fl = c.ints, c.floats
    a_s, a_l = fl[F_ALPHA_SHORT], fl[F_ALPHA_LONG]
    cnt = s.cnt[i]
    learn = cnt[C_SINCE_ALARM] >= ints[I_RESUME]
    rise2 = fl[F_HOLD_ABOVE2] * fl[F_THRESHOLD2]
    for j in range(n):
        if s.hold[i, j] > 0.0:  # a hold runs out I_HOLD samples after the rise, in use or not
            s.held[i, j] += 1
            if s.held[i, j] > ints[I_HOLD]:
                s.hold[i, j] = -1.0
        e = eps[j]
        if not (act[j] and np.isfinite(e)):
            continue
        e2 = e * e
        s.short[i, j] += a_s * (e2 - s.short[i, j])
        s.fast[i, j] += fl[F_ALPHA_FAST] * (e2 - s.fast[i, j])
        if learn:
            s.seen[i, j] += 1
            nl = s.learned[i, j]
            # a level learned over min_learned samples since the last alarm is established
            est = nl >= ints[I_MIN_LEARNED]
            level = fl[F_FLOOR2]
            if nl >= 1:
                level = max(s.long[i, j] / (1.0 - (1.0 - a_l) ** nl), fl[F_FLOOR2])
            ok = True
            if nl >= ints[I_GATE_AFTER]:
                ok = e2 <= fl[F_GATE2] * level
            if ints[I_HOLD] > 0 and est:
                # a row whose short average rises is judged against the level it had then, for
                # I_HOLD samples (a change's rise); the level itself learns on
                if s.hold[i, j] == 0.0:
                    if s.short[i, j] > rise2 * level:
                        s.hold[i, j] = level
                        s.held[i, j] = 0
                elif s.short[i, j] <= rise2 * (s.hold[i, j] if s.hold[i, j] > 0.0 else level):
                    s.hold[i, j] = 0.0  # back below: the next rise holds again
            if ok:
                s.long[i, j] += a_l * (e2 - s.long[i, j])
                s.learned[i, j] = nl + 1
    if cnt[C_K] < ints[I_WARMUP] or cnt[C_SINCE_ALARM] <= ints[I_HOLDOFF]:
        return False
    n_act = 0
    for j in range(n):
        if act[j]:
            n_act += 1
    alarm = False
    n_raised = 0  # rows above a quarter of the threshold (half of it in RMS)
    fast = False
    n_fast = 0  # the same for the fast average and its threshold
    for j in range(n):
        if not act[j]:
            continue
        nl = s.learned[i, j]
        thr = fl[F_THRESHOLD2] if n_act == ints[I_N_ROWS] else fl[F_THRESHOLD2] * fl[F_SLOW2]
        own = s.seen[i, j] >= ints[I_MIN_LEARNED] and nl >= 1
        if own:
            level = max(s.long[i, j] / (1.0 - (1.0 - a_l) ** nl), fl[F_FLOOR2])
            if s.hold[i, j] > 0.0:  # risen within the hold: the level it had before
                level = s.hold[i, j]
        elif s.ref[i, j] > 0.0 and cnt[C_SINCE_ALARM] < ints[I_RESUME] + ints[I_MIN_LEARNED]:
            # still re-learning, within the re-arm bound: the level established before the last
            # alarm, raised by what the new payload adds to the row's noise (_ref_rise), with the
            # stricter threshold (the estimate may still converge)
            level = max(s.ref[i, j] * s.ref_rise[i, j], fl[F_FLOOR2])
            thr = fl[F_THRESHOLD2] * fl[F_SLOW2]
        elif s.ref[i, j] > 0.0 and nl >= ints[I_GATE_AFTER]:
            # past the bound, not yet seen enough: what it learned since (trusted as for the gate)
            level = max(s.long[i, j] / (1.0 - (1.0 - a_l) ** nl), fl[F_FLOOR2])
            thr = fl[F_THRESHOLD2] * fl[F_SLOW2]
        else:
            continue
        # a joint at most the detector's speed within the selection memory creeps: friction the
        # model lacks errs there (Stribeck, soft friction), by less than the joint's Coulomb
        # friction; its row raises an alarm only beyond that (in the weighted equation's units)
        creep2 = 0.0
        if ints[I_SELECT] == 1 and s.since_crawl[i, j] <= ints[I_SEL_MEMORY]:
            creep2 = (fl[F_CREEP_MARGIN] * c.pi0[11 * n + j] / c.w[j]) ** 2
        if s.short[i, j] > thr * level + 1e-300 and s.short[i, j] > creep2:
            alarm = True
        if s.short[i, j] > 0.25 * thr * level + 1e-300:
            n_raised += 1
        if ints[I_FAST] == 1 and own and nl >= ints[I_FAST_LEARNED]:
            # only against a level the row has learned itself over the long window: not the
            # level of before an alarm, nor one still learning a new payload or the arm
            thf = fl[F_FAST2] * thr / fl[F_THRESHOLD2]  # the same slow-row and re-learning factors
            if s.fast[i, j] > thf * level + 1e-300 and s.fast[i, j] > creep2:
                fast = True
            if s.fast[i, j] > 0.25 * thf * level + 1e-300:
                n_fast += 1
    return (alarm and n_raised >= ints[I_MIN_ROWS]) or (fast and n_fast >= ints[I_MIN_ROWS])


@njit(cache=True)
def _alarm(c, s, i, k):  # pragma: no cover - compiled
    """What an alarm at sample k does: re-open P, count, restart the level (keeping it as ``ref``)."""
    ints, fl = c.ints, c.floats
    cnt = s.cnt[i]
    # the payload the model holds now, with which the levels kept as ref were learnt
    raw = np.empty(10)
    _payload_raw(c, s.theta[i], raw)
    _control_payload(c, s, i, raw, s.ref_pay[i], np.empty((10, 10)))
    if _keeps_start(c, s, i):
        for a in range(10):
            s.ref_pay[i, a] = s.start_pay[i, a]
    cnt[C_FOLLOWS] = 1
    _reopen(c, s.P[i])
    if ints[I_RESET_PAYLOAD] == 1:  # a new payload: nothing known of it but its prior
        p = s.theta.shape[1]
        for a in range(p - 10, p):  # (not k: the alarm's sample, recorded below)
            s.theta[i, a] = 0.0
    cnt[C_ALARMS] += 1
    cnt[C_SINCE_ALARM] = 0
    cnt[C_LAST_ALARM] = k
    a_l = fl[F_ALPHA_LONG]
    for j in range(s.seen.shape[1]):
        nl = s.learned[i, j]
        # the level this row had established (0: none) serves until it re-learns; kept without
        # the floor (applied where it serves), so that a noise rise scales what was learnt
        s.ref[i, j] = 0.0
        if s.seen[i, j] >= ints[I_MIN_LEARNED] and nl >= 1:
            s.ref[i, j] = max(s.long[i, j] / (1.0 - (1.0 - a_l) ** nl), 1e-300)
        s.seen[i, j] = 0
        s.learned[i, j] = 0
        s.long[i, j] = 0.0
        s.hold[i, j] = 0.0
        s.held[i, j] = 0
    if ints[I_REOPEN_AGAIN] == 1:
        cnt[C_REOPEN_AT] = k + ints[I_FREEZE]
    if ints[I_MOMENTUM] == 1:
        cnt[C_RESTART] = 1


@njit(cache=True)
def est_force_alarm_trial(c, s, i):  # pragma: no cover - compiled
    """Raise an alarm on trial i at its last stepped sample, as if the detector had.

    For a caller that knows of a change (a tool changer's signal) and for tests of what
    follows an alarm. Does nothing before the first sample.
    """
    if s.cnt[i, C_K] > 0:
        _alarm(c, s, i, s.cnt[i, C_K] - 1)


@njit(cache=True)
def est_step_trial(c, s, i, q, qd, tau):  # pragma: no cover - compiled
    """Advance trial i by one sample in place; return 1 on a change alarm at this sample, else 0.

    :func:`est_step_trial_in` with its scratch allocated for this call.
    """
    return est_step_trial_w(c, s, i, q, qd, tau, est_work(q.shape[0], s.theta.shape[1]))


@njit(cache=True)
def est_step_trial_w(c, s, i, q, qd, tau, w):  # pragma: no cover - compiled
    """:func:`est_step_trial_in` as a compiled function of its own (not inlined where it is
    called): the estimator's step, the largest of its kernels, is then compiled once for
    :func:`est_step_trial`, :func:`est_step_batch` and :func:`est_run_trial` (each inlining it
    cost a full compilation of the step: about 25 CPU s on the UR5)."""
    return est_step_trial_in(c, s, i, q, qd, tau, w)


@njit(cache=True, inline="always")
def est_step_trial_in(c, s, i, q, qd, tau, w):  # pragma: no cover - compiled
    """Advance trial i by one sample in place; return 1 on a change alarm at this sample, else 0.

    Parameters
    ----------
    c : EstCfg
    s : EstState
    i : int
        Trial index.
    q, qd : (n,)
        Measured joint positions [rad] and velocities [rad/s] at this sample.
    tau : (n,)
        Torque applied over this sample [N m]. A non-finite q, qd or tau skips the
        sample (counted in ``cnt[i, C_SKIPPED]``).
    w : EstWork
        Scratch (:func:`est_work`), reused from sample to sample (one per thread).
    """
    n = q.shape[0]
    p = s.theta.shape[1]
    ints, fl = c.ints, c.floats
    cnt = s.cnt[i]
    usable = _filtered_signals(c, s, i, q, qd, tau, w)
    act = w.act
    n_rows = ints[I_N_ROWS]
    for j in range(n):
        if ints[I_SELECT] == 1:
            if np.isfinite(qd[j]) and abs(qd[j]) <= fl[F_SEL_THRESHOLD]:
                s.since_slow[i, j] = 0
            else:
                s.since_slow[i, j] = min(s.since_slow[i, j] + 1, BIG)
            act[j] = s.since_slow[i, j] > ints[I_SEL_MEMORY]
            if np.isfinite(qd[j]) and abs(qd[j]) <= fl[F_DET_SPEED]:
                s.since_crawl[i, j] = 0
            else:
                s.since_crawl[i, j] = min(s.since_crawl[i, j] + 1, BIG)
            if s.since_slow[i, j] == ints[I_SEL_MEMORY] + 1 and s.learned[i, j] > 0:
                # back in use after a slow phase: the short average restarts at the level
                nl = s.learned[i, j]
                s.short[i, j] = s.long[i, j] / (1.0 - (1.0 - fl[F_ALPHA_LONG]) ** nl)
                s.fast[i, j] = s.short[i, j]
        else:
            act[j] = True
        act[j] = act[j] and usable and j < n_rows
    for j in range(n):
        s.eps[i, j] = np.nan
    th, Pi = s.theta[i], s.P[i]
    if usable:
        phi, y = w.phi, w.y
        _regression(c, w.qf, w.qdf, w.qddf, w.sf, w.tf, w.ym, w.phim, phi, y, w)
        pphi, row, nz = w.pphi, w.row, w.nz
        first = True
        for j in range(n_rows):
            if not act[j]:
                continue
            if first:
                s.lam[i] = (1.0 - fl[F_MU]) * s.lam[i] + fl[F_MU]
            lam_eff = s.lam[i] if first else 1.0
            first = False
            wj = c.w[j]
            for k in range(p):
                row[k] = phi[j, k] / wj
            s.eps[i, j] = _rls_row(th, Pi, row, y[j] / wj, lam_eff, pphi, nz)
        if not first and fl[F_CAP] > 0.0:
            tr = 0.0
            for k in range(p):
                tr += Pi[k, k]
            if tr > fl[F_CAP]:
                scale = fl[F_CAP] / tr
                for a in range(p):
                    for b in range(p):
                        Pi[a, b] *= scale
    alarm = 0
    if ints[I_DETECT] == 1:
        if cnt[C_REOPEN_AT] == cnt[C_K]:
            _reopen(c, Pi)
        _ref_rise(c, s, i, q, w)
        alarm = _detect_step(c, s, i, s.eps[i], act)
        _keep_start(c, s, i)
    cnt[C_K] += 1
    return alarm


@njit(cache=True, inline="always")
def _keeps_start(c, s, i):  # pragma: no cover - compiled
    """Whether the model control uses still holds the starting payload (``s.start_pay[i]``)."""
    return c.ints[I_KEEP_START] == 1 and s.cnt[i, C_FOLLOWS] == 0


@njit(cache=True, inline="always")
def _keep_start(c, s, i):  # pragma: no cover - compiled
    """Let the model control uses follow the estimate once the payload has changed: at the first
    alarm (:func:`_alarm`), or once the estimated mass has moved from its start by more than the
    detector's threshold times its standard deviation ``sqrt(P_mm)`` after the detector's warm-up.

    Before that the model keeps the starting payload: with the arm exact nothing is left to learn,
    and the estimate's wander on the unloaded arm (the regression's noise and the filters'
    start-up) only moved the model away from the exact one (drawn arms, exact URDF: the first
    segment's adaptive_ct / ct_oracle up to 3.5x; docs/changelog.md). A payload carried from the
    start, or one the detector misses, still moves the mass beyond the bound."""
    cnt = s.cnt[i]
    if c.ints[I_KEEP_START] != 1 or cnt[C_FOLLOWS] == 1 or cnt[C_K] < c.ints[I_WARMUP]:
        return
    a = s.theta.shape[1] - 10  # the payload's mass (the payload block's first parameter)
    var = s.P[i, a, a]
    dm = s.theta[i, a] - s.start_mass[i]
    if not (dm * dm <= c.floats[F_THRESHOLD2] * var):  # (a non-finite estimate follows too)
        cnt[C_FOLLOWS] = 1


@njit(cache=True, inline="always")
def _detect_step(c, s, i, eps, act):  # pragma: no cover - compiled
    """The detector's part of a sample: :func:`_detect`, then the alarm or the count since it."""
    cnt = s.cnt[i]
    if _detect(c, s, i, eps, act):
        _alarm(c, s, i, cnt[C_K])
        return 1
    cnt[C_SINCE_ALARM] = min(cnt[C_SINCE_ALARM] + 1, BIG)
    return 0


@njit(cache=True)
def est_detect_trial(c, s, i, eps, act):  # pragma: no cover - compiled
    """One sample of trial i's detector alone on given weighted prior errors ``eps (n,)`` of the
    rows in use ``act (n,)`` (bool): 1 on an alarm, else 0. The estimate is not stepped (an alarm
    still re-opens its covariance). For tests and replays of the detector on synthetic errors."""
    alarm = _detect_step(c, s, i, eps, act)
    s.cnt[i, C_K] += 1
    return alarm


@njit(cache=True, inline="always")
def _payload_raw(c, th, raw):  # pragma: no cover - compiled
    """The payload (10,) implied by an estimate theta, unprojected (mode "arm": least squares on pbasis)."""
    p = th.shape[0]
    if c.mode == MODE_PAYLOAD:
        for k in range(10):
            raw[k] = th[k]
        return
    for k in range(10):
        acc = 0.0
        for a in range(p):
            acc += c.pbasis_pinv[k, a] * (th[a] - c.sigma0[a])
        raw[k] = acc


@njit(cache=True, inline="always")
def _inertia_cov(c, P, out):  # pragma: no cover - compiled
    """The inertia block ``out[4:, 4:]`` of the payload parameters' covariance (the part
    :func:`compact_prior` reads; the rest of ``out (10, 10)`` is left as it is): P's own block in
    payload mode, else that block of ``pbasis_pinv P pbasis_pinv^T``."""
    if c.mode == MODE_PAYLOAD:
        for a in range(4, 10):
            for b in range(4, 10):
                out[a, b] = P[a, b]
        return
    p = P.shape[0]
    tmp = np.zeros((10, p))
    for a in range(4, 10):
        for b in range(p):
            acc = 0.0
            for k in range(p):
                acc += c.pbasis_pinv[a, k] * P[k, b]
            tmp[a, b] = acc
    for a in range(4, 10):
        for b in range(4, 10):
            acc = 0.0
            for k in range(p):
                acc += tmp[a, k] * c.pbasis_pinv[b, k]
            out[a, b] = acc


@njit(cache=True)
def compact_prior(raw, Pc, rho):  # pragma: no cover - compiled
    """Combine ``raw (10,)`` (covariance ``Pc (10, 10)``, of which only the inertia block
    ``Pc[4:, 4:]`` is read, and overwritten) with a prior that the
    payload is compact: its inertia about the frame ``I = m S(c)^T S(c) + 0.4 m rho^2 1``
    (a solid sphere of radius ``rho`` [m] at the estimated centre of mass ``c`` with the
    estimated mass ``m``), each of the six inertia components with standard deviation
    ``m rho^2 + 1e-6`` [kg m^2]. Six scalar Kalman updates (pseudo-measurements of the
    inertia) on the inertia block of ``Pc``, given the mass and first moments: those are left
    as they are (they are the well-determined part; moving them through their correlation
    with the inertia corrupted the unloaded arm's model, where the prior pins the inertia).

    Right after a swap the data determine the payload's mass and first moments within
    tens of milliseconds but its inertia only over a second (the inertia's columns are
    weakly excited); the prior keeps the model control uses at a plausible inertia
    meanwhile, and the data override it as P shrinks (no effect once the inertia is known).
    """
    m = max(raw[0], 0.0)
    hx, hy, hz = raw[1], raw[2], raw[3]
    mean = np.zeros(6)
    if m > 1e-9:
        h2 = hx * hx + hy * hy + hz * hz
        sph = 0.4 * m * rho * rho
        # (|h|^2 1 - h h^T) / m + sphere; order Ixx, Ixy, Iyy, Ixz, Iyz, Izz
        mean[0] = (h2 - hx * hx) / m + sph
        mean[1] = -hx * hy / m
        mean[2] = (h2 - hy * hy) / m + sph
        mean[3] = -hx * hz / m
        mean[4] = -hy * hz / m
        mean[5] = (h2 - hz * hz) / m + sph
    std = m * rho * rho + 1e-6
    R = std * std
    g = np.empty(10)
    row = np.empty(10)
    for t in range(6):
        r = 4 + t
        S = Pc[r, r] + R
        if not (np.isfinite(S) and S > 0.0):
            return
        innov = mean[t] - raw[r]
        for a in range(4, 10):
            g[a] = Pc[a, r] / S
            row[a] = Pc[r, a]
        for a in range(4, 10):
            raw[a] += g[a] * innov
            for b in range(4, 10):
                Pc[a, b] -= g[a] * row[b]


@njit(cache=True)
def presence_weight(m, var, present_var):  # pragma: no cover - compiled
    """Posterior probability that a payload is carried, given a mass estimate ``m`` [kg] of
    variance ``var`` [kg^2] and the variance ``present_var`` [kg^2] of a carried payload's mass.

    The prior is even odds between no payload (mass exactly 0: the unloaded arm, the state at the
    start and after every put-down) and a payload whose mass is normal about 0 with variance
    ``present_var``. With ``m`` normal about the true mass, the likelihood ratio of the two is
    ``sqrt(1 + present_var / var) exp(-m^2 present_var / (2 var (var + present_var)))``, and the
    weight is ``1 / (1 + ratio)``: about ``sqrt(var / present_var)`` for an estimate that is noise
    about 0, 1 once the mass is a few of its standard deviations away from 0, 0.5 with no data
    (``var >> present_var``). 1 when either variance is not > 0 (no weighting).
    """
    if not (var > 0.0 and present_var > 0.0 and np.isfinite(m) and np.isfinite(var)):
        return 1.0
    a = m * m * present_var / (2.0 * var * (var + present_var))
    if a > 700.0:
        return 1.0
    return 1.0 / (1.0 + np.sqrt(1.0 + present_var / var) * np.exp(-a))


@njit(cache=True, inline="always")
def _control_payload(c, s, i, raw, pay, Pc):  # pragma: no cover - compiled
    """The payload the model control uses: ``raw`` with the compact prior (if set); projected (if set)
    and then, in payload mode, scaled by :func:`presence_weight` of the raw mass (its variance
    ``P[0, 0]``, a carried payload's ``F_PRESENT2``): the posterior mean of a payload that may be
    absent. A scaled consistent body stays consistent (its pseudo-inertia scaled by a factor in
    [0, 1], within the same ball). ``Pc (10, 10)`` scratch."""
    m_raw = raw[0]
    rho = c.floats[F_PRIOR_RADIUS]
    if rho > 0.0:
        _inertia_cov(c, s.P[i], Pc)
        compact_prior(raw, Pc, rho)
    if c.ints[I_PROJECT] == 1:
        project_payload(raw, pay, c.floats[F_EIG_MIN], c.floats[F_RADIUS])
        if c.mode == MODE_PAYLOAD and c.floats[F_PRESENT2] > 0.0:
            wp = presence_weight(m_raw, s.P[i][0, 0], c.floats[F_PRESENT2])
            for k in range(10):
                pay[k] *= wp
    else:
        for k in range(10):
            pay[k] = raw[k]


@njit(cache=True)
def est_payload_trial(c, s, i, out):  # pragma: no cover - compiled
    """The payload (10,) about its frame implied by trial i's estimate, projected if set to."""
    raw = np.empty(10)
    _payload_raw(c, s.theta[i], raw)
    _control_payload(c, s, i, raw, out, np.empty((10, 10)))


@njit(cache=True)
def est_model_trial(c, s, i, pi_out):  # pragma: no cover - compiled
    """The model control uses for trial i, as standard parameters ``pi_out (13 n,)``
    (:func:`est_model_trial_in` with its scratch allocated for this call)."""
    est_model_trial_in(c, s, i, pi_out, est_work(c.w.shape[0], s.theta.shape[1]))


@njit(cache=True, inline="always")
def est_model_trial_in(c, s, i, pi_out, w):  # pragma: no cover - compiled
    """The model control uses for trial i, as standard parameters ``pi_out (13 n,)``; ``w``
    (:class:`EstWork`) scratch.

    Payload mode: the arm's ``pi0`` with the (projected) payload folded into link ``jp``
    through ``pmap``. Full mode: ``pi0 + Bpinv (theta_p - B pi0)``, where ``theta_p`` is
    theta with its payload part replaced by the projected one
    (``theta_p = theta + pbasis (payload_projected - payload_raw)``), so that
    ``B pi_out == theta_p``.
    """
    m = pi_out.shape[0]
    for k in range(m):
        pi_out[k] = c.pi0[k]
    th = s.theta[i]
    p = th.shape[0]
    raw, pay = w.raw, w.pay
    _payload_raw(c, th, raw)
    raw_est = raw
    if c.mode != MODE_PAYLOAD:  # mode "arm": theta's own payload
        raw_est = w.raw_est
        for k in range(10):
            raw_est[k] = raw[k]
    _control_payload(c, s, i, raw, pay, w.Pc)
    if _keeps_start(c, s, i):
        for k in range(10):
            pay[k] = s.start_pay[i, k]
    if c.mode == MODE_PAYLOAD:
        base = 10 * c.jp
        for a in range(10):
            acc = 0.0
            for b in range(10):
                acc += c.pmap[a, b] * pay[b]
            pi_out[base + a] += acc
        return
    d = w.d
    for a in range(p):
        acc = th[a] - c.sigma0[a]
        for k in range(10):
            acc += c.pbasis[a, k] * (pay[k] - raw_est[k])
        d[a] = acc
    for k in range(m):
        acc = 0.0
        for a in range(p):
            acc += c.Bpinv[k, a] * d[a]
        pi_out[k] += acc


@njit(cache=True)
def est_step_batch(c, s, q, qd, tau, alarm):  # pragma: no cover - compiled
    """:func:`est_step_trial` over every trial (``q, qd, tau (m, n)``), alarms into ``alarm (m,)``."""
    w = est_work(q.shape[1], s.theta.shape[1])
    for i in range(q.shape[0]):
        alarm[i] = est_step_trial_w(c, s, i, q[i], qd[i], tau[i], w)


@njit(cache=True)
def est_run_trial(
    c, s, i, q, qd, tau, theta_rec, payload_rec, eps_rec, alarm_rec, lam_rec
):  # pragma: no cover
    """Step trial i through a record ``(N, n)``, recording after every sample."""
    pay = np.empty(10)
    w = est_work(q.shape[1], s.theta.shape[1])
    for k in range(q.shape[0]):
        alarm_rec[k] = est_step_trial_w(c, s, i, q[k], qd[k], tau[k], w)
        theta_rec[k] = s.theta[i]
        est_payload_trial(c, s, i, pay)
        payload_rec[k] = pay
        eps_rec[k] = s.eps[i]
        lam_rec[k] = s.lam[i]
