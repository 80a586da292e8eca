"""The gradient laws' adaptation gains derived from the arm and the task
(:mod:`adaptive_dd.closed_loop.adaptation_gain`)."""

from __future__ import annotations

import dataclasses
from importlib import resources

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.benchmark.scenario_settings import with_settings
from adaptive_dd.closed_loop import adaptation_gain as ag
from adaptive_dd.controllers.registry import scenario_controller
from adaptive_dd.errors import ScenarioError


@pytest.fixture(scope="module")
def ur5():
    return load_scenario(str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap_exact.toml")))


def test_each_parameter_adapts_at_one_rate_and_the_fastest_mode_at_the_stated_rate(ur5):
    law = scenario_controller(ur5, "slotine_li")[1]
    lam, k = law.gains.roots()
    R = ag.payload_sensitivity(ur5.arm, ur5, k)
    g = ag.payload_gains(ur5.arm, ur5, k, lam)
    assert np.allclose(law.gamma, g)
    assert np.allclose(g * np.diag(R), (g * np.diag(R))[0])  # Gamma_ii R_ii: one rate
    fastest = np.linalg.eigvals(g[:, None] * R).real.max()  # the modes of theta~' = -Gamma R theta~
    assert fastest == pytest.approx(ag.RATE_OF_BANDWIDTH * lam.min(), rel=1e-9)
    # R is the regressor's weight through (kd M0)^-1: a sample of it by hand at one instant
    q, qd, qdd = (np.asarray(x).reshape(1, -1) for x in ur5.reference.sample(np.array([1.0])))
    j = ur5.arm.payload_joint
    Yp = ur5.arm.standard_regressor(q, qd, qdd)[0][:, 10 * j : 10 * j + 10] @ ur5.arm.payload_map
    M0 = ur5.arm.mass_matrix(q)[0]
    one = Yp.T @ np.linalg.solve(np.diag(k) @ M0, Yp)
    assert np.all(np.linalg.eigvalsh(0.5 * (one + one.T)) > -1e-9)


def test_a_heavier_arm_gets_larger_gains_at_the_same_rate_and_a_given_gamma_is_kept(ur5):
    """One constant adapted a light arm's payload far faster than a heavy one's (the rate is
    ``Gamma R``, ``R`` falls with the inertia): the derived gains grow with the arm's inertia and its
    fastest mode stays at the stated rate."""
    law = scenario_controller(ur5, "slotine_li")[1]
    light = law.gamma
    heavy_arm = ur5.arm.with_(armature=2.0 * np.asarray(ur5.arm.armature) + 1.0)
    heavy_sc = dataclasses.replace(ur5, arm=heavy_arm)
    heavy = scenario_controller(heavy_sc, "slotine_li")[1].gamma
    assert np.all(heavy > light)
    lam, k = law.gains.roots()
    for sc, g in ((ur5, light), (heavy_sc, heavy)):
        R = ag.payload_sensitivity(sc.arm, sc, k)
        assert np.linalg.eigvals(g[:, None] * R).real.max() == pytest.approx(ag.RATE_OF_BANDWIDTH * lam.min())
    given = [1.0] * 10
    assert np.array_equal(
        scenario_controller(with_settings(ur5, "slotine_li", {"gamma": given}), "slotine_li")[1].gamma, given
    )
    with pytest.raises(ScenarioError, match=r"slotine_li\.gamma: 10 positive"):
        with_settings(ur5, "slotine_li", {"gamma": [1.0] * 9})


def test_craig_hsu_sastry_keeps_the_constant_and_a_law_without_a_task_too(ur5):
    from adaptive_dd.controllers import make_controller

    assert np.array_equal(scenario_controller(ur5, "craig_hsu_sastry")[1].gamma, ag.DEFAULT_PAYLOAD_GAMMA)
    assert np.array_equal(make_controller("slotine_li", arm=ur5.arm).gamma, ag.DEFAULT_PAYLOAD_GAMMA)
    natural = scenario_controller(ur5, "natural_adaptive")[1]
    assert natural.gain == pytest.approx(natural._gain(scenario_controller(ur5, "slotine_li")[1].gamma[0]))


def test_the_derived_gains_learn_the_payload_faster_than_the_constant(ur5):
    """The UR5 (exact), 2 seeds, its 2 kg tool from 4 s to 7 s: slotine_li's error over its floor in
    the loaded segment with the derived gains is under half the constant's (6.9 against 21.6 over
    the whole 6 s segment, `python benchmarks/adaptation_gains.py`)."""
    from adaptive_dd.benchmark.runner import run_benchmark

    one = {
        k: getattr(ur5, k)[:1]
        for k in ("swap_times", "swap_masses", "swap_com", "swap_inertia")
        if getattr(ur5, k)
    }
    sc = dataclasses.replace(
        ur5,
        duration=7.0,
        seeds=2,
        controllers=("slotine_li_oracle", "slotine_li"),
        controller_options=(),
        **one,
    )
    loaded = {}
    for kind, s in (
        ("constant", with_settings(sc, "slotine_li", {"gamma": list(ag.DEFAULT_PAYLOAD_GAMMA)})),
        ("derived", sc),
    ):
        f = run_benchmark(s, progress=False).to_frame()
        loaded[kind] = f[(f.controller == "slotine_li") & (f.segment == 1)]["ratio_to_floor"].to_numpy()
    assert np.all(loaded["derived"] < 0.5 * loaded["constant"]), loaded


def test_validate_prints_the_derived_gains(ur5):
    from adaptive_dd.benchmark.preflight import resolved_settings

    lines = resolved_settings(ur5)
    said = [x for x in lines if x.startswith("controllers.slotine_li.gamma = [")]
    assert len(said) == 1 and "derived" in said[0], lines
    gains = scenario_controller(ur5, "slotine_li")[1].gamma
    assert f"{gains[0]:.4g}" in said[0]
