"""adaptive_ct's boost bandwidth per joint: the largest whose noise torque stays inside the torque
limit at every posture of the reference (adaptive_dd.closed_loop.boost); the per-sample limit on the
command is tests/test_boost_within_limits.py's."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.closed_loop.boost import NOISE_SIGMAS, boost_bandwidths

TEMPLATE = Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "population.toml"


def _noise(wb, w, z, m, vq, vv):
    return m * np.sqrt((wb**2 - w**2) ** 2 * vq + (2 * z * (wb - w)) ** 2 * vv)


def test_one_joint_bandwidth_fills_its_room():
    w, z, m, vq, vv = np.array([40.0]), 1.0, 2.0, np.array([1e-8]), np.array([5e-5])
    room = np.full((5, 1), 3.0)
    wb = boost_bandwidths(300.0, w, z, np.full((5, 1, 1), m), room, vq, vv)
    assert NOISE_SIGMAS * _noise(wb, w, z, m, vq, vv)[0] <= 3.0
    # within the 2 % steps of the largest: one step up is outside the room
    up = w + (wb - w) / 0.98
    assert NOISE_SIGMAS * _noise(up, w, z, m, vq, vv)[0] > 3.0
    assert 40.0 < wb[0] < 300.0


def test_ample_room_keeps_the_cap_and_no_room_no_boost():
    w, vq, vv = np.array([40.0, 40.0]), np.full(2, 1e-8), np.full(2, 5e-5)
    M = np.broadcast_to(np.eye(2), (3, 2, 2))
    wide = boost_bandwidths(300.0, w, 1.0, M, np.full((3, 2), 1e6), vq, vv)
    np.testing.assert_array_equal(wide, [300.0, 300.0])
    room = np.array([[1e6, -1.0]] * 3)  # the second joint's limit is below the reference's torque
    none = boost_bandwidths(300.0, w, 1.0, M, room, vq, vv)
    assert none[0] == 300.0 and none[1] == 40.0


def test_a_coupled_row_lowers_the_column_that_feeds_it():
    w, vq, vv = np.array([40.0, 40.0]), np.full(2, 1e-8), np.full(2, 5e-5)
    M = np.broadcast_to(np.array([[0.1, 1.0], [1.0, 0.1]]), (1, 2, 2))
    room = np.array([[1.0, 1e6]])  # row 0 is fed mostly by joint 1's boost
    wb = boost_bandwidths(300.0, w, 1.0, M, room, vq, vv)
    assert wb[1] < wb[0]
    std0 = np.sqrt(sum(M[0, 0, k] ** 2 * _noise(wb[k], 40.0, 1.0, 1.0, 1e-8, 5e-5) ** 2 for k in range(2)))
    assert NOISE_SIGMAS * std0 <= 1.0


def _drawn(arm_seed):
    from adaptive_dd.benchmark.population import population_scenario
    from adaptive_dd.benchmark.scenario import read_toml

    return population_scenario(read_toml(TEMPLATE), str(TEMPLATE), arm_seed)


def test_scenario_states_the_task_and_the_weak_shoulder_gets_less_boost():
    from adaptive_dd.controllers.registry import scenario_controller

    sc = _drawn(1)  # random:1: 6 joints, its first joint's limit 3.8 N m
    _, law = scenario_controller(sc, "adaptive_ct")
    wb = law.boost_bandwidths()
    assert wb[0] < 200.0 and wb[-1] == 300.0
    q, room = law.task
    M = sc.arm.mass_matrix(q)
    w = np.full(sc.arm.n_joints, 40.0)
    v = (wb**2 - w**2) ** 2 * np.asarray(sc.position_variance) + (2 * (wb - w)) ** 2 * np.asarray(
        sc.velocity_variance
    )
    std = np.sqrt(np.einsum("kjl,l->kj", M**2, v))
    assert np.all(NOISE_SIGMAS * std <= room + 1e-9)
    law.task = None  # no task: the cap on every joint
    np.testing.assert_array_equal(law.boost_bandwidths(), np.full(sc.arm.n_joints, 300.0))


@pytest.mark.slow
def test_the_boost_does_not_saturate_after_the_pick_up_whatever_its_caps(monkeypatch):
    """random:1 seed 0: with the boost at 300 rad/s on every joint and no limit on it the command
    saturated on 2.1 % of the loaded segment (all of it in the boost after the pick-up's alarm);
    held within the limits at each sample, neither with its caps nor at 300 rad/s does it beyond
    the benchmark's 1 %, and the segment tracks no worse than 1.2x its floor."""
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.closed_loop.controllers import AdaptiveCT

    sc = dataclasses.replace(_drawn(1), seeds=1, controllers=("ct_oracle", "adaptive_ct"))

    def loaded(run):
        t = res.t
        m = (t >= 4.0) & (t < 8.0)
        sat = np.asarray(run.saturated[0])  # (samples, joints): any joint at its limit
        err = np.sqrt(np.mean(run.e_norm[0][m].astype(float) ** 2))
        return sat.reshape(len(t), -1).any(axis=1)[m].mean(), err

    res = run_benchmark(sc, progress=False, keep_trajectories=1)
    sat, err = loaded(res.runs["adaptive_ct"])
    floor = loaded(res.runs["ct_oracle"])[1]
    monkeypatch.setattr(AdaptiveCT, "state_task", lambda self, scenario: None)
    res = run_benchmark(sc, progress=False, keep_trajectories=1)
    sat_cap, err_cap = loaded(res.runs["adaptive_ct"])
    assert sat < 0.01 and sat_cap < 0.01, (sat, sat_cap)
    assert err < 1.2 * floor and err_cap < 1.2 * floor
