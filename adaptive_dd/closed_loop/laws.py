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
  ``kd M0(q) s`` with ``s = e' + lam e`` and M0 the nominal inertia (armature included).

The model ``pi_model`` (13 n standard parameters ``[links, fv, fc, Ia]``) is the fixed one
of the configuration (``MODEL_FIXED``), the true one of the current segment
(``MODEL_TRUE``), or the trial's own (``MODEL_TRIAL``: the estimator's projected model, or
the nominal model plus the adapted payload). After an alarm, for ``boost_samples`` samples,
``M0(q) (dkp e + dkd e')`` is added (adaptive_ct's bandwidth boost).

The residual observer (``observer``, adaptive_ct's; :func:`_observe`): De Luca's
generalised-momentum observer of the torque the trial's model leaves unexplained,
``r = beta / (s + beta) (tau - d/dt p - wv)`` with ``p = M(q) qd`` and ``wv = g - C^T qd +
friction`` of ``pi_model``, discrete and consistent under a changing model (the momentum at the
last and at this measurement both with this sample's model), here low-passed once more
(``obs_stages = 2``: ``(beta / (s + beta))^2``, whose response to the measured velocity's white
noise rolls off instead of passing it at the gain beta up to the Nyquist frequency); ``r``
soft-thresholded at ``obs_kappa`` times its own learnt RMS level is added to the command. Noise
stays below the threshold; a payload's torque passes from the samples after the swap, before the
change is detected, and fades as the estimate learns it (``r`` is the residual of the current
model).

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

from adaptive_dd.plant.chain import (
    body_slotine_li_regressor_in,
    mass_matrix_in,
    momentum_form_in,
    rnea_ref_in,
    workspace,
)

__all__ = [
    "KIND_CT",
    "KIND_PD",
    "KIND_SLOTINE",
    "MODEL_FIXED",
    "MODEL_NONE",
    "MODEL_TRIAL",
    "MODEL_TRUE",
    "OBS_ROWS",
    "O_MC",
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

KIND_PD, KIND_CT, KIND_SLOTINE = 0, 1, 2
MODEL_NONE, MODEL_FIXED, MODEL_TRUE, MODEL_TRIAL = 0, 1, 2, 3

# rows of the observer's per-trial state LawState.obs (S, OBS_ROWS, n)
O_R = 0  # the observed residual torque r [N m] (the last stage's output)
O_LEVEL = 1  # its learnt mean square (winsorised, not bias-corrected) [N^2 m^2]
O_Q, O_QD = 2, 3  # the last fresh measurement
O_TAU = 4  # the applied torques summed since that measurement [N m] (written by the closed loop)
O_COUNT = 5  # [0]: observer updates so far, [1]: samples summed in O_TAU
O_R1 = 6  # the first stage's output (two stages)
O_TRIP = 7  # [0]: samples since the observer's residual last tripped the boost (obs_trip)
# the momentum test (obs_mtest; :func:`_momentum_test`)
M_WINDOWS = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32)  # its windows [fresh measurements]
M_RING = 33  # the integrated error's ring: the longest window plus one
M_ARM = 2.0  # level windows of free learning before the test is armed (the first may be a ramp-up)
O_MV = 8  # rows O_MV + w: the learnt mean square of window w's whitened sum [(rad/s)^2]
O_MB = O_MV + len(M_WINDOWS)  # the learnt drift of rho (the model's own error) [N m]
O_ME = O_MB + 1  # rows O_ME + i: the integrated error E, less the drift [N m s], a ring
O_MA = O_ME + M_RING  # rows O_MA + i: the integrated Coulomb allowance [N m s], a ring
O_MC = O_MA + M_RING  # [0]: updates of the test so far, [1]: 1 if it crossed at the last one (2: and
# started the boost asking the estimator to re-open: obs_mreopen)
OBS_ROWS = O_MC + 1


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
    obs_trip : float
        A row's residual beyond this many times its learnt RMS level starts the boost as an
        alarm would (the estimator's detector reads slower filters); 0: never.
    obs_trip_speed : float
        [rad/s] A row whose joint's measured speed is at most this (the detector's creeping
        speed) trips only beyond its threshold plus twice the model's Coulomb friction: near rest
        the measured speed's sign, hence the model's Coulomb torque, flips with the noise, and
        the residual with it by up to ``2 fc``.
    obs_mtest : float
        The momentum test (:func:`_momentum_test`) starts the boost as an alarm would when its
        statistic (the square root of a chi-square with ``n`` degrees of freedom) exceeds this;
        0: never.
    obs_mslow : float
        [rad/s] The momentum test takes a joint measured at most this fast at either end of a
        sample, or whose two ends differ in sign, as of unknown direction over it (its Coulomb
        torque anything within ``+-fc``: an allowance of ``2 fc`` per sample;
        :func:`_friction_allowance`).
    obs_mcreep, obs_mcreep_margin : float
        [rad/s], [-] A joint otherwise at most ``obs_mcreep`` fast gets an allowance of
        ``obs_mcreep_margin fc`` per sample (friction the model lacks near rest; the detector's
        ``speed`` and ``creep_margin``).
    obs_mreopen : bool
        A start of the boost by the momentum test also asks the estimator to re-open, as its
        detector's alarm does (``obs[O_MC, 1] = 2``, read by the closed loop's estimator sample).
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
    obs_trip: float
    obs_trip_speed: float
    obs_mtest: float = 0.0
    obs_mslow: float = 0.0
    obs_mreopen: bool = False
    obs_mcreep: float = 0.0
    obs_mcreep_margin: float = 0.0


class LawState(NamedTuple):
    """Per-trial state of a law: ``pi_model (S, 13 n)`` (MODEL_TRIAL), ``theta (S, 10)``
    adapted payload parameters, ``since_alarm (S,)`` samples since the last alarm, ``obs (S,
    OBS_ROWS, n)`` the residual observer's state (rows ``O_*`` of this module)."""

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
        obs = np.zeros((n_trials, OBS_ROWS, n))
        obs[:, O_TRIP, 0] = np.iinfo(np.int64).max // 2  # no trip yet
        return cls(pi, np.zeros((n_trials, 10)), big, obs)


@njit(cache=True)
def law_work(n):  # pragma: no cover - compiled
    """Scratch of one trial's :func:`law_trial_in` (allocated once per trial, not per sample):
    the chain workspace, ``(6, n)`` rows (e, e', qd_r, a, s, v), ``M (n, n)``, ``Y (n, 10)``,
    ``(6, 10)``, ``(10,)``; the observer's ``(2, 6, 10)``, ``(4, n)`` (p, wv at the last and this
    measurement), ``(2, n, 10)``; the momentum test's ``(n + 4, n)`` (``M^-1``, rho, the model's
    Coulomb friction, the window's sum and its whitened form)."""
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
        np.empty((n + 4, n)),
    )


