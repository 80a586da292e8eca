"""The N-joint online estimator (online): agreement with a numpy/Pinocchio pipeline,
stepping vs whole record, payload identification across a swap on a UR5, detection once,
no alarm at constant payload, re-arming after a false alarm, dropouts, projection."""

import numpy as np
import pinocchio as pin
import pytest
from detector_steps import detector_sample
from hypothesis import given, settings
from hypothesis import strategies as st

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.identification.filters import design_filter_bank, filter_record
from adaptive_dd.identification.online import (
    Detector,
    OnlineConfig,
    compact_prior,
    est_force_alarm_trial,
    est_init,
    est_model,
    est_model_trial,
    est_payload_trial,
    est_step,
    project_payload,
    run_online,
    state_alarms,
    state_skipped,
)
from adaptive_dd.identification.rls import RLSConfig, rls_init, rls_step
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
POSTURE = [0.0, -1.2, 1.2, -1.5, -1.5, 0.0]  # UR5: elbow up, wrist down
PAY_A = payload_parameters(1.0, [0.0, 0.0, 0.05], radius=0.05)
PAY_B = payload_parameters(2.5, [0.03, 0.0, 0.08], radius=0.05)


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def _record(arm, seed, n, payloads, swaps=(), speed=0.5):
    t = np.arange(n) * T
    rng = np.random.default_rng(seed)
    motion = exciting_motion(arm, t, rng, offset=POSTURE, speed=speed)
    return prescribed_record(arm, t, motion, payloads, swaps, rng=rng)


@pytest.fixture(scope="module")
def swap_record(ur5):
    """20 s at 1 kHz, the shipped sensor noise, 1 kg payload then 2.5 kg from 10 s on."""
    return _record(ur5, 1, 20_000, [PAY_A, PAY_B], [10_000])


def _com(p):
    return p[1:4] / p[0]


# ------------------------------------------------------------------------------------ settings
@pytest.mark.parametrize(
    "kw, match",
    [
        ({"mode": "joint"}, "mode.*'joint'"),
        ({"tau_f": 1e-4}, "tau_f = 0.0001"),
        ({"lam0": 1.5}, "lam0.*1.5"),
        ({"mu": -0.1}, "mu.*-0.1"),
        ({"selection": (0.05,)}, "selection"),
        ({"row_weights": (1.0, -1.0)}, "row_weights"),
        ({"detector": "yes"}, "detector.*str"),
        ({"project": 1}, "project.*1"),
        ({"max_trace": float("nan")}, "max_trace.*nan"),
        ({"bound_radius": 0.0}, "bound_radius.*0.0"),
        ({"prior_radius": -0.05}, "prior_radius.*-0.05"),
        ({"mode": "full"}, "mode must be one of \\('payload', 'arm'\\), got 'full'"),
    ],
)
def test_bad_settings_name_the_field_and_value(kw, match):
    with pytest.raises(ParameterError, match=match):
        OnlineConfig(**kw)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"threshold": 1.0}, "threshold.*1.0"),
        ({"short_window": 2.0}, "short_window < long_window"),
        ({"min_learned": 0}, "min_learned.*0"),
        ({"reopen_again": "no"}, "reopen_again.*'no'"),
        ({"floor": -1.0}, "floor.*-1.0"),
        ({"fast_window": 0.02}, "fast_window < short_window"),
        ({"fast_window": -0.001}, "fast_window"),
        ({"fast_threshold": 1.0}, "fast_threshold"),
    ],
)
def test_bad_detector_settings_name_the_field_and_value(kw, match):
    with pytest.raises(ParameterError, match=match):
        Detector(**kw)


def test_removed_options_are_unknown_settings(ur5):
    """``regression`` (the signals form, measured and removed: docs/changelog.md) is no setting."""
    from adaptive_dd.controllers import make_controller

    with pytest.raises(ParameterError, match=r"adaptive_ct\.estimator: .*'regression'"):
        make_controller("adaptive_ct", options={"estimator": {"regression": "signals"}}, arm=ur5)


def test_wrong_shapes_are_refused(ur5):
    c, s = est_init(OnlineConfig(), ur5, 2)
    with pytest.raises(SignalError, match=r"q must have shape \(2, 6\)"):
        est_step(c, s, np.zeros((2, 5)), np.zeros((2, 6)), np.zeros((2, 6)))
    with pytest.raises(ParameterError, match="row_weights must have 6"):
        est_init(OnlineConfig(row_weights=(1.0, 2.0)), ur5, 1)
    with pytest.raises(ParameterError, match="n_trials"):
        est_init(OnlineConfig(), ur5, 0)


# ------------------------------------------------------------------- the arithmetic, independently
def _rls_rows(phi, y, theta0, P0, cfg):
    rc = RLSConfig(lam0=cfg.lam0, mu=cfg.mu, p0=1.0, max_trace=1e12)
    st_ = rls_init(len(theta0), rc, theta0=theta0)._replace(P=P0.copy())
    for k in range(phi.shape[0]):
        for row in range(phi.shape[1]):
            st_, _ = rls_step(st_, phi[k, row], y[k, row], rc, forget=row == 0)
    return st_.theta


