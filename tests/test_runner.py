"""The closed-loop runner: compiled and Python paths agree, blocks of seeds, containment of
controller failures, bounded trajectories."""

import dataclasses

import numpy as np
import pytest

from adaptive_dd.benchmark.metrics import compute_metrics
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.controllers import ComputedTorque, Controller
from adaptive_dd.errors import ParameterError

BUILTIN = (
    "pd",
    "ct_nominal",
    "ct_oracle",
    "ct_oracle_textbook",
    "adaptive_ct",
    "adaptive_ct_paper",
    "slotine_li",
    "slotine_li_oracle",
)


@pytest.fixture(scope="module")
def swap_scenario():
    return dataclasses.replace(
        load_scenario(),
        seeds=2,
        duration=5.0,
        swap_times=(2.5, 4.0),
        swap_masses=(3.0, 1.0),
        controllers=BUILTIN,
    )


@pytest.fixture(scope="module")
def both_paths(swap_scenario):
    return (
        run_benchmark(swap_scenario, progress=False, engine="compiled"),
        run_benchmark(swap_scenario, progress=False, engine="python"),
    )


def test_compiled_and_python_paths_agree_alarms_included(both_paths):
    rc, rp = both_paths
    for name in BUILTIN:
        a, b = rc.runs[name], rp.runs[name]
        assert (a.engine, b.engine) == ("compiled", "python")
        np.testing.assert_allclose(_acc(a), _acc(b), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a.tau, b.tau, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(a.failed, b.failed)
        if a.sigma_hat is not None:
            np.testing.assert_allclose(a.sigma_hat, b.sigma_hat, rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(a.sigma_end, b.sigma_end, rtol=1e-12, atol=1e-12)
        assert a.alarm_times == b.alarm_times
    alarms = rc.runs["adaptive_ct"].alarm_times
    assert all(len(tr) == 2 for tr in alarms)  # both swaps detected, on both paths
    mc, mp = compute_metrics(rc), compute_metrics(rp)
    for name in BUILTIN:
        for sa, sb in zip(
            mc["controllers"][name]["segments"], mp["controllers"][name]["segments"], strict=True
        ):
            assert sa["rms_error"] == pytest.approx(sb["rms_error"], rel=1e-12)


def test_a_block_of_seeds_equals_the_same_seeds_in_a_full_run(swap_scenario, both_paths):
    rc, _ = both_paths
    sc = dataclasses.replace(swap_scenario, controllers=("adaptive_ct",))
    block = run_benchmark(sc, progress=False, seed_indices=[1])
    for x, y in zip(block.runs["adaptive_ct"].acc, rc.runs["adaptive_ct"].acc, strict=True):
        np.testing.assert_array_equal(x[0], y[1])


def test_only_the_first_seeds_keep_trajectories(swap_scenario):
    sc = dataclasses.replace(swap_scenario, seeds=3, controllers=("ct_oracle",))
    run = run_benchmark(sc, progress=False, keep_trajectories=1).runs["ct_oracle"]
    assert run.q.shape == (1, sc.n_samples, 2) and run.acc.sum_e2.shape[0] == 3
    assert run.e_norm.dtype == np.float32 and run.e_norm.shape == (3, sc.n_samples)


class Raises(Controller):
    def __init__(self, where, exc=RuntimeError):
        self.where, self.exc, self.name = where, exc, f"raises_{where}"

    def reset(self, n, T):
        super().reset(n, T)
        if self.where == "reset":
            raise self.exc("boom in reset")

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        if self.where == "command" and self.k > 100:
            raise self.exc("boom in command")
        if self.where == "shape":
            return np.zeros(3)
        self.k = getattr(self, "k", 0) + 1
        return np.zeros_like(q)

    def observe(self, q, qd, tau):
        if self.where == "observe":
            raise self.exc("boom in observe")


@pytest.mark.parametrize("where", ["reset", "command", "observe", "shape"])
def test_a_failing_controller_fails_only_its_own_trials(swap_scenario, where):
    sc = dataclasses.replace(swap_scenario, duration=0.5, swap_times=(), swap_masses=())
    ctrls = {"bad": Raises(where, AttributeError), "ct_oracle": ComputedTorque(oracle=True)}
    res = run_benchmark(sc, progress=False, controllers=ctrls)
    bad = res.runs["bad"]
    assert bad.failed.all() and bad.error
    assert (
        ("shape" in bad.error) if where == "shape" else (where in bad.error and "AttributeError" in bad.error)
    )
    assert not res.runs["ct_oracle"].failed.any()
    m = compute_metrics(res)["controllers"]
    assert m["bad"]["failed_trials"] == sc.seeds and m["bad"]["error"]
    # each trial's reason is the controller's own failure, not the NaN it left in its place
    whys = {f["why"] for f in m["bad"]["failures"]} | set(res.to_frame().query("controller == 'bad'").failure)
    assert whys == {bad.error}, whys
    assert m["ct_oracle"]["segments"][0]["rms_error"] < 1e-3


def test_engine_choice_is_checked(swap_scenario):
    with pytest.raises(ParameterError, match="engine"):
        run_benchmark(swap_scenario, progress=False, engine="gpu")
    with pytest.raises(ParameterError, match="no compiled path"):
        run_benchmark(swap_scenario, progress=False, engine="compiled", controllers={"x": Raises("none")})


def test_mass_learning_time_is_the_last_entry_into_the_band():
    from adaptive_dd.closed_loop.information import mass_learning_time

    m = np.array([[0.0, 2.0, 3.2, 2.99, 3.01, 3.0], [0.0, 3.0, 3.0, 3.0, 3.0, 2.0]])
    t = mass_learning_time(m, 3.0, 0.0, 0.01)
    assert t[0] == pytest.approx(0.03) and np.isnan(t[1])  # row 1 leaves the band at the end


def test_the_report_holds_the_information_limit_beside_the_learning_time(both_paths):
    rc, _ = both_paths
    m = compute_metrics(rc)["controllers"]
    seg = m["adaptive_ct"]["segments"][1]
    info = seg["information_time"]
    assert 0 < info["known"] < info["unknown"] < 1.0  # knowing the rest of the arm helps
    assert 0 < seg["mass_learning_time"] < 1.0
    assert seg["sigma_true"][0] == pytest.approx(0.429 + 3.0 * 0.04)  # J1 + m l1^2


def test_sensor_dropouts_are_held_skipped_and_counted_not_divergence(swap_scenario):
    """A lost measurement (NaN) is not a diverging trial: the law holds the last good one, the
    estimator skips and counts it; both paths agree and the report says how many."""
    sc = dataclasses.replace(swap_scenario, dropout=0.01, controllers=("ct_oracle", "adaptive_ct"))
    rc = run_benchmark(sc, progress=False, engine="compiled")
    rp = run_benchmark(sc, progress=False, engine="python")
    for name in sc.controllers:
        a, b = rc.runs[name], rp.runs[name]
        assert not a.failed.any() and a.dropped.min() > 20
        np.testing.assert_array_equal(a.dropped, b.dropped)
        np.testing.assert_allclose(_acc(a), _acc(b), rtol=1e-12, atol=1e-12)
    run = rc.runs["adaptive_ct"]
    assert (run.skipped > run.dropped).all()  # each loss taints the filters for 10 tau_f
    np.testing.assert_array_equal(run.skipped, rp.runs["adaptive_ct"].skipped)
    for tr in run.alarm_times:  # both swaps still found within 0.3 s, nothing before the first
        assert min(tr) > 2.5 and all(any(t < a < t + 0.3 for a in tr) for t in (2.5, 4.0)), tr
    m = compute_metrics(rc)["controllers"]["adaptive_ct"]
    assert m["dropped_samples"] == int(run.dropped.sum()) and m["failed_trials"] == 0
    with pytest.raises(Exception, match="dropout"):
        dataclasses.replace(sc, dropout=0.9)


def _acc(run):
    """A run's streamed sums (``StreamedSums`` but the error norm) as one flat array."""
    return np.concatenate([np.ravel(x) for x in run.acc[:-1]])
