"""The LuGre plant: pre-sliding below breakaway, sliding above, the implicit integrator's
convergence, and both closed-loop paths on it."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.errors import ParameterError, ScenarioError
from adaptive_dd.plant import TABLE1_SIGMA, ClosedFormTwoLink
from adaptive_dd.plant.arm_tables import arm_from_tables
from adaptive_dd.plant.simulator import ArmSimulator
from adaptive_dd.plant.two_link import closed_form_view
from adaptive_dd.plant.two_link_integrator import lugre_step, two_link_plant_step

ARM = ClosedFormTwoLink.sice(friction="lugre")
FP = ARM.friction_params


def _hold(tau, n, substeps=2):
    q, qd, z = np.zeros((1, 2)), np.zeros((1, 2)), np.zeros((1, 2))
    out = np.empty((n, 2))
    for k in range(n):
        q, qd, z = lugre_step(q, qd, z, tau[None], TABLE1_SIGMA[None], 1e-3, FP, substeps)
        out[k] = q[0]
    return out, qd[0], z[0]


@pytest.mark.parametrize("joint", [0, 1])
def test_a_torque_below_breakaway_deflects_the_joint_a_small_bounded_amount(joint):
    """80 % of d: a pre-sliding deflection of the order of tau / sigma0 (not 0, not sliding),
    reached within 0.1 s and then held: the joint stops."""
    d = TABLE1_SIGMA[5 + joint]
    tau = np.zeros(2)
    tau[joint] = 0.8 * d
    q, qd, z = _hold(tau, 2000)
    x = q[:, joint]
    scale = 0.8 * d / FP[3 + joint]  # tau / sigma0 [rad]
    assert 0.5 * scale < abs(x[-1]) < 5 * scale
    assert abs(x[-1] - x[999]) < 1e-3 * scale  # no drift from 1 s to 2 s
    assert abs(qd[joint]) < 1e-9
    assert abs(FP[3 + joint] * z[joint] - 0.8 * d) < 1e-6 * d  # the bristles carry the torque


def test_a_torque_above_static_friction_slides():
    """Above Fs = 1.5 d the joint slides (Stribeck: static 1.5 d, Coulomb d)."""
    d = TABLE1_SIGMA[5]
    q, qd, _ = _hold(np.array([1.6 * d, 0.0]), 1000)
    assert q[-1, 0] > 0.05 and qd[0] > 0.01
    q_below, _, _ = _hold(np.array([1.4 * d, 0.0]), 1000)  # between Fc and Fs: still held
    assert abs(q_below[-1, 0]) < 1e-3


def test_the_implicit_steps_converge_first_order_to_the_lugre_ode():
    """A 3 s open-loop run under sine torques: the micro-step error shrinks about tenfold with
    ten times as many micro-steps (first order), and is 1 % of the motion at the default."""
    t = np.arange(3000) * 1e-3
    tau = np.stack(
        [6 * np.sin(2 * np.pi * 0.7 * t) + 3 * np.sin(2 * np.pi * 2.1 * t), 1.5 * np.sin(5.6 * t)], -1
    )

    def run(substeps):
        q, qd, z = np.zeros((1, 2)), np.zeros((1, 2)), np.zeros((1, 2))
        out = np.empty((len(t), 2))
        for k in range(len(t)):
            q, qd, z = lugre_step(q, qd, z, tau[k][None], TABLE1_SIGMA[None], 1e-3, FP, substeps)
            out[k] = q[0]
        return out

    fine = run(1000)
    e10, e100 = np.abs(run(2) - fine).max(), np.abs(run(100) - fine).max()
    assert 5 < e10 / e100 < 20
    assert e10 < 0.02 * np.abs(fine).max()


def test_the_integrator_is_stable_however_stiff_the_bristles():
    """sigma0 = 1e9 N m/rad: bristle modes near 5e5 rad/s, h omega about 46 at the 0.1 ms
    micro-step (explicit RK4 diverges beyond 2.8): the state stays finite and bounded, and a
    torque below breakaway still holds the joint."""
    q, qd, z = np.zeros((1, 2)), np.zeros((1, 2)), np.zeros((1, 2))
    fp = (*FP[:3], 1e9, 1e9, *FP[5:])
    for k in range(1000):
        tau = np.array([[10 * np.sin(0.03 * k), 2 * np.cos(0.05 * k)]])
        q, qd, z = lugre_step(q, qd, z, tau, TABLE1_SIGMA[None], 1e-3, fp)
        assert np.all(np.isfinite(q)) and np.abs(qd).max() < 20
    q, qd, z = np.zeros((1, 2)), np.zeros((1, 2)), np.zeros((1, 2))
    for _ in range(200):
        q, qd, z = lugre_step(q, qd, z, np.array([[0.8 * TABLE1_SIGMA[5], 0]]), TABLE1_SIGMA[None], 1e-3, fp)
    assert 0 < q[0, 0] < 1e-7


def test_the_simulator_carries_the_bristle_state_and_plant_step_refuses_lugre():
    sim = ArmSimulator(1, 10, np.random.default_rng(0), arm=ARM)
    for _ in range(10):
        sim.step(np.array([[0.8 * TABLE1_SIGMA[5], 0.0]]))
    assert 0 < sim.z[0, 0] < TABLE1_SIGMA[5] / FP[3]
    z = np.zeros((1, 2))
    with pytest.raises(ParameterError, match="lugre_step"):
        two_link_plant_step(z, z, z.astype(bool), z + 1, z, TABLE1_SIGMA[None], 1e-3, 2, 3)


def test_lugre_parameters_from_a_scenario_table_and_their_errors():
    arm = arm_from_tables(
        None, {"friction": "lugre", "lugre_stiffness": [2e5, 5e4], "lugre_damping": [300, 60]}
    )
    assert arm.friction == "lugre"  # an Arm (issue 27), its closed forms' plant runs LuGre
    assert closed_form_view(arm).friction_params[3:] == (2e5, 5e4, 300.0, 60.0)
    default = closed_form_view(arm_from_tables(None, {"friction": "lugre"}))
    j = (TABLE1_SIGMA[0] + TABLE1_SIGMA[1] + 2 * TABLE1_SIGMA[2], TABLE1_SIGMA[1])
    np.testing.assert_allclose(default.lugre_sigma1, np.sqrt(1e5 * np.array(j)))
    with pytest.raises(ScenarioError, match=r"plant\.lugre_stiffness"):
        arm_from_tables(None, {"friction": "lugre", "lugre_stiffness": [1e5]})
    with pytest.raises(ScenarioError, match=r"plant\.lugre_damping\[1\]"):
        arm_from_tables(None, {"friction": "lugre", "lugre_damping": [300, -1]})


def test_compiled_and_python_closed_loops_agree_on_the_lugre_plant():
    sc = load_scenario(Path(__file__).parents[1] / "benchmarks" / "scenarios" / "lugre_friction.toml")
    sc = dataclasses.replace(sc, seeds=2, duration=3.0, swap_times=(1.5,), swap_masses=(3.0,))
    sc = dataclasses.replace(sc, controllers=("ct_oracle", "adaptive_ct"))
    rc = run_benchmark(sc, progress=False, engine="compiled")
    rp = run_benchmark(sc, progress=False, engine="python")
    for name in sc.controllers:
        a, b = rc.runs[name], rp.runs[name]
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
        np.testing.assert_allclose(_acc(a), _acc(b), rtol=1e-12, atol=1e-12)
    assert rc.runs["adaptive_ct"].alarm_times == rp.runs["adaptive_ct"].alarm_times
    assert all(any(0 <= x - 1.5 < 0.3 for x in tr) for tr in rc.runs["adaptive_ct"].alarm_times)


def _acc(run):
    """A run's streamed sums (``StreamedSums`` but the error norm) as one flat array."""
    return np.concatenate([np.ravel(x) for x in run.acc[:-1]])
