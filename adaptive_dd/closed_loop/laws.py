"""The computed-torque family for N joints: one typed configuration, one compiled kernel.

Every built-in law is

    tau = rnea_ref(pi_model, q, qd, qd_r, a) + fv qd_r + fc sgn(qd_r) + Ia a + feedback

with ``e = q_d - q``, ``e' = qd_d - qd`` and, per :class:`LawConfig`:

* ``KIND_PD``: no model, ``tau = kp e + kd e'`` (gains per joint, N m/rad, N m s/rad);
* ``KIND_CT``: computed torque, ``a = qdd_d + kd e' + kp e``; the reference-velocity law
  ``qd_r = qd_d + lam e`` (Coriolis and friction at the reference velocity, as the two-link
  ``ct_oracle``) or the textbook law ``qd_r = qd`` with Coulomb friction at ``sgn(qd_d)`` (as
  the two-link ``ct_oracle_textbook``: the sign of a noisy measured speed would chatter);
  no other feedback;
* ``KIND_SLOTINE``: Slotine-Li, ``qd_r = qd_d + lam e``, ``a = qdd_d + lam e'``, feedback
  ``kd M0(q) s`` with ``s = e' + lam e`` and M0 the nominal inertia (armature included), or
  ``kd s`` (``kd`` in N m s/rad) when ``feedback_inertia`` is false (the textbook form);
  with ``robust`` (sliding mode, Slotine 1985), plus ``rho sat(s / phi)`` per joint, ``rho`` the
  bound of the model's torque error ``|Y(q, qd, qd_r, a)| dpi`` (dpi the bound of each standard
  parameter's error, ``rho_pi``, and of the payload's, ``rho_payload``) and the boundary layer
  ``phi = rho / (lam M0_jj)`` (the balance condition ``k = lam phi`` of Slotine and Li, *Applied
  Nonlinear Control*, sec. 7.2: inside the layer the term is the feedback ``lam M0_jj s``);
* ``KIND_PD_GRAVITY``: PD plus gravity compensation (Takegaki and Arimoto 1981),
  ``tau = kp e + kd e' + g(q)`` with ``g`` the model's gravity torque.

The model ``pi_model`` (13 n standard parameters ``[links, fv, fc, Ia]``) is the fixed one
of the configuration (``MODEL_FIXED``), the true one of the current segment
(``MODEL_TRUE``), or the trial's own (``MODEL_TRIAL``: the estimator's projected model, or
the nominal model plus the adapted payload). After an alarm, for ``boost_samples`` samples and
its ramp, ``M0(q) (dkp e + dkd e')`` is added (adaptive_ct's bandwidth boost), its added bandwidth
scaled down at each sample as far as the torque limits need (``torque_limit``).

The residual observer (``observer``, adaptive_ct's; :mod:`adaptive_dd.closed_loop.residual_observer`)
adds to the command the torque the trial's model leaves unexplained, soft-thresholded at its own
learnt noise level.

Composite adaptation (``composite``, Slotine and Li 1989) adds to Slotine-Li's step the filtered
torque's prediction error (:mod:`adaptive_dd.closed_loop.composite`).

Other adaptation laws (``adapt_kind``, :mod:`adaptive_dd.closed_loop.adaptation`): Craig, Hsu and
Sastry's on computed torque (``KIND_CT``), integral concurrent learning's stack term and Lee, Kwon and
Park's natural gradient on Slotine-Li's structure.

Slotine-Li's payload adaptation: with ``Y_p = Y_j(q, qd, qd_r, a) P`` (the link-j block of
the Slotine-Li regressor times the payload map P of the payload frame),
``theta += T Gamma Y_p^T s``, then ``theta`` is clipped to ``[lo, hi]``; the mass kept
``>= 0`` and the centre of mass inside a ball of radius ``com_radius``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from adaptive_dd.closed_loop.adaptation import (
    ADAPT_CHS,
    ADAPT_ICL,
    ADAPT_NATURAL,
    chs_step,
    natural_step,
    payload_gradient_step,
)
from adaptive_dd.closed_loop.composite import ICL_ROWS, composite_term
from adaptive_dd.closed_loop.residual_observer import OBS_ROWS as O_ROWS
from adaptive_dd.closed_loop.residual_observer import _observe, observe_applied
from adaptive_dd.plant.chain import body_slotine_li_regressor_in, mass_matrix_in, rnea_ref_in, workspace
from adaptive_dd.plant.sampling import limit_crossings

__all__ = [
    "KIND_CT",
    "KIND_PD",
    "KIND_PD_GRAVITY",
    "KIND_SLOTINE",
    "MODEL_FIXED",
    "MODEL_NONE",
    "MODEL_TRIAL",
    "MODEL_TRUE",
    "OBS_ROWS",
    "LawConfig",
    "LawState",
    "law_batch",
    "law_trial",
    "law_trial_in",
    "law_work",
    "model_torque",
    "observe_applied",
]

Array = NDArray[np.float64]

KIND_PD, KIND_CT, KIND_SLOTINE, KIND_PD_GRAVITY = 0, 1, 2, 3
MODEL_NONE, MODEL_FIXED, MODEL_TRUE, MODEL_TRIAL = 0, 1, 2, 3

OBS_ROWS = max(O_ROWS, ICL_ROWS)
"""Rows of a law's per-trial state ``LawState.obs``: the residual observer's (``O_*``) or, the
observer off, the composite and ICL terms' (``C_*``, ``I_*``,
:mod:`adaptive_dd.closed_loop.composite`) or Craig-Hsu-Sastry's
(:mod:`adaptive_dd.closed_loop.adaptation`)."""


class LawConfig(NamedTuple):
    """A built-in law (see the module docstring).

    Attributes
    ----------
    kind, model : int
        ``KIND_*`` and ``MODEL_*``.
    reference_velocity : bool
        Computed torque: ``qd_r = qd_d + lam e`` (else ``qd``).
    kp, kd, lam : ndarray (n,)
        Gains per joint (PD: N m/rad and N m s/rad; others: 1/s^2, 1/s, 1/s).
    pi_fixed : ndarray (13 n,)
        The fixed (nominal) model; also M0 of the Slotine-Li feedback and the boost.
    boost_kp, boost_kd : ndarray (n,)
        Added feedback during a boost (1/s^2, 1/s), through M0(q).
    boost_samples : int
        Samples after an alarm during which the boost acts (0: never).
    boost_ramp : int
        Samples after those over which the boost's added bandwidth falls linearly to none
        (computed torque: ``w + f (wb - w)``, ``f`` from 1 to 0, with ``w = sqrt(kp)`` and ``wb``
        the boost's; 0: the boost ends at once).
    adapt : bool
        Slotine-Li adapts the payload (``theta``) after the command.
    gamma, lo, hi : ndarray (10,)
        Adaptation gains and box of the payload parameters (about the payload frame).
    com_radius : float
        [m] bound of the adapted centre of mass.
    payload_joint : int
        Link (0-based) carrying the payload frame.
    payload_map : ndarray (10, 10)
        Payload parameters about the payload frame -> about the link's joint frame.
    T : float
        Sample period [s] (the adaptation step).
    observer : bool
        The residual observer feeds the command (module docstring).
    obs_a : float
        ``exp(-beta T)``, beta the observer's bandwidth [rad/s] (of each stage).
    obs_stages : int
        1: De Luca's first-order observer; 2: its output low-passed once more at beta (the
        residual's noise, a differentiated momentum, then rolls off: module docstring).
    obs_kappa : float
        Soft threshold of ``r`` in units of its learnt RMS level.
    obs_alpha : float
        Weight of a sample in the level (``T`` over its 1 s window).
    obs_warmup : int
        Updates before ``r`` feeds the command (the level learnt meanwhile, not winsorised).
    feedback_inertia : bool
        Slotine-Li's feedback is ``kd M0(q) s`` (true) or ``kd s`` with ``kd`` in N m s/rad.
    robust : bool
        Slotine-Li plus the sliding-mode term ``rho sat(s / phi)`` (module docstring).
    rho_pi : ndarray (13 n,)
        Bound of the error of each standard parameter of ``pi_fixed`` (units of the parameter).
    rho_payload : ndarray (10,)
        Bound of each payload parameter (about the payload frame), the model having none.
    composite : bool
        Slotine-Li's adaptation adds the filtered-torque prediction error's term ``W^T R eps``
        (:mod:`adaptive_dd.closed_loop.composite`; its state in ``obs``, the observer off).
    comp_rate : float
        [rad/s] Rate of the composite term's first-order filter.
    comp_weight : ndarray (n,)
        Diagonal of its weight R [1/(N m s)] (also integral concurrent learning's).
    adapt_kind : int
        ``ADAPT_*`` of :mod:`adaptive_dd.closed_loop.adaptation`: Slotine-Li's gradient (0),
        Craig-Hsu-Sastry's (``KIND_CT``; ``comp_rate`` the rate [rad/s] of its acceleration's
        filter), integral concurrent learning's, Lee-Kwon-Park's natural gradient.
    icl_window : float
        [s] Integral concurrent learning's integration window.
    nat_gain : float
        The natural law's scalar gain ``gamma``.
    model_delay : int
        Samples after each swap before an oracle's true model (``MODEL_TRUE``) switches to the new
        segment's (``ct_oracle_late``; 0: at the swap).
    torque_limit : ndarray (n,)
        [N m] the actuators' limits, which the boost keeps the command within at each sample
        (:func:`_boost_within_limits`; inf: none).
    """

    kind: int
    model: int
    reference_velocity: bool
    kp: Array
    kd: Array
    lam: Array
    pi_fixed: Array
    boost_kp: Array
    boost_kd: Array
    boost_samples: int
    boost_ramp: int
    adapt: bool
    gamma: Array
    lo: Array
    hi: Array
    com_radius: float
    payload_joint: int
    payload_map: Array
    T: float
    observer: bool
    obs_a: float
    obs_stages: int
    obs_kappa: float
    obs_alpha: float
    obs_warmup: int
    feedback_inertia: bool = True
    robust: bool = False
    rho_pi: Array = np.zeros(1)
    rho_payload: Array = np.zeros(10)
    composite: bool = False
    comp_rate: float = 0.0
    comp_weight: Array = np.zeros(1)
    adapt_kind: int = 0
    icl_window: float = 0.0
    nat_gain: float = 0.0
    model_delay: int = 0
    torque_limit: Array = np.full(1, np.inf)


class LawState(NamedTuple):
    """Per-trial state of a law: ``pi_model (S, 13 n)`` (MODEL_TRIAL), ``theta (S, 10)``
    adapted payload parameters, ``since_alarm (S,)`` samples since the last alarm, ``obs (S,
    OBS_ROWS, n)`` the residual observer's state (rows ``O_*`` of
    :mod:`adaptive_dd.closed_loop.residual_observer`)."""

    pi_model: Array
    theta: Array
    since_alarm: NDArray[np.int64]
    obs: Array

    @classmethod
    def start(cls, cfg: LawConfig, n_trials: int) -> LawState:
        """Every trial at the fixed model, no payload adapted, no recent alarm."""
        pi = np.broadcast_to(cfg.pi_fixed, (n_trials, cfg.pi_fixed.shape[0])).copy()
        big = np.full(n_trials, np.iinfo(np.int64).max // 2, dtype=np.int64)
        n = cfg.kp.shape[0]
        return cls(pi, np.zeros((n_trials, 10)), big, np.zeros((n_trials, OBS_ROWS, n)))


@njit(cache=True)
def law_work(n):  # pragma: no cover - compiled
    """Scratch of one trial's :func:`law_trial_in` (allocated once per trial, not per sample):
    the chain workspace, ``(6, n)`` rows (e, e', qd_r, a, s, v), ``M (n, n)``, ``Y (n, 10)``,
    ``(6, 10)``, ``(10,)``; ``(2, 6, 10)`` and ``(2, n, 10)`` (the composite term's and the boost's
    scratch), the observer's ``(4, n)`` (p, wv at the last and this measurement); the composite
    term ``(10,)``."""
    return (
        workspace(n),
        np.empty((6, n)),
        np.empty((n, n)),
        np.empty((n, 10)),
        np.empty((6, 10)),
        np.empty(10),
        np.empty((2, 6, 10)),
        np.empty((4, n)),
        np.empty((2, n, 10)),
        np.empty(10),
    )


@njit(cache=True)
def model_torque(ch, pi, q, qd, qdr, qc, a, out):  # pragma: no cover - compiled
    """``rnea_ref(pi_links, q, qd, qdr, a) + fv qdr + fc sgn(qc) + Ia a`` into ``out (n,)``.

    ``pi (13 n,)`` standard parameters; ``qc`` the velocity whose sign sets the Coulomb torque
    (``qdr``; the textbook law: ``qd_d``); torques [N m].
    """
    _model_torque(ch, pi, q, qd, qdr, qc, a, workspace(q.shape[0]), out)


@njit(cache=True, _nrt=False)
def _model_torque(ch, pi, q, qd, qdr, qc, a, w, out):  # pragma: no cover - compiled
    n = q.shape[0]
    rnea_ref_in(ch, pi[: 10 * n], q, qd, qdr, a, w, out)
    for j in range(n):
        out[j] += pi[10 * n + j] * qdr[j] + pi[11 * n + j] * np.sign(qc[j]) + pi[12 * n + j] * a[j]


@njit(cache=True, _nrt=False)
def _add_nominal_inertia(ch, cfg, q, v, work, out):  # pragma: no cover - compiled
    """``out += M0(q) v`` with M0 the nominal mass matrix plus armature."""
    n = q.shape[0]
    m = work[2]
    mass_matrix_in(ch, cfg.pi_fixed[: 10 * n], q, work[0], m)
    for r in range(n):
        acc = cfg.pi_fixed[12 * n + r] * v[r]
        for c in range(n):
            acc += m[r, c] * v[c]
        out[r] += acc


@njit(cache=True, _nrt=False)
def _adapt_payload(ch, cfg, q, qd, qdr, a, s, theta, pi_model, work):  # pragma: no cover - compiled
    """One gradient step of the payload parameters, projected; pi_model rebuilt from them (with
    ``cfg.composite`` or ICL the step adds ``work[9]``, the composite or ICL term)."""
    body_slotine_li_regressor_in(ch, cfg.payload_joint, q, qd, qdr, a, work[0], work[4], work[3])
    extra = cfg.composite or cfg.adapt_kind == ADAPT_ICL
    payload_gradient_step(cfg, work[3], s, work[5], work[9], extra, theta, pi_model)  # Y_p^T s = P^T Y_j^T s


@njit(cache=True, _nrt=False)
def _sliding_term(ch, cfg, q, qd, qdr, a, s, work, out):  # pragma: no cover - compiled
    """``out += rho sat(s / phi)`` (module docstring): ``rho_r = sum_c |Y[r, c]| rho_pi[c]`` over
    the links' Slotine-Li regressor blocks, the payload's (``|Y_j P|``) and friction and armature
    (``|qd_r| dfv + dfc + |a| dIa``); ``phi = rho / (lam M0_jj)``."""
    n = q.shape[0]
    rho, yb, m = work[7][0], work[3], work[2]
    d = cfg.rho_pi
    for r in range(n):
        rho[r] = abs(qdr[r]) * d[10 * n + r] + d[11 * n + r] + abs(a[r]) * d[12 * n + r]
    for j in range(n):
        body_slotine_li_regressor_in(ch, j, q, qd, qdr, a, work[0], work[4], yb)
        for r in range(n):
            acc = 0.0
            for c in range(10):
                acc += abs(yb[r, c]) * cfg.rho_pi[10 * j + c]
            rho[r] += acc
        if j == cfg.payload_joint:
            for r in range(n):
                acc = 0.0
                for k in range(10):
                    yp = 0.0
                    for c in range(10):
                        yp += yb[r, c] * cfg.payload_map[c, k]
                    acc += abs(yp) * cfg.rho_payload[k]
                rho[r] += acc
    mass_matrix_in(ch, cfg.pi_fixed[: 10 * n], q, work[0], m)
    for j in range(n):
        u = (m[j, j] + cfg.pi_fixed[12 * n + j]) * cfg.lam[j] * s[j]
        if np.isfinite(rho[j]) and np.isfinite(u):
            out[j] += min(max(u, -rho[j]), rho[j])


@njit(cache=True)
def law_trial(
    ch, cfg, pi_true, pi_model, theta, since_alarm, obs, q, qd, q_d, qd_d, qdd_d, out
):  # pragma: no cover
    """Torque command ``out (n,)`` [N m] of one trial from its measured ``q, qd (n,)``.

    ``pi_true (13 n,)`` the current true model (MODEL_TRUE), ``pi_model (13 n,)`` and
    ``theta (10,)`` the trial's model and adapted payload (updated in place when the law
    adapts), ``since_alarm`` samples since its estimator's last alarm, ``obs (OBS_ROWS, n)``
    the residual observer's state (updated in place when ``cfg.observer``).
    """
    law_trial_in(
        ch,
        cfg,
        pi_true,
        pi_model,
        theta,
        since_alarm,
        obs,
        q,
        qd,
        q_d,
        qd_d,
        qdd_d,
        law_work(q.shape[0]),
        out,
    )


def actuator_limits(arm) -> Array:
    """``(n,)`` [N m] the torque limits the command is held within (inf where the arm's actuator
    does not saturate): :class:`LawConfig`'s ``torque_limit``."""
    act = arm.actuator  # a writable copy: a read-only array is another type to numba (a second compile)
    lim = np.broadcast_to(np.asarray(act.torque_limit, dtype=float), (arm.n_joints,))
    return np.array(lim if act.saturate else np.full(arm.n_joints, np.inf), dtype=float)