def _pin_momentum(arm, q, qd):
    """By Pinocchio, per sample: the known arm's ``M qd`` (with armature) and ``g - C^T qd`` (with
    friction), and the payload link's two per unit parameter (differences of a model holding that
    link alone): (N, n), (N, n), (N, n, 10), (N, n, 10)."""
    model, j, n = arm.model, arm.payload_joint, arm.n_joints
    alone = model.copy()
    for b in range(1, n + 1):
        alone.inertias[b] = pin.Inertia.Zero()
    data, data_alone = model.createData(), alone.createData()
    base = arm.pi_links[10 * j : 10 * j + 10]

    def form(m, d, pq, v):
        mm = np.atleast_2d(pin.crba(m, d, pq))
        mm = np.triu(mm) + np.triu(mm, 1).T
        cor = np.atleast_2d(pin.computeCoriolisMatrix(m, d, pq, v))
        return mm @ v, pin.computeGeneralizedGravity(m, d, pq) - cor.T @ v

    N = q.shape[0]
    p, w = np.empty((N, n)), np.empty((N, n))
    py, wy = np.empty((N, n, 10)), np.empty((N, n, 10))
    for k in range(N):
        pq = arm.pin_configuration(q[k])
        p[k], w[k] = form(model, data, pq, qd[k])
        p[k] += arm.armature * qd[k]
        w[k] += arm.viscous * qd[k] + arm.coulomb * np.sign(qd[k])
        alone.inertias[j + 1] = pin.Inertia.FromDynamicParameters(base)
        p0, w0 = form(alone, data_alone, pq, qd[k])
        for c in range(10):
            params = base.copy()
            params[c] += 1.0
            alone.inertias[j + 1] = pin.Inertia.FromDynamicParameters(params)
            p1, w1 = form(alone, data_alone, pq, qd[k])
            py[k, :, c], wy[k, :, c] = p1 - p0, w1 - w0
    return p, w, py, wy


def test_momentum_form_equals_a_numpy_pinocchio_pipeline(ur5, swap_record):
    """The momentum form by Pinocchio (M, C, g), scipy's lfilter (momentum channels started in
    their steady state, the others at rest) and rls_step: the same estimate as the compiled step."""
    n = 300
    r = swap_record
    cfg = OnlineConfig(align=False, selection=None, detector=None, max_trace=1e12, lam0=0.999,
                             mu=0.01, row_weights=(1.0,) * 6)  # fmt: skip
    rec = run_online(ur5, cfg, r.q_meas[:n], r.qd_meas[:n], r.tau[:n])
    p, w, py, wy = _pin_momentum(ur5, r.q_meas[:n], r.qd_meas[:n])
    bank = design_filter_bank("M2", cfg.tau_f, T)

    def g(x, out, steady):
        return filter_record(bank, x, axis=0, initial=x[0] if steady else None)[..., out]

    phi = (g(py, 1, True) + g(wy, 0, False)) @ ur5.payload_map
    y = g(r.tau[:n], 0, False) - g(p, 1, True) - g(w, 0, False)
    _, s0 = est_init(cfg, ur5, 1)
    theta = _rls_rows(phi, y, np.zeros(10), s0.P[0], cfg)
    scale = np.maximum(np.abs(theta), 1e-3)
    assert np.max(np.abs(rec.theta[0, -1] - theta) / scale) < 1e-6
    assert np.max(np.abs(theta) / scale) > 1e-3  # it did move


