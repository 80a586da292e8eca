"""Compiled plug-ins: a user's law in the compiled closed loop, held to the built-in it reproduces.

The shipped example ``examples/plugins/pd_gravity_plugin.py`` (PD plus gravity compensation,
written against the public protocol only) against the built-in ``pd_gravity`` on the same
scenario and seeds; faults planted through its parameters (one compiled specialisation serves
them all); the declarations' errors; the slow path's note for a plain-Python plug-in. The tests
that run the compiled loop are slow: a fresh cache compiles the loop for each plug-in (its
caching: ``tests/test_plugin_cache.py``).
"""

import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.closed_loop.runner import run_closed_loop
from adaptive_dd.controllers import Gains
from adaptive_dd.controllers.plugins import compiled_form, is_compiled
from adaptive_dd.errors import ParameterError

PLUGINS = Path(__file__).resolve().parent.parent / "examples" / "plugins"
SCENARIO = PLUGINS / "pd_gravity.toml"


@pytest.fixture(scope="module")
def example():
    """The example plug-in's module, imported as the runner imports it (the scenario's folder)."""
    sys.path.insert(0, str(PLUGINS))
    try:
        import pd_gravity_plugin
    finally:
        sys.path.remove(str(PLUGINS))
    return pd_gravity_plugin


def _scenario(controllers, seeds=2, duration=3.0, keep_table=True):
    data = tomllib.loads(SCENARIO.read_text())
    data["run"].update(controllers=controllers, seeds=seeds, duration=duration)
    if not keep_table:
        data.pop("controllers")
    if duration <= data["payload"][0]["at"]:
        data.pop("payload")  # too short for the swap
    return parse_scenario(data, str(SCENARIO), name="plugin_test")


def _rms(run):
    """RMS tracking error per trial and segment [rad]."""
    return np.sqrt(run.acc.sum_e2 / run.acc.e_norm.shape[1])


def _planted(example, fault):
    """The example plug-in with a fault planted in its parameters (same compiled functions)."""

    class Faulty(example.PDGravityPlugin):
        name = "faulty"

        def parameters(self, sample_period):
            kp, kd = super().parameters(sample_period)
            return fault(kp, kd)

    return Faulty


@pytest.mark.slow
def test_the_example_reproduces_the_builtin_pd_gravity(example):
    sc = _scenario(["pd_gravity", "pd_gravity_plugin:PDGravityPlugin", "pd_gravity_oracle"])
    res = run_benchmark(sc, progress=False)
    ours, builtin = res.runs["pd_gravity_plugin"], res.runs["pd_gravity"]
    assert ours.engine == "compiled" and not ours.error and not ours.failed.any()
    assert ours.floor == "pd_gravity_oracle"
    assert np.max(np.abs(_rms(ours) - _rms(builtin))) < 1e-9
    np.testing.assert_allclose(ours.q, builtin.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ours.tau, builtin.tau, rtol=0, atol=1e-6)
    # results, labels and the per-seed table as for a built-in: the same ratios to the same floor
    table = res.summary().set_index(["controller", "segment"])["ratio_mean"]
    np.testing.assert_allclose(
        table["pd_gravity_plugin"].to_numpy(), table["pd_gravity"].to_numpy(), rtol=1e-9
    )
    per_seed = res.to_frame()
    assert set(per_seed["controller"]) >= {"pd_gravity_plugin", "pd_gravity"}


@pytest.mark.slow
@pytest.mark.parametrize(
    "fault",
    [
        lambda kp, kd: (kp, -kd),  # the damping's sign flipped
        lambda kp, kd: (kp * 1.001, kd),  # the stiffness 0.1 % off
    ],
)
def test_a_planted_fault_is_caught(example, fault):
    sc = _scenario(["pd_gravity"], keep_table=False)
    builtin = run_closed_loop(sc).runs["pd_gravity"]
    ctrl = _planted(example, fault)(sc.arm, Gains(sc.bandwidth, sc.damping))
    ours = run_closed_loop(sc, {"faulty": ctrl}).runs["faulty"]
    assert ours.engine == "compiled"
    assert np.max(np.abs(_rms(ours) - _rms(builtin))) > 1e-9  # the comparison above would fail


@pytest.mark.slow
def test_a_non_finite_command_fails_its_trials_not_the_run(example):
    sc = _scenario(["pd_gravity"], keep_table=False)
    ctrl = _planted(example, lambda kp, kd: (kp * np.nan, kd))(sc.arm, Gains(sc.bandwidth, sc.damping))
    run = run_closed_loop(sc, {"faulty": ctrl}).runs["faulty"]
    assert run.failed.all() and (run.failed_at == 0).all() and not run.error
    assert np.all(np.isfinite(run.acc.sum_e2))  # the trial froze at rest: no NaN in the metrics
    run.explain_failures(1.0, 100.0)  # the reason names the command, its joint, the terms not declared
    assert set(run.failed_why.values()) == {
        "non-finite torque command (joint 1) (if it reads mass_matrix, bias, which it does not declare in "
        "needs: those terms are NaN in its loop; declare what it reads)"
    }


