"""Identities of the dynamics (eqs. 3-9) and the cross-check against Pinocchio."""

import numpy as np
import pinocchio as pin
import pytest

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant import (
    TABLE1_PHYSICAL,
    TABLE1_SIGMA,
    Payload,
    PhysicalParameters,
    coriolis_matrix,
    forward_dynamics,
    friction,
    inverse_dynamics,
    mass_matrix,
    payload_sigma_delta,
    regressor,
    regressor_reference,
    validate_sigma,
)
from adaptive_dd.plant.pinocchio_model import base_parameter_map, build_model, two_link_cross_check


def random_states(rng, n=50):
    return rng.uniform(-3, 3, (n, 2)), rng.uniform(-4, 4, (n, 2)), rng.uniform(-40, 40, (n, 2))


def test_table1_physical_maps_onto_table1():
    np.testing.assert_allclose(TABLE1_PHYSICAL.to_sigma(), TABLE1_SIGMA, rtol=0, atol=1e-12)


def test_payload_delta_matches_parallel_axis_construction():
    p = Payload(3.0, 0.07)
    np.testing.assert_allclose(
        TABLE1_PHYSICAL.with_payload(p).to_sigma(),
        TABLE1_SIGMA + payload_sigma_delta(3.0, 0.07),
        atol=1e-12,
    )
    np.testing.assert_allclose(payload_sigma_delta(1.0, 0.0)[:3], [0.04, 0.04, 0.04])


def test_regressor_times_sigma_is_inverse_dynamics(rng):
    q, qd, qdd = random_states(rng)
    sig = TABLE1_SIGMA * rng.uniform(0.5, 1.5, (50, 7))
    sig[:, 2] = np.minimum(sig[:, 2], 0.9 * np.sqrt(sig[:, 0] * sig[:, 1]))
    np.testing.assert_allclose(
        regressor(q, qd, qdd) @ TABLE1_SIGMA,
        inverse_dynamics(q, qd, qdd, TABLE1_SIGMA),
        atol=1e-12,
    )
    tau = inverse_dynamics(q, qd, qdd, sig)
    np.testing.assert_allclose((regressor(q, qd, qdd) @ sig[..., None])[..., 0], tau, atol=1e-12)
    np.testing.assert_allclose(forward_dynamics(q, qd, tau, sig), qdd, atol=1e-9)


def test_equation_of_motion_assembles_from_parts(rng):
    q, qd, qdd = random_states(rng)
    m, c = mass_matrix(q, TABLE1_SIGMA), coriolis_matrix(q, qd, TABLE1_SIGMA)
    tau = (m @ qdd[..., None] + c @ qd[..., None])[..., 0] + friction(qd, TABLE1_SIGMA)
    np.testing.assert_allclose(tau, inverse_dynamics(q, qd, qdd, TABLE1_SIGMA), atol=1e-12)


def test_slotine_li_regressor_reduces_to_regressor_when_reference_is_actual(rng):
    q, qd, qdd = random_states(rng)
    np.testing.assert_allclose(regressor_reference(q, qd, qd, qdd), regressor(q, qd, qdd), atol=1e-12)
    qr, ar = rng.normal(size=(2, 50, 2))
    y = regressor_reference(q, qd, qr, ar) @ TABLE1_SIGMA
    m, c = mass_matrix(q, TABLE1_SIGMA), coriolis_matrix(q, qd, TABLE1_SIGMA)
    expect = (
        (m @ ar[..., None] + c @ qr[..., None])[..., 0]
        + TABLE1_SIGMA[3:5] * qr
        + TABLE1_SIGMA[5:] * np.sign(qr)
    )
    np.testing.assert_allclose(y, expect, atol=1e-12)


def test_batch_axes_broadcast_and_are_kept(rng):
    q = rng.normal(size=(3, 4, 2))
    assert mass_matrix(q, TABLE1_SIGMA).shape == (3, 4, 2, 2)
    assert regressor(q, q, q).shape == (3, 4, 2, 7)
    assert mass_matrix(q[0, 0], TABLE1_SIGMA).shape == (2, 2)
    sig = np.broadcast_to(TABLE1_SIGMA, (3, 1, 7))
    assert inverse_dynamics(q, q, q, sig).shape == (3, 4, 2)


def test_mass_matrix_spd_and_skew_symmetry(rng):
    q, qd, _ = random_states(rng, 200)
    m = mass_matrix(q, TABLE1_SIGMA)
    np.testing.assert_allclose(m, np.swapaxes(m, -1, -2))
    assert np.linalg.eigvalsh(m).min() > 0
    # analytic dM/dt for eq. (3): d/dt (r cos q2) = -r sin q2 qd2
    rs = TABLE1_SIGMA[2] * np.sin(q[:, 1]) * qd[:, 1]
    mdot = -np.stack([np.stack([2 * rs, rs], -1), np.stack([rs, 0 * rs], -1)], -2)
    n = mdot - 2 * coriolis_matrix(q, qd, TABLE1_SIGMA)
    np.testing.assert_allclose(n, -np.swapaxes(n, -1, -2), atol=1e-12)
    x = rng.normal(size=(200, 2, 1))
    np.testing.assert_allclose(np.swapaxes(x, -1, -2) @ n @ x, 0, atol=1e-10)


