"""One controller registry for every arm (issue 27): ``make_controller`` builds each built-in name
on the two-link and on an N-joint arm from one table, ``CONTROLLERS``, whose defaults are the
ones the controllers get, and names what does not apply to an arm."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from adaptive_dd.closed_loop import controllers as chain_controllers
from adaptive_dd.closed_loop.adaptation_gain import DEFAULT_PAYLOAD_GAMMA
from adaptive_dd.controllers import CONTROLLERS, controllers_for, gains_for, make_controller
from adaptive_dd.controllers.registry import ABSENT, Setting
from adaptive_dd.controllers.slotine_li import default_bounds
from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.arm import Arm
from adaptive_dd.plant.two_link import ClosedFormTwoLink

TWO, CHAIN = ClosedFormTwoLink.sice(), Arm.sice(general=True)  # general: the N-joint controllers


def test_every_name_builds_on_the_arms_the_table_says():
    from adaptive_dd.closed_loop.arena_laws import ARENA_CONTROLLERS, ARM_LAWS

    assert set(CONTROLLERS) - set(controllers_for(TWO)) == set(ARENA_CONTROLLERS)  # N-joint only
    assert set(controllers_for(CHAIN)) == set(ARM_LAWS)
    assert set(CONTROLLERS) - set(controllers_for(CHAIN)) == {"adaptive_ct_paper"}
    for name, entry in CONTROLLERS.items():
        assert entry.knows and entry.law
        if entry.applies_to("two_link"):
            two = make_controller(name, arm=TWO)
            assert type(two).__module__.startswith("adaptive_dd.controllers.")
            assert two.name == name
        if entry.applies_to("chain"):
            chain = make_controller(name, gains_for(CHAIN, 40.0, 1.0), arm=CHAIN)
            assert isinstance(chain, ARM_LAWS[entry.chain])
            assert chain.name == name


def test_the_table_defaults_are_what_each_arm_gets():
    # N-joint: the class built bare (its own defaults) agrees with the table's
    ac = chain_controllers.AdaptiveCT(CHAIN)
    sl = chain_controllers.SlotineLi(CHAIN)
    chain = {
        "adaptive_ct": {"boost_bandwidth": ac.boost_bandwidth, "boost_duration": ac.boost_duration},
        "slotine_li": {"max_mass": sl.max_mass, "com_radius": sl.com_radius},
    }
    # the N-joint gains are derived from the task (None in the table); bare, the constant
    assert CONTROLLERS["slotine_li"].settings_on("chain")["gamma"] is None
    assert tuple(sl.gamma) == DEFAULT_PAYLOAD_GAMMA
    # two-link: what make_controller built with no settings
    a2, s2 = make_controller("adaptive_ct", arm=TWO), make_controller("slotine_li", arm=TWO)
    two = {
        "adaptive_ct": {"boost_bandwidth": a2.boost_bandwidth, "boost_duration": a2.boost_duration},
        "slotine_li": {"gamma": tuple(s2.gamma)},
    }
    for name, got in chain.items():
        want = CONTROLLERS[name].settings_on("chain")
        assert {k: want[k] for k in got} == got
    for name, got in two.items():
        want = CONTROLLERS[name].settings_on("two_link")
        assert {k: want[k] for k in got} == got
    lo, hi = default_bounds(TWO.sigma, TWO)  # the box the two-link slotine_li had before the table
    np.testing.assert_array_equal(s2.lo, lo)
    np.testing.assert_array_equal(s2.hi, hi)
    assert CONTROLLERS["adaptive_ct"].settings_on("two_link")["boost_duration"] == 0.2
    assert CONTROLLERS["adaptive_ct"].settings_on("chain")["boost_duration"] == 1.0


def test_the_table_is_where_the_defaults_come_from(monkeypatch):
    entry = CONTROLLERS["adaptive_ct"]
    settings = {**entry.settings, "boost_duration": Setting("planted", 0.05, 0.07)}
    monkeypatch.setitem(CONTROLLERS, "adaptive_ct", dataclasses.replace(entry, settings=settings))
    assert make_controller("adaptive_ct", arm=TWO).boost_duration == 0.05
    assert make_controller("adaptive_ct", gains_for(CHAIN), arm=CHAIN).boost_duration == 0.07


def test_two_link_only_names_and_settings_say_so_on_an_n_joint_arm():
    with pytest.raises(ParameterError, match=r"'adaptive_ct_paper' is for the two-link arm only.*paper's"):
        make_controller("adaptive_ct_paper", gains_for(CHAIN), arm=CHAIN)
    with pytest.raises(
        ParameterError, match=r"controllers\.pd\.sigma: not a setting on this 2-joint arm.*\[model\]"
    ):
        make_controller("pd", gains_for(CHAIN), {"sigma": list(TWO.sigma)}, arm=CHAIN)
    assert CONTROLLERS["pd"].settings["sigma"].chain is ABSENT
    with pytest.raises(ParameterError, match=r"controllers\.ct_oracle: unknown setting\(s\) \['gain'\]"):
        make_controller("ct_oracle", gains_for(CHAIN), {"gain": 1}, arm=CHAIN)
    with pytest.raises(ParameterError, match=r"unknown controller 'nope'.*this 2-joint arm"):
        make_controller("nope", arm=CHAIN)


def test_slotine_li_box_settings_on_the_two_link_arm():
    big = make_controller("slotine_li", options={"max_mass": 10.0, "com_radius": 0.2}, arm=TWO)
    _, hi = default_bounds(TWO.sigma, TWO, 10.0, 0.2)
    np.testing.assert_array_equal(big.hi, hi)
    assert not np.array_equal(hi, default_bounds(TWO.sigma, TWO)[1])
    with pytest.raises(ParameterError, match=r"controllers\.slotine_li\.max_mass: a number > 0"):
        make_controller("slotine_li", options={"max_mass": -1.0}, arm=TWO)
    with pytest.raises(ParameterError, match="gamma must be 7 positive gains"):
        make_controller("slotine_li", options={"gamma": [1.0] * 10}, arm=TWO)
    with pytest.raises(ParameterError, match=r"controllers\.slotine_li\.gamma: 10 positive"):
        make_controller("slotine_li", gains_for(CHAIN), {"gamma": [1.0] * 7}, arm=CHAIN)


def test_per_joint_bandwidth_on_an_n_joint_arm():
    c = make_controller("ct_nominal", gains_for(CHAIN, [30.0, 50.0], 1.0), arm=CHAIN)
    np.testing.assert_array_equal(c.gains.bandwidth, [30.0, 50.0])
    c = make_controller("ct_nominal", gains_for(CHAIN, [30.0, 50.0], 1.0), {"bandwidth": 20.0}, arm=CHAIN)
    np.testing.assert_array_equal(c.gains.bandwidth, [20.0, 20.0])
    with pytest.raises(ParameterError, match="bandwidth must be > 0"):
        gains_for(CHAIN, [30.0, -1.0])


def test_the_docs_page_holds_the_registry_table():
    from pathlib import Path

    from adaptive_dd.controllers.registry import inventory

    page = (Path(__file__).resolve().parents[1] / "docs" / "controllers.md").read_text(encoding="utf-8")
    start = page.index("<!-- inventory: generated by adaptive_dd.controllers.registry.inventory() -->")
    end = page.index("<!-- /inventory -->")
    assert page[start:end].split("\n", 1)[1].strip() == inventory().strip(), (
        "docs/controllers.md's controller table is out of step with CONTROLLERS: paste the output of "
        "python -c 'from adaptive_dd.controllers.registry import inventory; print(inventory())'"
    )


def test_validate_says_each_arms_default_from_the_table():
    from importlib import resources

    from adaptive_dd.benchmark.preflight import resolved_settings
    from adaptive_dd.benchmark.scenario import load_scenario

    two = resolved_settings(load_scenario())
    ur5 = load_scenario(str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap_exact.toml")))
    chain = resolved_settings(ur5)
    assert "controllers.slotine_li.max_mass = 5.0 kg   (default)" in two
    assert "controllers.slotine_li.max_mass = 20.0 kg   (default)" in chain
    assert "controllers.adaptive_ct.boost_duration = 0.2 s   (default)" in two
    assert "controllers.adaptive_ct.boost_duration = 1.0 s   (default)" in chain
    assert not any("adaptive_ct_paper" in line for line in two + chain)


def test_the_nominal_inertia_of_the_gains_is_any_arms():
    """Issue 27: ``Gains.nominal_inertia`` was two-link only (the paper's sigma)."""
    from adaptive_dd.controllers import Gains
    from adaptive_dd.robots import ROBOTS, robot_urdf

    ur5 = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    m = Gains().nominal_inertia(arm=ur5)
    assert m.shape == (6,)
    np.testing.assert_allclose(m, np.diagonal(ur5.mass_matrix(np.zeros(6))), rtol=1e-12)
    loaded = ur5.sigma_with_payload(2.0)
    assert np.all(Gains().nominal_inertia(loaded, arm=ur5)[:3] > m[:3])  # a payload adds inertia
    # the paper's arm, as an Arm (general kernels) and by its closed forms: the same numbers
    np.testing.assert_allclose(
        Gains().nominal_inertia(arm=Arm.sice(general=True)), Gains().nominal_inertia(), rtol=1e-12
    )


def test_make_controller_with_the_scenario_is_the_controller_its_benchmark_runs():
    """make_controller("adaptive_ct", arm=sc.arm, scenario=sc), as the library guide's run_trial
    line builds it, skipped the task's room and the model's stated uncertainty: its trial on the
    drawn UR5 was 1.8 times the benchmark's own in the first segment. It is now the same trial,
    to the last digit, with or without the arm given."""
    import warnings

    from adaptive_dd import load_scenario, run_benchmark, run_trial

    sc = load_scenario("ur5_tool_swap")
    sc = dataclasses.replace(
        sc.with_controllers(["ct_oracle", "adaptive_ct"]), seeds=1, duration=1.5, swap_times=(0.5, 1.0),
        swap_masses=sc.swap_masses[:2], swap_com=sc.swap_com[:2], swap_inertia=sc.swap_inertia[:2],
    )  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ran = run_benchmark(sc, progress=False).to_frame()
        ref = ran[ran["controller"] == "adaptive_ct"]["rms_error_rad"].to_numpy()
        for kw in ({"arm": sc.arm}, {}):
            one = run_trial(make_controller("adaptive_ct", scenario=sc, **kw), sc, 0).to_frame()
            np.testing.assert_array_equal(one["rms_error_rad"].to_numpy(), ref)