@njit(cache=True, _nrt=False)
def _boost_within_limits(ch, cfg, since_alarm, q, e, ed, work, out):  # pragma: no cover - compiled
    """Add the boost ``M0(q) (dkp e + dkd e')`` ``since_alarm`` samples after an alarm (its gains
    for ``boost_samples``, then its added bandwidth ramped down to none over ``boost_ramp``
    samples: :class:`LawConfig`), its added bandwidth ``x_j = s X_j`` scaled by the largest ``s`` in
    ``[0, 1]`` whose command ``out`` stays within ``cfg.torque_limit`` (a command already beyond
    its limit: not further; ``s = 0`` always is).

    ``kp + dkp = (w + s X)^2`` and ``kd + dkd = 2 zeta (w + s X)``: the added torque is
    ``s^2 M0 (X^2 e) + s M0 (X (2 w e + 2 zeta e'))``, quadratic in ``s`` per joint; the
    candidates are 1 and the crossings of each joint's limits. Every joint keeps the double pole
    at ``-(w_j + s X_j)``, as the two-link ``boost_within_trial``.
    """
    n = q.shape[0]
    f = 1.0
    if since_alarm >= cfg.boost_samples:  # the ramped end: f from 1 to 0
        f = 1.0 - (since_alarm - cfg.boost_samples + 1) / (cfg.boost_ramp + 1)
    rows = work[1]
    va, vb = rows[4], rows[5]
    for j in range(n):
        w0 = np.sqrt(max(cfg.kp[j], 0.0))
        x = f * cfg.boost_kd[j] * w0 / cfg.kd[j] if cfg.kd[j] > 0.0 else 0.0  # f (wb - w)
        z = 0.5 * cfg.kd[j] / w0 if w0 > 0.0 else 0.0
        va[j] = x * x * e[j]
        vb[j] = x * (2.0 * w0 * e[j] + 2.0 * z * ed[j])
    m = work[2]
    mass_matrix_in(ch, cfg.pi_fixed[: 10 * n], q, work[0], m)
    t = work[7]
    A, B, hi, lo = t[0], t[1], t[2], t[3]
    for r in range(n):
        ar = cfg.pi_fixed[12 * n + r] * va[r]
        br = cfg.pi_fixed[12 * n + r] * vb[r]
        for c in range(n):
            ar += m[r, c] * va[c]
            br += m[r, c] * vb[c]
        A[r], B[r] = ar, br
        lim = cfg.torque_limit[r]
        if np.isfinite(lim):
            room = max(lim, abs(out[r]))
            hi[r], lo[r] = room - out[r], -room - out[r]
        else:
            hi[r], lo[r] = np.inf, -np.inf
    xs = work[8].reshape(work[8].size)  # 20 n >= 4 n + 1 candidates; scratch, no allocation per sample
    xs[0] = 1.0
    k = 1
    for r in range(n):
        if np.isfinite(hi[r]):
            k = limit_crossings(A[r], B[r], hi[r], 1.0, xs, k)
            k = limit_crossings(A[r], B[r], lo[r], 1.0, xs, k)
    best = 0.0
    for i in range(k):  # the largest candidate within every joint's limits
        s = xs[i]
        if s <= best:
            continue
        ok = True
        for r in range(n):
            if np.isfinite(hi[r]):
                g = A[r] * s * s + B[r] * s
                tol = 1e-9 * (1.0 + hi[r] - lo[r])
                if g > hi[r] + tol or g < lo[r] - tol:
                    ok = False
                    break
        if ok:
            best = s
    if best > 0.0:
        for r in range(n):
            o = out[r] + A[r] * best * best + B[r] * best
            if np.isfinite(hi[r]):  # a crossing's rounding kept at the limit, not past it
                room = max(cfg.torque_limit[r], abs(out[r]))
                o = min(max(o, -room), room)
            out[r] = o