def test_momentum_channels_equal_the_banks_filters_one_per_signal(ur5, swap_record):
    """The compiled momentum form (one summing state per equation entry, 12 n channels) gives
    ``G0 tau``, ``G1 p + G0 wv`` and ``G1 py + G0 wy`` of the bank run on each of the 23 n
    signals apart (momentum signals started in their steady state, the others at rest), to
    round-off, also across a restart after an alarm."""
    from adaptive_dd.identification import online_kernel as K
    from adaptive_dd.identification.filters import filter_step
    from adaptive_dd.plant.chain import momentum_form

    N, restart_at = 400, 250
    r = swap_record
    q, qd, tau = (np.ascontiguousarray(x[:N]) for x in (r.q_meas, r.qd_meas, r.tau))
    cfg = OnlineConfig(align=False, selection=None, detector=None)
    c, s = est_init(cfg, ur5, 1)
    n = ur5.n_joints
    assert s.xf.shape == (1, K.MOMENTUM_CHANNELS * n, cfg.bank.order) == (1, 12 * n, 2)
    got = np.empty((N, n, 12))  # tf, ym, phim
    w = K.est_work(n, 10)
    for k in range(N):
        if k == restart_at:
            s.cnt[0, K.C_RESTART] = 1
        K._filtered_signals(c, s, 0, q[k], qd[k], tau[k], w)
        got[k, :, 0], got[k, :, 1], got[k, :, 2:] = w.tf, w.ym, w.phim
    bank = cfg.bank
    pi, jp = ur5.pi, ur5.payload_joint
    want = np.empty_like(got)
    x = np.zeros((n, 23, bank.order))  # per joint: tau, p, wv, py (10), wy (10)
    for k in range(N):
        p, wv, py, wy = np.empty(n), np.empty(n), np.empty((n, 10)), np.empty((n, 10))
        momentum_form(ur5.chain, pi[: 10 * n], jp, q[k], qd[k], p, wv, py, wy)
        p += ur5.armature * qd[k]
        wv += ur5.viscous * qd[k] + ur5.coulomb * np.sign(qd[k])
        u = np.concatenate([tau[k][:, None], p[:, None], wv[:, None], py, wy], axis=1)  # (n, 23)
        if k in (0, restart_at):
            momentum = np.zeros(23, dtype=bool)
            momentum[[1, *range(3, 13)]] = True
            x = np.where(momentum[:, None], bank.steady_state(u), 0.0)
        x, f = filter_step(bank, x, u)
        want[k, :, 0] = f[:, 0, 0]
        want[k, :, 1] = f[:, 1, 1] + f[:, 2, 0]
        want[k, :, 2:] = f[:, 3:13, 1] + f[:, 13:, 0]
    scale = np.abs(want).max(axis=0)  # per joint and entry
    assert np.all(np.abs(got - want) <= 1e-9 * scale + 1e-12), np.max(np.abs(got - want) / (scale + 1e-12))
    jump = np.abs(want[restart_at, :, 1] - want[restart_at - 1, :, 1]).max()
    assert jump > 1e-3 * scale[:, 1].max()  # the restart did change the filtered equation


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_momentum_form_is_exact_and_forgets_the_old_payload_at_an_alarm(ur5, seed):
    """Noise-free record (torques exact at the samples): the momentum form's prior errors stay
    at the level of an estimate still converging, and after a swap its filters restart, so the
    centre of mass is within 1 cm 100 ms after the swap."""
    t = np.arange(2_000) * T
    rng = np.random.default_rng(seed)
    r = prescribed_record(ur5, t, exciting_motion(ur5, t, rng, offset=POSTURE), [PAY_A, PAY_B], [1_500])
    rec = run_online(ur5, OnlineConfig(align=False), r.q_meas, r.qd_meas, r.tau)
    eps = np.nanmax(np.abs(rec.eps[0, 1_000:1_500]))
    assert eps < 5e-3, eps
    (alarms,) = rec.alarm_times()
    assert len(alarms) == 1 and 1.5 <= alarms[0] < 1.53, alarms
    assert np.linalg.norm(rec.com[0, 1_600] - _com(PAY_B)) < 0.01, rec.com[0, 1_600]
    assert abs(rec.mass[0, 1_600] - PAY_B[0]) < 0.01 * PAY_B[0], rec.mass[0, 1_600]


@pytest.mark.parametrize("mode", ["payload", "arm"])
def test_stepping_equals_the_whole_record_bit_for_bit(ur5, mode):
    """Two trials, 1.6 s, a swap at 1.0 s (an alarm inside), a dropout: every output identical."""
    n = 1600
    recs = [_record(ur5, seed, n, [PAY_A, PAY_B], [1000]) for seed in (3, 4)]
    q = np.stack([r.q_meas for r in recs])
    qd = np.stack([r.qd_meas for r in recs])
    tau = np.stack([r.tau for r in recs])
    q[1, 300, 2] = np.nan
    cfg = OnlineConfig(mode=mode)
    rec = run_online(ur5, cfg, q, qd, tau)
    c, s = est_init(cfg, ur5, 2)
    theta = np.empty_like(rec.theta)
    eps = np.empty_like(rec.eps)
    alarm = np.zeros(rec.alarm.shape, dtype=bool)
    pay = np.empty(10)
    for k in range(n):
        info = est_step(c, s, q[:, k], qd[:, k], tau[:, k])
        theta[:, k], eps[:, k], alarm[:, k] = s.theta, info.eps, info.alarm
        est_payload_trial(c, s, 1, pay)
        assert np.array_equal(pay, rec.payload[1, k])
    assert rec.alarm.any(axis=1).all()
    assert np.array_equal(alarm, rec.alarm)
    assert np.array_equal(theta, rec.theta)
    assert np.array_equal(eps, rec.eps, equal_nan=True)
    assert np.array_equal(state_skipped(s), rec.n_skipped)
    assert rec.n_skipped.tolist() == [0, 1]


# ---------------------------------------------------------------------------------- payload mode
def test_payload_mode_identifies_each_segment_and_detects_the_swap_once(ur5, swap_record):
    rec = run_online(ur5, OnlineConfig(), swap_record.q_meas, swap_record.qd_meas, swap_record.tau)
    for end, pay in ((9_999, PAY_A), (19_999, PAY_B)):
        m = rec.mass[0, end]
        assert abs(m - pay[0]) < 0.05 * pay[0], (end, m)
        assert np.linalg.norm(rec.com[0, end] - _com(pay)) < 0.01, (end, rec.com[0, end])
    (alarms,) = rec.alarm_times()
    assert len(alarms) == 1 and 10.0 <= alarms[0] < 10.05, alarms


