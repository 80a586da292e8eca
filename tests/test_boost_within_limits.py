"""The two-link ``adaptive_ct``'s boost within the arm's torque limits, and its detector's speed gate
read apart from the RLS's data selection."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.controllers import make_controller
from adaptive_dd.controllers.compiled_form import compiled_spec
from adaptive_dd.controllers.feedback import _sice_sigma
from adaptive_dd.controllers.laws import boost_batch
from adaptive_dd.experiments import table2_torque, trial_rngs
from adaptive_dd.identification.two_link_online import TwoLinkOnlineConfig, run_two_link_online
from adaptive_dd.plant import TABLE1_SIGMA, PayloadSchedule, simulate_open_loop

W, WB, Z = 40.0, 300.0, 1.0
LIM = np.array([70.0, 15.0])


def _states(n=400, seed=0):
    rng = np.random.default_rng(seed)
    q, qd = rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
    q_d = q + rng.normal(scale=0.005, size=(n, 2))
    qd_d = qd + rng.normal(scale=0.3, size=(n, 2))
    tau = rng.normal(scale=[30.0, 8.0], size=(n, 2))
    return tau, q, qd, q_d, qd_d


def _boost(tau, q, qd, q_d, qd_d, lim):
    dkp, dkd = WB**2 - W**2, 2.0 * Z * (WB - W)
    on = np.ones(len(q), dtype=bool)
    return boost_batch(tau, q, qd, q_d, qd_d, _sice_sigma(), dkp, dkd, on, W * W, 2.0 * Z * W, lim)


def test_the_boost_takes_the_largest_bandwidth_within_the_limits():
    """Every command stays within the limits (or a command already beyond one goes no further);
    where the whole boost fits it is the whole boost to the bit; elsewhere the bandwidth is the
    largest on a fine grid of bandwidths whose command fits (within the grid's step)."""
    args = _states()
    tau = args[0]
    full = _boost(*args, None)
    out = _boost(*args, LIM)
    room = np.maximum(LIM, np.abs(tau))
    assert np.all(np.abs(out) <= room + 1e-6)
    fits = np.all(np.abs(full) <= LIM, axis=1)
    assert 0.02 < fits.mean() < 0.98
    np.testing.assert_array_equal(out[fits], full[fits])
    sg = _sice_sigma()
    x = np.linspace(0.0, WB - W, 26_001)
    for k in np.nonzero(~fits)[0][:60]:
        _, q, qd, q_d, qd_d = (a[k] for a in args)
        rc = sg[2] * np.cos(q[1])
        m0 = np.array([[sg[0] + sg[1] + 2 * rc, sg[1] + rc], [sg[1] + rc, sg[1]]])
        cmd = tau[k] + np.outer(x**2 + 2 * W * x, m0 @ (q_d - q)) + np.outer(2 * Z * x, m0 @ (qd_d - qd))
        best = x[np.all(np.abs(cmd) <= room[k] + 1e-9, axis=1)].max()
        grid = cmd[np.searchsorted(x, best)]
        np.testing.assert_allclose(out[k], grid, atol=0.05)


def test_the_arms_limits_reach_the_compiled_boost():
    ctrl = make_controller("adaptive_ct")
    np.testing.assert_array_equal(ctrl.torque_limit, LIM)
    np.testing.assert_array_equal(compiled_spec(ctrl, 1e-3).gains.boost_lim, LIM)


def test_the_detector_reads_an_equation_the_rls_skips():
    """With a selection the motion never passes (the RLS updates nothing), the detector still reads
    both equations' prior errors and finds a 3 kg swap at 4 s within 0.15 s (with its gate inside
    the selection it never could)."""
    sched = PayloadSchedule(times=(4.0,), masses=(3.0,))
    r = simulate_open_loop(table2_torque(2, 5000), trial_rngs(5, 2), payload=sched)
    cfg = dataclasses.replace(TwoLinkOnlineConfig(), selection=(1e3, 0.0))
    rec = run_two_link_online(r.q_meas, r.qd_meas, r.tau, cfg, TABLE1_SIGMA)
    np.testing.assert_array_equal(rec.theta[:, -1], np.broadcast_to(rec.theta[:, 0], (2, 7)))  # no update
    for times in rec.alarm_times():
        assert len(times) >= 1 and 4.0 < times[0] < 4.15, times


if __name__ == "__main__":  # pragma: no cover
    pytest.main([__file__, "-q"])


def test_the_boosts_caps_read_no_payload_the_scheduled_nor_the_rated():
    """``adaptive_ct``'s boost was sized on the torque room beside the scheduled payloads, which no
    other law is told: its caps now read the bare torque limits, whatever the schedule or the rating."""
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
    from adaptive_dd.closed_loop.boost import task_room

    d = read_toml(
        Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml"
    )
    d["run"].update(seeds=1)
    rooms = []
    for masses in ((1.0, 0.5, 0.0), (0.2, 0.1, 0.0), (1.4, 1.4, 0.0)):
        for p, m in zip(d["payload"], masses, strict=True):
            p["mass"] = m
        sc = parse_scenario(d, "v3.toml")
        rooms.append(task_room(sc)[1])
        rooms.append(task_room(sc, sc.arm.with_(payload_capacity=0.2))[1])
    limit = np.asarray(sc.arm.actuator.torque_limit, dtype=float)
    assert all(np.array_equal(r, np.broadcast_to(limit, r.shape)) for r in rooms)


def test_the_n_joint_boost_keeps_the_command_within_the_limits_and_is_whole_where_it_fits(rng):
    """At each sample the boost's added bandwidth is scaled by the largest common factor whose
    command stays within the limits (as the two-link law's): a grid of the factor finds none
    larger, a command already beyond a limit is not pushed further, and with room to spare the
    whole boost is added."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.closed_loop.laws import LawState, law_batch

    sc = load_scenario(
        str(
            Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml"
        )
    )
    arm, n, T = sc.arm, sc.arm.n_joints, sc.sample_period
    cfg = make_controller("adaptive_ct", arm=arm).law_config(T)._replace(observer=False)
    lim = np.asarray(cfg.torque_limit)
    assert np.array_equal(lim, arm.actuator.torque_limit)
    K = 200
    q_d, qd_d, qdd_d = np.array([0.3, -0.6, 0.4]), np.array([0.2, -0.1, 0.3]), np.zeros(n)
    scale = np.logspace(-3.0, 0.0, K)[:, None]  # errors from far inside the limits to far beyond
    q = q_d + scale * rng.normal(0.0, 0.02, (K, n))
    qd = qd_d + scale * rng.normal(0.0, 0.5, (K, n))
    boosted, off = LawState.start(cfg, K), LawState.start(cfg, K)  # an alarm now; none
    boosted.since_alarm[:] = 0
    out = law_batch(arm.chain, cfg, boosted, q, qd, q_d, qd_d, qdd_d)
    base = law_batch(arm.chain, cfg, off, q, qd, q_d, qd_d, qdd_d)
    whole = law_batch(
        arm.chain, cfg._replace(torque_limit=np.full(n, np.inf)), boosted, q, qd, q_d, qd_d, qdd_d
    )
    room = np.maximum(lim, np.abs(base))
    assert np.all(np.abs(out) <= room + 1e-9)
    fits = np.all(np.abs(whole) <= room, axis=1)
    assert fits.any() and (~fits).any()
    np.testing.assert_allclose(out[fits], whole[fits], rtol=0, atol=1e-9)
    # where it does not fit: the largest factor on a grid whose command is within the limits
    M0 = arm.mass_matrix(q)
    w = np.sqrt(cfg.kp)
    X = cfg.boost_kd * w / cfg.kd  # the added bandwidth
    z = 0.5 * cfg.kd / w
    e, ed = q_d - q, qd_d - qd
    A = np.einsum("kij,kj->ki", M0, X**2 * e)
    B = np.einsum("kij,kj->ki", M0, X * (2 * w * e + 2 * z * ed))
    s = np.linspace(0.0, 1.0, 2001)
    for k in np.flatnonzero(~fits)[:20]:
        cmd = base[k] + s[:, None] ** 2 * A[k] + s[:, None] * B[k]
        ok = np.all(np.abs(cmd) <= room[k] + 1e-9, axis=1)
        best = s[ok].max()
        grid = base[k] + best**2 * A[k] + best * B[k]
        np.testing.assert_allclose(out[k], grid, atol=0.02 * np.abs(B[k]).max() + 1e-6)
