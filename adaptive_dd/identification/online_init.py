"""Packing of the N-joint online estimator's settings into its compiled form.

:func:`est_init` turns an :class:`~adaptive_dd.identification.online_config.OnlineConfig` and an
arm into the read-only :class:`~adaptive_dd.identification.online_slots.EstCfg` (``_pack``: the
slot arrays, the prior covariances, the filter realisations) and the initial per-trial
:class:`~adaptive_dd.identification.online_slots.EstState`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from adaptive_dd.errors import ParameterError
from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.arm_prior import ArmUncertainty, prior_covariance
from adaptive_dd.identification.filters import summing_realisation
from adaptive_dd.identification.online_config import (
    WARMUP,
    WARMUP_ARM,
    Array,
    OnlineConfig,
    derived_row_weights,
    detector_floor,
    payload_prior,
    reopen_mass_std,
)
from adaptive_dd.identification.online_slots import MAX_FILTER_ORDER, EstCfg, EstState
from adaptive_dd.identification.payload_information import filter_noise_gram
from adaptive_dd.plant.arm import Arm
from adaptive_dd.plant.payload import payload_parameters


def _detector_velocity_variance(arm: Arm) -> Array:
    """The sensor's velocity noise variance per joint [(rad/s)^2] the detector weighs the rows'
    noise by (``EstCfg.vdet``); all equal when the arm states none."""
    v = np.asarray(arm.sensor.velocity_variance, dtype=float) * np.ones(arm.n_joints)
    if not (np.all(np.isfinite(v)) and v.max() > 0.0):
        v = np.ones(arm.n_joints)
    return np.maximum(v, 1e-6 * v.max())


def _pack(cfg: OnlineConfig, arm: Arm) -> tuple[EstCfg, Array]:
    n = arm.n_joints
    pi0 = np.ascontiguousarray(arm.pi, dtype=float)
    pmap = np.ascontiguousarray(arm.payload_map)
    jp = arm.payload_joint
    # a payload of unknown mass shaped as the arm states (a disk of payload_radius), its centre
    # within payload_offset of the payload frame
    shape = payload_parameters(1.0, radius=arm.payload_radius)
    S0 = payload_prior(cfg.payload_mass_std, arm.payload_offset, shape)
    det = cfg.detector
    S1 = payload_prior(reopen_mass_std(det, arm) if det else 0.0, arm.payload_offset, shape)
    if cfg.mode == "payload":
        p = 10
        indep = np.arange(10, dtype=np.int64)
        Bpinv = np.zeros((13 * n, 10))
        sigma0 = np.zeros(10)
        pbasis = np.eye(10)
        pbasis_pinv = np.eye(10)
        U = np.eye(10)
        P0, Pr = S0, S1
        n_rows = jp + 1  # joints after the payload's link do not feel it
    else:
        B = arm.base.B
        pb = B.shape[0]
        p = pb + 10
        indep = np.asarray(arm.base.independent, dtype=np.int64)
        Bb = np.linalg.pinv(B)
        Bpinv = np.hstack((Bb, Bb @ arm.payload_basis))  # the payload block enters through B
        sigma0 = np.concatenate((B @ pi0, np.zeros(10)))
        pbasis = np.vstack((np.zeros((pb, 10)), np.eye(10)))
        pbasis_pinv = pbasis.T.copy()
        U = pbasis.copy()
        P0 = np.zeros((p, p))
        if cfg.arm_prior_cov is not None:  # what an identification knows, with its correlations
            C = np.asarray(cfg.arm_prior_cov, dtype=float)
            if C.shape != (pb, pb):
                raise ParameterError(
                    f"OnlineConfig.arm_prior_cov is {C.shape[0]} x {C.shape[1]}; this arm has {pb} "
                    "base parameters"
                )
            P0[:pb, :pb] = cfg.p0_arm * np.eye(pb) + C
        else:
            levels = cfg.arm_uncertainty if cfg.arm_uncertainty is not None else ArmUncertainty()
            P0[:pb, :pb] = cfg.p0_arm * np.eye(pb) + B @ prior_covariance(arm, levels) @ B.T
        P0[pb:, pb:] = S0
        Pr = np.zeros((p, p))
        Pr[pb:, pb:] = S1
        n_rows = n
    cap = cfg.max_trace if cfg.max_trace is not None else max(np.trace(P0), np.trace(Pr))
    w = derived_row_weights(arm) if cfg.row_weights is None else np.asarray(cfg.row_weights, dtype=float)
    if w.shape != (n,):
        raise ParameterError(f"OnlineConfig.row_weights must have {n} values (joints), got {w.shape[0]}")
    b = cfg.bank
    sel_threshold = 0.0 if cfg.selection is None else float(cfg.selection[0])
    scalars = dict(
        align=bool(cfg.align),
        project=bool(cfg.project),
        select=cfg.selection is not None,
        sel_threshold=sel_threshold,
        sel_memory=0 if cfg.selection is None else cfg.samples(cfg.selection[1]),
        taint=cfg.samples(cfg.taint),
        n_rows=int(n_rows),
        lam0=float(cfg.lam0),
        mu=float(cfg.mu),
        max_trace=float(cap),
        eig_min=float(cfg.eig_min),
        bound_radius=0.0 if cfg.bound_radius is None else float(cfg.bound_radius),
        prior_radius=0.0 if cfg.prior_radius is None else float(cfg.prior_radius),
        prior_noise=float(cfg.prior_noise),
        # the centred prior on the model's first moments
        com_size=float(arm.payload_offset) if cfg.payload_priors else 0.0,
        present2=0.0,
    )
    if cfg.mode == "payload":  # a carried payload's mass: the re-opened prior's (sized by the capacity)
        scalars["present2"] = float((reopen_mass_std(det, arm) if det else cfg.payload_mass_std) ** 2)
    scalars.update(_detector_scalars(cfg, arm, w, sel_threshold))
    Am, Bm, Cm, Dm = summing_realisation(b)
    if b.order > MAX_FILTER_ORDER:  # the step's scratch (EstWork.ftmp): it allocates nothing
        raise ParameterError(
            f"the estimator's filter bank is of order {b.order}; at most {MAX_FILTER_ORDER} (a lower order)"
        )
    xm1 = np.linalg.solve(np.eye(b.order) - Am, Bm[:, 1])
    c = np.ascontiguousarray
    return EstCfg(
        ch=arm.chain,
        mode=K.MODE_PAYLOAD if cfg.mode == "payload" else K.MODE_ARM,
        pi0=pi0,
        jp=int(jp),
        pmap=pmap,
        indep=indep,
        Bpinv=c(Bpinv),
        sigma0=c(sigma0),
        pbasis=c(pbasis),
        pbasis_pinv=c(pbasis_pinv),
        U=U,
        P_reopen=c(Pr),
        Am=Am,
        Bm=Bm,
        Cm=Cm,
        Dm=Dm,
        xm1=xm1,
        w=c(w),
        vdet=c(_detector_velocity_variance(arm)),
        vrow=c(filter_noise_gram(cfg.tau_f, cfg.sample_period)[1, 1] / w**2),  # G1's noise gain
        **scalars,
    ), P0


def _detector_scalars(cfg: OnlineConfig, arm: Arm, w: Array, sel_threshold: float) -> dict:
    """:class:`~adaptive_dd.identification.online_slots.EstCfg`'s detector settings (none without a
    detector: the fields' defaults, zero and false)."""
    det, T = cfg.detector, cfg.sample_period
    if det is None:
        return {}
    warm = det.warmup if det.warmup is not None else (WARMUP_ARM if cfg.mode == "arm" else WARMUP)
    freeze = cfg.samples(det.freeze)
    fast = det.fast_window is not None
    held = det.hold_above > 0.0
    hold = cfg.rise_samples if det.hold_time is None else cfg.seconds(det.hold_time)
    return dict(
        detect=True,
        warmup=cfg.seconds(warm),
        min_learned=int(det.min_learned),
        holdoff=cfg.seconds(det.holdoff),
        freeze=freeze,
        resume=int(np.ceil(freeze * det.resume)),
        reopen_again=bool(det.reopen_again),
        gate_after=int(det.gate_after),
        alpha_short=float(min(1.0, T / det.short_window)),
        alpha_long=float(min(1.0, T / det.long_window)),
        threshold2=float(det.threshold**2),
        relearn2=float(det.relearn_factor**2),
        gate2=float(det.gate**2),
        floor2=float((detector_floor(det) / w.max()) ** 2),  # [N m] on the row of the largest weight
        fast=fast,
        alpha_fast=float(min(1.0, T / det.fast_window) if fast else 0.0),
        fast2=float(det.fast_threshold**2 if fast else 0.0),
        fast_learned=cfg.seconds(det.long_window) if fast else 0,
        det_speed=float(max(det.speed, sel_threshold)),
        creep_margin=float(det.creep_margin),
        hold_above2=float(det.hold_above**2 if held else 0.0),
        hold=max(hold, 1) if held else 0,
        # payload mode: control keeps the starting payload until the first alarm (the kernel's
        # _keep_start); in mode "arm" the payload block also takes up the arm's error meanwhile
        keep_start=cfg.mode == "payload",
    )