@njit(cache=True)
def model_torque(ch, pi, q, qd, qdr, qc, a, out):  # pragma: no cover - compiled
    """``rnea_ref(pi_links, q, qd, qdr, a) + fv qdr + fc sgn(qc) + Ia a`` into ``out (n,)``.

    ``pi (13 n,)`` standard parameters; ``qc`` the velocity whose sign sets the Coulomb torque
    (``qdr``; the textbook law: ``qd_d``); torques [N m].
    """
    _model_torque(ch, pi, q, qd, qdr, qc, a, workspace(q.shape[0]), out)


@njit(cache=True)
def _model_torque(ch, pi, q, qd, qdr, qc, a, w, out):  # pragma: no cover - compiled
    n = q.shape[0]
    rnea_ref_in(ch, pi[: 10 * n], q, qd, qdr, a, w, out)
    for j in range(n):
        out[j] += pi[10 * n + j] * qdr[j] + pi[11 * n + j] * np.sign(qc[j]) + pi[12 * n + j] * a[j]


@njit(cache=True)
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


@njit(cache=True)
def _adapt_payload(ch, cfg, q, qd, qdr, a, s, theta, pi_model, work):  # pragma: no cover - compiled
    """One gradient step of the payload parameters, projected; pi_model rebuilt from them."""
    n = q.shape[0]
    j = cfg.payload_joint
    yb = work[3]
    body_slotine_li_regressor_in(ch, j, q, qd, qdr, a, work[0], work[4], yb)
    g = work[5]  # Y_p^T s = P^T (Y_j^T s)
    for c in range(10):
        acc = 0.0
        for r in range(n):
            acc += yb[r, c] * s[r]
        g[c] = acc
    for k in range(10):
        upd = 0.0
        for c in range(10):
            upd += cfg.payload_map[c, k] * g[c]
        upd *= cfg.T * cfg.gamma[k]
        th = theta[k] + (upd if np.isfinite(upd) else 0.0)
        theta[k] = min(max(th, cfg.lo[k]), cfg.hi[k])
    theta[0] = max(theta[0], 0.0)
    mc = np.sqrt(theta[1] ** 2 + theta[2] ** 2 + theta[3] ** 2)
    lim = cfg.com_radius * theta[0]
    if mc > lim:
        f = lim / mc
        theta[1], theta[2], theta[3] = f * theta[1], f * theta[2], f * theta[3]
    for c in range(pi_model.shape[0]):
        pi_model[c] = cfg.pi_fixed[c]
    for c in range(10):
        acc = 0.0
        for k in range(10):
            acc += cfg.payload_map[c, k] * theta[k]
        pi_model[10 * j + c] += acc


