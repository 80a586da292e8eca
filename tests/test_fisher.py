"""Fisher information and Cramér-Rao bounds: closed-form case, two sensitivity methods, swap time."""

import numpy as np
import pytest

from adaptive_dd.errors import ParameterError
from adaptive_dd.experiments import table2_torque
from adaptive_dd.identification.fisher import (
    crb_from_fisher,
    fisher_from_sensitivities,
    fisher_information,
    linear_gaussian_crb,
    mass_information_time,
    output_variances,
)
from adaptive_dd.identification.sensitivity import (
    chain_sensitivities,
    finite_difference_sensitivities,
    local_sensitivities,
    simulate_trajectory,
)
from adaptive_dd.plant.parameters import TABLE1_SIGMA, payload_sigma_delta


def test_least_squares_std_matches_closed_form_bound(rng):
    """Linear-Gaussian y = Phi sigma + e: Monte-Carlo std of LS equals sqrt(diag(s^2 (Phi^T Phi)^-1))."""
    phi = rng.normal(size=(200, 4)) * [1.0, 0.1, 3.0, 0.5]
    sigma, s2 = np.array([1.0, -2.0, 0.5, 3.0]), 0.04
    y = phi @ sigma + np.sqrt(s2) * rng.standard_normal((4000, 200))
    est = np.linalg.lstsq(phi, y.T, rcond=None)[0].T
    np.testing.assert_allclose(est.std(axis=0), linear_gaussian_crb(phi, s2), rtol=0.10)
    np.testing.assert_allclose(est.mean(axis=0), sigma, atol=3 * linear_gaussian_crb(phi, s2).max())


def test_general_machinery_equals_closed_form_on_linear_case(rng):
    """The sensitivities of y = Phi sigma are Phi: F and the bound equal the closed form."""
    phi = rng.normal(size=(300, 2, 7))
    var = np.array([0.01, 0.04])
    info = fisher_from_sensitivities(phi, var)
    res = crb_from_fisher(info, TABLE1_SIGMA, "linear", 300)
    closed = linear_gaussian_crb((phi / np.sqrt(var)[:, None]).reshape(-1, 7), 1.0)
    np.testing.assert_allclose(res.crb_std, closed, rtol=1e-9)
    np.testing.assert_allclose(res.crb_std_pct, 100 * closed / TABLE1_SIGMA, rtol=1e-9)


def test_forward_sensitivities_equal_finite_differences_without_coulomb():
    """Smooth arm (d = 0): the forward sensitivity equations match central differences to 1e-5."""
    tau = table2_torque(1, 1500)[0]
    sg = TABLE1_SIGMA.copy()
    sg[5:] = 0.0
    q, qd = simulate_trajectory(sg, tau, 1e-3, qd0=(0.01, 0.01))
    a, _, p = local_sensitivities(q, qd, tau, sg, 1e-3)
    s = chain_sensitivities(a, p)[..., :5]
    fd = (
        finite_difference_sensitivities(
            sg, tau, 1e-3, qd0=(0.01, 0.01), rel_step=1e-5, direction=np.eye(7)[:5] * sg[:5, None]
        )
        / sg[:5]
    )
    err = np.abs(s - fd).max(axis=0) / np.abs(fd).max(axis=0)
    assert err.max() < 1e-5


def test_bounds_from_sensitivities_and_finite_differences_agree_on_table2():
    """With stick-slip (Table 2): the two methods' bounds agree within 2 % per parameter."""
    tau = table2_torque(1, 6000)[0]
    a = fisher_information(TABLE1_SIGMA, tau)
    b = fisher_information(TABLE1_SIGMA, tau, method="finite_difference")
    np.testing.assert_allclose(a.crb_std_pct, b.crb_std_pct, rtol=0.02)
    assert a.condition_number > 1


@pytest.fixture(scope="module")
def table2_bound():
    return fisher_information(TABLE1_SIGMA, table2_torque(1, 4000)[0])


def test_fewer_signals_or_torque_noise_give_larger_bounds(table2_bound):
    tau = table2_torque(1, 4000)[0]
    vel = fisher_information(TABLE1_SIGMA, tau, measured=("qd",))
    assert np.all(vel.crb_std > 1.5 * table2_bound.crb_std)
    tiny = fisher_information(TABLE1_SIGMA, tau, torque_variance=(1e-14, 1e-14))
    np.testing.assert_allclose(tiny.crb_std, table2_bound.crb_std, rtol=1e-4)
    noisy = fisher_information(TABLE1_SIGMA, tau, torque_variance=(1e-4, 1e-4))
    assert np.all(noisy.crb_std > 2 * table2_bound.crb_std)


def test_bound_scales_with_noise_std(table2_bound):
    """Four times the variances: exactly twice the bound (F is linear in R^-1)."""
    tau = table2_torque(1, 4000)[0]
    r = fisher_information(TABLE1_SIGMA, tau, position_variance=(4e-8, 4e-7), velocity_variance=(2e-4, 4e-4))
    np.testing.assert_allclose(r.crb_std, 2 * table2_bound.crb_std, rtol=1e-9)


