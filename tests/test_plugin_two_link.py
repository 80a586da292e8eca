"""A compiled plug-in on the paper's arm runs in the two-link compiled loop, not on the Python path.

Held to the Python path (the plug-in's functions called trial by trial, the model terms from the
closed forms' regressor and mass matrix: :class:`~adaptive_dd.controllers.plugins.PythonForm`)
on the same scenario and seeds: trajectories, torques, estimates and alarms equal. A plug-in that
needs the arm's kernels is refused there before the run, naming the route that has them.
"""

import tomllib
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.controllers.plugins import CLOSED_FORMS, PythonForm
from adaptive_dd.errors import ParameterError, ScenarioError

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml"
PLUGINS = ROOT / "examples" / "plugins"


def _scenario(seeds=2, duration=2.0, controllers=("ct_oracle",)):
    data = tomllib.loads(SCENARIO.read_text())
    data["run"].update(seeds=seeds, duration=duration, controllers=list(controllers))
    data["payload"] = [{"at": 1.0, "mass": 3.0}] if duration > 1.0 else []
    return parse_scenario(data, str(SCENARIO), name="plugin_two_link")


class EveryTerm:
    """PD plus each model term, a per-trial state, an estimate of the seven base parameters and an
    alarm: every channel between the loop and a plug-in."""

    name = "every_term"
    needs = ("gravity", "mass_matrix", "bias")
    state_size = 3
    has_detector = True

    def __init__(self, kp, kd):
        self.kp, self.kd = np.asarray(kp, dtype=float), np.asarray(kd, dtype=float)

    def parameters(self, sample_period):
        return (self.kp, self.kd, sample_period)

    @staticmethod
    @njit
    def reset(p, x):
        x[0], x[1], x[2] = 0.0, 0.0, 0.0

    @staticmethod
    @njit
    def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
        kp, kd, _ = p
        g, m, c = terms[0], terms[1], terms[2]
        for j in range(2):
            a = qdd_d[j] + kp[j] * (q_d[j] - q[j]) + kd[j] * (qd_d[j] - qd[j])
            tau[j] = g[j] + c[j]
            for k in range(2):
                tau[j] += m[j, k] * a if k == j else 0.5 * m[j, k] * a
        x[1] = m[0, 1] + c[1]

    @staticmethod
    @njit
    def observe(p, x, q, qd, tau):
        x[0] += 1.0
        x[2] += p[2] * tau[0] * tau[0]
        return 1 if x[0] == 500.0 else 0

    @staticmethod
    @njit
    def estimate(p, x, out):
        for j in range(7):
            out[j] = x[1] + j * x[2]


def test_a_compiled_plugin_on_the_papers_arm_runs_compiled_and_equals_the_python_path():
    sc = _scenario()
    ctrl = EveryTerm(np.array([1600.0, 1600.0]), np.array([80.0, 80.0]))
    python = PythonForm("every_term", ctrl, sc.closed_forms, "the test's reference")
    ours = run_benchmark(sc, controllers={"every_term": ctrl}, progress=False, keep_trajectories=2)
    ref = run_benchmark(sc, controllers={"every_term": python}, progress=False, keep_trajectories=2)
    a, b = ours.runs["every_term"], ref.runs["every_term"]
    assert a.engine == "compiled" and b.engine == "python" and not a.error and not a.failed.any()
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.tau, b.tau, rtol=0, atol=1e-9)
    np.testing.assert_allclose(a.sigma_hat, b.sigma_hat, rtol=1e-12, atol=0)
    np.testing.assert_allclose(a.sigma_end, b.sigma_end, rtol=1e-12, atol=0)
    assert a.alarm_times == b.alarm_times == [[0.499], [0.499]]
    assert np.ptp(a.tau[0, :, 0]) > 1.0  # the law moved the arm: the comparison is not of zeros


@pytest.mark.slow
def test_the_example_in_a_scenario_on_the_papers_arm_runs_compiled(monkeypatch):
    """Named in a scenario's controllers (found on the Python path), built as the run builds it
    (wrapped for the closed forms' other users, unwrapped by the benchmark): the compiled loop,
    the Python path's results."""
    from adaptive_dd.controllers.registry import scenario_controller

    monkeypatch.syspath_prepend(str(PLUGINS))
    sc = _scenario(controllers=("pd_gravity_plugin:PDGravityPlugin",))
    run = run_benchmark(sc, progress=False, keep_trajectories=1).runs["pd_gravity_plugin"]
    assert run.engine == "compiled" and not run.failed.any()
    _, wrapped = scenario_controller(sc, sc.controllers[0])
    assert isinstance(wrapped, PythonForm) and wrapped.why == CLOSED_FORMS
    python = PythonForm("pd_gravity_plugin", wrapped.ctrl, sc.closed_forms, "the test's reference")
    ref = run_benchmark(sc, controllers={"pd_gravity_plugin": python}, progress=False, keep_trajectories=1)
    np.testing.assert_allclose(run.q, ref.runs["pd_gravity_plugin"].q, rtol=0, atol=1e-12)


def test_a_bare_plugin_with_engine_python_runs_on_the_python_path_as_its_own():
    """A compiled plug-in passed as it is (``controllers=``) with ``engine="python"``: its functions
    called trial by trial (not as a plain-Python controller's), the compiled run's results."""
    sc = _scenario(seeds=1, duration=0.3)
    ctrl = EveryTerm(np.array([1600.0, 1600.0]), np.array([80.0, 80.0]))
    fast = run_benchmark(sc, controllers={"e": ctrl}, progress=False, keep_trajectories=1).runs["e"]
    slow = run_benchmark(sc, controllers={"e": ctrl}, progress=False, keep_trajectories=1, engine="python")
    slow = slow.runs["e"]
    assert fast.engine == "compiled" and slow.engine == "python" and not slow.failed.any()
    np.testing.assert_allclose(slow.q, fast.q, rtol=0, atol=1e-12)