@njit(cache=True)
def _momentum(ch, pi, q, qd, work, p, wv):  # pragma: no cover - compiled
    """``p = M(q) qd + Ia qd`` and ``wv = g - C^T qd + fv qd + fc sgn(qd)`` of ``pi (13 n,)``."""
    n = q.shape[0]
    pyw = work[8]
    # link np.int64(0), not 0: the literal 0 is a type of its own, which compiled momentum_form_in
    # once more (4.5 CPU s) beside the estimator's int64 one
    momentum_form_in(ch, pi[: 10 * n], np.int64(0), q, qd, work[0], work[6], p, wv, pyw[0], pyw[1])
    for j in range(n):
        p[j] += pi[12 * n + j] * qd[j]
        wv[j] += pi[10 * n + j] * qd[j] + pi[11 * n + j] * np.sign(qd[j])


@njit(cache=True)
def _mass(ch, pi, q, work, m):  # pragma: no cover - compiled
    """``m = M(q) + diag(Ia)`` of ``pi (13 n,)`` (the momentum test's metric)."""
    n = q.shape[0]
    mass_matrix_in(ch, pi[: 10 * n], q, work[0], m)
    for j in range(n):
        m[j, j] += pi[12 * n + j]


@njit(cache=True, inline="always")
def _coulomb(pi, n, j):  # pragma: no cover - compiled
    """The model's Coulomb friction of joint ``j`` [N m]."""
    return abs(pi[11 * n + j])


@njit(cache=True)
def _spd_inverse(a, out):  # pragma: no cover - compiled
    """``out = a^-1`` of a symmetric positive definite ``a (n, n)`` (Gauss-Jordan, no pivoting;
    ``a`` destroyed). A non-positive pivot leaves ``out`` the identity."""
    n = a.shape[0]
    for r in range(n):
        for c in range(n):
            out[r, c] = 1.0 if r == c else 0.0
    for k in range(n):
        piv = a[k, k]
        if not piv > 0.0:
            for r in range(n):
                for c in range(n):
                    out[r, c] = 1.0 if r == c else 0.0
            return
        for c in range(n):
            a[k, c] /= piv
            out[k, c] /= piv
        for r in range(n):
            if r != k:
                f = a[r, k]
                if f != 0.0:
                    for c in range(n):
                        a[r, c] -= f * a[k, c]
                        out[r, c] -= f * out[k, c]


@njit(cache=True, inline="always")
def _sign_unknown(cfg, qd_last, qd_now):  # pragma: no cover - compiled
    """Whether the true speed's sign over a sample is not known from its two measured ends: one at
    most ``obs_mslow`` fast, or the two of opposite signs."""
    return min(abs(qd_last), abs(qd_now)) <= cfg.obs_mslow or qd_last * qd_now <= 0.0


@njit(cache=True, inline="always")
def _friction_allowance(cfg, qd_last, qd_now, fc):  # pragma: no cover - compiled
    """[N m] How far the model's Coulomb torque over one sample (the trapezoid of ``fc sgn(qd)`` at
    its two measured ends) may be from the plant's, for a joint measured ``qd_last``, ``qd_now``:
    ``2 fc`` where the sign of the true speed is not known over the sample (an end within
    ``obs_mslow``, the stated velocity noise's quantile, or the two ends of opposite signs: the
    joint may reverse or stick within it, its friction then anything within ``+-fc``); else
    ``obs_mcreep_margin fc`` where the slower end is just above ``obs_mslow``, falling linearly to
    none at ``obs_mcreep`` (friction the model lacks, a Stribeck bump or a soft law, errs near
    rest by a fraction of the Coulomb level: the detector's creeping rule; a flat allowance up to
    ``obs_mcreep`` cost vertical3 its gain); else none."""
    if _sign_unknown(cfg, qd_last, qd_now):
        return 2.0 * fc
    slow = min(abs(qd_last), abs(qd_now))
    if slow <= cfg.obs_mcreep:
        return cfg.obs_mcreep_margin * fc * (cfg.obs_mcreep - slow) / (cfg.obs_mcreep - cfg.obs_mslow)
    return 0.0


