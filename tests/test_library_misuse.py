"""What a library user's plausible slips get: a clear refusal, not a silently different run."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from adaptive_dd import load_scenario, run_benchmark
from adaptive_dd.benchmark.metrics import compute_metrics
from adaptive_dd.benchmark.report import format_report
from adaptive_dd.errors import ParameterError, ScenarioError


def _short():
    sc = load_scenario()
    return dataclasses.replace(sc.with_controllers(["ct_oracle", "pd"]), duration=2.0, swap_times=(1.0,),
                               swap_masses=(3.0,), seeds=5)  # fmt: skip


@pytest.mark.parametrize(
    ("given", "said"), [([1.5], "[1.5] among them"), ([0, 0], "[0] twice"), ([], "empty")]
)
def test_seed_indices_that_are_not_distinct_integers_are_refused(given, said):
    """[1.5] ran seed 1, [0, 0] ran seed 0 twice (its rows and its weight doubled), without a word."""
    with pytest.raises(
        ParameterError, match=rf"seed_indices must be distinct integers >= 0.*{re.escape(said)}"
    ):
        run_benchmark(_short(), progress=False, seed_indices=given)


def test_the_metrics_and_the_report_count_the_seeds_that_ran():
    """seed_indices=[3, 4] of a 5-seed scenario: metrics["seeds"] said 5 and the report "5 seeds"."""
    res = run_benchmark(_short(), progress=False, seed_indices=[3, np.int64(4)])
    m = compute_metrics(res)
    assert m["seeds"] == 2 and res.seed_indices == (3, 4)
    text = format_report(m, res)
    assert ": 2 seeds," in text and "controllers x 2 seeds" in text and "5 seeds" not in text


def test_with_controllers_refuses_a_bare_string():
    """with_controllers("pd") split the name into letters: 12 errors of unknown controllers 'p', 'd'."""
    with pytest.raises(
        ScenarioError, match=r"with_controllers: a list of names, got the string 'pd': pass \['pd'\]"
    ):
        load_scenario().with_controllers("pd")


def test_fit_output_error_refuses_a_non_finite_record_and_wrong_lengths():
    """A NaN in q crashed the fit with "cannot unpack non-iterable NoneType" (a NaN cost never rose);
    a std or sigma0 of the wrong length gave raw broadcasting errors."""
    from pathlib import Path

    from adaptive_dd.errors import SignalError
    from adaptive_dd.identification.model import arm_model
    from adaptive_dd.identification.output_error import fit_output_error, measurement_std
    from adaptive_dd.identification.records import simulate_record

    sc = load_scenario(
        Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "ident_vertical3.toml"
    )
    rec = simulate_record(sc.arm, sc.reference, 0.6, [np.random.default_rng(0)])
    model, std = arm_model(sc.arm), measurement_std(sc.arm)
    q = rec.q[0].copy()
    q[300, 1] = np.nan
    with pytest.raises(SignalError, match=r"q must be finite: nan at sample 300, joint 2"):
        fit_output_error(model, q, rec.qd[0], rec.tau[0], rec.sigma_true, std, max_iter=2)
    with pytest.raises(ParameterError, match=r"std must be one number or \(6,\)"):
        fit_output_error(model, rec.q[0], rec.qd[0], rec.tau[0], rec.sigma_true, std[:3], max_iter=2)
    with pytest.raises(ParameterError, match=r"sigma0 must be \(\d+,\) base parameters"):
        fit_output_error(model, rec.q[0], rec.qd[0], rec.tau[0], rec.sigma_true[:-1], std, max_iter=2)


def test_a_built_ins_python_form_on_a_urdf_arm_names_the_shapes_it_takes():
    """pd_gravity's command on the UR5 with a (1, 6) reference (the two-link classes' batch form, the
    Controller docstring's) raised a 30-line numba typing error: one row is taken, other shapes are
    named."""
    from adaptive_dd.controllers import make_controller
    from adaptive_dd.errors import SignalError

    arm = load_scenario("ur5_tool_swap_exact").arm
    c = make_controller("pd_gravity", arm=arm)
    c.reset(2, 1e-3)
    q = np.zeros((2, 6))
    one = c.command(q, q, np.zeros((1, 6)), np.zeros((1, 6)), np.zeros((1, 6)))
    assert one.shape == (2, 6)
    np.testing.assert_array_equal(one, c.command(q, q, np.zeros(6), np.zeros(6), np.zeros(6)))
    with pytest.raises(
        SignalError, match=r"q and qd must be \(n_trials, n\) = \(2, 6\).*got \(2, 6\), \(2, 6\), \(2, 6\)"
    ):
        c.command(q, q, q, q, q)


def test_numpy_scalars_are_numbers_to_the_validators():
    """np.float32 and np.int64 settings were refused ("must be a finite number > 0.0, got
    np.float32(0.001)") where other entry points took them; bools are still not numbers."""
    from adaptive_dd.controllers import make_controller
    from adaptive_dd.identification.online_config import OnlineConfig
    from adaptive_dd.identification.two_link_online_config import TwoLinkOnlineConfig

    assert make_controller("ct_oracle_late", options={"delay": np.int64(0)}).name == "ct_oracle_late"
    assert TwoLinkOnlineConfig(sample_period=np.float32(1e-3)).sample_period == np.float32(1e-3)
    assert OnlineConfig(sample_period=np.float32(1e-3), tau_f=np.int64(1)).tau_f == 1
    with pytest.raises(ParameterError, match=r"sample_period must be a finite number"):
        OnlineConfig(sample_period=True)


def test_an_error_of_a_scenario_changed_in_code_does_not_blame_its_file():
    """replace(load_scenario(), seeds=2.0) said "payload_swap.toml: run.seeds: ..." of a file that is
    fine; it names the change in code."""
    with pytest.raises(
        ScenarioError, match=r"^Scenario from .*payload_swap\.toml, as changed in code: run\.seeds"
    ):
        dataclasses.replace(load_scenario(), seeds=2.0)


def test_identification_inputs_given_in_code_are_named_when_wrong():
    """simulate_record(..., rngs=one Generator) raised "has no len()", rngs=[] "need at least one
    array to stack", payload=2.0 "cannot reshape"; fit_log with a wrong-length used, an IndexError.
    One Generator is one record; the rest are named."""
    from adaptive_dd.identification.log_fit import fit_log
    from adaptive_dd.identification.model import arm_model
    from adaptive_dd.identification.records import simulate_record

    sc = load_scenario("vertical3_payload_exact")
    one = simulate_record(sc.arm, sc.reference, 0.05, np.random.default_rng(0))
    assert one.q.shape == (1, 50, 3)
    with pytest.raises(ParameterError, match=r"rngs is a list of numpy Generators, one per record, got \[\]"):
        simulate_record(sc.arm, sc.reference, 0.05, [])
    with pytest.raises(ParameterError, match=r"payload is its 10 inertial parameters .*got 2\.0"):
        simulate_record(sc.arm, sc.reference, 0.05, [np.random.default_rng(0)], payload=2.0)
    model = arm_model(sc.arm)
    with pytest.raises(ParameterError, match=r"used is one flag per joint \(3,\).*got \(2,\)"):
        fit_log(model, one.q[0].tolist(), one.qd[0], one.tau[0], [True, True], np.ones(model.p, bool),
                tau_f=0.01, sample_period=1e-3)  # fmt: skip


def test_a_detector_threshold_the_estimator_does_not_read_is_refused():
    """detector.threshold (the paper's construction's energy test) on the default exact estimator
    was accepted and changed nothing (1.5, 4 and 1e6 gave bit-identical runs): refused, naming the
    setting that does; the paper's construction still takes it."""
    from adaptive_dd.controllers import make_controller
    from adaptive_dd.identification.two_link_online_config import ChangeDetector, TwoLinkOnlineConfig

    with pytest.raises(
        ParameterError, match=r"threshold = 7\.0: the energy test of the paper's construction.*glr_threshold"
    ):
        make_controller("adaptive_ct", options={"detector": {"threshold": 7.0}})
    assert (
        make_controller("adaptive_ct", options={"detector": {"glr_threshold": 200.0}}).name == "adaptive_ct"
    )
    cfg = TwoLinkOnlineConfig(construction="paper", detector=ChangeDetector(threshold=7.0))
    assert cfg.detector.threshold == 7.0