def test_the_plain_python_plugin_runs_on_the_slow_path_and_says_so_once(capsys):
    sc = _scenario(["pd_gravity_python:PDGravityPython"], seeds=2, duration=0.05, keep_table=False)
    run = run_closed_loop(sc).runs["pd_gravity_python"]
    out = capsys.readouterr().err  # beside the compilation messages, apart from the report
    assert run.engine == "python" and not run.failed.any()
    assert out.count("slow Python path") == 1 and "pd_gravity_python" in out and "numba.njit" in out


def test_a_plain_python_law_on_the_papers_arm_says_so_too(capsys):
    """The closed forms' runner ran a plain-Python law without the note the docs promise."""
    import dataclasses

    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario

    class PlainPD:
        def reset(self, n, T):
            pass

        def command(self, q, qd, q_d, qd_d, qdd_d):
            return 100.0 * (q_d - q) + 10.0 * (qd_d - qd)

        def observe(self, q, qd, tau):
            pass

    sc = dataclasses.replace(load_scenario(), seeds=1, duration=0.2, swap_times=(0.1,), swap_masses=(1.0,))
    run_benchmark(sc, progress=False, controllers={"plain": PlainPD()})
    err = capsys.readouterr().err
    assert err.count("slow Python path") == 1 and "plain: a plain-Python controller" in err


class _Declares:
    """A compiled plug-in's shape with its declarations set per test."""

    reset = command = observe = staticmethod(njit(lambda p, x: None))


@pytest.mark.parametrize(
    ("attrs", "match"),
    [
        ({"needs": ("gravity", "jacobian")}, r"needs \['jacobian'\].*allowed"),
        ({"state_size": -1}, "state_size"),
        ({"state_size": 2.5}, "state_size"),
        ({"estimate": lambda p, x, out: None}, "estimate must be a numba.njit"),
        (
            {"parameters": lambda self, T: {"kp": 1.0}},
            r"parameters\(0\.001\) returned a dict, which numba cannot",
        ),
    ],
)
def test_bad_declarations_are_errors_naming_the_key(attrs, match):
    ctrl = type("Bad", (_Declares,), attrs)()
    with pytest.raises(ParameterError, match=match):
        compiled_form("bad", ctrl, 2, 1e-3)


def test_a_half_compiled_plugin_is_an_error_naming_what_is_not_compiled():
    class Half(_Declares):
        def observe(self, q, qd, tau):
            pass

    with pytest.raises(ParameterError, match=r"\['observe'\] are not"):
        is_compiled(Half())
    assert not is_compiled(object()) and is_compiled(_Declares())


class _Counter:
    """A compiled plug-in with state, alarms and an estimate: PD on the reference, a count of the
    samples observed as its 'estimate', an alarm at the 500th sample."""

    has_detector = True
    state_size = 1

    def __init__(self, kp, kd):
        self.kp, self.kd = kp, kd

    def parameters(self, sample_period):
        return (self.kp, self.kd, 500.0)

    @staticmethod
    @njit
    def reset(p, x):
        x[0] = 0.0

    @staticmethod
    @njit
    def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
        for j in range(q.shape[0]):
            tau[j] = p[0][j] * (q_d[j] - q[j]) + p[1][j] * (qd_d[j] - qd[j])

    @staticmethod
    @njit
    def observe(p, x, q, qd, tau):
        x[0] += 1.0
        return 1 if x[0] == p[2] else 0

    @staticmethod
    @njit
    def estimate(p, x, out):
        for c in range(out.shape[0]):
            out[c] = x[0]


class _Overrun(_Counter):
    """:class:`_Counter` that writes past its one float of state (``state_size`` too small)."""

    @staticmethod
    @njit
    def observe(p, x, q, qd, tau):
        x[0] += 1.0
        x[1] = x[0]  # beyond state_size: the next trial's state, were indices not checked
        return 0


def test_a_compiled_plugins_functions_run_with_their_indices_checked():
    """numba checks no index by default: a plug-in writing past its state would write into the
    next trial's (results that change from run to run, no error). The loop runs its functions
    compiled again with bounds checking, once per function."""
    from adaptive_dd.controllers.plugins import _bounds_checked

    form = compiled_form("overrun", _Overrun(np.ones(2), np.ones(2)), 3, 1e-3)
    observe = form.observe
    assert observe is _bounds_checked(_Overrun.observe)  # made once, found again
    assert observe.targetoptions["boundscheck"] and not _Overrun.observe.targetoptions.get("boundscheck")
    with pytest.raises(IndexError):
        observe(form.params, form.state[0], np.zeros(2), np.zeros(2), np.zeros(2))
    fine = compiled_form("counter", _Counter(np.ones(2), np.ones(2)), 3, 1e-3)
    assert fine.observe(fine.params, fine.state[0], np.zeros(2), np.zeros(2), np.zeros(2)) == 0


