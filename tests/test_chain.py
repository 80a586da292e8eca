"""The compiled serial-chain kernels (adaptive_dd.plant.chain) against Pinocchio and by identities."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from chain_models import random_chain_model
from hypothesis import given, settings
from hypothesis import strategies as st

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant import chain as C
from adaptive_dd.plant.dynamics import coriolis_matrix as coriolis_2link
from adaptive_dd.plant.dynamics import inverse_dynamics as inverse_dynamics_2link
from adaptive_dd.plant.dynamics import mass_matrix as mass_matrix_2link
from adaptive_dd.plant.parameters import TABLE1_SIGMA
from adaptive_dd.plant.pinocchio_model import build_model

ATOL = 1e-10


def _state(n: int, rng: np.random.Generator, k: int) -> list[np.ndarray]:
    return [rng.uniform(-2.0, 2.0, size=n) for _ in range(k)]


def _pin_m(model, data, pq):
    m = np.atleast_2d(pin.crba(model, data, pq))
    return np.triu(m) + np.triu(m, 1).T


def _pin_ref(model, data, pq, qd, qdr, qddr):
    m = _pin_m(model, data, pq)
    c = np.atleast_2d(pin.computeCoriolisMatrix(model, data, pq, qd))
    g = pin.computeGeneralizedGravity(model, data, pq)
    return m @ qddr + c @ qdr + g


chains = settings(max_examples=30, deadline=None)


@chains
@given(n=st.integers(1, 7), seed=st.integers(0, 2**32 - 1))
def test_kernels_match_pinocchio(n, seed):
    rng = np.random.default_rng(seed)
    model = random_chain_model(n, rng)
    data = model.createData()
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    q, qd, qdd, qdr, qddr, tau = _state(n, rng, 6)
    pq = C.pin_configuration(model, q)
    out, mat, reg = np.empty(n), np.empty((n, n)), np.empty((n, 10 * n))

    C.rnea(ch, pi, q, qd, qdd, out)
    np.testing.assert_allclose(out, pin.rnea(model, data, pq, qd, qdd), rtol=0, atol=ATOL)
    C.mass_matrix(ch, pi, q, mat)
    np.testing.assert_allclose(mat, _pin_m(model, data, pq), rtol=0, atol=ATOL)
    C.coriolis_matrix(ch, pi, q, qd, mat)
    np.testing.assert_allclose(
        mat, np.atleast_2d(pin.computeCoriolisMatrix(model, data, pq, qd)), rtol=0, atol=ATOL
    )
    C.rnea_ref(ch, pi, q, qd, qdr, qddr, out)
    np.testing.assert_allclose(out, _pin_ref(model, data, pq, qd, qdr, qddr), rtol=0, atol=ATOL)
    assert C.forward_dynamics(ch, pi, np.zeros(n), q, qd, tau, out)
    np.testing.assert_allclose(out, pin.aba(model, data, pq, qd, tau), rtol=0, atol=ATOL)
    C.regressor(ch, q, qd, qdd, reg)
    np.testing.assert_allclose(
        reg,
        np.reshape(pin.computeJointTorqueRegressor(model, data, pq, qd, qdd), (n, 10 * n)),
        rtol=0,
        atol=ATOL,
    )
    C.slotine_li_regressor(ch, q, qd, qdr, qddr, reg)
    np.testing.assert_allclose(reg @ pi, _pin_ref(model, data, pq, qd, qdr, qddr), rtol=0, atol=ATOL)


@chains
@given(n=st.integers(1, 7), seed=st.integers(0, 2**32 - 1))
def test_momentum_form_matches_pinocchio(n, seed):
    """p = M qd, wv = g - C^T qd with Pinocchio's M, C, g; link j's blocks add up to them, and
    d/dt p + wv is the inverse dynamics along a motion (central differences)."""
    rng = np.random.default_rng(seed)
    model = random_chain_model(n, rng)
    data = model.createData()
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    q, qd, qdd = _state(n, rng, 3)
    pq = C.pin_configuration(model, q)
    p, wv, py, wy = np.empty(n), np.empty(n), np.empty((n, 10)), np.empty((n, 10))
    ps, ws = np.zeros(n), np.zeros(n)
    for j in range(n):
        C.momentum_form(ch, pi, j, q, qd, p, wv, py, wy)
        assert not np.any(py[j + 1 :]) and not np.any(wy[j + 1 :])
        ps += py @ pi[10 * j : 10 * j + 10]
        ws += wy @ pi[10 * j : 10 * j + 10]
    cor = np.atleast_2d(pin.computeCoriolisMatrix(model, data, pq, qd))
    g = pin.computeGeneralizedGravity(model, data, pq)
    for got_p, got_w in ((p, wv), (ps, ws)):
        np.testing.assert_allclose(got_p, _pin_m(model, data, pq) @ qd, rtol=0, atol=ATOL)
        np.testing.assert_allclose(got_w, g - cor.T @ qd, rtol=0, atol=ATOL)
    # along q(t) = q + t qd + t^2 qdd / 2 at t = 0: d/dt p + wv = rnea(q, qd, qdd)
    h = 1e-5
    pp, pm = np.empty(n), np.empty(n)
    C.momentum_form(ch, pi, 0, q + h * qd + 0.5 * h * h * qdd, qd + h * qdd, pp, ws, py, wy)
    C.momentum_form(ch, pi, 0, q - h * qd + 0.5 * h * h * qdd, qd - h * qdd, pm, ws, py, wy)
    tau = np.empty(n)
    C.rnea(ch, pi, q, qd, qdd, tau)
    np.testing.assert_allclose((pp - pm) / (2 * h) + wv, tau, rtol=0, atol=1e-6 * (1.0 + np.abs(tau).max()))


@settings(max_examples=10, deadline=None)
@given(n=st.integers(1, 7), seed=st.integers(0, 2**32 - 1))
def test_momentum_columns_reuse_the_kinematics_bit_for_bit(n, seed):
    """Link j's columns from the kinematics a call for link 0 left in the workspace are those of a
    call for link j itself, to the last bit (the estimator of mode "arm" reads every link's so)."""
    from adaptive_dd.plant.chain_regressor import momentum_columns_in

    rng = np.random.default_rng(seed)
    model = random_chain_model(n, rng)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    q, qd = _state(n, rng, 2)
    w, a = C.workspace(n), np.empty((2, 6, 10))
    p, wv, py, wy = np.empty(n), np.empty(n), np.empty((n, 10)), np.empty((n, 10))
    ref = [np.empty((n, 10)) for _ in range(2)]
    for j in range(n):
        C.momentum_form(ch, pi, j, q, qd, p, wv, *ref)
        C.momentum_form_in(ch, pi, 0, q, qd, w, a, p, wv, py, wy)
        momentum_columns_in(j, w, a, py, wy)
        assert np.array_equal(py, ref[0]) and np.array_equal(wy, ref[1]), j


@settings(max_examples=8, deadline=None)
@given(n=st.integers(1, 5), seed=st.integers(0, 2**32 - 1))
def test_slotine_li_regressor_column_by_column(n, seed):
    """Column k is the change of Pinocchio's M qddr + C qdr + g when pi_k grows by 1.

    (The torque is linear in pi; a unit vector itself, a massless first moment, is
    not a valid Pinocchio inertia.)
    """
    rng = np.random.default_rng(seed)
    model = random_chain_model(n, rng)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    q, qd, qdr, qddr = _state(n, rng, 4)
    pq = C.pin_configuration(model, q)
    reg = np.empty((n, 10 * n))
    C.slotine_li_regressor(ch, q, qd, qdr, qddr, reg)
    base = _pin_ref(model, model.createData(), pq, qd, qdr, qddr)
    for k in range(10 * n):
        shifted = model.copy()
        j = k // 10
        params = pi[10 * j : 10 * j + 10].copy()
        params[k % 10] += 1.0
        shifted.inertias[j + 1] = pin.Inertia.FromDynamicParameters(params)
        col = _pin_ref(shifted, shifted.createData(), pq, qd, qdr, qddr) - base
        np.testing.assert_allclose(reg[:, k], col, rtol=0, atol=ATOL, err_msg=f"column {k}")


@chains
@given(n=st.integers(1, 7), seed=st.integers(0, 2**32 - 1))
def test_identities(n, seed):
    rng = np.random.default_rng(seed)
    model = random_chain_model(n, rng)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    q, qd, qdd, qdr, qddr = _state(n, rng, 5)
    tau, tau_ref = np.empty(n), np.empty(n)
    reg, body = np.empty((n, 10 * n)), np.empty((n, 10))

    C.rnea(ch, pi, q, qd, qdd, tau)
    C.regressor(ch, q, qd, qdd, reg)
    np.testing.assert_allclose(reg @ pi, tau, rtol=0, atol=ATOL)
    for j in range(n):
        C.body_regressor(ch, j, q, qd, qdd, body)
        np.testing.assert_allclose(body, reg[:, 10 * j : 10 * j + 10], rtol=0, atol=ATOL)
    C.rnea_ref(ch, pi, q, qd, qd, qdd, tau_ref)
    np.testing.assert_allclose(tau_ref, tau, rtol=0, atol=ATOL)

    C.slotine_li_regressor(ch, q, qd, qdr, qddr, reg)
    C.rnea_ref(ch, pi, q, qd, qdr, qddr, tau_ref)
    np.testing.assert_allclose(reg @ pi, tau_ref, rtol=0, atol=ATOL)
    for j in range(n):
        C.body_slotine_li_regressor(ch, j, q, qd, qdr, qddr, body)
        np.testing.assert_allclose(body, reg[:, 10 * j : 10 * j + 10], rtol=0, atol=ATOL)

    m = np.empty((n, n))
    C.mass_matrix(ch, pi, q, m)
    np.testing.assert_array_equal(m, m.T)
    assert np.linalg.eigvalsh(m).min() > 0.0

    # dM/dt by central differences along qd (error O(h^2) ~ 1e-10): dM/dt - 2C skew-symmetric
    h = 1e-5
    mp, mm, c = np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    C.mass_matrix(ch, pi, q + h * qd, mp)
    C.mass_matrix(ch, pi, q - h * qd, mm)
    C.coriolis_matrix(ch, pi, q, qd, c)
    skew = (mp - mm) / (2 * h) - 2 * c
    np.testing.assert_allclose(skew + skew.T, 0.0, atol=1e-6 * (1.0 + np.abs(c).max()))


def test_gravity_and_coriolis_closed_form():
    """A pendulum about y and the SICE two-link arm: closed forms, independent of Pinocchio.

    A planted sign error in gravity (pendulum) or in the Coriolis/centrifugal term
    (two-link arm, ``dynamics.py`` closed forms) fails here.
    """
    mass, length, g = 1.7, 0.35, 9.81
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelRY(), pin.SE3.Identity(), "pendulum")
    model.appendBodyToJoint(
        j, pin.Inertia(mass, np.array([length, 0.0, 0.0]), np.eye(3) * 1e-3), pin.SE3.Identity()
    )
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    out = np.empty(1)
    for q in (0.0, 0.7, -2.0):
        C.rnea(ch, pi, np.array([q]), np.zeros(1), np.zeros(1), out)
        # com at (l cos q, 0, -l sin q): gravity's moment about +y is m g l cos q, held by -m g l cos q
        assert out[0] == pytest.approx(-mass * g * length * np.cos(q), abs=1e-12)

    model = build_model()  # SICE arm, joints about z, gravity along -z gives no torque
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    sigma = np.asarray(TABLE1_SIGMA, dtype=float).copy()
    sigma[3:] = 0.0  # no friction: rigid body only
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, qd, qdd = _state(2, rng, 3)
        m, c = np.empty((2, 2)), np.empty((2, 2))
        C.mass_matrix(ch, pi, q, m)
        C.coriolis_matrix(ch, pi, q, qd, c)
        C.rnea(ch, pi, q, qd, qdd, out2 := np.empty(2))
        np.testing.assert_allclose(m, mass_matrix_2link(q, sigma), rtol=0, atol=1e-9)
        np.testing.assert_allclose(c @ qd, coriolis_2link(q, qd, sigma) @ qd, rtol=0, atol=1e-9)
        np.testing.assert_allclose(out2, inverse_dynamics_2link(q, qd, qdd, sigma), rtol=0, atol=1e-9)


