"""One arm type (issue 27, item 1): :class:`Arm` is what a user builds and passes; the paper's closed
forms (eqs. 3-9) are its fast path, chosen by :func:`closed_form_view` and held here to the general
kernels on ``Arm.sice()``: the mass matrix, the torque, and a closed-loop trial; the paper's sigma is
:func:`paper_sigma`, a map of the arm's base parameters; the old name warns."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.errors import ParameterError
from adaptive_dd.plant import ArmSimulator, PayloadSchedule
from adaptive_dd.plant.arm import Arm
from adaptive_dd.plant.dynamics import regressor as paper_regressor
from adaptive_dd.plant.kind import is_chain, is_two_link
from adaptive_dd.plant.two_link import ClosedFormTwoLink, closed_form_view
from adaptive_dd.plant.two_link_view import paper_sigma
from adaptive_dd.robots import ROBOTS, robot_urdf

MASSES = np.array([0.0, 1.5, 4.0])


@pytest.fixture(scope="module")
def sice():
    arm = Arm.sice()
    return arm, closed_form_view(arm)


def _states(rng, m=8):
    # |qd| > 0.05: the sign of the velocity (Coulomb friction) is the same in both forms
    qd = rng.normal(size=(m, 2))
    qd = np.where(np.abs(qd) < 0.05, 0.5, qd)
    return rng.uniform(-3.0, 3.0, (m, 2)), qd, 3.0 * rng.normal(size=(m, 2))


def test_the_paper_arm_has_its_closed_forms_and_other_arms_none(sice):
    arm, view = sice
    assert is_two_link(arm) and is_two_link(view) and view.n_joints == 2  # asks the view, not the class
    np.testing.assert_allclose(view.sigma, ClosedFormTwoLink.sice().sigma, rtol=1e-14, atol=0)
    assert (
        view.actuator == ClosedFormTwoLink.sice().actuator and view.sensor == ClosedFormTwoLink.sice().sensor
    )
    assert closed_form_view(arm) is view  # cached: one geometry test per arm
    assert closed_form_view(view) is view
    assert closed_form_view(Arm.sice(general=True)) is None
    assert closed_form_view(Arm.from_urdf(robot_urdf("vertical3"), ROBOTS["vertical3"].payload_frame)) is None
    assert closed_form_view(None) is None and closed_form_view(np.zeros(7)) is None


def test_paper_sigma_is_a_map_of_the_arms_base_parameters(sice):
    arm, view = sice
    np.testing.assert_allclose(paper_sigma(arm), ClosedFormTwoLink.sice().sigma, rtol=1e-12, atol=1e-15)
    loaded = paper_sigma(arm, arm.sigma_with_payload(MASSES))  # (3, p) -> (3, 7)
    np.testing.assert_allclose(loaded, view.sigma_with_payload(MASSES), rtol=1e-12, atol=1e-15)
    # the map is exact: the closed-form regressor on the mapped sigma is the general torque
    rng = np.random.default_rng(5)
    q, qd, qdd = _states(rng)
    s = arm.sigma * rng.uniform(0.5, 2.0, arm.sigma.shape)  # any parameters of this geometry
    s[list(arm.sigma_names).index("my2")] = s[list(arm.sigma_names).index("Ia2")] = 0.0
    np.testing.assert_allclose(
        paper_regressor(q, qd, qdd) @ paper_sigma(arm, s), arm.regressor(q, qd, qdd) @ s, atol=1e-11
    )
    for name in ("my2", "Ia2"):  # no term in the closed forms: they map to nothing
        unit = np.eye(len(arm.sigma))[list(arm.sigma_names).index(name)]
        np.testing.assert_array_equal(paper_sigma(arm, unit), np.zeros(7))
    np.testing.assert_array_equal(paper_sigma(view), view.sigma)
    with pytest.raises(ParameterError, match=r"paper_sigma: .*3-joint arm"):
        paper_sigma(Arm.from_urdf(robot_urdf("vertical3"), ROBOTS["vertical3"].payload_frame))
    with pytest.raises(ParameterError, match=r"shape \(\.\.\., 9\)"):
        paper_sigma(arm, np.zeros(7))


def test_the_closed_form_mass_matrix_is_the_general_one(sice):
    arm, view = sice
    q = np.random.default_rng(1).uniform(-3.0, 3.0, (6, 1, 2))
    general = arm.mass_matrix(q, arm.sigma_with_payload(MASSES))
    closed = view.mass_matrix(q, view.sigma_with_payload(MASSES))
    assert closed.shape == general.shape == (6, 3, 2, 2)
    np.testing.assert_allclose(closed, general, rtol=1e-12, atol=1e-14)


def test_the_closed_form_torque_is_the_general_one(sice):
    arm, view = sice
    q, qd, qdd = _states(np.random.default_rng(2))
    for m in MASSES:
        closed = view.regressor(q, qd, qdd) @ view.sigma_with_payload(m)
        general = arm.inverse_dynamics(q, qd, qdd, arm.sigma_with_payload(m))
        np.testing.assert_allclose(closed, general, rtol=1e-12, atol=1e-12)


def test_a_scenario_of_the_arm_runs_the_closed_forms_and_equals_the_general_kernels():
    """A trial with a payload swap on ``Arm.sice()``: the scenario takes the closed forms by itself,
    and its closed loop (plant, computed torque, sensors, D/A) is the general kernels' to round-off."""
    base = load_scenario("adaptive_dd/scenarios/payload_swap.toml")
    base = dataclasses.replace(
        base, duration=0.6, seeds=1, controllers=("pd", "ct_oracle"), swap_times=(0.3,), swap_masses=(3.0,)
    )
    fast = dataclasses.replace(base, arm=Arm.sice())
    general = dataclasses.replace(base, arm=Arm.sice(general=True))
    assert fast.closed_forms is closed_form_view(fast.arm) and general.closed_forms is None
    assert is_two_link(fast.arm) and is_chain(general.arm)
    rf, rg = run_benchmark(fast), run_benchmark(general)
    assert list(rf.runs) == list(rg.runs)
    for name in rf.runs:
        a, b = rf.runs[name], rg.runs[name]
        assert not a.failed.any() and not b.failed.any()
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-10, err_msg=name)
        np.testing.assert_allclose(a.qd, b.qd, rtol=0, atol=1e-8, err_msg=name)
        np.testing.assert_allclose(a.tau, b.tau, rtol=0, atol=1e-9, err_msg=name)
        np.testing.assert_allclose(a.e_norm, b.e_norm, rtol=1e-8, atol=1e-12, err_msg=name)