@pytest.mark.parametrize("wrapped", [True, False])
def test_a_plugin_that_needs_the_arms_kernels_is_refused_before_the_run(wrapped):
    class NeedsKernels(EveryTerm):
        needs = ("regressor",)

    sc = _scenario(seeds=1, duration=0.05)
    ctrl = NeedsKernels(np.ones(2), np.ones(2))
    ctrl = PythonForm("k", ctrl, sc.closed_forms, CLOSED_FORMS) if wrapped else ctrl
    with pytest.raises(ParameterError, match=r"controllers\.k: needs 'regressor'.*sice_general\.toml"):
        run_benchmark(sc, controllers={"k": ctrl}, progress=False)


def test_a_plugin_whose_init_fails_on_the_closed_forms_is_named_with_what_they_offer(monkeypatch):
    """The Slotine-Li example reads the payload's basis of an arm from a URDF: on the paper's
    closed forms its constructor fails, said as the plug-in's error (not an internal one), with
    what the closed forms' record offers and where the rest is."""
    from adaptive_dd.controllers.registry import scenario_controller

    monkeypatch.syspath_prepend(str(PLUGINS))
    sc = _scenario(seeds=1, duration=0.05)
    with pytest.raises(
        ParameterError, match=r"controllers\.SlotineLiPlugin: AttributeError: .*sice_general\.toml"
    ):
        scenario_controller(sc, "slotine_li_plugin:SlotineLiPlugin")


def _with_floor(floor, controllers=("pd", "pd_gravity_plugin:PDGravityPlugin")):
    data = tomllib.loads(SCENARIO.read_text())
    data["run"].update(seeds=1, duration=2.0, controllers=list(controllers))
    data["payload"] = [{"at": 1.0, "mass": 3.0}]
    data["controllers"] = {"PDGravityPlugin": {"floor": floor}}
    return parse_scenario(data, str(SCENARIO), name="plugin_floor")


@pytest.mark.slow  # a run of the plug-in's two-link loop (the CLI's floor test runs in the default set)
def test_a_scenario_sets_a_plugins_floor_on_the_papers_arm(monkeypatch):
    """``[controllers.NAME] floor`` replaces the class's own (the example's ``pd_gravity_oracle``
    runs on N-joint arms only): the wrapped plug-in's run carries it, and with no gravity in the
    paper's horizontal plane PD plus gravity is ``pd`` to the bit."""
    monkeypatch.syspath_prepend(str(PLUGINS))
    res = run_benchmark(_with_floor("pd"), progress=False, keep_trajectories=1)
    run = res.runs["pd_gravity_plugin"]
    assert run.engine == "compiled" and run.floor == "pd"
    np.testing.assert_array_equal(run.q, res.runs["pd"].q)


@pytest.mark.parametrize(
    ("floor", "words"),
    [
        (
            "pdx",
            "'pdx' is not one of the run's controllers (by the names their results carry: pd, "
            "pd_gravity_plugin)",
        ),
        (3, "or false for none; got 3"),
    ],
)
def test_a_floor_that_names_no_controller_of_the_run_is_an_error_of_the_file(monkeypatch, floor, words):
    monkeypatch.syspath_prepend(str(PLUGINS))
    with pytest.raises(ScenarioError, match=r"controllers\.PDGravityPlugin\.floor") as info:
        _with_floor(floor)
    assert words in str(info.value)


def test_a_floor_that_cannot_run_on_the_papers_arm_is_left_out_and_said(monkeypatch, capsys):
    """The command line adds each missing floor; one built for N-joint arms only (the example's
    ``pd_gravity_oracle``) aborted a run on the paper's arm naming a controller nobody listed. It is
    left out, and the note names the setting that gives the plug-in a floor."""
    from adaptive_dd.cli.benchmark import with_floors

    monkeypatch.syspath_prepend(str(PLUGINS))
    sc = _scenario(controllers=("pd", "pd_gravity_plugin:PDGravityPlugin"))
    out = with_floors(sc)
    assert out.controllers == ("pd", "pd_gravity_plugin:PDGravityPlugin", "ct_oracle")
    err = capsys.readouterr().err
    assert (
        "pd_gravity_oracle, the floor of pd_gravity_plugin:PDGravityPlugin, does not run on this arm" in err
    )
    assert (
        "set the floor of [controllers.PDGravityPlugin]" in err and "ct_oracle added (the floor of pd" in err
    )


def test_a_plugins_bad_setting_names_the_scenario_file(monkeypatch, tmp_path):
    """A plug-in's table is checked when the run builds it; its error named the table, not the file."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.controllers.registry import scenario_controller

    monkeypatch.syspath_prepend(str(PLUGINS))
    path = tmp_path / "mine.toml"
    text = (ROOT / "examples" / "plugins" / "slotine_li.toml").read_text()
    path.write_text(text + "\n[controllers.SlotineLiPlugin]\nnope = 1\n")
    sc = load_scenario(path)
    with pytest.raises(ParameterError, match=rf"^{path}: controllers.SlotineLiPlugin: unknown setting"):
        scenario_controller(sc, "slotine_li_plugin:SlotineLiPlugin")