def test_the_control_model_carries_the_payload(ur5, swap_record):
    """est_model_trial: the arm's pi with the estimated payload folded in; its torques match the truth."""
    r = swap_record
    cfg = OnlineConfig()
    c, s = est_init(cfg, ur5, 1)
    for k in range(9_000):
        est_step(c, s, r.q_meas[k : k + 1], r.qd_meas[k : k + 1], r.tau[k : k + 1])
    pi = np.empty(78)
    est_model_trial(c, s, 0, pi)
    j = ur5.payload_joint
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)
    expect = ur5.pi.copy()
    expect[10 * j : 10 * j + 10] += ur5.payload_map @ pay
    assert np.allclose(pi, expect, rtol=0, atol=1e-12)
    true_pi = ur5.pi.copy()
    true_pi[10 * j : 10 * j + 10] += ur5.payload_map @ PAY_A
    k = np.arange(0, 9_000, 97)
    W = ur5.standard_regressor(r.q[k], r.qd[k], r.qdd[k])
    err = np.abs(W @ (pi - true_pi)).max()
    assert err < 0.02 * np.abs(W @ true_pi).max(), err
    assert np.array_equal(est_model(c, s)[0], pi)


def test_no_alarm_over_a_long_run_at_constant_payload(ur5):
    """Two 30 s trials (different motions and noise), one payload throughout: no alarm."""
    recs = [_record(ur5, seed, 30_000, [PAY_B]) for seed in (11, 12)]
    stack = [np.stack([getattr(r, a) for r in recs]) for a in ("q_meas", "qd_meas", "tau")]
    rec = run_online(ur5, OnlineConfig(), *stack)
    assert not rec.alarm.any(), rec.alarm_times()
    assert np.all(np.abs(rec.mass[:, -1] - PAY_B[0]) < 0.05 * PAY_B[0])


def test_the_fast_average_detects_a_swap_sooner(ur5, swap_record):
    """The fast average (4 ms, 6x in RMS) raises the swap's alarm samples before the 20 ms
    average alone does, with no other alarm over the 20 s record; a 10 N m error on the elbow
    alone for 60 ms alarms within it."""
    fast = dict(fast_window=0.004, fast_threshold=6.0)
    hits = {}
    for name, kw in (("slow", {"fast_window": None}), ("fast", fast)):
        cfg = OnlineConfig(detector=Detector(**kw))
        rec = run_online(ur5, cfg, swap_record.q_meas, swap_record.qd_meas, swap_record.tau)
        (hits[name],) = np.nonzero(rec.alarm[0])
    assert len(hits["slow"]) == len(hits["fast"]) == 1, hits
    assert 10_000 <= hits["fast"][0] < hits["slow"][0] < 10_050, hits
    r = _record(ur5, 5, 4_000, [PAY_B])
    tau = r.tau.copy()
    tau[2_500:2_560, 2] += 10.0
    cfg = OnlineConfig(detector=Detector(**fast))
    (one,) = run_online(ur5, cfg, r.q_meas, r.qd_meas, tau).alarm_times()
    assert len(one) >= 1 and 2.5 <= one[0] < 2.6, one


def _slow_wrist_record(ur5, seed, n, payloads, swaps=()):
    """A record whose joint 4 (wrist 2) creeps at 0.06-0.14 rad/s (in use by the estimator, slower
    than the detector's speed: where friction the model lacks errs), the others as ``_record``."""
    t = np.arange(n) * T
    rng = np.random.default_rng(seed)
    q, qd, qdd = exciting_motion(ur5, t, rng, offset=POSTURE)
    w = 2 * np.pi * 1.5
    q[:, 4] = POSTURE[4] + 0.1 * t + 0.04 / w * np.sin(w * t)
    qd[:, 4] = 0.1 + 0.04 * np.cos(w * t)
    qdd[:, 4] = -0.04 * w * np.sin(w * t)
    return prescribed_record(ur5, t, (q, qd, qdd), payloads, swaps, rng=rng)


def test_an_error_at_a_creeping_joint_within_its_friction_does_not_alarm(ur5):
    """Friction the model lacks errs at a joint near rest (the UR5's false alarms on Stribeck and
    soft plants came from one wrist row whose joint crept at 0.05-0.07 rad/s), by about the
    friction itself. A 0.7 N m burst for 30 ms on a wrist joint (Coulomb friction 1 N m) that
    creeps at 0.06-0.14 rad/s raises no alarm; the detector without the creeping rule
    (``speed = 0``) alarms on it, and so does the default one for the same burst on that joint
    moving fast, or for a 3 N m burst (beyond its friction) on the creeping joint. A payload swap
    on the creeping record is detected within 50 ms."""
    assert ur5.coulomb[4] == 1.0
    k_b = 2_500
    r = _slow_wrist_record(ur5, 3, 4_000, [PAY_A])

    def alarms(rec, burst, k, cfg=None):
        tau = rec.tau.copy()
        tau[k : k + 30, 4] += burst
        return run_online(ur5, cfg or OnlineConfig(), rec.q_meas, rec.qd_meas, tau).alarm_times()[0]

    assert alarms(r, 0.4, k_b) == []
    ungated = alarms(r, 0.4, k_b, OnlineConfig(detector=Detector(speed=0.0)))
    assert len(ungated) >= 1 and 2.5 <= ungated[0] < 2.55, ungated
    beyond = alarms(r, 3.0, k_b)
    assert len(beyond) >= 1 and 2.5 <= beyond[0] < 2.55, beyond
    fast = _record(ur5, 3, 4_000, [PAY_A])
    speed = np.abs(fast.qd[:, 4])
    k_f = next(k for k in range(1_500, 3_900) if speed[k - 100 : k + 30].min() > 0.4)
    hit = alarms(fast, 0.4, k_f)
    assert len(hit) >= 1 and k_f * T <= hit[0] < (k_f + 50) * T, (k_f, hit)
    sw = _slow_wrist_record(ur5, 3, 4_000, [PAY_A, PAY_B], [3_000])
    (swap,) = run_online(ur5, OnlineConfig(), sw.q_meas, sw.qd_meas, sw.tau).alarm_times()
    assert len(swap) == 1 and 3.0 <= swap[0] < 3.05, swap