@njit(cache=True)
def _momentum_test(cfg, obs, mt, qd, m):  # pragma: no cover - compiled
    """One fresh update of the momentum test; ``obs[O_MC, 1]`` set to 1 if it crossed.

    ``mt (n + 4, n)``: ``M^-1`` of this measurement (rows ``0..n-1``), the mean residual ``rho``
    over the ``m`` samples since the last measurement (row ``n``), the model's Coulomb friction
    (row ``n + 1``); rows ``n + 2, n + 3`` scratch. The integrated momentum error ``E_k = sum (rho
    - b) m T`` (``b`` the row's drift, learnt over the level's window) telescopes: over a window
    of ``w`` updates its sum ``S = E_k - E_(k-w)`` is the missing torque's integral plus the two
    end momenta's noise, whatever ``w``; a step ``d`` of missing torque is a ramp ``d w T`` in it.
    ``u = M^-1 S`` (the unexplained velocity change: the velocity noise, independent per joint,
    whitens it) per window of :data:`M_WINDOWS`; a joint whose friction over a sample is not
    known (:func:`_friction_allowance`: near rest or reversing, ``2 fc``; creeping, a fraction of
    ``fc``) has that allowance, summed over the window: once the test is armed, the friction
    torques within it that explain ``u`` best are removed from it first (three passes of
    coordinate descent, metric ``1 / V``). Statistic: the largest over windows of ``sqrt(sum_j
    u_j^2 / V_j)``, ``V`` each window's and row's learnt mean square of ``u``, learnt only on
    windows without allowance (elsewhere it keeps its bias-corrected value; a window whose level
    has learnt nothing is not tested): freely for :data:`M_ARM` level windows, then winsorised at
    the threshold. Learnt on every window before it armed, the first seconds' reversals raised
    the levels and the test was blind for a second or more after it armed. Armed
    after those: learnt over the first second alone, on a reference that ramps up over it, the
    levels were too low for the full motion (vertical3 drawn: starts at 1.18-1.19 s in 2 of 10
    trials, none from 2 s on)."""
    n = qd.shape[0]
    rho, fc, sm, u = mt[n], mt[n + 1], mt[n + 2], mt[n + 3]
    c = obs[O_MC, 0]
    pos = int(c) % M_RING
    prev = (int(c) + M_RING - 1) % M_RING
    dt = m * cfg.T
    for j in range(n):
        obs[O_ME + pos, j] = obs[O_ME + prev, j] + (rho[j] - obs[O_MB, j]) * dt
        obs[O_MA + pos, j] = obs[O_MA + prev, j] + _friction_allowance(cfg, obs[O_QD, j], qd[j], fc[j]) * dt
    c += 1.0
    obs[O_MC, 0] = c
    alpha = cfg.obs_alpha
    armed = c * alpha > M_ARM
    bias = 1.0 - (1.0 - alpha) ** c
    bias0 = 1.0 - (1.0 - alpha) ** (c - 1.0)
    z2 = cfg.obs_mtest * cfg.obs_mtest
    best = 0.0
    for w in range(len(M_WINDOWS)):
        mw = M_WINDOWS[w]
        if c <= mw:
            continue
        back = (pos + M_RING - mw) % M_RING
        clean = True
        for j in range(n):
            sm[j] = obs[O_ME + pos, j] - obs[O_ME + back, j]
            clean = clean and obs[O_MA + pos, j] == obs[O_MA + back, j]
        for r in range(n):
            acc = 0.0
            for j in range(n):
                acc += mt[r, j] * sm[j]
            u[r] = acc
        v = obs[O_MV + w]
        learnt = True
        for r in range(n):
            sm[r] = u[r] * u[r]  # before the allowance (the levels learn it where there is none)
            learnt = learnt and v[r] > 0.0
        if armed and learnt and not clean:
            for _ in range(3):
                for j in range(n):
                    al = obs[O_MA + pos, j] - obs[O_MA + back, j]
                    if al <= 0.0:
                        continue
                    num, den = 0.0, 0.0
                    for r in range(n):
                        wr = bias / v[r]
                        num += mt[r, j] * wr * u[r]
                        den += mt[r, j] * mt[r, j] * wr
                    cj = min(max(num / den, -al), al) if den > 0.0 else 0.0
                    for r in range(n):
                        u[r] -= mt[r, j] * cj
        tot = 0.0
        for r in range(n):
            if armed and learnt:
                tot += u[r] * u[r] * bias / v[r]
            if clean:
                x = min(sm[r], z2 * v[r] / bias) if armed and learnt else sm[r]
            else:  # the level's own estimate: its bias-corrected value unchanged
                x = v[r] / bias0 if bias0 > 0.0 else 0.0
            v[r] += alpha * (x - v[r])
        if tot > best:
            best = tot
    if c > M_RING:
        for j in range(n):
            obs[O_MB, j] += alpha * (rho[j] - obs[O_MB, j])
    obs[O_MC, 1] = 1.0 if armed and np.isfinite(best) and best > z2 else 0.0


