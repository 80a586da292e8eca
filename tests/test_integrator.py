"""The N-joint sampled-data plant (adaptive_dd.plant.integrator)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from chain_models import random_chain_model

from adaptive_dd.errors import ParameterError
from adaptive_dd.experiments import table2_torque
from adaptive_dd.plant import ClosedFormTwoLink
from adaptive_dd.plant import chain as C
from adaptive_dd.plant import integrator as S
from adaptive_dd.plant.pinocchio_model import build_model
from adaptive_dd.plant.two_link_integrator import two_link_plant_step

T = 1e-3


def _rk4_over_aba(model, q, qd, tau, dt, substeps):
    """Reference: classical RK4 on (q, qd) with pin.aba, in the kernels' joint coordinates."""
    data = model.createData()

    def f(x, v):
        return pin.aba(model, data, C.pin_configuration(model, x), v, tau)

    h = dt / substeps
    for _ in range(substeps):
        a1 = f(q, qd)
        w = qd + 0.5 * h * a1
        a2 = f(q + 0.5 * h * qd, w)
        x = qd + 0.5 * h * a2
        a3 = f(q + 0.5 * h * w, x)
        y = qd + h * a3
        a4 = f(q + h * x, y)
        q = q + h / 6 * (qd + 2 * w + 2 * x + y)
        qd = qd + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
    return q, qd


@pytest.mark.parametrize("law", ["stick-slip", "tanh", "stribeck"])
def test_frictionless_step_is_rk4_over_aba(law, rng):
    n = 5
    model = random_chain_model(n, rng)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    armature = rng.uniform(0.0, 0.3, size=n)
    model.armature = armature  # pin.aba includes it
    pp = S.plant_params(ch, pi, np.zeros(n), np.zeros(n), armature, law=law)
    for _ in range(3):
        q, qd, tau = rng.uniform(-1, 1, size=n), rng.uniform(-2, 2, size=n), rng.uniform(-5, 5, size=n)
        q_ref, qd_ref = _rk4_over_aba(model, q, qd, tau, T, 2)
        stuck = np.ones(n, dtype=bool)
        assert S.plant_step(ch, pp, q, qd, tau, T, 2, stuck)
        np.testing.assert_allclose(q, q_ref, rtol=0, atol=1e-10)
        np.testing.assert_allclose(qd, qd_ref, rtol=0, atol=1e-10)
        assert not stuck.any()


def test_frictionless_chain_conserves_energy(rng):
    """No torque input, no friction: kinetic + potential energy constant within RK4 accuracy."""
    n = 4
    model = random_chain_model(n, rng)
    data = model.createData()
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    pp = S.plant_params(ch, pi, np.zeros(n), np.zeros(n))
    q, qd = rng.uniform(-1, 1, size=n), rng.uniform(-1, 1, size=n)

    def energy(q, qd):
        pq = C.pin_configuration(model, q)
        return pin.computeKineticEnergy(model, data, pq, qd) + pin.computePotentialEnergy(model, data, pq)

    n_samples = 1000
    e0 = energy(q, qd)
    q_out, qd_out = np.empty((n_samples, n)), np.empty((n_samples, n))
    tau = np.zeros((n_samples, n))
    assert S.plant_run(ch, pp, q, qd, tau, T, 2, q_out, qd_out) == n_samples
    drift = max(abs(energy(q_out[k], qd_out[k]) - e0) for k in range(0, n_samples, 50))
    scale = abs(pin.computeKineticEnergy(model, data, C.pin_configuration(model, q), qd)) + 1.0
    assert np.abs(qd_out).max() > 0.1  # it moved
    assert drift < 1e-8 * scale, drift