def test_the_detector_rearms_within_its_bound(ur5):
    """A glitch raises a false alarm; a payload swap right after the documented re-arm bound
    raises the next alarm. Without the creeping-joint rule (``speed = 0``): on this record the
    swap is found by the shoulder-pan row, whose joint creeps at 0.07 rad/s with a 0.2 N m error
    (its Coulomb friction is 6 N m); with the rule no row finds it within the record, the moving
    rows' levels, re-learnt from 300 samples after the glitch, absorbing the swap's rising error
    (a limit of the level's learning, docs/change_detection.md, "Creeping joints")."""
    cfg = OnlineConfig(detector=Detector(speed=0.0))
    bound = cfg.rearm_samples
    assert bound == 500  # holdoff 200; resume 10 x 30 + min_learned 200 samples
    k1 = 1_500
    r = _record(ur5, 7, 4_000, [PAY_A])
    tau = r.tau.copy()
    tau[k1 : k1 + 20, 1] += 8.0
    first = run_online(ur5, cfg, r.q_meas, r.qd_meas, tau)
    (hits,) = np.nonzero(first.alarm[0])
    assert len(hits) == 1 and k1 <= hits[0] < k1 + 30, hits
    k2 = hits[0] + bound + 1
    r = _record(ur5, 7, 4_000, [PAY_A, PAY_B], [k2])  # the same motion and noise, a swap at k2
    tau = r.tau.copy()
    tau[k1 : k1 + 20, 1] += 8.0
    rec = run_online(ur5, cfg, r.q_meas, r.qd_meas, tau)
    (hits2,) = np.nonzero(rec.alarm[0])
    # within 92 ms: the rows judge it on what they re-learnt since the glitch (within 60 ms while a
    # row out of use kept its pre-glitch level past the bound, which after a real swap is stale:
    # the iiwa's false alarms, test_the_level_before_an_alarm_serves_no_longer_than_the_rearm_bound)
    assert len(hits2) == 2 and hits2[0] == hits[0] and k2 <= hits2[1] < k2 + 100, hits2


@pytest.mark.parametrize("before", [0.05, 0.15, 0.29, 0.45])
def test_a_swap_just_after_a_forced_false_alarm_is_still_detected(ur5, before):
    """A false alarm forced `before` s ahead of a true swap: the swap still raises one alarm,
    within the re-arm bound, and the payload is identified."""
    ks = 2_000
    r = _record(ur5, 5, 3_500, [PAY_A, PAY_B], [ks])
    cfg = OnlineConfig()
    c, s = est_init(cfg, ur5, 1)
    kf = ks - round(before / T)
    hits = []
    for k in range(3_500):
        if est_step(c, s, r.q_meas[k : k + 1], r.qd_meas[k : k + 1], r.tau[k : k + 1]).alarm[0]:
            hits.append(k)
        if k == kf:
            est_force_alarm_trial(c, s, 0)
    assert state_alarms(s).tolist() == [len(hits) + 1]
    assert len(hits) == 1 and ks <= hits[0] <= max(ks + 50, kf + cfg.rearm_samples), hits
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)
    assert abs(pay[0] - PAY_B[0]) < 0.05 * PAY_B[0]
    assert np.linalg.norm(_com(pay) - _com(PAY_B)) < 0.01


def test_a_glitch_just_before_a_swap_does_not_mask_it(ur5):
    """A torque glitch (20 ms, 8 N m) raises a false alarm 0.29 s before a swap: the swap raises another."""
    ks = 2_000
    r = _record(ur5, 5, 3_500, [PAY_A, PAY_B], [ks])
    tau = r.tau.copy()
    kg = ks - 290
    tau[kg : kg + 20, 1] += 8.0
    cfg = OnlineConfig()
    rec = run_online(ur5, cfg, r.q_meas, r.qd_meas, tau)
    hits = np.flatnonzero(rec.alarm[0])
    assert len(hits) == 2 and kg <= hits[0] < kg + 30 and ks <= hits[1] < ks + 50, hits
    assert abs(rec.mass[0, -1] - PAY_B[0]) < 0.05 * PAY_B[0]
    assert np.linalg.norm(rec.com[0, -1] - _com(PAY_B)) < 0.01