@njit(cache=True, inline="always")
def observe_applied(obs, tau):  # pragma: no cover - compiled
    """Add the torque ``tau (n,)`` applied over one sample to the residual observer's state
    ``obs (OBS_ROWS, n)`` (the closed loop calls it after each sample's actuation)."""
    for j in range(tau.shape[0]):
        obs[O_TAU, j] += tau[j]
    obs[O_COUNT, 1] += 1.0


@njit(cache=True)
def _observe(ch, cfg, pi, q, qd, obs, work, out):  # pragma: no cover - compiled
    """One sample of the residual observer (module docstring) at a fresh measurement ``q, qd``;
    its soft-thresholded output added to ``out``.

    ``obs`` holds the last fresh measurement and the applied torques summed since (``O_TAU``,
    ``O_COUNT[1]`` samples: the closed loop adds each sample's). Over those ``m`` samples the
    mean residual is ``rho = sum tau / m - (wv_last + wv_now) / 2 - (p_now - p_last) / (m T)``,
    both momenta with ``pi`` (consistent when the model changes), and ``r <- a^m r + (1 - a^m)
    rho``. A measurement equal to the last one (a lost sample held) is not fresh: ``r`` is
    kept and the torques go on being summed. The level learns ``min(r^2, kappa^2 level)``
    (winsorised: a payload's residual raises it slowly, a higher noise still gets learnt).
    """
    n = q.shape[0]
    held = obs[O_COUNT, 0] >= 1.0
    for j in range(n):
        held = held and q[j] == obs[O_Q, j] and qd[j] == obs[O_QD, j]
    m = obs[O_COUNT, 1]
    if obs[O_COUNT, 0] >= 1.0 and m >= 1.0 and not held:
        pw = work[7]
        _momentum(ch, pi, obs[O_Q], obs[O_QD], work, pw[0], pw[1])
        _momentum(ch, pi, q, qd, work, pw[2], pw[3])
        am = cfg.obs_a**m
        finite = True
        for j in range(n):
            rho = obs[O_TAU, j] / m - 0.5 * (pw[1, j] + pw[3, j]) - (pw[2, j] - pw[0, j]) / (m * cfg.T)
            if cfg.obs_mtest > 0.0:
                work[9][n, j] = rho
            if not np.isfinite(rho):
                finite = False
                continue
            if cfg.obs_stages == 2:
                obs[O_R1, j] = am * obs[O_R1, j] + (1.0 - am) * rho
                rho = obs[O_R1, j]
            obs[O_R, j] = am * obs[O_R, j] + (1.0 - am) * rho
        if cfg.obs_mtest > 0.0:
            obs[O_MC, 1] = 0.0
            if finite:
                mt = work[9]
                _mass(ch, pi, q, work, work[2])
                _spd_inverse(work[2], mt[:n])
                fc = mt[n + 1]
                for j in range(n):
                    fc[j] = _coulomb(pi, n, j)
                _momentum_test(cfg, obs, mt, qd, m)
    if not held:
        c = obs[O_COUNT, 0] + 1.0
        bias = 1.0 - (1.0 - cfg.obs_alpha) ** c
        for j in range(n):
            r2 = obs[O_R, j] * obs[O_R, j]
            if c > cfg.obs_warmup:
                r2 = min(r2, cfg.obs_kappa**2 * obs[O_LEVEL, j] / bias)
            obs[O_LEVEL, j] += cfg.obs_alpha * (r2 - obs[O_LEVEL, j])
            obs[O_Q, j], obs[O_QD, j], obs[O_TAU, j] = q[j], qd[j], 0.0
        obs[O_COUNT, 0] = c
        obs[O_COUNT, 1] = 0.0
    c = obs[O_COUNT, 0]
    if c <= cfg.obs_warmup:
        return
    bias = 1.0 - (1.0 - cfg.obs_alpha) ** c
    for j in range(n):
        thr = cfg.obs_kappa * np.sqrt(obs[O_LEVEL, j] / bias)
        r = obs[O_R, j]
        if r > thr:
            out[j] += r - thr
        elif r < -thr:
            out[j] += r + thr


