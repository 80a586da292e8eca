"""The compiled closed loop: plant, sensors, estimator and control law of a trial in one numba call.

For the built-in controllers (``pd``, ``ct_nominal``, ``ct_oracle``, ``ct_oracle_textbook``,
``adaptive_ct``, ``adaptive_ct_paper``, ``slotine_li``, ``slotine_li_oracle``)
:func:`closed_loop_block` runs a block of samples of every trial, trials in parallel
across cores (``numba.prange``), calling the same compiled pieces as the Python path:
the actuator and sensor models
(:mod:`adaptive_dd.plant.sampling`), the plant integrator, the control laws
(:mod:`adaptive_dd.controllers.laws`), the online estimator
(:mod:`adaptive_dd.identification.online_kernel`) and the streamed metrics
(:mod:`adaptive_dd.benchmark.streaming`). A controller spec says which law, with which
gains and model (:func:`compiled_spec`); plug-in controllers have none and run on the
Python path.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from adaptive_dd.benchmark.streaming import accumulate_trial
from adaptive_dd.controllers.laws import boost_trial, ct_trial, pd_trial, slotine_li_trial
from adaptive_dd.identification.online_kernel import C_SINCE_ALARM, online_step_trial
from adaptive_dd.plant.integrator import step_one
from adaptive_dd.plant.sampling import actuate_trial, measure_trial

__all__ = ["LAW_ADAPTIVE", "LAW_CT", "LAW_CT_ORACLE", "LAW_PD", "CompiledSpec", "compiled_spec"]

LAW_PD, LAW_CT, LAW_CT_ORACLE, LAW_ADAPTIVE, LAW_SLOTINE, LAW_SLOTINE_ORACLE = 0, 1, 2, 3, 4, 5

# slots of CompiledSpec.gains
G_KP, G_KD, G_LAM, G_PD_KP1, G_PD_KP2, G_PD_KD1, G_PD_KD2, G_DKP, G_DKD, G_BOOST_N = range(10)


class CompiledSpec(NamedTuple):
    """What the compiled loop needs of a controller: the law, its gains, its model, its estimator."""

    law: int
    gains: np.ndarray  # (10,) see G_*
    sigma: np.ndarray  # (7,) fixed model (CT) or nominal model (adaptive: start and boost)
    online: object  # OnlineConfig or None
    extra: np.ndarray = np.zeros(24)  # Slotine-Li: gamma (7), lo (7), hi (7), projection (3)


def compiled_spec(ctrl, sample_period: float) -> CompiledSpec | None:
    """The spec of a built-in controller, or None (run it on the Python path)."""
    import dataclasses

    from adaptive_dd.controllers.adaptive import AdaptiveCT
    from adaptive_dd.controllers.feedback import PD, ComputedTorque
    from adaptive_dd.controllers.slotine_li import PROJECTION, SlotineLi

    g = np.zeros(10)
    kind = type(ctrl)
    if kind is PD:
        g[G_PD_KP1 : G_PD_KP2 + 1], g[G_PD_KD1 : G_PD_KD2 + 1] = ctrl.kp, ctrl.kd
        return CompiledSpec(LAW_PD, g, np.zeros(7), None)
    if kind is ComputedTorque:
        gn = ctrl.gains
        g[G_KP], g[G_KD], g[G_LAM] = gn.kp, gn.kd, gn.lam if ctrl.reference else -1.0
        return CompiledSpec(LAW_CT_ORACLE if ctrl.oracle else LAW_CT, g, np.asarray(ctrl.sigma, float), None)
    if kind is SlotineLi:
        g[G_KP], g[G_KD], g[G_LAM] = 0.0, ctrl.kd, ctrl.lam
        extra = np.concatenate((ctrl.gamma, ctrl.lo, ctrl.hi, PROJECTION))
        law = LAW_SLOTINE_ORACLE if ctrl.oracle else LAW_SLOTINE
        return CompiledSpec(law, g, np.asarray(ctrl.theta0, float), None, extra)
    if kind is AdaptiveCT:
        gn = ctrl.gains
        g[G_KP], g[G_KD], g[G_LAM] = gn.kp, gn.kd, gn.lam
        if ctrl.boost_bandwidth is not None:
            g[G_DKP], g[G_DKD] = ctrl.boost_gains
            g[G_BOOST_N] = ctrl.boost_duration / sample_period
        online = ctrl.online
        if online.sample_period != sample_period:
            online = dataclasses.replace(online, sample_period=sample_period)
        return CompiledSpec(LAW_ADAPTIVE, g, np.asarray(ctrl.sigma_nominal, float), online)
    return None


@njit(cache=True)
def _command(
    law, g, sg_fixed, sg_true, sg_model, since_alarm, q, qd, q_d, qd_d, qdd_d, out, extra, T
):  # pragma: no cover
    if law == LAW_SLOTINE:
        slotine_li_trial(
            q, qd, q_d, qd_d, qdd_d, sg_model, sg_fixed, g[G_LAM], g[G_KD], T,
            extra[0:7], extra[7:14], extra[14:21], extra[21:24], out,
        )  # fmt: skip
    elif law == LAW_SLOTINE_ORACLE:
        th = sg_true.copy()
        slotine_li_trial(
            q, qd, q_d, qd_d, qdd_d, th, sg_fixed, g[G_LAM], g[G_KD], T,
            extra[0:0], extra[7:14], extra[14:21], extra[21:24], out,
        )  # fmt: skip
    elif law == LAW_PD:
        pd_trial(q, qd, q_d, qd_d, g[G_PD_KP1 : G_PD_KP2 + 1], g[G_PD_KD1 : G_PD_KD2 + 1], out)
    elif law == LAW_CT:
        ct_trial(q, qd, q_d, qd_d, qdd_d, sg_fixed, g[G_KP], g[G_KD], g[G_LAM], out)
    elif law == LAW_CT_ORACLE:
        ct_trial(q, qd, q_d, qd_d, qdd_d, sg_true, g[G_KP], g[G_KD], g[G_LAM], out)
    else:
        ct_trial(q, qd, q_d, qd_d, qdd_d, sg_model, g[G_KP], g[G_KD], g[G_LAM], out)
        if g[G_BOOST_N] > 0 and since_alarm < g[G_BOOST_N]:
            boost_trial(q, qd, q_d, qd_d, sg_fixed, g[G_DKP], g[G_DKD], out)


@njit(cache=True, parallel=True)
def closed_loop_block(
    k0, k1, noise, ref, sig_seg, swap_k, plant_f, plant_i, law, g, sg_fixed,
    extra, q, qd, stuck, slip, zb, failed, failed_at,
    xf, u_last, cnt, tau_prev, theta, P, lam, short, long, sigma_model,
    ci, cf, A, B, C, D, d, group, rows,
    seg_start, seg_settled, acc, e_norm, sigma_end, seg_end, alarm_t, n_alarms,
    rec_n, q_rec, qd_rec, tau_rec, sat_rec, sig_rec,
    drop, hq, hqd, n_drop,
):  # pragma: no cover - compiled  # fmt: skip
    """Samples ``k0 .. k1 - 1`` of every trial (prange over trials); state arrays updated in place.

    noise : (n, k1 - k0, 4) standard normal; ref : (N, 6) q_d, qd_d, qdd_d; sig_seg : (n_sw + 1, 7)
    true sigma before the first swap and after each; swap_k : (n_sw,) sample of each swap;
    plant_f : [T, max_speed, max_error, lim1, lim2, lsb1, lsb2, res1, res2, std1..4, friction
    velocity, stribeck ratio, stribeck velocity, LuGre sigma0 (2), sigma1 (2)]; zb : (n, 2) LuGre
    bristle state;
    plant_i : [substeps, saturate, quantize_dac, quantize_encoder, friction code].
    """
    n = q.shape[0]
    T, max_speed, max_error = plant_f[0], plant_f[1], plant_f[2]
    lim, lsb, res, std = plant_f[3:5], plant_f[5:7], plant_f[7:9], plant_f[9:13]
    adaptive = law == LAW_ADAPTIVE
    estimates = adaptive or law == LAW_SLOTINE
    for i in prange(n):
        qm = np.empty(2)
        qdm = np.empty(2)
        cmd = np.empty(2)
        tau = np.empty(2)
        eps = np.empty(2)
        lost_q = np.full(2, np.nan)
        has_drop = drop.shape[1] > 0
        for k in range(k0, k1):
            w = 0
            while w < swap_k.shape[0] and k >= swap_k[w]:
                w += 1
            sg_true = sig_seg[w]
            measure_trial(q[i], qd[i], noise[i, k - k0], res, std, plant_i[3] == 1, qm, qdm)
            lost = has_drop and drop[i, k - k0]
            if lost:  # the law gets the last good measurement, the estimator the NaN
                n_drop[i] += 1
                qm[0], qm[1], qdm[0], qdm[1] = hq[i, 0], hq[i, 1], hqd[i, 0], hqd[i, 1]
            else:
                hq[i, 0], hq[i, 1], hqd[i, 0], hqd[i, 1] = qm[0], qm[1], qdm[0], qdm[1]
            e1, e2 = ref[k, 0] - q[i, 0], ref[k, 1] - q[i, 1]
            _command(
                law, g, sg_fixed, sg_true, theta[i] if law == LAW_SLOTINE else sigma_model[i],
                cnt[i, C_SINCE_ALARM], qm, qdm, ref[k, 0:2], ref[k, 2:4], ref[k, 4:6], cmd, extra, T,
            )  # fmt: skip
            bad = not (np.isfinite(cmd[0]) and np.isfinite(cmd[1]))
            if max(abs(e1), abs(e2)) > max_error:
                bad = True
            if bad:
                cmd[0], cmd[1] = 0.0, 0.0
            mask = actuate_trial(cmd, lim, lsb, plant_i[1] == 1, plant_i[2] == 1, tau)
            if failed[i]:
                tau[0], tau[1] = 0.0, 0.0
            p1, p2 = q[i, 0], q[i, 1]
            if i < rec_n:
                qd_rec[i, k, 0], qd_rec[i, k, 1] = qd[i, 0], qd[i, 1]
            step_one(
                q, qd, stuck, slip, zb, i, tau, sg_true, T, plant_i[0], plant_i[4], plant_f[13:20],
            )  # fmt: skip
            ok = np.isfinite(q[i, 0]) and np.isfinite(q[i, 1])
            ok = ok and abs(qd[i, 0]) < max_speed and abs(qd[i, 1]) < max_speed
            if bad or not ok or failed[i]:
                if not failed[i]:
                    failed_at[i] = k
                failed[i] = True
                q[i, 0] = p1 if np.isfinite(p1) else 0.0
                q[i, 1] = p2 if np.isfinite(p2) else 0.0
                qd[i, 0], qd[i, 1] = 0.0, 0.0
                stuck[i, 0], stuck[i, 1] = True, True
            s = accumulate_trial(acc[i], e_norm[i], k, seg_start, seg_settled, e1, e2, tau, mask)
            if adaptive:
                alarm = online_step_trial(
                    i, xf, u_last, cnt, tau_prev, theta, P, lam, short, long, sigma_model,
                    lost_q if lost else qm, lost_q if lost else qdm, tau,
                    ci, cf, A, B, C, D, d, group, rows, eps,
                )  # fmt: skip
                if alarm == 1 and n_alarms[i] < alarm_t.shape[1]:
                    alarm_t[i, n_alarms[i]] = k * T
                    n_alarms[i] += 1
            if estimates and k == seg_end[s] - 1:
                sigma_end[i, s] = theta[i]
            if i < rec_n:
                q_rec[i, k, 0], q_rec[i, k, 1] = ref[k, 0] - e1, ref[k, 1] - e2
                tau_rec[i, k, 0], tau_rec[i, k, 1] = tau[0], tau[1]
                sat_rec[i, k, 0], sat_rec[i, k, 1] = (mask & 1) != 0, (mask & 2) != 0
                if estimates:
                    for j in range(7):
                        sig_rec[i, k, j] = theta[i, j]
