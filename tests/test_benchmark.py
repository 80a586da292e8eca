"""The benchmark: metrics, fault containment, outputs and the CLI."""

import dataclasses
import json

import numpy as np
import pytest

from adaptive_dd.benchmark.metrics import _settling_time, compute_metrics, moving_rms
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.cli import main
from adaptive_dd.controllers import ComputedTorque, adaptive_ct


@pytest.fixture(scope="module")
def small_run():
    sc = dataclasses.replace(
        load_scenario(),
        seeds=2,
        duration=3.0,
        swap_times=(1.5,),
        swap_masses=(3.0,),
        controllers=("ct_nominal", "ct_oracle", "adaptive_ct"),
    )
    return run_benchmark(sc, progress=False)


def test_metrics_layout_and_content(small_run):
    m = compute_metrics(small_run)
    c = m["controllers"]
    assert set(c) == {"ct_nominal", "ct_oracle", "adaptive_ct"}
    for v in c.values():
        assert v["failed_trials"] == 0
        assert [s["mass"] for s in v["segments"]] == [0.0, 3.0]
        for s in v["segments"]:
            for key in (
                "start",
                "end",
                "mass",
                "rms_error",
                "max_error",
                "settling_time",
                "rms_torque",
                "saturation_fraction",
                "mass_estimate",
            ):
                assert key in s
    seg = [c[n]["segments"][1] for n in ("ct_nominal", "ct_oracle", "adaptive_ct")]
    assert seg[1]["rms_error"] < seg[2]["rms_error"] < seg[0]["rms_error"]
    assert seg[0]["mass_estimate"] is None
    assert seg[2]["mass_estimate"] == pytest.approx(3.0, rel=0.1)
    assert c["ct_oracle"]["segments"][0]["settling_time"] is None
    assert seg[2]["settling_time"] < 1.0
    # the change detector of adaptive_ct fires within 0.2 s of the swap; fixed models have none
    assert 0.0 < seg[2]["detection_delay"] < 0.2 and seg[1]["detection_delay"] is None
    # once the transient is over, adaptive_ct tracks about like the oracle
    assert seg[2]["rms_error_settled"] < 2 * seg[1]["rms_error_settled"]
    json.dumps(m)  # serialisable


def test_rms_error_metric_matches_a_direct_computation(small_run):
    m = compute_metrics(small_run)
    run = small_run.runs["ct_oracle"]
    e = np.sqrt(((small_run.q_d[None, 1500:] - run.q[:, 1500:]) ** 2).sum(-1))
    assert m["controllers"]["ct_oracle"]["segments"][1]["rms_error"] == pytest.approx(
        np.sqrt((e**2).mean(axis=1)).mean()
    )


class NaNAfter(ComputedTorque):
    """A controller that goes bad in trial 0 after 0.5 s."""

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        tau = super().command(q, qd, q_d, qd_d, qdd_d, sigma_true)
        self.k = getattr(self, "k", 0) + 1
        if self.k > 500:
            tau[0] = np.nan
        return tau


class Raises(ComputedTorque):
    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        self.k = getattr(self, "k", 0) + 1
        if self.k > 300:
            raise np.linalg.LinAlgError("singular")
        return super().command(q, qd, q_d, qd_d, qdd_d, sigma_true)


def test_a_failing_trial_or_controller_does_not_take_the_benchmark_down():
    sc = dataclasses.replace(load_scenario(), seeds=3, duration=1.5, swap_times=(1.0,), swap_masses=(1.0,))
    res = run_benchmark(
        sc, progress=False, controllers={"nan": NaNAfter(), "raises": Raises(), "good": adaptive_ct()}
    )
    m = compute_metrics(res)["controllers"]
    assert m["nan"]["failed_trials"] == 1 and m["nan"]["rms_error"] is not None
    assert m["raises"]["failed_trials"] == 3 and "LinAlgError" in m["raises"]["error"]
    assert m["raises"]["rms_error"] is None
    assert m["good"]["failed_trials"] == 0
    assert np.isfinite(m["good"]["rms_error"])


def test_moving_rms_and_settling_time():
    x = np.random.default_rng(0).normal(size=(2, 300))
    naive = np.array([[np.sqrt((r[max(0, k - 9) : k + 1] ** 2).mean()) for k in range(300)] for r in x])
    np.testing.assert_allclose(moving_rms(x, 10), naive)
    above = np.zeros((3, 100), bool)
    above[0, :20] = True
    above[1, [5, 50, 95]] = True
    above[2, :] = True
    st = _settling_time(above, 30)
    assert st[0] == 20 and st[1] == 6 and np.isnan(st[2])  # row 1: quiet 6..49 (44 >= 30)


def test_cli_benchmark_writes_its_outputs(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text("""
[run]
duration = 1.2
seeds = 2
controllers = ["ct_nominal", "ct_oracle", "adaptive_ct"]
[[payload]]
at = 0.6
mass = 3.0
""")
    out = tmp_path / "out"
    assert (
        main(["benchmark", str(p), "--out", str(out), "--no-progress", "--json", str(tmp_path / "m.json")])
        == 0
    )
    text = capsys.readouterr().out
    assert "Targets (measured, not asserted)" in text and "ct_oracle" in text
    data = json.loads((tmp_path / "m.json").read_text())
    assert set(data["controllers"]) == {"ct_nominal", "ct_oracle", "adaptive_ct"}
    for f in ("metrics.csv", "tracking_error.png", "estimates.png"):
        assert (out / f).is_file()
    assert len((out / "metrics.csv").read_text().splitlines()) == 1 + 3 * 2


def test_cli_benchmark_reports_a_bad_scenario(tmp_path, capsys):
    p = tmp_path / "bad.toml"
    p.write_text("[run]\ncontrollers = ['nope']\n")
    assert main(["benchmark", str(p), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert str(p) in err and "unknown controller 'nope'" in err


def test_releasing_the_error_norm_as_the_run_goes_changes_no_figure(small_run):
    """The CLI derives per controller what needs the per-sample error norm and frees it
    (run_benchmark(on_run=release_error_norm)): every metric equals the kept-norm run's."""
    from adaptive_dd.benchmark.metrics import error_trace, release_error_norm

    released = run_benchmark(small_run.scenario, progress=False, on_run=release_error_norm)
    assert all(r.e_norm.shape[0] == 0 for r in released.runs.values())
    a, b = compute_metrics(small_run)["controllers"], compute_metrics(released)["controllers"]
    for name in a:
        for sa, sb in zip(a[name]["segments"], b[name]["segments"], strict=True):
            for key in (
                "rms_error",
                "settling_time",
                "max_error",
                "ratio_to_floor",
                "detection_delay",
                "time_to_floor",
            ):
                assert sa.get(key) == sb.get(key), (name, key)
        np.testing.assert_array_equal(
            error_trace(small_run, small_run.runs[name]), error_trace(released, released.runs[name])
        )