def test_the_simulator_takes_an_arm_of_the_paper_geometry(sice):
    arm, view = sice
    rng = [np.random.default_rng(0)]
    sched = PayloadSchedule(times=(0.005,), masses=(2.0,))
    a = ArmSimulator(1, 10, rng, arm=arm, payload=sched)
    assert a.arm is view
    with pytest.raises(ParameterError, match=r"ArmSimulator\(arm=\.\.\.\): needs an arm of the paper's"):
        ArmSimulator(1, 10, rng, arm=Arm.sice(general=True))


def test_the_old_name_warns_and_is_the_closed_form_record():
    import adaptive_dd.plant as plant
    import adaptive_dd.plant.two_link as two_link

    for module in (plant, two_link):
        with pytest.warns(FutureWarning, match=r"TwoLinkArm is deprecated: the one arm type is .*Arm"):
            assert module.TwoLinkArm is ClosedFormTwoLink
    with pytest.warns(FutureWarning, match=r"use Arm\.from_urdf"):
        old = ClosedFormTwoLink.from_urdf(robot_urdf("sice_arm"), "tip")
    np.testing.assert_array_equal(old.sigma, closed_form_view(Arm.sice()).sigma)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        from adaptive_dd.plant import Arm as _  # noqa: F401  the one arm type: no warning


def test_the_registry_gives_an_arm_of_the_paper_geometry_its_closed_forms(sice):
    from adaptive_dd.controllers import make_controller
    from adaptive_dd.controllers.registry import controllers_for, gains_for

    arm, view = sice
    general = Arm.sice(general=True)
    assert "adaptive_ct_paper" in controllers_for(arm) and "adaptive_ct_paper" not in controllers_for(general)
    assert type(gains_for(arm)) is type(gains_for(view)) is not type(gains_for(general))
    fast = make_controller("slotine_li", gains_for(arm), arm=arm)
    assert type(fast) is type(make_controller("slotine_li", gains_for(view), arm=view))
    assert type(fast).__module__.startswith("adaptive_dd.controllers.")
    slow = make_controller("slotine_li", gains_for(general), arm=general)
    assert type(slow).__module__.startswith("adaptive_dd.closed_loop.")


def test_simulation_takes_the_arm(sice):
    from adaptive_dd.simulation import Simulation

    base = load_scenario("adaptive_dd/scenarios/payload_swap.toml")
    sim = Simulation(dataclasses.replace(base, arm=sice[0], controllers=("ct_oracle",)))
    assert sim.arm is sice[0] and sim.scenario.closed_forms is sice[1]  # the arm, run on its closed forms
    sim.reset()