def test_non_finite_samples_are_skipped_and_counted(ur5):
    r = _record(ur5, 8, 6_000, [PAY_A])
    q, qd, tau = r.q_meas.copy(), r.qd_meas.copy(), r.tau.copy()
    rng = np.random.default_rng(0)
    bad = rng.choice(np.arange(1_000, 5_000), 12, replace=False)
    q[bad[:4], 0] = np.nan
    qd[bad[4:8], 3] = np.inf
    tau[bad[8:], 5] = np.nan
    rec = run_online(ur5, OnlineConfig(), q, qd, tau)
    assert rec.n_skipped.tolist() == [12]
    assert np.all(np.isfinite(rec.theta)) and np.all(np.isfinite(rec.payload))
    assert np.all(np.isnan(rec.eps[0, bad]))  # no equation used at a bad sample
    assert not rec.alarm.any()
    assert abs(rec.mass[0, -1] - PAY_A[0]) < 0.05 * PAY_A[0]


# ----------------------------------------------------------------------------------- projection
def _pseudo_inertia(p):
    m, h = p[0], p[1:4]
    ixx, ixy, iyy, ixz, iyz, izz = p[4:]
    inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    J = np.zeros((4, 4))
    J[:3, :3] = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    J[:3, 3] = J[3, :3] = h
    J[3, 3] = m
    return J


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-5.0, 5.0), min_size=10, max_size=10), st.floats(1e-3, 1.0))
def test_projection_keeps_mass_nonnegative_and_pseudo_inertia_psd(values, scale):
    raw = np.array(values) * np.array([1.0] + [scale] * 3 + [scale**2] * 6)
    out = np.empty(10)
    project_payload(raw, out, 0.0)
    tol = 1e-12 * max(1.0, np.abs(raw).max())
    assert out[0] >= -tol
    assert np.linalg.eigvalsh(_pseudo_inertia(out)).min() >= -tol
    again = np.empty(10)
    project_payload(out, again, 0.0)  # a consistent payload is its own projection
    assert np.allclose(again, out, rtol=0, atol=1e-9 * max(1.0, np.abs(out).max()))
    # nearest in the pseudo-inertia's Frobenius norm: no farther than the origin-free clip of J
    J = _pseudo_inertia(raw)
    lam, V = np.linalg.eigh(J)
    assert np.allclose(
        _pseudo_inertia(out), (V * np.maximum(lam, 0)) @ V.T, atol=1e-9 * max(1, np.abs(J).max())
    )


def test_projection_leaves_a_rigid_body_unchanged():
    rng = np.random.default_rng(3)
    for _ in range(20):
        p = payload_parameters(rng.uniform(0.1, 5), rng.uniform(-0.1, 0.1, 3), radius=rng.uniform(0, 0.1))
        out = np.empty(10)
        project_payload(p, out, 0.0)
        assert np.allclose(out, p, rtol=0, atol=1e-12)  # a flat disk lies on the boundary


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-5.0, 5.0), min_size=10, max_size=10),
    st.floats(1e-3, 1.0),
    st.floats(0.01, 0.5),
)
def test_projection_onto_a_ball_is_consistent_and_within_it(values, scale, radius):
    raw = np.array(values) * np.array([1.0] + [scale] * 3 + [scale**2] * 6)
    out = np.empty(10)
    project_payload(raw, out, 0.0, radius)
    J = _pseudo_inertia(out)
    tol = 1e-12 * max(1.0, np.abs(raw).max())
    assert out[0] >= 0.0
    assert np.linalg.eigvalsh(J).min() >= -tol
    assert np.trace(J[:3, :3]) <= out[0] * radius**2 + tol  # tr(Sigma) <= m R^2
    assert np.linalg.norm(out[1:4]) <= out[0] * radius + tol  # |m c| <= m R
    again = np.empty(10)
    project_payload(out, again, 0.0, radius)  # a payload within the ball is its own projection
    assert np.allclose(again, out, rtol=0, atol=1e-9 * max(1.0, np.abs(out).max()))


def test_projection_of_a_point_mass_on_the_ball_surface_does_not_divide_by_zero():
    """Found by hypothesis: a first projection left a point mass exactly on the ball's surface
    (no spread, tr_s = 0, room < 0 by round-off); projecting it again divided 0 by 0."""
    raw = np.array([0.0, 1.708142752371046, -1.9, -1.0554732485163179, -1.9, 0.0, 0.0])
    raw = np.r_[raw, 0.8246017042535403, 2.190343359432653, -1.8179526042325196]
    raw *= np.array([1.0] + [1e-3] * 3 + [1e-6] * 6)
    out, again = np.empty(10), np.empty(10)
    project_payload(raw, out, 0.0, 0.1437920259974524)
    project_payload(out, again, 0.0, 0.1437920259974524)
    assert np.all(np.isfinite(again)) and np.allclose(again, out, rtol=1e-9, atol=1e-15), (out, again)