def _channels(cfg: OnlineConfig, n: int) -> int:
    """Filter channels of the momentum form, n joints."""
    return K.arm_momentum_channels(n) if cfg.mode == "arm" else K.MOMENTUM_CHANNELS * n


def est_init(
    cfg: OnlineConfig, arm: Arm, n_trials: int, sigma_nominal: ArrayLike | None = None
) -> tuple[EstCfg, EstState]:
    """Compiled configuration and initial state of ``n_trials`` estimators.

    Parameters
    ----------
    cfg : OnlineConfig
    arm : Arm
        The arm (its standard parameters ``arm.pi`` are the known part in payload mode).
    n_trials : int
    sigma_nominal : array_like (p,) or (n_trials, p), optional
        Nominal base parameters: in mode ``"arm"`` the initial estimate (default ``arm.sigma``,
        its payload in the payload block); in payload mode the initial payload is the one it implies
        (``arm.payload_from_sigma``; default no payload).

    Returns
    -------
    EstCfg, EstState
    """
    if not isinstance(cfg, OnlineConfig):
        raise ParameterError(f"cfg must be a OnlineConfig, got {type(cfg).__name__}")
    if not isinstance(n_trials, int | np.integer) or isinstance(n_trials, bool) or n_trials < 1:
        raise ParameterError(f"n_trials must be an integer >= 1, got {n_trials!r}")
    c, P0 = _pack(cfg, arm)
    n = arm.n_joints
    p = P0.shape[0]
    if sigma_nominal is None:
        th0 = np.zeros(10) if cfg.mode == "payload" else np.concatenate((arm.sigma, np.zeros(10)))
    else:
        s = np.asarray(sigma_nominal, dtype=float)
        if s.shape[-1] != arm.base.count or not np.all(np.isfinite(s)):
            raise ParameterError(
                f"sigma_nominal must be {arm.base.count} finite base parameters, got shape {s.shape}"
            )
        pay = arm.payload_from_sigma(s).params
        # mode "arm": the nominal arm known to the prior, its payload in the payload block
        th0 = pay if cfg.mode == "payload" else np.concatenate((s - pay @ arm.payload_basis.T, pay))
    theta = np.broadcast_to(th0, (n_trials, p)).copy()
    cnt = np.zeros((n_trials, K.N_CNT), dtype=np.int64)
    cnt[:, K.C_SINCE_ALARM] = K.BIG
    cnt[:, K.C_LAST_ALARM] = -1
    cnt[:, K.C_REOPEN_AT] = -1
    m = n_trials
    state = EstState(
        xf=np.zeros((m, _channels(cfg, n), cfg.bank.order)),
        u_last=np.zeros((m, 4 * n)),
        tau_prev=np.zeros((m, n)),
        cnt=cnt,
        since_slow=np.zeros((m, n), dtype=np.int64),
        seen=np.zeros((m, n), dtype=np.int64),
        learned=np.zeros((m, n), dtype=np.int64),
        theta=theta,
        P=np.broadcast_to(P0, (m, p, p)).copy(),
        lam=np.full(m, cfg.lam0),
        short=np.zeros((m, n)),
        long=np.zeros((m, n)),
        ref=np.zeros((m, n)),
        eps=np.full((m, n), np.nan),
        fast=np.zeros((m, n)),
        since_crawl=np.zeros((m, n), dtype=np.int64),
        hold=np.zeros((m, n)),
        held=np.zeros((m, n), dtype=np.int64),
        ref_pay=np.zeros((m, 10)),
        ref_rise=np.ones((m, n)),
        start_pay=np.zeros((m, 10)),
        start_mass=theta[:, p - 10].copy(),
        pvar=np.zeros((m, n)),
        pshort=np.zeros((m, n)),
        pfast=np.zeros((m, n)),
        plong=np.zeros((m, n)),
        pref=np.zeros((m, n)),
        eout=np.full((m, n), np.nan),
        nvar=np.zeros((m, n)),
        nshort=np.zeros((m, n)),
        nlong=np.zeros((m, n)),
        nref=np.zeros((m, n)),
    )
    for i in range(m):  # the payload the model control uses at the start
        K.est_payload_trial(c, state, i, state.start_pay[i])
    return c, state