@njit(cache=True)
def _trip(cfg, pi, qd, obs):  # pragma: no cover - compiled
    """A row of the observer's output beyond ``obs_trip`` times its learnt level (plus twice its
    Coulomb friction when its joint is at most ``obs_trip_speed``) sets ``O_TRIP`` to 0."""
    n = qd.shape[0]
    c = obs[O_COUNT, 0]
    if c <= cfg.obs_warmup:
        return
    bias = 1.0 - (1.0 - cfg.obs_alpha) ** c
    for j in range(n):
        rms = np.sqrt(obs[O_LEVEL, j] / bias)
        flip = 0.0 if abs(qd[j]) > cfg.obs_trip_speed else 2.0 * abs(pi[11 * n + j])
        if abs(obs[O_R, j]) > cfg.obs_trip * rms + flip:
            obs[O_TRIP, 0] = 0.0


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
        _add_nominal_inertia(ch, cfg, q, s, work, out)
        if cfg.adapt:
            for j in range(n):
                s[j] = ed[j] + cfg.lam[j] * e[j]
            _adapt_payload(ch, cfg, q, qd, qdr, a, s, theta, pi_model, work)
    trips = cfg.obs_trip > 0.0 or cfg.obs_mtest > 0.0
    if cfg.observer and trips:  # samples since the observer last tripped the boost
        obs[O_TRIP, 0] += 1.0
        if obs[O_TRIP, 0] < since_alarm:
            since_alarm = int(obs[O_TRIP, 0])
    boosting = cfg.boost_samples > 0 and since_alarm < cfg.boost_samples + cfg.boost_ramp
    if boosting:
        f = 1.0
        if since_alarm >= cfg.boost_samples:  # the ramped end: f from 1 to 0
            f = 1.0 - (since_alarm - cfg.boost_samples + 1) / (cfg.boost_ramp + 1)
        for j in range(n):
            dkp, dkd = cfg.boost_kp[j], cfg.boost_kd[j]
            if f < 1.0:  # the added bandwidth f (wb - w): kp = w^2, kd = 2 z w, boost_kd = 2 z (wb - w)
                w0 = np.sqrt(max(cfg.kp[j], 0.0))
                dw = f * dkd * w0 / cfg.kd[j] if cfg.kd[j] > 0.0 else 0.0
                dkp, dkd = dw * (2.0 * w0 + dw), f * dkd
            v[j] = dkp * e[j] + dkd * ed[j]
        _add_nominal_inertia(ch, cfg, q, v, work, out)
    if cfg.observer:
        _observe(ch, cfg, pi_model, q, qd, obs, work, out)
        # a trip starts a boost; it does not prolong one (nor restart it while it ramps down)
        if cfg.obs_trip > 0.0 and not boosting:
            _trip(cfg, pi_model, qd, obs)
        if cfg.obs_mtest > 0.0 and not boosting and obs[O_MC, 1] > 0.0:
            obs[O_TRIP, 0] = 0.0
            if cfg.obs_mreopen:
                obs[O_MC, 1] = 2.0


@njit(cache=True)
def _law_loop(ch, cfg, pi_true, st, q, qd, q_d, qd_d, qdd_d, out):  # pragma: no cover - compiled
    work = law_work(q.shape[1])  # one per call: trials run one after the other here
    for i in range(q.shape[0]):
        law_trial_in(
            ch, cfg, pi_true[i], st.pi_model[i], st.theta[i], st.since_alarm[i], st.obs[i],
            q[i], qd[i], q_d, qd_d, qdd_d, work, out[i],
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
