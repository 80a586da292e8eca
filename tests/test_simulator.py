"""The sampled-data simulator: integration accuracy, sticking, sensors, faults."""

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.experiments import table2_torque, trial_rngs
from adaptive_dd.plant import (
    TABLE1_PHYSICAL,
    TABLE1_SIGMA,
    ActuatorConfig,
    ArmSimulator,
    ClosedFormTwoLink,
    PayloadSchedule,
    SensorConfig,
    simulate_open_loop,
    two_link_plant_step,
)
from adaptive_dd.plant.pinocchio_model import build_model

NO_SENSOR_EFFECTS = SensorConfig(quantize=False, position_variance=(0, 0), velocity_variance=(0, 0))
IDEAL_ACTUATOR = ActuatorConfig((70.0, 15.0), saturate=False, quantize=False)


def test_integration_matches_pinocchio_aba_with_scipy():
    """Smooth case (no Coulomb friction): our RK4 vs solve_ivp on pin.aba plus viscous friction,
    over three quarters of the 1-Hz torque's period (the reference's 750 calls of solve_ivp are
    most of this test's CPU; a wrong dynamics term shows far above 1e-9 within it)."""
    sigma = TABLE1_SIGMA.copy()
    sigma[5:] = 0.0
    model = build_model(TABLE1_PHYSICAL)
    data = model.createData()
    b = sigma[3:5]
    T, n = 1e-3, 750
    tau = table2_torque(1, n)[0]

    def f(t, x):
        k = min(int(t / T + 1e-9), n - 1)
        return np.concatenate([x[2:], pin.aba(model, data, x[:2], x[2:], tau[k] - b * x[2:])])

    x = np.array([0.1, -0.2, 0.5, 0.3])
    ref = [x]
    for k in range(n):
        sol = solve_ivp(f, (k * T, (k + 1) * T), ref[-1], rtol=1e-11, atol=1e-12, method="DOP853")
        ref.append(sol.y[:, -1])
    ref = np.array(ref)
    q, qd = x[None, :2], x[None, 2:]
    stuck, slip = np.zeros((1, 2), bool), np.ones((1, 2))
    for k in range(n):
        q, qd, stuck, slip = two_link_plant_step(q, qd, stuck, slip, tau[k][None], sigma[None], T, 2)
    np.testing.assert_allclose(q[0], ref[-1, :2], atol=1e-9)
    np.testing.assert_allclose(qd[0], ref[-1, 2:], atol=1e-8)


def test_arm_sticks_without_chattering_below_coulomb_friction():
    tau = np.broadcast_to([3.0, 0.7], (1, 3000, 2))  # |tau| < d = (3.208, 0.743)
    res = simulate_open_loop(tau, np.random.default_rng(0), sensor=NO_SENSOR_EFFECTS)
    assert np.all(res.q == 0.0) and np.all(res.qd == 0.0)


def test_arm_breaks_away_above_coulomb_friction_and_stops_again():
    tau = np.zeros((1, 3000, 2))
    tau[0, :1000] = [4.0, 1.0]  # above d: moves
    res = simulate_open_loop(tau, np.random.default_rng(0), sensor=NO_SENSOR_EFFECTS)
    assert np.all(res.qd[0, 900] > 0)
    # torque removed: friction stops both joints, and they stay exactly at rest
    assert np.all(res.qd[0, -500:] == 0.0)
    assert np.all(np.diff(res.q[0, -500:], axis=0) == 0.0)


def test_sticking_respects_coupling_torque():
    """Joint 2 stays stuck only while the reaction of joint 1's motion is below d2."""
    tau = np.zeros((1, 200, 2))
    tau[0, :, 0] = 60.0  # large joint-1 torque, no joint-2 torque
    res = simulate_open_loop(tau, np.random.default_rng(0), sensor=NO_SENSOR_EFFECTS)
    # the coupling inertia (J2 + r) qdd1 > d2, so joint 2 is dragged backwards at first;
    # later the centrifugal torque r sin(q2) qd1^2 turns it round
    assert np.all(res.qd[0, 1:20, 1] < 0)
    assert res.qd[0, -1, 1] > res.qd[0, 20, 1]


