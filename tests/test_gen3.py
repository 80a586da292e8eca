"""A user's own arm, nobody tuned for it (issue 28): the Kinova Gen3 (7 joints, four of them
continuous) written from Kinova's published URDF, and its payload-swap scenarios in
``benchmarks/scenarios/gen3_drawn.toml`` / ``gen3_exact.toml``, written from the docs alone (no
``[controllers]`` table).

The arm loads through the scenario as a user's URDF does (``[arm] urdf`` relative to the file),
its models and compiled kernels match Pinocchio's, its reference stays within the data sheet's
limits with the heaviest payload, and a short two-seed run of the drawn scenario finds the
pick-up in every trial with no false alarm.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.preflight import reference_problems, torque_problems
from adaptive_dd.benchmark.scenario import load_scenario, parse_scenario
from adaptive_dd.benchmark.scenario_settings import with_settings
from adaptive_dd.identification.online import OnlineConfig
from adaptive_dd.identification.row_weights import task_row_weights
from adaptive_dd.plant.pinocchio_check import cross_check
from adaptive_dd.robots import robot_urdf

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "benchmarks" / "scenarios"


@pytest.fixture(scope="module")
def drawn():
    return load_scenario(SCENARIOS / "gen3_drawn.toml")


def test_the_scenarios_read_the_shipped_urdf_and_state_no_estimator_settings(drawn):
    exact = load_scenario(SCENARIOS / "gen3_exact.toml")
    for sc, path in ((drawn, "gen3_drawn.toml"), (exact, "gen3_exact.toml")):
        assert Path(sc.arm.urdf).resolve() == robot_urdf("gen3")
        assert sc.arm.n_joints == 7 and sc.arm.payload_capacity == 4.0
        assert np.array_equal(sc.arm.armature, [0.2] * 4 + [0.05] * 3)
        assert "controllers" not in tomllib.loads((SCENARIOS / path).read_text())
    assert np.isinf(drawn.arm.position_limits[[0, 2, 4, 6]]).all()  # the continuous joints
    # the two files differ only by the drawn plant
    assert exact.reference == drawn.reference and exact.swap_times == drawn.swap_times


@pytest.mark.parametrize("payload", [None, {"mass": 2.0, "com": [0.02, 0.0, 0.06]}])
def test_the_arm_passes_the_pinocchio_cross_check(drawn, payload):
    results = cross_check(drawn.arm, payload, n_states=8, rng=np.random.default_rng(28))
    assert results and all(r.passed for r in results), [str(r) for r in results if not r.passed]


def test_the_reference_is_within_the_limits_with_every_payload(drawn):
    assert reference_problems(drawn) == []
    assert torque_problems(drawn) == []
    q, qd, _ = drawn.reference.sample(np.arange(drawn.n_samples) * drawn.sample_period)
    assert np.all(np.abs(qd).max(axis=0) < 0.75 * drawn.arm.velocity_limits)
    assert np.all(np.ptp(q, axis=0) > 0.5)  # every joint is excited


def test_a_short_two_seed_run_finds_the_pick_up_with_no_false_alarm():
    """The drawn scenario cut to 5.5 s, the 2 kg pick-up at 3.5 s; ct_oracle and adaptive_ct,
    seeds 0 and 1: no trial fails, each finds the swap within the benchmark's window and has no
    other alarm, and adaptive_ct in the loaded segment is within 2x its floor."""
    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.closed_loop.types import run_constants

    data = tomllib.loads((SCENARIOS / "gen3_drawn.toml").read_text())
    data["run"] = {**data["run"], "duration": 5.5, "seeds": 2, "controllers": ["ct_oracle", "adaptive_ct"]}
    data["payload"] = [{**data["payload"][0], "at": 3.5}]
    sc = parse_scenario(data, str(SCENARIOS / "gen3_drawn.toml"), name="gen3_short")
    res = run_closed_loop(sc, seed_indices=(0, 1), keep_trajectories=0)
    ac, oracle = res.runs["adaptive_ct"], res.runs["ct_oracle"]
    assert not np.any(ac.failed) and not np.any(oracle.failed)
    for times in ac.alarm_times:
        found = [t for t in times if 0 <= t - 3.5 < FALSE_ALARM_WINDOW]
        assert found and len(found) == len(times), times
    rc = run_constants(sc)
    n = (rc.seg_end - rc.seg_start).astype(float)
    ratio = np.sqrt(ac.acc.sum_e2 / n) / np.sqrt(oracle.acc.sum_e2 / n)
    assert np.all(ratio[:, 1] < 2.0), ratio


def test_validate_says_what_the_estimator_derives_and_from_what(drawn):
    """A scenario with no estimator table: ``validate`` prints the settings the run derives for
    adaptive_ct (mode, row weights, re-opened payload mass, the detector's floor) with the rule each
    comes from, and says when the rated payload is missing."""
    from adaptive_dd.benchmark.preflight import derived_estimator_settings, resolved_settings

    lines = derived_estimator_settings(drawn)
    printed = resolved_settings(drawn)
    keys = (".estimator.", ".detector.", "arm.payload_offset")
    assert lines == [line for line in printed if any(k in line for k in keys)]
    assert (
        "estimator.mode = 'arm'   (derived: the [plant.uncertainty] levels, [model] uncertainty not"
        in lines[0]
    )
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml

    data = read_toml(SCENARIOS / "gen3_drawn.toml")
    data["model"] = {"uncertainty": {"mass": 0.05}}  # stated: said as such, not as the plant's draw
    data["arm"] = {**{k: v for k, v in data["arm"].items() if k != "urdf"}, "robot": "gen3"}
    stated = derived_estimator_settings(parse_scenario(data, "g.toml"))
    assert "(derived: the model's stated uncertainty ([model] uncertainty))" in stated[0]
    w = task_row_weights(drawn.arm, OnlineConfig(sample_period=drawn.sample_period), drawn)  # noise's scale
    assert f"row_weights = {[float(f'{x:.4g}') for x in w]}   (derived: each equation's RMS error" in lines[1]
    assert "carrying 4 kg x sqrt(tau_f / T)" in lines[1]
    assert "reopen_mass_std = 2.4 kg   (derived: 0.6 x arm.payload_capacity 4 kg)" in lines[2]
    noise = w.max() / np.sqrt(OnlineConfig().tau_f / drawn.sample_period)  # the heaviest row's [N m]
    assert lines[3] == (
        f"controllers.adaptive_ct.detector.floor = {min(0.05, noise / 4):.3g} N m   (derived: the heaviest "
        "row's noise in the first pass over the threshold 4, at most 0.05 N m)"
    )
    assert lines[4].startswith("arm.payload_offset = 0.1 m, arm.payload_radius = 0.05 m   (the estimator's")
    assert "the offset the default: state how far" in lines[4]
    exact = derived_estimator_settings(load_scenario(SCENARIOS / "gen3_exact.toml"))
    assert "estimator.mode = 'payload'   (default: no [model] uncertainty or [plant.uncertainty]" in exact[0]
    data = tomllib.loads((SCENARIOS / "gen3_drawn.toml").read_text())
    del data["arm"]["payload_capacity"]
    data["arm"]["urdf"] = str(robot_urdf("gen3"))
    given = with_settings(
        parse_scenario(data, "x.toml"), "adaptive_ct", {"detector": {"reopen_mass_std": 1.5}}
    )
    assert "reopen_mass_std = 1.5 kg   (given)" in derived_estimator_settings(given)[2]
    unstated = derived_estimator_settings(parse_scenario(data, "x.toml"))
    assert "reopen_mass_std = 10 kg   (default: no [arm] payload_capacity stated" in unstated[2]


def test_excitation_limits_of_continuous_joints_raise_no_warning(drawn):
    """``adaptive-dd excite`` on the Gen3 printed numpy's "invalid value encountered in reduce" (the
    mean of a continuous joint's [-inf, inf]); its joints are centred on 0 within +-pi, quietly."""
    import warnings

    from adaptive_dd.identification.excitation import ExcitationLimits

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lim = ExcitationLimits.of_arm(drawn.arm, margin=0.1)
    np.testing.assert_allclose(lim.lower[[0, 2, 4, 6]], -np.pi)
    np.testing.assert_allclose(lim.upper[[0, 2, 4, 6]], np.pi)
    np.testing.assert_allclose(lim.upper[[1, 3, 5]], [2.31, 2.56, 2.13])


def test_excite_lengthens_a_ramp_that_would_leave_the_velocity_limits(drawn):
    """``adaptive-dd excite`` wrote its design with a 0.5 s ramp, and the ramp into it took the
    Gen3's joint 7 to 4.9 times its velocity limit (the design keeps to the limits only once under
    way). The ramp is now doubled until the whole reference keeps to them."""
    import dataclasses

    from adaptive_dd.benchmark.scenario import Reference
    from adaptive_dd.cli.excite import ramp_within_limits

    n = drawn.arm.n_joints
    ref = Reference(
        offset=(0.0,) * n,
        amplitude=((1.0, 0.3),) * n,  # starts 1.0 rad from the offset: a 0.5 s ramp is fast
        frequency=((0.1, 0.2),) * n,
        phase=((np.pi / 2, 0.0),) * n,
        ramp=0.5,
    )
    vmax = drawn.arm.velocity_limits

    def peak(r):
        _, qd, _ = dataclasses.replace(ref, ramp=r).sample(np.arange(0.0, r + 10.0, 1e-3))
        return np.abs(qd).max(axis=0) / vmax

    assert peak(0.5).max() > 1.0  # the case: beyond the limit during the ramp
    ramp = ramp_within_limits(ref, drawn.arm, 10.0)
    assert ramp > 0.5 and peak(ramp).max() <= 1.0
    assert peak(ramp / 2).max() > 1.0  # the shortest doubling that keeps to the limits
    slow = dataclasses.replace(ref, amplitude=((0.05, 0.0),) * n)
    assert ramp_within_limits(slow, drawn.arm, 10.0) == 0.5  # within already: kept


def test_validate_shows_a_handed_on_covariance_by_its_shape():
    """``[model] from = "model.json"`` hands adaptive_ct a 65 x 65 prior covariance on the Gen3;
    ``validate`` printed it whole, 80 000 characters on one line. It prints its shape."""
    import dataclasses

    from adaptive_dd.benchmark.scenario import format_scenario
    from adaptive_dd.benchmark.scenario_checks import freeze
    from adaptive_dd.benchmark.scenario_format import _brief

    cov = np.eye(65).tolist()
    shown = repr(_brief({"estimator": {"arm_prior_cov": cov, "row_weights": [1.0, 0.5], "x": 3}}))
    assert shown == "{'estimator': {'arm_prior_cov': <65 x 65 matrix>, 'row_weights': [1.0, 0.5], 'x': 3}}"
    assert repr(_brief(list(range(20)))) == "<20 numbers>"
    sc = load_scenario(SCENARIOS / "gen3_exact.toml")
    opts = (("adaptive_ct", freeze({"estimator": {"arm_prior_cov": cov}})),)
    text = format_scenario(dataclasses.replace(sc, controller_options=opts))
    line = next(x for x in text.splitlines() if x.startswith("controllers.adaptive_ct"))
    assert line == "controllers.adaptive_ct = {'estimator': {'arm_prior_cov': <65 x 65 matrix>}}"
