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


def test_the_boosts_room_is_sized_on_the_rated_payload_not_the_schedule():
    """``adaptive_ct``'s boost was sized on the scheduled payloads (and a ``[plant]``'s own
    parameters), which no other law is told: with ``[arm] payload_capacity`` stated, the room is
    the same whatever the schedule carries, and it is the model's with the rated payload."""
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
    assert np.array_equal(rooms[0], rooms[1]) and np.array_equal(rooms[0], rooms[2])
    sc = parse_scenario(d, "v3.toml")
    arm = sc.arm
    t = np.arange(0, sc.n_samples, 10) * sc.sample_period
    q, qd, qdd = sc.reference.sample(t)
    rated = arm.sigma_with_payload(1.5, radius=sc.payload_radius)
    tau = np.maximum(
        np.abs(arm.inverse_dynamics(q, qd, qdd, arm.sigma)), np.abs(arm.inverse_dynamics(q, qd, qdd, rated))
    )
    assert np.allclose(rooms[0], np.asarray(arm.actuator.torque_limit) - tau)
    lighter = task_room(sc, arm.with_(payload_capacity=0.5))[1]  # a smaller rating leaves more room
    assert np.all(lighter >= rooms[0] - 1e-9) and np.any(lighter > rooms[0] + 1e-3)