def test_payload_swap_keeps_state_continuous_and_changes_sigma():
    sched = PayloadSchedule(times=(0.5,), masses=(3.0,))
    res = simulate_open_loop(
        table2_torque(1, 1000), np.random.default_rng(0), payload=sched, sensor=NO_SENSOR_EFFECTS
    )
    k = 500
    assert res.mass[0, k - 1] == 0.0 and res.mass[0, k] == 3.0
    np.testing.assert_allclose(res.sigma[0, k, 0] - res.sigma[0, k - 1, 0], 3.0 * 0.04)
    step = np.abs(np.diff(res.qd[0], axis=0))
    assert step[k - 1].max() < 5 * np.median(step.max(axis=1)) + 1e-3


def test_sensor_noise_and_quantization():
    cfg = SensorConfig()
    n = 200_000
    q = np.full((n, 2), 0.123456789)
    qm, qdm = cfg.measure(q, np.zeros((n, 2)), np.random.default_rng(1).standard_normal((n, 4)))
    np.testing.assert_allclose(qm.var(axis=0), cfg.position_variance, rtol=0.02)
    np.testing.assert_allclose(qdm.var(axis=0), cfg.velocity_variance, rtol=0.02)
    qq, _ = SensorConfig(position_variance=(0, 0)).measure(q[:1], q[:1], np.zeros((1, 4)))
    res = 2 * np.pi / np.array([614400, 507904])
    np.testing.assert_allclose(qq / res, np.round(qq / res), atol=1e-6)
    assert np.all(np.abs(qq - q[:1]) <= res / 2)


def test_actuator_saturation_and_dac_quantization():
    act = ClosedFormTwoLink.sice().actuator
    tau, sat = act.apply(np.array([[100.0, -20.0], [1.0001, 0.5]]))
    assert sat.tolist() == [[True, True], [False, False]]
    lsb = 2 * np.array([70.0, 15.0]) / 4096
    assert tau[0, 0] <= 70.0 and tau[0, 1] == -15.0
    np.testing.assert_allclose(tau / lsb, np.round(tau / lsb), atol=1e-9)
    assert np.all(np.abs(tau[1] - [1.0001, 0.5]) <= lsb / 2)
    raw, _ = ActuatorConfig((70.0, 15.0), saturate=False, quantize=False).apply(np.array([[100.0, 0.1234]]))
    np.testing.assert_array_equal(raw, [[100.0, 0.1234]])


def test_trials_are_reproducible_and_independent_of_batch_size():
    tau = table2_torque(4, 300)
    a = simulate_open_loop(tau, trial_rngs(7, 4))
    b = simulate_open_loop(tau[:1], trial_rngs(7, 1))
    np.testing.assert_array_equal(a.q_meas[0], b.q_meas[0])
    assert not np.array_equal(a.q_meas[0], a.q_meas[1])


def test_batch_of_payloads_in_one_call():
    sched = PayloadSchedule(initial_mass=np.array([0.0, 1.0, 3.0]))
    res = simulate_open_loop(table2_torque(3, 500), np.random.default_rng(0), payload=sched)
    np.testing.assert_allclose(res.mass[:, 0], [0, 1, 3])
    # heavier payload, smaller motion of joint 2 under the same torque
    amp = np.abs(res.q[:, :, 1]).max(axis=1)
    assert amp[0] > amp[1] > amp[2]


def test_a_diverging_trial_is_stopped_and_the_others_go_on():
    sim = ArmSimulator(3, 100, np.random.default_rng(0), actuator=IDEAL_ACTUATOR)
    for k in range(50):
        tau = np.array([[1e6, 1e6], [10.0, 2.0], [np.nan, 0.0] if k == 3 else [5.0, 1.0]])
        sim.step(tau)
    assert sim.failed.tolist() == [True, False, True]
    assert sim.failed_at[2] == 3
    assert np.all(np.isfinite(sim.q)) and sim.qd[1, 0] > 0  # the healthy trial moves on


def test_bad_simulator_input():
    with pytest.raises(ParameterError, match="sample_period"):
        ArmSimulator(1, 10, np.random.default_rng(0), sample_period=0.0)
    with pytest.raises(ParameterError, match="strictly increasing"):
        PayloadSchedule(times=(5.0, 2.0), masses=(1.0, 3.0))
    with pytest.raises(ParameterError, match="payload mass"):
        PayloadSchedule(times=(1.0,), masses=(-3.0,))
    with pytest.raises(SignalError, match="non-finite"):
        simulate_open_loop(np.full((1, 5, 2), np.nan), np.random.default_rng(0))
    with pytest.raises(SignalError, match="shape"):
        simulate_open_loop(np.zeros((5, 2)), np.random.default_rng(0))
    with pytest.raises(ParameterError, match="one Generator per trial"):
        ArmSimulator(2, 10, trial_rngs(0, 3))
