"""A compiled plug-in that needs the arm's regressor: Slotine-Li written against the public API
(``examples/plugins/slotine_li_plugin.py``, over :mod:`adaptive_dd.controllers.kernels`) held to
the built-in ``slotine_li`` per seed, a planted sign error caught; the need refused where the arm
has no kernels. The tests that run the compiled loop are slow: a fresh cache compiles it for
each plug-in (a few seconds to a few tens)."""

import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.controllers.plugins import PythonForm, compiled_form
from adaptive_dd.errors import ParameterError

PLUGINS = Path(__file__).resolve().parent.parent / "examples" / "plugins"
SCENARIO = PLUGINS / "slotine_li.toml"


@pytest.fixture(scope="module")
def example():
    sys.path.insert(0, str(PLUGINS))
    try:
        import slotine_li_plugin
    finally:
        sys.path.remove(str(PLUGINS))
    return slotine_li_plugin


def _scenario(controllers, seeds=3, duration=3.0):
    data = tomllib.loads(SCENARIO.read_text())
    data["run"].update(controllers=controllers, seeds=seeds, duration=duration)
    return parse_scenario(data, str(SCENARIO), name="regressor_plugin_test")


def _rms(run):
    """RMS tracking error per trial and segment [rad]."""
    return np.sqrt(run.acc.sum_e2 / run.acc.e_norm.shape[1])


def test_the_regressor_need_is_declared_and_refused_where_the_arm_has_no_kernels(example):
    from adaptive_dd.closed_loop.plugin_loop import NEED_MASS_MATRIX, NEED_REGRESSOR
    from adaptive_dd.controllers import Gains
    from adaptive_dd.plant.two_link import ClosedFormTwoLink

    sc = _scenario(["slotine_li"], seeds=1)
    ctrl = example.SlotineLiPlugin(sc.arm, Gains(40.0, 1.0))
    form = compiled_form("slotine_li_plugin", ctrl, 2, 1e-3)
    assert form.need == NEED_MASS_MATRIX | NEED_REGRESSOR and form.state.shape == (2, 10)
    closed = ClosedFormTwoLink.sice()
    with pytest.raises(ParameterError, match=r"controllers\.sl: needs 'regressor'.*sice_general\.toml"):
        PythonForm("sl", ctrl, closed, "the paper's closed-form two-link runtime").reset(2, 1e-3)


@pytest.mark.slow
def test_the_slotine_li_plugin_reproduces_the_builtin_per_seed(example):
    sc = _scenario(["slotine_li", "slotine_li_plugin:SlotineLiPlugin", "slotine_li_oracle"])
    res = run_benchmark(sc, progress=False)
    ours, builtin = res.runs["slotine_li_plugin"], res.runs["slotine_li"]
    assert ours.engine == "compiled" and not ours.error and not ours.failed.any()
    assert ours.floor == "slotine_li_oracle"
    assert np.max(np.abs(_rms(ours) - _rms(builtin))) < 1e-9  # every seed and segment [rad]
    np.testing.assert_allclose(ours.tau, builtin.tau, rtol=0, atol=1e-6)
    np.testing.assert_allclose(ours.sigma_end, builtin.sigma_end, rtol=1e-9, atol=1e-9)
    # the law adapted: the payload segment's estimate moved from the nominal model
    assert np.all(np.abs(ours.sigma_end[:, 1] - sc.arm.sigma).max(axis=1) > 1e-3)

    class SignError(example.SlotineLiPlugin):
        """The gradient step's sign flipped (the same compiled functions)."""

        name = "sign_error"

        def parameters(self, sample_period):
            p = super().parameters(sample_period)
            return (p[0], p[1], -p[2], *p[3:])

    planted = run_benchmark(sc.with_controllers(["slotine_li"]), progress=False,
                            controllers={"sign_error": SignError(sc.arm, example_gains(sc))})  # fmt: skip
    gap = np.abs(_rms(planted.runs["sign_error"]) - _rms(builtin))
    assert gap[:, 1].min() > 1e-5  # every seed's payload segment differs: the fault is seen


def example_gains(sc):
    from adaptive_dd.controllers import Gains

    return Gains(float(np.max(sc.bandwidth)), sc.damping)
