"""Layout of the N-joint online estimator's compiled configuration and state.

The columns of the per-trial counters ``EstState.cnt`` (``C_*``), the NamedTuples :class:`EstCfg` (read-only
configuration, built by :func:`~adaptive_dd.identification.online.est_init`), :class:`EstState`
(per-trial state, stepped in place) and :class:`EstWork` (a trial's scratch, :func:`est_work`).
The step itself is :mod:`~adaptive_dd.identification.online_kernel`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from adaptive_dd.plant.chain import (
    Chain,
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
MAX_FILTER_ORDER = 16
"""The largest order of the estimator's filter bank (its step's scratch, ``EstWork.ftmp``)."""
MOMENTUM_CHANNELS = 12  # per joint: G0 tau, G1 p + G0 wv and the payload link's G1 py + G0 wy (10)
MODE_PAYLOAD = 0
MODE_ARM = 1


class EstCfg(NamedTuple):
    """Everything the compiled step needs (built by ``est_init``; read-only): arrays, then the scalar
    settings of :class:`~adaptive_dd.identification.online_config.OnlineConfig` and its
    :class:`~adaptive_dd.identification.online_config.Detector` (in samples where those are in
    seconds, squared where the kernels compare squares).

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
    Am, Bm, Cm, Dm : the bank's summing realisation (order x order, order x 2, order, 2)
        One state, inputs ``u0, u1``, output ``G0 u0 + G1 u1``
        (:func:`~adaptive_dd.identification.filters.summing_realisation`; the momentum form).
    xm1 : (order,)
        Its state of a unit constant ``u1`` and ``u0 = 0``.
    w : (n,)
        Row weights: equation j is divided by ``w[j]`` (the rows' updates and the detector's
        prior errors).
    vdet : (n,)
        The sensor's velocity noise variance per joint [(rad/s)^2] (the detector's
        :func:`_ref_rise`: how much a payload raises each row's noise).
    vrow : (n,)
        The variance of weighted row j's error per unit of ``(M diag(vdet) M^T)_jj``: the noise
        gain of the filter ``G1`` over ``w[j]^2`` (the detector's :func:`_posture_noise`).
    align, project : bool
        Align the torque with the measurement (:attr:`OnlineConfig.align`); project the payload
        the model control uses onto consistent bodies (:attr:`OnlineConfig.project`).
    select : bool
        Data selection on (:attr:`OnlineConfig.selection`): a row is used once its joint has been
        faster than ``sel_threshold`` [rad/s] for ``sel_memory`` samples.
    taint : int
        Samples after a non-finite input during which the filtered equations are not used.
    n_rows : int
        Rows (joints ``0 .. n_rows - 1``) that carry information (payload mode: the payload's
        link and those before it).
    lam0, mu : float
        The forgetting factor's start and its rate towards 1 per sample.
    max_trace : float
        Cap on the trace of P (<= 0: none).
    eig_min, bound_radius : float
        The projection's smallest eigenvalue of the pseudo-inertia and the radius [m] of the ball
        about the payload frame the projected payload lies in (0: none).
    prior_radius, prior_noise, com_size, present2 : float
        The model's compact prior's radius [m] (0: none) and its weight against P scaled by the
        rows' learned noise (0: unscaled); the centred prior's length [m] on the first moments
        (0: none); payload mode's variance [kg^2] of a carried payload's mass (0: no presence
        weight) (:mod:`~adaptive_dd.identification.online_control_model`).
    detect : bool
        The change detector runs; the settings below are its (:class:`Detector`), 0 and false
        without it (their defaults).
    warmup, min_learned, holdoff, resume, freeze, gate_after, fast_learned, hold : int
        Samples: no alarm before ``warmup``; a row's own level once learned over
        ``min_learned``; no alarm ``holdoff`` after one; the level learns again ``resume`` after
        an alarm; the covariance re-opened once more ``freeze`` after one (if ``reopen_again``);
        the learning gate after ``gate_after`` learned samples; the fast average may alarm once
        the row has learned ``fast_learned``; a risen row is held against its level for ``hold``
        (0: no hold).
    reopen_again, fast, keep_start : bool
        Re-open once more after the filters' memory; the fast average may alarm; control keeps the
        starting payload until the payload changes (payload mode, :func:`_keep_start`).
    alpha_short, alpha_long, alpha_fast : float
        The averages' weights of a sample.
    threshold2, relearn2, gate2, fast2, hold_above2 : float
        Squared: the alarm's RMS ratio, its factor against a level not established since the last
        alarm, the learning gate's ratio, the fast average's threshold, the ratio at which a row
        rises.
    floor2 : float
        Floor of the detector's level (squared weighted error).
    det_speed, creep_margin : float
        A joint no faster than ``det_speed`` [rad/s] within the selection memory creeps; its row
        alarms only beyond ``creep_margin`` times its Coulomb friction.
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
    Am: np.ndarray
    Bm: np.ndarray
    Cm: np.ndarray
    Dm: np.ndarray
    xm1: np.ndarray
    w: np.ndarray
    vdet: np.ndarray
    vrow: np.ndarray
    align: bool
    project: bool
    select: bool
    sel_threshold: float
    sel_memory: int
    taint: int
    n_rows: int
    lam0: float
    mu: float
    max_trace: float
    eig_min: float
    bound_radius: float
    prior_radius: float
    prior_noise: float
    com_size: float
    present2: float
    # the detector's: zero and false without one
    detect: bool = False
    warmup: int = 0
    min_learned: int = 0
    holdoff: int = 0
    resume: int = 0
    freeze: int = 0
    gate_after: int = 0
    fast_learned: int = 0
    hold: int = 0
    reopen_again: bool = False
    fast: bool = False
    keep_start: bool = False
    alpha_short: float = 0.0
    alpha_long: float = 0.0
    alpha_fast: float = 0.0
    threshold2: float = 0.0
    relearn2: float = 0.0
    gate2: float = 0.0
    fast2: float = 0.0
    hold_above2: float = 0.0
    floor2: float = 0.0
    det_speed: float = 0.0
    creep_margin: float = 0.0


class EstState(NamedTuple):
    """State of a batch of estimators; every array has the trial axis first.

    Attributes
    ----------
    xf : (m, MOMENTUM_CHANNELS n, order) (payload mode) or (m, arm_momentum_channels(n), order)
        Filter states of the momentum form: ``G0 tau``, ``G1 p + G0 wv`` (n each) and
        ``G1 py + G0 wy`` (10 n, row-major (n, 10)); mode "arm": every link's.
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
    pvar : (m, n)
        The variance the estimate's covariance predicts for each row's prior error at the last
        sample, ``phi_j^T P phi_j`` in the recursive least squares' own scaling (0 where a row
        was not used): what the estimate's uncertainty adds to the row's noise.
    pshort, pfast : (m, n)
        Detector: ``pvar`` averaged by the short and the fast average (what they exceed the
        level's own share of it by is added to the level the squared errors' averages are
        judged against, :func:`_detect`).
    plong : (m, n)
        Detector: ``pvar`` averaged as the level learns (the share of the level that is the
        estimate's uncertainty).
    pref : (m, n)
        Detector: ``plong`` (bias-corrected) when ``ref`` was set, kept with it.
    eout : (m, n)
        Detector: the prior error at the last sample of each row out of use because its joint is
        slow (a reversal), at the estimate it does not update; NaN for the others.
    nvar : (m, n)
        Detector: the variance the measured velocity's noise gives weighted row j's error at the
        measured posture, ``vrow_j (M(q) diag(vdet) M(q)^T)_jj`` (the known arm's inertia, armature
        included), at the last sample
        (:func:`~adaptive_dd.identification.online_detector._posture_noise`).
    nshort, nlong : (m, n)
        Detector: ``nvar`` averaged as the short average and the level are (the level's at the
        samples it learns): what ``nshort`` exceeds ``nlong``'s mean by is what the posture adds
        to the row's noise over the postures the level was learnt at.
    nref : (m, n)
        Detector: ``nlong``'s mean for the level kept as ``ref`` at the last alarm.
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
    pvar: np.ndarray
    pshort: np.ndarray
    pfast: np.ndarray
    plong: np.ndarray
    pref: np.ndarray
    eout: np.ndarray
    nvar: np.ndarray
    nshort: np.ndarray
    nlong: np.ndarray
    nref: np.ndarray


class EstWork(NamedTuple):
    """Scratch of one trial's step and model (:func:`est_work`): allocated once per run of
    trials, not at every sample (:func:`est_step_trial_in`, :func:`est_model_trial_in`).

    Attributes
    ----------
    chain : tuple
        ``workspace(n)`` of :mod:`adaptive_dd.plant.chain`.
    a2 : (2, 6, 10)
        Scratch of ``momentum_form_in``.
    u : (4 n,)
        The channels ``q, qd, tau, sgn(qd)`` of this sample.
    tf, ym : (n,); phim : (n, 10)
        Payload mode's filtered equation ``tf - ym = phim pmap theta`` (:func:`_filtered_signals`).
    act : (n,) bool
        Rows used at this sample.
    phi : (n, p); y : (n,)
        The regression.
    pphi, row : (p,); nz : (p,) int64
        Scratch of :func:`_rls_row`.
    u1, u0, yf : (MOMENTUM_CHANNELS n,)
        The momentum form's inputs (G1, G0) and outputs; ``p, wv (n,)`` and ``py, wy (n, 10)``
        are views into ``u1, u0``.
    raw, raw_est, pay : (10,); Pc : (10, 10); d : (p,)
        Scratch of the model control uses (``pphi, row, d`` and ``Pc`` also serve its priors and
        projection, after the step's own use of them).
    Mr, Mr0 : (n, n); pir : (10 n,)
        Scratch of the detector's :func:`_ref_rise`.
    arm : (3 (4 n + 10 n^2) + 22 n,)
        Mode "arm"'s momentum channels, zeros (``_arm_momentum_channels``: its inputs, outputs and
        the momentum form's, as views; the inputs it never writes stay 0).
    ftmp : (MAX_FILTER_ORDER,)
        Scratch of a filter bank's step of an order other than 2 (``_summed_channels``).
    cov : (10, p); rq : (p, 10); rs : (10, 10)
        Scratch of the payload's inertia covariance in mode "arm" (``_inertia_cov``) and of an
        alarm's re-opening (``_reopen_in``).

    The step (``est_step_model``) is compiled without reference counting: nothing it calls may
    allocate, so every scratch it needs is here.
    """

    chain: tuple
    a2: np.ndarray
    u: np.ndarray
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
    raw: np.ndarray
    raw_est: np.ndarray
    pay: np.ndarray
    Pc: np.ndarray
    d: np.ndarray
    Mr: np.ndarray
    Mr0: np.ndarray
    pir: np.ndarray
    arm: np.ndarray
    ftmp: np.ndarray
    cov: np.ndarray
    rq: np.ndarray
    rs: np.ndarray


@njit(cache=True)
def est_work(n, p):  # pragma: no cover - compiled
    """Scratch (:class:`EstWork`) of a trial's step and model, n joints, p parameters."""
    nch = MOMENTUM_CHANNELS * n
    u1, u0 = np.zeros(nch), np.zeros(nch)
    return EstWork(
        workspace(n), np.empty((2, 6, 10)), np.empty(4 * n), np.empty(n), np.empty(n), np.empty((n, 10)),
        np.zeros(n, dtype=np.bool_), np.empty((n, p)), np.empty(n),
        np.empty(p), np.empty(p), np.empty(p, dtype=np.int64),
        u1, u0, np.empty(nch), u1[n : 2 * n], u0[n : 2 * n],
        u1[2 * n :].reshape((n, 10)), u0[2 * n :].reshape((n, 10)),
        np.empty(10), np.empty(10), np.empty(10), np.empty((10, 10)), np.empty(p),
        np.empty((n, n)), np.empty((n, n)), np.empty(10 * n),
        np.zeros(3 * (4 * n + 10 * n * n) + 22 * n), np.empty(MAX_FILTER_ORDER), np.empty((10, p)),
        np.empty((p, 10)), np.empty((10, 10)),
    )  # fmt: skip