def test_forward_dynamics_with_armature_matches_pinocchio(rng):
    model = random_chain_model(5, rng)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    armature = rng.uniform(0.0, 0.5, size=5)
    model.armature = armature
    data = model.createData()
    q, qd, tau = _state(5, rng, 3)
    out = np.empty(5)
    assert C.forward_dynamics(ch, pi, armature, q, qd, tau, out)
    np.testing.assert_allclose(out, pin.aba(model, data, C.pin_configuration(model, q), qd, tau), atol=ATOL)


def test_forward_dynamics_flags_a_singular_mass_matrix():
    model = random_chain_model(2, np.random.default_rng(1))
    ch = C.chain_from_model(model)
    out = np.empty(2)
    assert not C.forward_dynamics(ch, np.zeros(20), np.zeros(2), np.zeros(2), np.zeros(2), np.ones(2), out)
    assert np.all(np.isnan(out))
    with pytest.raises(SignalError, match="positive definite"):
        C.forward_dynamics_batch(ch, np.zeros(20), np.zeros(2), np.zeros(2), np.zeros(2), np.ones(2))


def test_batch_wrappers_agree_with_the_kernels(rng):
    n = 4
    model = random_chain_model(n, rng)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    q, qd, qdd, qdr, qddr = (rng.normal(size=(3, 2, n)) for _ in range(5))
    tau = C.rnea_batch(ch, pi, q, qd, qdd)
    assert tau.shape == (3, 2, n)
    m = C.mass_matrix_batch(ch, pi, q)
    c = C.coriolis_matrix_batch(ch, pi, q, qd)
    y = C.regressor_batch(ch, q, qd, qdd)
    ysl = C.slotine_li_regressor_batch(ch, q, qd, qdr, qddr)
    ref = C.rnea_ref_batch(ch, pi, q, qd, qdr, qddr)
    qdd_back = C.forward_dynamics_batch(ch, pi, np.zeros(n), q, qd, tau)
    assert m.shape == c.shape == (3, 2, n, n) and y.shape == ysl.shape == (3, 2, n, 10 * n)
    np.testing.assert_allclose(np.einsum("...ij,j->...i", y, pi), tau, atol=ATOL)
    np.testing.assert_allclose(np.einsum("...ij,j->...i", ysl, pi), ref, atol=ATOL)
    np.testing.assert_allclose(qdd_back, qdd, atol=1e-8)
    one = np.empty(n)
    C.rnea_ref(ch, pi, q[1, 0], qd[1, 0], qdr[1, 0], qddr[1, 0], one)
    np.testing.assert_array_equal(ref[1, 0], one)
    np.testing.assert_allclose(
        np.einsum("...ij,...j->...i", m, qddr) + np.einsum("...ij,...j->...i", c, qdr),
        ref - C.rnea_batch(ch, pi, q, np.zeros_like(q), np.zeros_like(q)),
        atol=ATOL,
    )
    # one state broadcast against a batch
    assert C.rnea_batch(ch, pi, q[0, 0], qd, qdd).shape == (3, 2, n)
    with pytest.raises(SignalError, match="shape"):
        C.rnea_batch(ch, pi, q[..., :2], qd, qdd)
    with pytest.raises(SignalError, match="non-finite"):
        C.rnea_batch(ch, pi, np.full(n, np.nan), qd, qdd)
    with pytest.raises(ParameterError, match="pi has shape"):
        C.rnea_batch(ch, pi[:-1], q, qd, qdd)