def test_projection_onto_a_ball_leaves_a_body_within_it_unchanged_and_empties_a_vanishing_mass():
    rng = np.random.default_rng(4)
    for _ in range(20):  # a disk of radius <= 0.1 m whose centre is <= 0.1 m out lies in a 0.25 m ball
        p = payload_parameters(rng.uniform(0.1, 5), rng.uniform(-0.1, 0.1, 3) / np.sqrt(3), radius=0.1)
        out = np.empty(10)
        project_payload(p, out, 0.0, 0.25)
        assert np.allclose(out, p, rtol=0, atol=1e-12)  # a flat disk lies on the PSD boundary
    # what the estimator left with no payload on: 1.6 g holding 4e-3 kg m^2 of inertia
    raw = np.array([1.6e-3, 2e-4, -1e-4, 3e-4, 4e-3, 1e-4, 3e-3, 0.0, -2e-4, 2e-3])
    out = np.empty(10)
    project_payload(raw, out, 0.0, 0.25)
    assert out[0] <= raw[0]
    assert np.abs(out[4:]).max() <= 2 * out[0] * 0.25**2 + 1e-18  # inertia of at most m R^2 per axis
    assert np.linalg.norm(out[1:4]) <= out[0] * 0.25 + 1e-18
    zero = np.empty(10)
    project_payload(np.r_[0.0, 0.0, 0.0, 0.0, raw[4:]], zero, 0.0, 0.25)  # no mass: nothing else either
    assert np.all(zero == 0.0)
    unbounded = np.empty(10)
    project_payload(raw, unbounded, 0.0)  # without the ball, PSD only: the inertia stays
    assert unbounded[4] > 1e-3


def test_the_control_model_is_projected_but_the_state_is_not(ur5):

    c, s = est_init(OnlineConfig(), ur5, 1)
    s.theta[0] = PAY_A
    s.theta[0, 0] = -2.0  # a negative mass in the estimator's state
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)
    assert s.theta[0, 0] == -2.0
    assert pay[0] >= 0 and np.linalg.eigvalsh(_pseudo_inertia(pay)).min() >= -1e-12
    c2, s2 = est_init(OnlineConfig(project=False, prior_radius=None), ur5, 1)
    c2 = c2._replace(com_size=0.0)  # and no centred prior (tests/test_centred_prior.py)
    s2.theta[0] = s.theta[0]
    est_payload_trial(c2, s2, 0, pay)
    assert np.array_equal(pay, s.theta[0])


# ------------------------------------------------------------------------------------ compact prior
def _sphere_inertia(pay, rho):
    m, h = pay[0], pay[1:4]
    full = (h @ h * np.eye(3) - np.outer(h, h)) / m + 0.4 * m * rho**2 * np.eye(3)
    return full[[0, 0, 1, 0, 1, 2], [0, 1, 1, 2, 2, 2]]  # Ixx, Ixy, Iyy, Ixz, Iyz, Izz


def test_the_compact_prior_moves_only_an_uninformed_inertia():
    """compact_prior: an inertia with a large variance goes to the sphere at the centre of mass, one
    with a small variance stays; the mass and first moments never move; the covariance shrinks."""
    raw = PAY_B.copy()
    raw[4:] = [0.5, 0.1, -0.3, 0.05, 0.2, 0.4]  # an inertia far from any compact body
    rho = 0.05
    P = np.diag(np.r_[np.full(4, 1e-6), np.full(6, 1e3)])
    out, Pc = raw.copy(), P.copy()
    compact_prior(out, Pc, rho)
    assert np.array_equal(out[:4], raw[:4])
    assert np.allclose(out[4:], _sphere_inertia(raw, rho), rtol=0, atol=1e-6), out[4:]
    assert np.all(np.diag(Pc)[4:] < np.diag(P)[4:]) and np.linalg.eigvalsh(Pc).min() > -1e-12
    P = np.diag(np.r_[np.full(4, 1e-6), np.full(6, 1e-14)])  # the data know the inertia
    out = raw.copy()
    compact_prior(out, P.copy(), rho)
    assert np.allclose(out, raw, rtol=0, atol=1e-6) and not np.array_equal(out, raw)


def test_the_prior_is_on_the_control_model_only_and_off_when_asked(ur5, swap_record):
    """150 ms after the swap the prior brings the control model's inertia nearer the truth; the
    estimator's state does not depend on it, and before the projection neither do the mass and
    first moments."""

    r = swap_record
    runs = {}
    for rho in (0.05, None):
        for project in (True, False):
            c, s = est_init(OnlineConfig(prior_radius=rho, project=project), ur5, 1)
            c = c._replace(com_size=0.0)  # the compact prior alone (tests/test_centred_prior.py)
            for k in range(10_150):
                est_step(c, s, r.q_meas[k : k + 1], r.qd_meas[k : k + 1], r.tau[k : k + 1])
            pay = np.empty(10)
            est_payload_trial(c, s, 0, pay)
            runs[rho, project] = (s.theta[0].copy(), pay)
    assert np.array_equal(runs[0.05, True][0], runs[None, True][0])
    assert np.array_equal(runs[0.05, False][1][:4], runs[None, False][1][:4])
    assert np.array_equal(runs[None, False][1], runs[None, False][0])  # off and unprojected: the state
    err_on = np.abs(runs[0.05, True][1][4:] - PAY_B[4:]).max()
    err_off = np.abs(runs[None, True][1][4:] - PAY_B[4:]).max()
    assert err_on < 0.5 * err_off, (err_on, err_off)