@njit(cache=True, inline="always")
def law_trial_in(
    ch, cfg, pi_true, pi_model, theta, since_alarm, obs, q, qd, q_d, qd_d, qdd_d, work, out
):  # pragma: no cover
    """:func:`law_trial` with its scratch ``work`` (:func:`law_work`) given: no allocation per sample."""
    n = q.shape[0]
    rows = work[1]
    e, ed, qdr, a, s, v = rows[0], rows[1], rows[2], rows[3], rows[4], rows[5]
    for j in range(n):
        e[j] = q_d[j] - q[j]
        ed[j] = qd_d[j] - qd[j]
    if cfg.kind == KIND_PD:
        for j in range(n):
            out[j] = cfg.kp[j] * e[j] + cfg.kd[j] * ed[j]
        return
    if cfg.kind == KIND_PD_GRAVITY:
        for j in range(n):
            v[j] = 0.0
        _model_torque(ch, pi_true if cfg.model == MODEL_TRUE else cfg.pi_fixed, q, v, v, v, v, work[0], out)
        for j in range(n):
            out[j] += cfg.kp[j] * e[j] + cfg.kd[j] * ed[j]
        return
    for j in range(n):
        if cfg.kind == KIND_CT:
            a[j] = qdd_d[j] + cfg.kd[j] * ed[j] + cfg.kp[j] * e[j]
            qdr[j] = qd_d[j] + cfg.lam[j] * e[j] if cfg.reference_velocity else qd[j]
        else:
            a[j] = qdd_d[j] + cfg.lam[j] * ed[j]
            qdr[j] = qd_d[j] + cfg.lam[j] * e[j]
    qc = qdr if cfg.reference_velocity else qd_d
    w = work[0]
    if cfg.model == MODEL_TRUE:
        _model_torque(ch, pi_true, q, qd, qdr, qc, a, w, out)
    elif cfg.model == MODEL_TRIAL:
        _model_torque(ch, pi_model, q, qd, qdr, qc, a, w, out)
    else:
        _model_torque(ch, cfg.pi_fixed, q, qd, qdr, qc, a, w, out)
    if cfg.kind == KIND_SLOTINE:
        for j in range(n):
            s[j] = cfg.kd[j] * (ed[j] + cfg.lam[j] * e[j])
        if cfg.feedback_inertia:
            _add_nominal_inertia(ch, cfg, q, s, work, out)
        else:
            for j in range(n):
                out[j] += s[j]
        if cfg.robust:
            for j in range(n):
                s[j] = ed[j] + cfg.lam[j] * e[j]
            _sliding_term(ch, cfg, q, qd, qdr, a, s, work, out)
        if cfg.adapt:
            for j in range(n):
                s[j] = ed[j] + cfg.lam[j] * e[j]
            if cfg.adapt_kind == ADAPT_NATURAL:
                natural_step(ch, cfg, q, qd, qdr, a, s, theta, pi_model, work)
            else:
                if cfg.composite or cfg.adapt_kind == ADAPT_ICL:
                    composite_term(ch, cfg, q, qd, theta, obs, work, work[9])
                _adapt_payload(ch, cfg, q, qd, qdr, a, s, theta, pi_model, work)
    elif cfg.adapt and cfg.adapt_kind == ADAPT_CHS:
        chs_step(ch, cfg, q, qd, e, ed, theta, pi_model, obs, work)
    if cfg.observer:
        _observe(ch, cfg, pi_model, q, qd, obs, work, out)
    boosting = cfg.boost_samples > 0 and since_alarm < cfg.boost_samples + cfg.boost_ramp
    if boosting:  # last: the limit applies to everything else the law adds
        _boost_within_limits(ch, cfg, since_alarm, q, e, ed, work, out)