def test_workspace_variants_equal_the_allocating_kernels_bit_for_bit(rng):
    """The ``*_in`` kernels (scratch given, reused across calls) give the very same numbers as the
    allocating ones, whatever the scratch held before (NaN here: a kernel reading stale scratch
    would spread it)."""
    n = 5
    model = random_chain_model(n, rng)
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    w, a = C.workspace(n), np.empty((6, 10))
    for arr in w:
        arr[...] = np.nan
    a[...] = np.nan
    for _ in range(3):  # the same scratch, again and again
        q, qd, qdd, qdr, qddr = _state(n, rng, 5)
        want, got = np.empty(n), np.empty(n)
        C.rnea(ch, pi, q, qd, qdd, want)
        C.rnea_in(ch, pi, q, qd, qdd, w, got)
        np.testing.assert_array_equal(got, want)
        C.rnea_ref(ch, pi, q, qd, qdr, qddr, want)
        C.rnea_ref_in(ch, pi, q, qd, qdr, qddr, w, got)
        np.testing.assert_array_equal(got, want)
        m_want, m_got = np.empty((n, n)), np.empty((n, n))
        C.mass_matrix(ch, pi, q, m_want)
        C.mass_matrix_in(ch, pi, q, w, m_got)
        np.testing.assert_array_equal(m_got, m_want)
        for j in (0, n - 1):
            y_want, y_got = np.empty((n, 10)), np.empty((n, 10))
            C.body_regressor(ch, j, q, qd, qdd, y_want)
            C.body_regressor_in(ch, j, q, qd, qdd, w, a, y_got)
            np.testing.assert_array_equal(y_got, y_want)
            C.body_slotine_li_regressor(ch, j, q, qd, qdr, qddr, y_want)
            C.body_slotine_li_regressor_in(ch, j, q, qd, qdr, qddr, w, a, y_got)
            np.testing.assert_array_equal(y_got, y_want)
            C.body_regressor(ch, j, q, qd, qdd, y_want)
            C.rnea(ch, pi, q, qd, qdd, want)
            C.rnea_body_regressor_in(ch, pi, j, q, qd, qdd, w, a, got, y_got)
            np.testing.assert_array_equal(got, want)
            np.testing.assert_array_equal(y_got, y_want)
    assert np.isfinite(m_got).all()


