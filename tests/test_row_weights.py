"""The N-joint estimator's row weights: each equation's noise in a first pass over the task, on the
scale of the filters' memory (identification/row_weights.py)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import default_scenario_path, load_scenario
from adaptive_dd.benchmark.scenario_settings import with_settings
from adaptive_dd.controllers.registry import scenario_controller
from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import (
    Detector,
    OnlineConfig,
    derived_row_weights,
    est_detect_trial,
    est_init,
    run_online,
)
from adaptive_dd.identification.row_weights import (
    first_pass_row_weights,
    momentum_form_error,
    pass_mass,
    task_row_weights,
)
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
SCENARIOS = default_scenario_path().parent
POSTURE = [0.0, -1.2, 1.2, -1.5, -1.5, 0.0]  # UR5: elbow up, wrist down


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def _motion(arm, n, seed=0):
    t = np.arange(n) * T
    return exciting_motion(arm, t, np.random.default_rng(seed), offset=POSTURE, speed=0.5)


@pytest.mark.parametrize("mass", [0.0, 5.0])
def test_the_momentum_form_error_is_the_filters_discretisation_on_an_exact_record(ur5, mass):
    """No noise, no D/A step: the error is a small fraction of the filtered torque on every row
    (a sign slip in ``Mdot qd`` or a missing armature would leave the Coriolis or inertial torque);
    with a 5 kg payload in the record and in the equations' ``sigma`` the same (the payload's
    parameters left out of ``sigma`` would leave its torque)."""
    exact = ur5.with_(actuator=dataclasses.replace(ur5.actuator, quantize=False))
    motion = _motion(exact, 4000)
    pay = payload_parameters(mass, None, radius=exact.payload_radius) if mass else np.zeros(10)
    rec = prescribed_record(exact, np.arange(4000) * T, motion, [pay])
    sigma = exact.sigma_with_payload(mass) if mass else None
    bank = OnlineConfig(sample_period=T).bank
    err = momentum_form_error(exact, bank, rec.q_meas, rec.qd_meas, rec.tau, sigma)
    scale = np.sqrt(np.mean(rec.tau[1000:] ** 2, axis=0))
    assert np.all(np.sqrt(np.mean(err[1000:] ** 2, axis=0)) < 2e-3 * scale)
    if mass:
        unknown = momentum_form_error(exact, bank, rec.q_meas, rec.qd_meas, rec.tau)
        assert np.sqrt(np.mean(unknown[1000:, 1] ** 2)) > 0.05 * scale[1]


def test_a_payload_raises_the_rows_noise_and_the_task_pass_carries_the_capacity(ur5):
    """The measured velocity's noise enters each row through the momentum ``M qd``, which a payload
    makes larger: at 5 kg the shoulder and elbow rows' errors grow; the scenario's pass carries
    the arm's ``payload_capacity``, else the scenario's heaviest payload."""
    cfg = OnlineConfig(sample_period=T)
    motion = _motion(ur5, 6000)
    light = first_pass_row_weights(ur5, cfg, motion)
    heavy = first_pass_row_weights(ur5, cfg, motion, mass=5.0)
    assert np.all(heavy[1:3] > 1.2 * light[1:3])
    sc = load_scenario(SCENARIOS / "ur5_tool_swap.toml")
    assert sc.arm.payload_capacity == 5.0 and pass_mass(sc.arm, sc) == 5.0
    assert pass_mass(sc.arm.with_(payload_capacity=None), sc) == max(sc.swap_masses)
    cfg = OnlineConfig(sample_period=sc.sample_period)
    m = sc.reference.sample(np.arange(6000) * sc.sample_period)
    np.testing.assert_array_equal(
        task_row_weights(sc.arm, cfg, sc), first_pass_row_weights(sc.arm, cfg, m, mass=5.0)
    )


def test_the_first_pass_weights_are_the_errors_the_estimator_sees():
    """The estimator itself over the same noisy record of the exact UR5's reference, with the torque
    limits' weights: its prior errors' RMS per row [N m] after the first third, times the square
    root of the filters' memory in samples, is within 10 % of the first pass's weights (its data
    selection, its momentum form, the scale the covariance is on)."""
    sc = load_scenario(SCENARIOS / "ur5_tool_swap_exact.toml")
    arm, cfg = sc.arm, OnlineConfig(sample_period=sc.sample_period)
    t = np.arange(6000) * sc.sample_period
    motion = sc.reference.sample(t)
    w = first_pass_row_weights(arm, cfg, motion)
    rec = prescribed_record(arm, t, motion, [np.zeros(10)], rng=np.random.default_rng(0))
    w0 = derived_row_weights(arm)
    out = run_online(arm, dataclasses.replace(cfg, row_weights=tuple(w0)), rec.q_meas, rec.qd_meas, rec.tau)
    sd = np.sqrt(np.nanmean((out.eps[0, 2000:] * w0) ** 2, axis=0))
    np.testing.assert_allclose(w, np.sqrt(cfg.tau_f / cfg.sample_period) * sd, rtol=0.1)
    assert np.all(w[3:] < 0.5 * w0[3:])  # the wrist's rows carry less error than their torque limits say


def test_a_noisier_sensor_raises_its_rows_weight(ur5):
    """Ten times the velocity noise on the last joint: its row's error, hence its weight, grows;
    no sensor noise at all: the weights still follow (the D/A step and the form's own error)."""
    cfg = OnlineConfig(sample_period=T)
    motion = _motion(ur5, 6000)
    base = first_pass_row_weights(ur5, cfg, motion)
    vv = np.asarray(ur5.sensor.velocity_variance, dtype=float) * np.ones(6)
    vv[-1] *= 100.0
    loud = ur5.with_(sensor=dataclasses.replace(ur5.sensor, velocity_variance=tuple(vv)))
    assert first_pass_row_weights(loud, cfg, motion)[-1] > 3.0 * base[-1]
    quiet = ur5.with_(sensor=dataclasses.replace(ur5.sensor, velocity_variance=(0.0,) * 6))
    w = first_pass_row_weights(quiet, cfg, motion)
    assert np.all(np.isfinite(w)) and np.all(w > 0)


def test_a_joint_that_never_moves_gets_its_torque_limits_weight_on_the_others_scale(ur5):
    """The still joint's row keeps no sample: its weight is its torque limit's, scaled as the most
    weighted of the other rows against their torque limits (none counted many times over)."""
    motion = tuple(np.array(x) for x in _motion(ur5, 3000))
    for x, v in zip(motion, (POSTURE[-1], 0.0, 0.0), strict=True):
        x[:, -1] = v
    ratio = first_pass_row_weights(ur5, OnlineConfig(sample_period=T), motion) / derived_row_weights(ur5)
    assert np.all(np.isfinite(ratio)) and ratio[-1] == pytest.approx(ratio[:-1].max(), rel=1e-12)


def test_a_scenario_gives_adaptive_ct_the_first_pass_weights():
    """The exact UR5 (payload mode): the reference's first pass over the largest; given weights are
    kept; the drawn UR5 (mode "arm" from the stated uncertainty) and the same given an identified
    prior (``arm_prior_cov``): the first pass on the noise's scale."""
    sc = load_scenario(SCENARIOS / "ur5_tool_swap_exact.toml")
    ctrl = scenario_controller(sc, "adaptive_ct")[1]
    assert ctrl.online.mode == "payload"
    expect = task_row_weights(sc.arm, OnlineConfig(sample_period=sc.sample_period), sc)
    relative = task_row_weights(sc.arm, OnlineConfig(sample_period=sc.sample_period), sc, relative=True)
    np.testing.assert_array_equal(ctrl.online.row_weights, relative)
    np.testing.assert_allclose(relative, expect / expect.max(), rtol=1e-12)
    given = (1.0, 1.0, 1.0, 0.5, 0.5, 0.5)
    mine = with_settings(sc, "adaptive_ct", {"estimator": {"row_weights": given}})
    assert tuple(scenario_controller(mine, "adaptive_ct")[1].online.row_weights) == given
    drawn = load_scenario(SCENARIOS / "ur5_tool_swap.toml")
    stated = scenario_controller(drawn, "adaptive_ct")[1]
    assert stated.online.mode == "arm"
    np.testing.assert_array_equal(stated.online.row_weights, expect)
    prior = (1e-4 * np.eye(sc.arm.base.count)).tolist()
    identified = with_settings(drawn, "adaptive_ct", {"estimator": {"arm_prior_cov": prior}})
    ctrl = scenario_controller(identified, "adaptive_ct")[1]
    assert ctrl.online.mode == "arm"
    np.testing.assert_array_equal(ctrl.online.row_weights, expect)


def test_the_first_pass_kept_with_the_arm_is_the_one_of_these_settings():
    """task_row_weights keeps its pass with the arm: asked again with another filter or data
    selection it runs that pass, not the kept one (each equal to the pass run directly)."""
    sc = load_scenario(SCENARIOS / "ur5_tool_swap_exact.toml")
    motion = sc.reference.sample(np.arange(6000) * sc.sample_period)
    for cfg in (
        OnlineConfig(sample_period=sc.sample_period),
        OnlineConfig(sample_period=sc.sample_period, tau_f=0.02),
        OnlineConfig(sample_period=sc.sample_period, selection=(0.2, 6.0)),
    ):
        np.testing.assert_array_equal(
            task_row_weights(sc.arm, cfg, sc),
            first_pass_row_weights(sc.arm, cfg, motion, mass=pass_mass(sc.arm, sc)),
        )


def _alarms(arm, w, err):
    """The detector alone (``est_detect_trial``) over the rows' errors ``err (N, n)`` [N m] weighted
    by ``w``, every row in use and moving: the samples at which it alarms."""
    c, s = est_init(OnlineConfig(row_weights=tuple(float(x) for x in w), detector=Detector()), arm, 1)
    s.since_crawl[:] = K.BIG
    act = np.ones(arm.n_joints, dtype=np.bool_)
    return [k for k in range(err.shape[0]) if est_detect_trial(c, s, 0, err[k] / w, act)]


def test_the_detectors_floor_is_in_newton_metres_whatever_the_weights_scale(ur5):
    """Rows far quieter than the floor (0.05 N m on the row of the largest weight, alarm at 4x), then
    a step on that row: 0.15 N m raises no alarm and 0.3 N m does, with the torque limits' weights
    and with ten times them (a floor read in the weighted units would stand at 0.5 N m there)."""
    w = derived_row_weights(ur5)
    j = int(np.argmax(w))
    err = 1e-4 * np.random.default_rng(0).standard_normal((3000, ur5.n_joints))
    for step, alarm in ((0.15, False), (0.3, True)):
        e = err.copy()
        e[2000:, j] += step
        for scale in (1.0, 10.0):
            assert bool(_alarms(ur5, scale * w, e)) == alarm, (step, scale)