class _Stateless(_Counter):
    """:class:`_Counter` that declares no state and still counts in ``x[0]``."""

    state_size = 0


def test_a_plugin_declaring_no_state_has_none_to_write():
    """``state_size = 0``: each trial's state is empty, so ``x[0]`` is an IndexError like any index
    past the declared size (it wrote into a float of padding before, unnoticed)."""
    form = compiled_form("stateless", _Stateless(np.ones(2), np.ones(2)), 3, 1e-3)
    assert form.state.shape == (3, 0)
    with pytest.raises(IndexError):
        form.observe(form.params, form.state[0], np.zeros(2), np.zeros(2), np.zeros(2))


@pytest.mark.slow
def test_an_index_past_the_state_fails_the_plugins_trials_and_names_state_size():
    sc = _scenario(["pd_gravity"], seeds=2, duration=0.5, keep_table=False)
    m0 = sc.arm.nominal_inertia()
    run = run_closed_loop(sc, {"overrun": _Overrun(1600.0 * m0, 80.0 * m0)}).runs["overrun"]
    assert run.engine == "compiled" and run.failed.all()
    assert run.error.startswith("IndexError in the compiled plug-in") and "state_size" in run.error


class _Bar:
    """A progress bar's calls, in order."""

    def __init__(self):
        self.calls, self.done = [], 0

    def clear(self):
        self.calls.append("clear")

    def refresh(self):
        self.calls.append("refresh")

    def update(self, n):
        self.calls.append("update")
        self.done += n


@pytest.mark.slow
def test_state_alarms_and_estimates_reach_the_results():
    sc = _scenario(["pd_gravity"], seeds=3, duration=2.5, keep_table=False)
    m0 = sc.arm.nominal_inertia()
    ctrl = _Counter(1600.0 * m0, 80.0 * m0)
    bar = _Bar()
    run = run_closed_loop(sc, {"counter": ctrl}, keep_trajectories=2, bar=bar).runs["counter"]
    assert bar.calls[:2] == ["clear", "refresh"] and bar.done == 2500  # hidden while compiling
    assert not run.error and run.engine == "compiled"
    assert run.alarm_times == [[pytest.approx(0.499)]] * 3  # the 500th sample, k = 499
    ends = [2000, 2500]  # samples observed at each segment's end (swap at 2 s, T = 1 ms)
    np.testing.assert_array_equal(run.sigma_end[:, :, 0], [ends] * 3)
    assert run.sigma_hat.shape[0] == 2
    np.testing.assert_array_equal(run.sigma_hat[:, :, 0], np.tile(np.arange(1, 2501), (2, 1)))


@pytest.mark.slow
def test_the_compiled_plugin_on_the_python_path_agrees_with_the_compiled_loop(example, capsys):
    """engine='python' calls the same njit functions trial by trial, the model terms from the arm's
    regressor instead of the compiled loop's recursive Newton-Euler: the same law to rounding."""
    sc = _scenario(["pd_gravity_plugin:PDGravityPlugin"], seeds=2, duration=2.5)
    fast = run_closed_loop(sc).runs["pd_gravity_plugin"]
    slow = run_closed_loop(sc, engine="python").runs["pd_gravity_plugin"]
    assert fast.engine == "compiled" and slow.engine == "python" and not slow.error
    assert "compiled plug-in on the slow Python path (engine='python')" in capsys.readouterr().err
    assert np.max(np.abs(_rms(fast) - _rms(slow))) < 1e-9


@pytest.mark.slow
def test_the_compiled_plugin_runs_on_the_papers_closed_forms(example):
    """On the paper's two-link runtime the same class runs in the two-link compiled loop, and with
    engine='python' on the Python path (its gravity from the paper's regressor, eq. 8): the same
    law (tests/test_plugin_two_link.py holds every term equal)."""
    from adaptive_dd.benchmark.scenario import load_scenario

    data = tomllib.loads(Path(load_scenario().source).read_text())
    data["run"].update(controllers=["ct_oracle", "pd_gravity_plugin:PDGravityPlugin"], seeds=2, duration=1.0)
    data.pop("payload", None)
    data.pop("controllers", None)
    sc = parse_scenario(data, str(SCENARIO), name="two_link_plugin")
    assert sc.closed_forms is not None
    run = run_benchmark(sc, progress=False).runs["pd_gravity_plugin"]
    assert run.engine == "compiled" and not run.error and not run.failed.any()
    assert np.all(_rms(run) < 0.05)  # PD with gravity tracks the paper's arm within 50 mrad
    slow = run_benchmark(sc, progress=False, engine="python").runs["pd_gravity_plugin"]
    assert slow.engine == "python" and np.max(np.abs(_rms(run) - _rms(slow))) < 1e-12