@pytest.mark.parametrize("mass", [0.0, 1.0, 3.0])
def test_cross_check_against_pinocchio_passes(mass):
    res = two_link_cross_check(TABLE1_PHYSICAL, Payload(mass) if mass else None, n_states=100)
    assert len(res) == 9
    for r in res:
        assert r.passed, str(r)


def test_cross_check_detects_a_wrong_model(monkeypatch):
    # a model whose link 2 is longer than ours must be flagged
    import adaptive_dd.plant.pinocchio_model as pm

    wrong = PhysicalParameters(**{**TABLE1_PHYSICAL.__dict__, "l1": 0.25})
    real_build = pm.build_model
    monkeypatch.setattr(pm, "build_model", lambda params, payload=None: real_build(wrong, payload))
    res = pm.two_link_cross_check(TABLE1_PHYSICAL, n_states=20)
    assert not all(r.passed for r in res)


def test_pinocchio_regressor_columns_directly(rng):
    model = build_model(TABLE1_PHYSICAL)
    data = model.createData()
    q, qd, qdd = random_states(rng, 5)
    k = base_parameter_map(0.2)
    for i in range(5):
        y = pin.computeJointTorqueRegressor(model, data, q[i], qd[i], qdd[i])
        phi = regressor(q[i], qd[i], qdd[i])
        np.testing.assert_allclose(y @ k, phi[:, :3], atol=1e-10)
        # the mass of body 2 enters J1 through m2 l1^2
        np.testing.assert_allclose(y[:, 10], 0.04 * phi[:, 0], atol=1e-10)


@pytest.mark.parametrize(
    "sigma, match",
    [
        ([0.429, 0.071, 0.162, 5.2, 1.1, 3.2], "shape"),
        ([0.0, 0.071, 0.162, 5.2, 1.1, 3.2, 0.7], "J1 must be > 0"),
        ([0.429, 0.071, 0.162, -1, 1.1, 3.2, 0.7], "b1 must be >= 0"),
        ([0.1, 0.071, 0.162, 5.2, 1.1, 3.2, 0.7], "J1\\*J2 - r\\^2"),
        ([np.nan, 0.071, 0.162, 5.2, 1.1, 3.2, 0.7], "non-finite"),
    ],
)
def test_bad_sigma_is_rejected(sigma, match):
    with pytest.raises(ParameterError, match=match):
        validate_sigma(sigma)
    with pytest.raises(ValueError):
        mass_matrix([0, 0], sigma)


def test_bad_states_are_rejected():
    with pytest.raises(SignalError, match="q must have shape"):
        mass_matrix([0, 0, 0], TABLE1_SIGMA)
    with pytest.raises(SignalError, match="qd has a non-finite value"):
        inverse_dynamics([0, 0], [0, np.inf], [0, 0], TABLE1_SIGMA)
    with pytest.raises(SignalError, match="tau"):
        forward_dynamics([0, 0], [0, 0], [np.nan, 0], TABLE1_SIGMA)


@pytest.mark.parametrize(
    "field, value",
    [
        ("m1", 0.0),
        ("m2", -1.0),
        ("I1", 0.0),
        ("a2", -0.1),
        ("l1", 0.0),
        ("b1", -1.0),
        ("d2", float("nan")),
    ],
)
def test_bad_physical_parameters_are_rejected(field, value):
    kw = {**TABLE1_PHYSICAL.__dict__, field: value}
    with pytest.raises(ParameterError, match=f"PhysicalParameters.{field}"):
        PhysicalParameters(**kw)


def test_bad_payload_is_rejected():
    with pytest.raises(ParameterError, match="mass"):
        Payload(-1.0)
    with pytest.raises(ParameterError, match="radius"):
        payload_sigma_delta(1.0, -0.1)


def test_the_positive_definiteness_check_passes_a_definite_matrix_only():
    """It printed a negative "max error" against a tolerance of 0 and passed a singular matrix; it
    prints the smallest eigenvalue over the largest, which must be above 0."""
    from adaptive_dd.plant.pinocchio_model import positive_definite_check

    good = positive_definite_check(np.diag([2.0, 0.5]))
    assert good.passed and "smallest eigenvalue / largest  2.50e-01  (must be > 0)" in str(good)
    assert float(str(good).split("largest")[1].split()[0]) == 0.25
    assert not positive_definite_check(np.diag([1.0, 0.0])).passed
    assert not positive_definite_check(np.diag([1.0, -0.1])).passed