# ------------------------------------------------------------------------ against the plant
def _closed_loop(arm, seed, n, payloads, swap):
    """UR5 on the compiled stick-slip plant (RK4, 2 substeps) under a computed-torque law with
    the true model on the measured state (40 rad/s), the shipped sensor noise; (q_m, qd_m, tau)."""
    from adaptive_dd.plant.chain import rnea
    from adaptive_dd.plant.integrator import plant_params, plant_step

    t = np.arange(n) * T
    rng = np.random.default_rng(seed)
    qr, qdr, qddr = exciting_motion(arm, t, rng, offset=POSTURE, speed=0.4)
    j = arm.payload_joint
    pis = []
    for p in payloads:
        pi = arm.pi_links.copy()
        pi[10 * j : 10 * j + 10] += arm.payload_map @ p
        pis.append(pi)
    pps = [plant_params(arm.chain, pi, arm.viscous, arm.coulomb, arm.armature, arm.friction) for pi in pis]
    sq, sv = np.sqrt(arm.sensor.position_variance), np.sqrt(arm.sensor.velocity_variance)
    lim = np.asarray(arm.actuator.torque_limit)
    q, qd = qr[0].copy(), qdr[0].copy()
    out = [np.empty((n, 6)) for _ in range(3)]
    stuck = np.zeros(6, dtype=bool)
    tau = np.empty(6)
    for k in range(n):
        s = int(k >= swap)
        qm = q + sq * rng.standard_normal(6)
        qdm = qd + sv * rng.standard_normal(6)
        a = qddr[k] + 1600.0 * (qr[k] - qm) + 80.0 * (qdr[k] - qdm)
        rnea(arm.chain, pis[s], qm, qdm, a, tau)
        tau[:] = np.clip(tau + arm.viscous * qdm + arm.coulomb * np.sign(qdr[k]), -lim, lim)
        out[0][k], out[1][k], out[2][k] = qm, qdm, tau
        assert plant_step(arm.chain, pps[s], q, qd, tau, T, 2, stuck)
    return out


@pytest.mark.slow  # a kernel no other default test compiles (about 20-60 CPU-s cold)
def test_payload_mode_on_the_stick_slip_plant_in_closed_loop(ur5):
    """The simulated plant (stick-slip friction, zero-order hold, RK4), 12 s, swap at 6 s."""
    qm, qdm, tau = _closed_loop(ur5, 21, 12_000, [PAY_A, PAY_B], 6_000)
    rec = run_online(ur5, OnlineConfig(), qm, qdm, tau)
    for end, pay in ((5_999, PAY_A), (11_999, PAY_B)):
        assert abs(rec.mass[0, end] - pay[0]) < 0.05 * pay[0], (end, rec.mass[0, end])
        assert np.linalg.norm(rec.com[0, end] - _com(pay)) < 0.01, (end, rec.com[0, end])
    (alarms,) = rec.alarm_times()
    assert len(alarms) == 1 and 6.0 <= alarms[0] < 6.05, alarms


def _drive_detector(c, s, eps_of, act_of, k0, k1):
    """Feed the detector of trial 0 alone (``_detect``, then what the step does with its answer)
    over samples ``k0 .. k1 - 1``; ``eps_of(k)``, ``act_of(k)``: the rows' prior errors and use
    at sample k. The alarm samples."""
    from adaptive_dd.identification import online_kernel as K

    hits = []
    s.since_crawl[0, :] = K.BIG  # every joint moving faster than the detector's speed
    for k in range(k0, k1):
        if detector_sample(c, s, eps_of(k), act_of(k)):
            hits.append(k)
    return hits


def test_the_level_before_an_alarm_serves_no_longer_than_the_rearm_bound(ur5):
    """After an alarm a row that stays out of use is compared with its pre-alarm level only within
    resume + min_learned samples: a swap raises the residual's noise (the velocity's noise times
    the inertia a row carries), and a row back in use after the bound with 10x its old noise
    raises no alarm; the same row back within the bound does (the pre-alarm level still serves)."""
    from adaptive_dd.identification import online_kernel as K

    cfg = OnlineConfig(detector=Detector(fast_window=None))
    n = ur5.n_joints
    bound = int(cfg.samples(cfg.detector.freeze) * cfg.detector.resume) + cfg.detector.min_learned
    rng = np.random.default_rng(5)
    noise = rng.standard_normal((20_000, n))
    k_alarm = 3_000
    for back, alarms in ((bound + 300, False), (bound - 150, True)):
        c, s = est_init(cfg, ur5, 1)

        def eps_of(k, back=back):
            e = 0.1 * noise[k].copy()
            if k >= k_alarm + back:
                e[0] *= 10.0  # the new payload's noise on row 0, back in use
            return e

        def act_of(k, back=back):
            act = np.ones(n, dtype=np.bool_)
            act[0] = not (k_alarm < k < k_alarm + back)  # row 0 out of use after the alarm
            return act

        assert _drive_detector(c, s, eps_of, act_of, 0, k_alarm) == []  # steady noise: no alarm
        K._alarm(c, s, 0, k_alarm)  # the swap's alarm
        hits = _drive_detector(c, s, eps_of, act_of, k_alarm + 1, k_alarm + 1_500)
        if alarms:
            assert len(hits) >= 1 and k_alarm + back <= hits[0] < k_alarm + back + 50, hits
        else:
            assert hits == [], (back, hits)