def test_encoder_quantization_is_added_as_uniform_variance():
    var = output_variances(encoder_counts=(614400, 507904))
    delta = 2 * np.pi / np.array([614400, 507904])
    np.testing.assert_allclose(var[:2], np.array([1e-8, 1e-7]) + delta**2 / 12, rtol=1e-12)
    assert np.all(np.isinf(output_variances(measured=("qd",))[:2]))
    with pytest.raises(ParameterError, match="measured"):
        output_variances(measured=("tau",))
    with pytest.raises(ParameterError, match="> 0"):
        output_variances(position_variance=(0.0, 1e-8))


@pytest.fixture(scope="module")
def swap_record():
    tau = table2_torque(1, 2500)[0]
    sa = TABLE1_SIGMA + payload_sigma_delta(3.0)
    q, qd = simulate_trajectory(sa, tau, 1e-3)
    return q, qd, tau, sa


def test_mass_time_matches_finite_difference_information(swap_record):
    """Known arm: the time from the forward sensitivities equals the one from finite differences."""
    q, qd, tau, sa = swap_record
    k0, direction = 500, payload_sigma_delta(1.0)
    t = mass_information_time(q, qd, tau, k0, 1e-3, sa, direction, mass=3.0)
    s = finite_difference_sensitivities(sa, tau[k0:], 1e-3, q[k0], qd[k0], direction=direction)[..., 0]
    info = np.cumsum((s**2 / output_variances()).sum(axis=-1))
    t_fd = np.flatnonzero(1.96 / np.sqrt(np.maximum(info, 1e-300)) <= 0.05 * 3.0)[0] * 1e-3
    assert t is not None and abs(t - t_fd) <= 2e-3
    assert t > 0


def test_mass_time_scales_with_noise_and_others(swap_record):
    q, qd, tau, sa = swap_record
    args = (q, qd, tau, 500, 1e-3, sa, payload_sigma_delta(1.0))
    base = mass_information_time(*args, rel=0.025, mass=3.0)
    # 4x the variances at 5 % needs exactly the information of 1x at 2.5 %
    quad = mass_information_time(*args, (4e-8, 4e-7), (2e-4, 4e-4), rel=0.05, mass=3.0)
    assert base == quad
    assert mass_information_time(*args, rel=0.05, mass=3.0) < base
    unknown = mass_information_time(*args, rel=0.05, mass=3.0, others="unknown")
    assert unknown is not None and unknown > mass_information_time(*args, rel=0.05, mass=3.0)
    assert mass_information_time(*args, rel=1e-7, mass=3.0) is None
    with pytest.raises(ParameterError, match="k_swap"):
        mass_information_time(q, qd, tau, 2499, 1e-3, sa, payload_sigma_delta(1.0), mass=3.0)


def test_unknown_initial_state_costs_information(table2_bound):
    """The Schur complement over the initial state: never more information, here much less on d2."""
    tau = table2_torque(1, 4000)[0]
    unk = fisher_information(TABLE1_SIGMA, tau, initial_state="unknown")
    assert np.all(unk.crb_std >= table2_bound.crb_std * (1 - 1e-9))
    assert unk.crb_std[6] > 1.5 * table2_bound.crb_std[6]
    with pytest.raises(ParameterError, match="initial_state"):
        fisher_information(TABLE1_SIGMA, tau, initial_state="guessed")


def test_a_zero_parameter_keeps_its_bound_and_an_uninformed_one_is_infinite():
    """Coulomb friction of 0 (allowed): its bound is sqrt((F^-1)_ii), the others unchanged by it (it
    was 0 and moved b1's 11x); a record with no motion informs nothing: infinite bounds, not 0 %;
    finite differences step a zero parameter on the others' scale (they divided 0 by 0)."""
    tau = table2_torque(1, 1500)[0]
    sg = TABLE1_SIGMA.copy()
    sg[5:] = 0.0
    r = fisher_information(sg, tau, qd0=(0.01, 0.01))
    np.testing.assert_allclose(r.crb_std, np.sqrt(np.diag(np.linalg.inv(r.information))), rtol=1e-6)
    assert np.all(np.isnan(r.crb_std_pct[5:])) and np.all(np.isfinite(r.crb_std_pct[:5]))
    rest = fisher_information(TABLE1_SIGMA, np.tile([0.5, 0.2], (1000, 1)))  # below breakaway
    assert np.all(np.isinf(rest.crb_std)) and np.all(np.isinf(rest.crb_std_pct))
    one = crb_from_fisher(np.diag([4.0, 1.0, 0, 0, 0, 0, 0]), TABLE1_SIGMA, "sensitivity", 10)
    np.testing.assert_allclose(one.crb_std[:2], [0.5, 1.0])
    assert np.all(np.isinf(one.crb_std[2:]))
    fd = fisher_information(sg, tau, qd0=(0.01, 0.01), method="finite_difference")
    assert np.all(np.isfinite(fd.crb_std))


def test_velocities_alone_with_an_unknown_start_are_bounded():
    """q1 never enters the dynamics: with velocities alone measured the start's block is singular
    (it raised numpy's LinAlgError); the bound is the Schur complement over the seen states."""
    tau = table2_torque(1, 1500)[0]
    unk = fisher_information(TABLE1_SIGMA, tau, measured=("qd",), initial_state="unknown")
    known = fisher_information(TABLE1_SIGMA, tau, measured=("qd",))
    assert np.all(np.isfinite(unk.crb_std)) and np.all(unk.crb_std >= known.crb_std * (1 - 1e-9))