def _pendulum(mass=2.0, length=0.3, extra_joints=0):
    """A joint about y with its link along x under gravity -z (torque m g l cos q), optionally more links."""
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelRY(), pin.SE3.Identity(), "shoulder")
    model.appendBodyToJoint(
        j, pin.Inertia(mass, np.array([length, 0, 0]), np.eye(3) * 0.01), pin.SE3.Identity()
    )
    for k in range(extra_joints):
        placement = pin.SE3(np.eye(3), np.array([2 * length, 0, 0]))
        j = model.addJoint(j, pin.JointModelRY(), placement, f"joint{k + 2}")
        model.appendBodyToJoint(
            j, pin.Inertia(mass, np.array([length, 0, 0]), np.eye(3) * 0.01), pin.SE3.Identity()
        )
    return model


def test_coulomb_holds_below_breakaway_and_releases_above():
    mass, length, g = 2.0, 0.3, 9.81
    hold = mass * g * length  # gravity torque at q = 0
    model = _pendulum(mass, length)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    for fc, moves in ((1.05 * hold, False), (0.95 * hold, True)):
        pp = S.plant_params(ch, pi, np.array([0.1]), np.array([fc]))
        q, qd, stuck = np.zeros(1), np.zeros(1), np.zeros(1, dtype=bool)
        for _ in range(500):
            assert S.plant_step(ch, pp, q, qd, np.zeros(1), T, 2, stuck)
        if moves:
            # the link falls: rotation about +y by q puts the com at z = -l sin q, so q grows
            assert q[0] > 0.01 and qd[0] > 0.0 and not stuck[0]
        else:
            assert q[0] == 0.0 and qd[0] == 0.0 and stuck[0]
    # an applied torque helping gravity breaks it away, one resisting it keeps it held
    pp = S.plant_params(ch, pi, np.array([0.1]), np.array([1.05 * hold]))
    for tau, moves in ((0.1 * hold, True), (-0.1 * hold, False)):
        q, qd, stuck = np.zeros(1), np.zeros(1), np.zeros(1, dtype=bool)
        for _ in range(200):
            S.plant_step(ch, pp, q, qd, np.array([tau]), T, 2, stuck)
        assert (q[0] > 0.0) == moves and (q[0] == 0.0) != moves


def test_three_joint_vertical_chain_stays_held_then_releases():
    model = _pendulum(extra_joints=2)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    g_torque = np.empty(3)
    C.rnea(ch, pi, np.zeros(3), np.zeros(3), np.zeros(3), g_torque)  # torques holding it at q = 0
    q, qd, stuck = np.zeros(3), np.zeros(3), np.zeros(3, dtype=bool)
    pp = S.plant_params(ch, pi, np.full(3, 0.1), 1.01 * np.abs(g_torque))
    for _ in range(300):
        assert S.plant_step(ch, pp, q, qd, np.zeros(3), T, 2, stuck)
    assert np.all(q == 0.0) and np.all(qd == 0.0) and stuck.all()
    # weaken the middle joint only: it slides, and the joints it loads may follow
    pp = S.plant_params(ch, pi, np.full(3, 0.1), np.abs(g_torque) * np.array([1.01, 0.5, 1.01]))
    for _ in range(300):
        assert S.plant_step(ch, pp, q, qd, np.zeros(3), T, 2, stuck)
    assert q[1] > 0.0 and not stuck[1]


@pytest.mark.parametrize("law", ["stick-slip", "tanh", "stribeck"])
def test_reproduces_the_two_link_plant_on_the_sice_arm(law):
    """SICE arm (Table 1, joints about z, link 1 of 0.2 m along x), Table 2 torques, 2000 samples.

    The same modes are chosen by both stick-slip rules all along (module docstring
    of integrator), so the states agree to round-off.
    """
    arm = ClosedFormTwoLink.sice(friction=law)
    model = build_model(arm)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    sigma = np.asarray(arm.sigma)
    pp = S.plant_params(
        ch,
        pi,
        sigma[3:5],
        sigma[5:7],
        law=law,
        friction_velocity=arm.friction_velocity,
        stribeck_ratio=arm.stribeck_ratio,
        stribeck_velocity=arm.stribeck_velocity,
    )
    tau = table2_torque(1, 2000)[0]
    q, qd, stuck = np.zeros(2), np.zeros(2), np.zeros(2, dtype=bool)
    q2, qd2, st2, sl2 = np.zeros(2), np.zeros(2), np.zeros(2, dtype=bool), np.ones(2)
    worst, n_stuck = 0.0, 0
    for k in range(tau.shape[0]):
        assert S.plant_step(ch, pp, q, qd, tau[k], T, 2, stuck)
        q2, qd2, st2, sl2 = two_link_plant_step(
            q2, qd2, st2, sl2, tau[k], sigma, T, 2, arm.friction_code, arm.friction_params
        )
        worst = max(worst, np.abs(q - q2).max(), np.abs(qd - qd2).max())
        np.testing.assert_array_equal(stuck, st2)
        n_stuck += int(stuck.sum())
    assert worst < 1e-9
    if law == "stick-slip":
        assert n_stuck > 50  # the torques do make joints stick: the mode logic was exercised


