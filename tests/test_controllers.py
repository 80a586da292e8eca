"""Controllers: control laws, the online estimators inside adaptive control."""

import dataclasses

import numpy as np
import pytest

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.controllers import (
    ComputedTorque,
    Gains,
    SlotineLi,
    adaptive_ct,
    computed_torque_law,
)
from adaptive_dd.errors import ParameterError
from adaptive_dd.plant import (
    TABLE1_SIGMA,
    inverse_dynamics,
    payload_mass_from_sigma,
    payload_sigma_delta,
    project_sigma,
    validate_sigma,
)

CLEAN = {"position_variance": (0.0, 0.0), "velocity_variance": (0.0, 0.0)}


def short_scenario(**kw):
    base = dict(seeds=1, duration=3.0, swap_times=(1.5,), swap_masses=(3.0,))
    base.update(kw)
    return dataclasses.replace(load_scenario(), **base)


def test_computed_torque_is_inverse_dynamics_on_the_reference(rng):
    q, qd, qdd = rng.normal(size=(3, 20, 2))
    sig = np.broadcast_to(TABLE1_SIGMA, (20, 7))
    tau = computed_torque_law(q, qd, q, qd, qdd, sig, 1600.0, 80.0)
    np.testing.assert_allclose(tau, inverse_dynamics(q, qd, qdd, TABLE1_SIGMA), atol=1e-12)


def test_oracle_tracks_and_nominal_model_suffers_from_the_payload():
    sc = short_scenario(seeds=2)
    res = run_benchmark(
        sc,
        progress=False,
        controllers={"ct_oracle": ComputedTorque(oracle=True), "ct_nominal": ComputedTorque()},
    )
    seg = slice(1600, 3000)
    err = {n: np.sqrt(((res.q_d[seg] - r.q[:, seg]) ** 2).sum(-1).mean()) for n, r in res.runs.items()}
    assert err["ct_oracle"] < 1e-3
    assert err["ct_nominal"] > 10 * err["ct_oracle"]


def test_slotine_li_gains_give_the_computed_torque_poles():
    for zeta in (1.0, 2.0):
        sl = SlotineLi(Gains(40.0, zeta))
        assert sl.lam * sl.kd == pytest.approx(1600.0)
        assert sl.lam + sl.kd == pytest.approx(2 * zeta * 40.0)
    with pytest.raises(ParameterError, match="gamma"):
        SlotineLi(gamma=[1.0, 2.0])


def test_slotine_li_adaptation_reduces_the_error_of_a_wrong_model():
    sc = short_scenario(swap_times=(), swap_masses=(), duration=3.0, **CLEAN)
    wrong = project_sigma(TABLE1_SIGMA + payload_sigma_delta(2.0))  # believes a 2 kg payload
    res = run_benchmark(
        sc,
        progress=False,
        controllers={
            "fixed": SlotineLi(gamma=np.full(7, 1e-12), theta0=wrong),
            "adapt": SlotineLi(theta0=wrong),
        },
    )
    late = slice(2000, 3000)
    err = {n: np.sqrt(((res.q_d[late] - r.q[:, late]) ** 2).sum(-1).mean()) for n, r in res.runs.items()}
    assert err["adapt"] < 0.5 * err["fixed"]
    m = payload_mass_from_sigma(res.runs["adapt"].sigma_hat[0, -1])
    assert m < 1.5  # moved from the wrong 2 kg towards 0


def test_reference_velocity_ct_with_the_true_model_is_slotine_li_without_adaptation(rng):
    """With lam, the CT law's velocity terms are Y(q, qd, qd_r, .) sigma: Slotine-Li's law."""
    from adaptive_dd.plant.dynamics import regressor_reference

    q, qd, q_d, qd_d, qdd_d = rng.normal(size=(5, 30, 2))
    lam, kp, kd = 40.0, 1600.0, 80.0
    tau = computed_torque_law(q, qd, q_d, qd_d, qdd_d, np.broadcast_to(TABLE1_SIGMA, (30, 7)), kp, kd, lam)
    e, ed = q_d - q, qd_d - qd
    y = regressor_reference(q, qd, qd_d + lam * e, qdd_d + lam * ed)
    # Y sigma holds M qdd_r = M (qdd_d + lam e_dot); CT has M (qdd_d + kd e_dot + kp e)
    from adaptive_dd.plant import mass_matrix

    extra = np.einsum("nij,nj->ni", mass_matrix(q, TABLE1_SIGMA), (kd - lam) * ed + kp * e)
    np.testing.assert_allclose(tau, y @ TABLE1_SIGMA + extra, atol=1e-10)