@pytest.mark.parametrize(
    "record",
    [
        ClosedFormTwoLink.sice(),
        ClosedFormTwoLink.sice(friction="tanh", payload_radius=0.03),
        ClosedFormTwoLink.from_sigma([0.5, 0.09, 0.12, 3.0, 1.0, 2.0, 0.5], l1=0.3, l2=0.25),
    ],
    ids=["sice", "tanh", "sigma-only"],
)
def test_a_closed_form_record_is_the_fast_path_of_its_arm(record, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    arm = record.to_arm()
    written = str(arm.urdf).startswith(str(tmp_path))  # the paper's Table 1 arm: the shipped URDF
    assert arm.n_joints == 2 and arm.payload_frame == "tip" and written == (record.physical is None)
    view = closed_form_view(arm)
    assert view == record  # exactly the record (held on the arm): a scenario given one runs its numbers
    np.testing.assert_array_equal(view.sigma, record.sigma)
    fresh = dataclasses.replace(arm, general=False)  # read back from its URDF: to round-off
    np.testing.assert_allclose(closed_form_view(fresh).sigma, record.sigma, rtol=1e-12, atol=1e-15)
    assert (view.l1, view.l2) == pytest.approx((record.l1, record.l2), rel=1e-15)
    assert (view.actuator, view.sensor, view.friction) == (record.actuator, record.sensor, record.friction)
    assert view.payload_radius == record.payload_radius
    np.testing.assert_allclose(paper_sigma(arm), record.sigma, rtol=1e-12, atol=1e-15)
    assert record.to_arm() == arm  # the same text, the same file
    lugre = dataclasses.replace(record, friction="lugre", lugre_stiffness=(2e4, 3e4)).to_arm()
    assert lugre.friction == "lugre" and closed_form_view(lugre).lugre_stiffness == (2e4, 3e4)


def test_a_record_read_from_an_arm_gives_that_arm_back(sice, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    arm, view = sice
    assert view.to_arm() is arm
    sc = load_scenario("benchmarks/scenarios/sice_urdf.toml")
    assert sc.arm.urdf == robot_urdf("sice_arm") and sc.closed_forms is closed_form_view(sc.arm)
    assert sc.closed_forms.to_arm() is sc.arm
    other = dataclasses.replace(view, friction="tanh")  # no longer that arm's closed forms
    assert other.to_arm() != arm and other.to_arm().friction == "tanh"
    assert str(other.to_arm().urdf).startswith(str(tmp_path))


def test_the_closed_form_slotine_li_regressor_is_the_general_one(sice):
    """``Y_r(q, qd, qd_r, qdd_r) sigma = M qdd_r + C(q, qd) qd_r + B qd_r + D sgn(qd_r)`` with the
    general mass matrix and Christoffel C of the chain: the factorisation the Slotine-Li argument
    (``dM/dt - 2C`` skew) needs, on both paths."""
    from adaptive_dd.plant.chain import coriolis_matrix_batch
    from adaptive_dd.plant.dynamics import regressor_reference

    arm, view = sice
    rng = np.random.default_rng(3)
    q, qd, qdd_r = _states(rng)
    _, qd_r, _ = _states(rng)
    closed = np.einsum("...ij,j->...i", regressor_reference(q, qd, qd_r, qdd_r), view.sigma)
    m = arm.mass_matrix(q)
    c = coriolis_matrix_batch(arm.chain, arm.pi_links, q, qd)
    general = (
        np.einsum("...ij,...j->...i", m, qdd_r)
        + np.einsum("...ij,...j->...i", c, qd_r)
        + arm.viscous * qd_r
        + arm.coulomb * np.sign(qd_r)
    )
    np.testing.assert_allclose(closed, general, rtol=1e-12, atol=1e-12)


def test_an_unwritable_cache_does_not_stop_a_scenario_of_the_paper_numbers(tmp_path, monkeypatch):
    """A scenario's [arm] of the paper's numbers becomes an Arm whose URDF goes to the user's cache;
    a cache that cannot be written (here a file where the folder would be) falls back to the
    temporary folder, so that the scenario still loads, with the same closed forms."""
    blocker = tmp_path / "cache"
    blocker.write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    record = ClosedFormTwoLink.from_sigma([0.5, 0.09, 0.12, 3.0, 1.0, 2.0, 0.5], l1=0.3, l2=0.25)
    arm = record.to_arm()
    assert str(arm.urdf).startswith(str(tmp_path / "tmp")) and closed_form_view(arm) == record