def test_run_agrees_with_the_step(rng):
    n, n_trials, n_samples = 3, 4, 50
    model = random_chain_model(n, rng)
    ch = C.chain_from_model(model)
    pi = np.stack([C.standard_parameters(model) * rng.uniform(0.8, 1.2) for _ in range(n_trials)])
    fv, fc = rng.uniform(0, 0.5, size=(n_trials, n)), rng.uniform(0, 1.0, size=(n_trials, n))
    tau = rng.uniform(-3, 3, size=(n_samples, n_trials, n))
    q, qd = np.zeros((n_trials, n)), np.zeros((n_trials, n))
    stuck = np.zeros((n_trials, n), dtype=bool)
    for t in range(n_trials):
        pp = S.plant_params(ch, pi[t], fv[t], fc[t])  # law 0 (stick-slip), the default friction parameters
        for k in range(n_samples):
            assert S.plant_step(ch, pp, q[t], qd[t], tau[k, t], T, 2, stuck[t])
        q1, qd1 = np.zeros(n), np.zeros(n)
        q_out, qd_out = np.empty((n_samples, n)), np.empty((n_samples, n))
        assert S.plant_run(ch, pp, q1, qd1, np.ascontiguousarray(tau[:, t]), T, 2, q_out, qd_out) == n_samples
        np.testing.assert_array_equal(q_out[-1], q[t])
        np.testing.assert_array_equal(qd_out[-1], qd[t])
        assert np.abs(q[t]).max() > 0.0


def test_a_singular_mass_matrix_is_reported():
    model = random_chain_model(2, np.random.default_rng(0))
    ch = C.chain_from_model(model)
    pp = S.plant_params(ch, np.zeros(20), np.zeros(2), np.zeros(2))
    q, qd = np.zeros(2), np.zeros(2)
    assert not S.plant_step(ch, pp, q, qd, np.ones(2), T, 2, np.zeros(2, dtype=bool))
    q_out, qd_out = np.empty((5, 2)), np.empty((5, 2))
    assert S.plant_run(ch, pp, np.zeros(2), np.zeros(2), np.ones((5, 2)), T, 2, q_out, qd_out) == 0


def test_plant_params_are_checked():
    ch = C.chain_from_model(random_chain_model(2, np.random.default_rng(0)))
    pi = np.ones(20)
    with pytest.raises(ParameterError, match="friction law"):
        S.plant_params(ch, pi, np.zeros(2), np.zeros(2), law="viscous")
    with pytest.raises(ParameterError, match="plant fc must be >= 0"):
        S.plant_params(ch, pi, np.zeros(2), np.array([1.0, -1.0]))
    with pytest.raises(ParameterError, match="plant pi must be 20 finite"):
        S.plant_params(ch, pi[:10], np.zeros(2), np.zeros(2))
    with pytest.raises(ParameterError, match="stribeck_ratio"):
        S.plant_params(ch, pi, np.zeros(2), np.zeros(2), stribeck_ratio=0.5)
    pp = S.plant_params(ch, pi, np.zeros(2), np.zeros(2), law="stribeck")
    assert pp.law == 2 and pp.armature.shape == (2,)