def _model_with(joint: pin.JointModel, name: str = "odd") -> pin.Model:
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "first")
    model.appendBodyToJoint(j, pin.Inertia.Random(), pin.SE3.Identity())
    j = model.addJoint(j, joint, pin.SE3.Identity(), name)
    model.appendBodyToJoint(j, pin.Inertia.Random(), pin.SE3.Identity())
    return model


@pytest.mark.parametrize(
    ("joint", "reason"),
    [
        (pin.JointModelFreeFlyer(), "JointModelFreeFlyer"),
        (pin.JointModelSpherical(), "JointModelSpherical"),
        (pin.JointModelHZ(0.1), "JointModelHZ"),
    ],
)
def test_chain_from_model_rejects_other_joints(joint, reason):
    with pytest.raises(ParameterError, match=f"joint 2 'odd'.*{reason}"):
        C.chain_from_model(_model_with(joint))


def test_chain_from_model_rejects_a_branch():
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "trunk")
    model.addJoint(j1, pin.JointModelRY(), pin.SE3.Identity(), "left")
    model.addJoint(j1, pin.JointModelRY(), pin.SE3.Identity(), "right")
    with pytest.raises(ParameterError, match=r"joint 3 'right'.*not a serial chain"):
        C.chain_from_model(model)


def test_continuous_joint_configuration():
    model = _model_with(pin.JointModelRUBY(), "wheel")
    assert model.nq == 3
    np.testing.assert_allclose(
        C.pin_configuration(model, np.array([0.3, 1.2])), [0.3, np.cos(1.2), np.sin(1.2)]
    )
    with pytest.raises(SignalError, match="expected \\(2,\\)"):
        C.pin_configuration(model, np.zeros(3))


