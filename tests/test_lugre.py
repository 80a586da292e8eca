"""The LuGre plant: pre-sliding below breakaway, sliding above, the implicit integrator's
convergence, both closed-loop paths on it, and the same law on any arm (the general kernels)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.errors import ParameterError, ScenarioError
from adaptive_dd.plant import TABLE1_SIGMA, Arm, ClosedFormTwoLink
from adaptive_dd.plant.arm_tables import arm_from_tables
from adaptive_dd.plant.integrator import plant_params, plant_step
from adaptive_dd.plant.simulator import ArmSimulator
from adaptive_dd.plant.two_link import closed_form_view
from adaptive_dd.plant.two_link_integrator import lugre_step, two_link_plant_step
from adaptive_dd.robots import robot_urdf

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


@pytest.mark.slow  # the LuGre plant's closed loop compiled for it alone: about 40 s of a fresh run
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


def _lugre_params(arm):
    n, pi = arm.n_joints, np.asarray(arm.pi, dtype=float)
    return plant_params(
        arm.chain, pi[: 10 * n], pi[10 * n : 11 * n], pi[11 * n : 12 * n], pi[12 * n :], law="lugre",
        friction_velocity=arm.friction_velocity, stribeck_ratio=arm.stribeck_ratio,
        stribeck_velocity=arm.stribeck_velocity, lugre_stiffness=arm.lugre_stiffness,
        lugre_damping=arm.lugre_sigma1,
    )  # fmt: skip


def test_the_general_lugre_step_is_the_two_link_step_on_the_papers_arm():
    arm = dataclasses.replace(Arm.sice(), friction="lugre", general=True)
    two = closed_form_view(dataclasses.replace(arm, general=False))
    assert arm.friction_params == pytest.approx(two.friction_params, rel=1e-14)
    pp = _lugre_params(arm)
    q, qd, stuck = np.zeros(2), np.zeros(2), np.zeros(2, dtype=bool)
    q2, qd2, z2 = np.zeros(2), np.zeros(2), np.zeros(2)
    k = np.arange(800)[:, None] * 1e-3
    taus = 12.0 * np.sin(k * np.array([4.0, 6.0])) + np.array([0.5, -0.3])  # reversals, sticking
    for tau in taus:
        assert plant_step(arm.chain, pp, q, qd, np.ascontiguousarray(tau), 1e-3, 2, stuck)
        q2, qd2, z2 = lugre_step(q2, qd2, z2, tau, np.asarray(two.sigma), 1e-3, two.friction_params)
        np.testing.assert_allclose(q, q2, rtol=0, atol=1e-11)
        np.testing.assert_allclose(pp.law.z, z2, rtol=0, atol=1e-13)
    assert np.abs(qd).max() > 0.1 and not stuck.any()  # it slid, and LuGre holds no joint stuck


def test_a_six_joint_arm_pre_slides_below_breakaway_by_each_joints_own_stiffness():
    """Gravity held by the command, joint j pushed by 0.7 of its Coulomb level: it comes to rest
    with its bristles carrying the push (``sigma0_j z_j``, its own stiffness), having moved by at
    least that deflection and not much more (pre-sliding, no breakaway); the other joints' bristles
    carry next to nothing."""
    ur5 = dataclasses.replace(
        Arm.from_urdf(robot_urdf("ur5")), friction="lugre", lugre_stiffness=(1e5, 2e5, 1e5, 3e4, 2e4, 1e4)
    )
    q0 = np.array([0.0, -1.2, 1.4, -1.6, -1.5, 0.3])
    hold = ur5.inverse_dynamics(q0, np.zeros(6), np.zeros(6))
    for j in (1, 5):
        pp = _lugre_params(ur5)
        q, qd, stuck = q0.copy(), np.zeros(6), np.zeros(6, dtype=bool)
        push = hold.copy()
        push[j] += 0.7 * ur5.coulomb[j]
        for _ in range(400):
            assert plant_step(ur5.chain, pp, q, qd, push, 1e-3, 2, stuck)
        z, deflection = pp.law.z, 0.7 * ur5.coulomb[j] / ur5.lugre_stiffness[j]
        assert np.abs(qd).max() < 1e-6
        assert z[j] == pytest.approx(deflection, rel=0.02)
        assert deflection < q[j] - q0[j] < 3 * deflection
        assert np.delete(np.abs(z), j).max() < 0.02 * deflection


def test_lugre_on_any_arm_from_a_scenario_table_and_its_errors():
    ur5 = arm_from_tables({"robot": "ur5"}, {"friction": "lugre", "lugre_stiffness": 2e5})
    assert ur5.friction == "lugre" and ur5.lugre_stiffness == (2e5,) * 6
    m0 = np.diag(ur5.mass_matrix(np.zeros(6)))
    np.testing.assert_allclose(ur5.lugre_sigma1, np.sqrt(2e5 * m0))
    assert len(ur5.friction_params) == 3 + 12
    with pytest.raises(ScenarioError, match=r"plant\.lugre_stiffness' must be one number or a list of 6"):
        arm_from_tables({"robot": "ur5"}, {"friction": "lugre", "lugre_stiffness": [1e5, 1e5]})
    with pytest.raises(ParameterError, match=r"Arm\.lugre_damping must be one value or 6"):
        dataclasses.replace(ur5, lugre_damping=(1.0, 2.0))
    with pytest.raises(ParameterError, match="LuGre needs its bristle state"):
        from adaptive_dd.plant.integrator import friction_law

        friction_law(3)


@pytest.mark.slow
def test_every_controller_meets_the_n_joint_lugre_plant_with_its_bristles_at_rest():
    """The run's plant record carries the bristles: each controller's trials start them at rest (a
    law run after another gives what it gives alone), and both paths agree on the general kernels."""
    sc = load_scenario(Path(__file__).parents[1] / "benchmarks" / "scenarios" / "sice_general.toml")
    sc = dataclasses.replace(
        sc, arm=dataclasses.replace(sc.arm, friction="lugre"), seeds=2, duration=1.0, swap_times=(0.5,),
        swap_masses=(2.0,), controllers=("ct_oracle", "pd"),
    )  # fmt: skip
    both = run_benchmark(sc, progress=False, engine="compiled")
    with pytest.warns(UserWarning, match="floor ct_oracle did not run"):
        alone = run_benchmark(dataclasses.replace(sc, controllers=("pd",)), progress=False, engine="compiled")
    np.testing.assert_array_equal(both.runs["pd"].q, alone.runs["pd"].q)
    python = run_benchmark(sc, progress=False, engine="python")
    for name in sc.controllers:
        np.testing.assert_allclose(both.runs[name].q, python.runs[name].q, rtol=0, atol=1e-12)