@njit(cache=True)
def _law_loop(ch, cfg, pi_true, st, q, qd, q_d, qd_d, qdd_d, out):  # pragma: no cover - compiled
    """:func:`law_trial` for every trial: one compiled law for this loop and :func:`law_trial`'s
    other callers (inlining the law here compiled it a second time)."""
    for i in range(q.shape[0]):
        law_trial(
            ch, cfg, pi_true[i], st.pi_model[i], st.theta[i], st.since_alarm[i], st.obs[i],
            q[i], qd[i], q_d, qd_d, qdd_d, out[i],
        )  # fmt: skip


def law_batch(ch, cfg: LawConfig, state: LawState, q, qd, q_d, qd_d, qdd_d, pi_true=None) -> Array:
    """:func:`law_trial` for every trial: ``q, qd (S, n)``, reference ``(n,)``; returns ``(S, n)``.

    ``pi_true (S, 13 n)`` is needed only for ``MODEL_TRUE``; ``state`` is updated in place.
    """
    q = np.ascontiguousarray(q, dtype=float)
    qd = np.ascontiguousarray(qd, dtype=float)
    if pi_true is None:
        pi_true = np.zeros((q.shape[0], 13 * q.shape[1]))
    out = np.empty_like(q)
    c = np.ascontiguousarray
    _law_loop(
        ch, cfg, c(pi_true, dtype=float), state, q, qd,
        c(q_d, dtype=float), c(qd_d, dtype=float), c(qdd_d, dtype=float), out,
    )  # fmt: skip
    return out