ERD_ARMS = [  # example-robot-data's URDFs (the robots and test extras)
    "ur_description/urdf/ur5_robot.urdf",
    "panda_description/urdf/panda.urdf",
    "z1_description/urdf/z1.urdf",
]


@pytest.mark.parametrize("name", ERD_ARMS)
def test_example_robot_data_arms(name):
    from adaptive_dd.errors import ParameterError
    from adaptive_dd.robots.example_robot_data import urdf_path

    try:
        path = urdf_path(f"example-robot-data:{name}")
    except ParameterError as exc:  # the optional package (the robots and test extras)
        pytest.skip(str(exc))
    model = pin.buildModelFromUrdf(str(path))
    if name.startswith("panda"):  # the fingers are a branch: keep the 7 arm joints
        model = pin.buildReducedModel(
            model, [model.getJointId(f"panda_finger_joint{i}") for i in (1, 2)], pin.neutral(model)
        )
    n = model.nv
    ch, pi = C.chain_from_model(model), C.standard_parameters(model)
    data = model.createData()
    rng = np.random.default_rng(7)
    q, qd, qdd = _state(n, rng, 3)
    pq = C.pin_configuration(model, q)
    out, m = np.empty(n), np.empty((n, n))
    C.rnea(ch, pi, q, qd, qdd, out)
    np.testing.assert_allclose(out, pin.rnea(model, data, pq, qd, qdd), atol=ATOL)
    C.mass_matrix(ch, pi, q, m)
    np.testing.assert_allclose(m, _pin_m(model, data, pq), atol=ATOL)
    C.coriolis_matrix(ch, pi, q, qd, m)
    np.testing.assert_allclose(m, pin.computeCoriolisMatrix(model, data, pq, qd), atol=ATOL)