def test_floors_the_reference_velocity_law_tracks_better_than_the_textbook_law():
    sc = short_scenario(seeds=1, duration=3.0, swap_times=(), swap_masses=(), **CLEAN)
    res = run_benchmark(
        sc,
        progress=False,
        controllers={
            "ref": ComputedTorque(oracle=True),
            "textbook": ComputedTorque(oracle=True, reference_velocity=False),
            "sl": SlotineLi(oracle=True),
        },
    )
    late = slice(1000, 3000)
    err = {n: np.sqrt(((res.q_d[late] - r.q[:, late]) ** 2).sum(-1).mean()) for n, r in res.runs.items()}
    assert err["ref"] < 0.5 * err["textbook"]
    assert err["ref"] == pytest.approx(err["sl"], rel=0.2)  # same law up to K_D


def test_adaptive_ct_learns_a_swap_and_boosts_only_after_an_alarm():
    sc = short_scenario(seeds=2, duration=4.0, swap_times=(2.0,), swap_masses=(3.0,))
    ctrl = adaptive_ct()
    res = run_benchmark(sc, progress=False, controllers={"a": ctrl, "o": ComputedTorque(oracle=True)})
    run = res.runs["a"]
    for times in run.alarm_times:
        assert len(times) == 1 and 2.0 < times[0] < 2.1
    np.testing.assert_allclose(payload_mass_from_sigma(run.sigma_hat[:, -1]), 3.0, rtol=0.05)
    assert run.floor == "ct_oracle"
    seg = slice(2000, 4000)
    err = {n: np.sqrt(((res.q_d[seg] - r.q[:, seg]) ** 2).sum(-1).mean()) for n, r in res.runs.items()}
    assert err["a"] < 1.5 * err["o"]
    # the boost term is zero unless an alarm is recent
    q = np.zeros((2, 2))
    ctrl.reset(2, 1e-3)
    assert np.all(ctrl.estimator.state.since_alarm * 1e-3 > ctrl.boost_duration)
    t0 = ctrl.command(q, q, q + 0.01, q, q)
    ctrl.estimator.state.cnt[:, 7] = 0  # pretend an alarm just happened
    t1 = ctrl.command(q, q, q + 0.01, q, q)
    assert np.all(np.abs(t1) > np.abs(t0))


def test_projection_gives_positive_definite_models(rng):
    bad = rng.normal(size=(200, 7))
    p = project_sigma(bad)
    assert np.all(p[:, :2] > 0) and np.all(p[:, 3:] >= 0) and np.all(p[:, 2] >= 0)
    assert np.all(p[:, 0] * p[:, 1] - p[:, 2] ** 2 > 0)
    validate_sigma(p)  # a projected model is always accepted
    np.testing.assert_array_equal(project_sigma(p), p)
    np.testing.assert_array_equal(project_sigma(TABLE1_SIGMA), TABLE1_SIGMA)


def test_payload_mass_inverts_the_payload_delta():
    for m in (0.0, 1.0, 3.0):
        np.testing.assert_allclose(payload_mass_from_sigma(TABLE1_SIGMA + payload_sigma_delta(m, 0.07)), m)


def test_bad_gains_and_detector():
    with pytest.raises(ParameterError, match="bandwidth"):
        Gains(bandwidth=0.0)
    with pytest.raises(ParameterError, match="damping"):
        Gains(damping=-1.0)
    with pytest.raises(ParameterError, match="boost_bandwidth"):
        adaptive_ct(boost_bandwidth=-1.0)


def test_each_builtin_owns_its_compiled_form_and_a_subclass_runs_in_python():
    from adaptive_dd.controllers import CONTROLLERS, make_controller
    from adaptive_dd.controllers.compiled_form import LAW_ADAPTIVE, LAW_PD, compiled_spec

    on_two_link = [n for n, e in CONTROLLERS.items() if e.applies_to("two_link")]
    specs = {n: compiled_spec(make_controller(n), 0.001) for n in on_two_link}
    assert specs["pd"].law == LAW_PD and specs["adaptive_ct"].law == LAW_ADAPTIVE
    assert len({s.law for s in specs.values()}) == 6  # ct_oracle(_textbook), adaptive_ct(_paper) share
    pd = make_controller("pd")
    np.testing.assert_array_equal(compiled_spec(pd, 0.001).gains.pd_kd, pd.kd)

    class Mine(type(pd)):
        pass

    assert compiled_spec(Mine(), 0.001) is None  # its Python form may differ: the Python path
    ac = compiled_spec(make_controller("adaptive_ct", options={"boost_duration": 0.1}), 0.002)
    assert ac.gains.boost_samples == pytest.approx(50.0) and ac.online.sample_period == 0.002
    assert ac.gains.lam == pytest.approx(make_controller("adaptive_ct").gains.lam)
