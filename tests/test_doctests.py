"""The curated API reference: every listed object documented, and its Examples run.

The list is ``docs/_ext/api_list.py`` (the reference's index is written from it). Each object
needs numpydoc Parameters (a class: Parameters or Attributes) and, where it returns something,
Returns; and an Examples section whose doctests pass here, every one of them. The examples that
compile kernels (the closed loop takes minutes to compile on a cold cache) are in :data:`SLOW` and
run under the slow marker.
"""

from __future__ import annotations

import doctest
import importlib
import inspect
import sys
from pathlib import Path

import pytest
from numpydoc.docscrape import ClassDoc, FunctionDoc

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

from api_list import GROUPS, listed  # noqa: E402

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
CLOSED_LOOP = "runs the compiled closed loop (minutes to compile on a cold cache)"
RK4 = "simulates the arm with its compiled RK4 step (about a minute to compile on a cold cache)"
ESTIMATOR = "steps the compiled estimator (about a minute to compile on a cold cache)"
SLOW = {
    "adaptive_dd.benchmark.runner.run_benchmark": CLOSED_LOOP,
    "adaptive_dd.benchmark.types.BenchmarkResult": CLOSED_LOOP,
    "adaptive_dd.benchmark.types.ControllerRun": CLOSED_LOOP,
    "adaptive_dd.simulation.run_trial": CLOSED_LOOP,
    "adaptive_dd.plotting.plot_payload_estimates": CLOSED_LOOP,
    "adaptive_dd.plotting.plot_benchmark_estimates": CLOSED_LOOP,
    "adaptive_dd.plotting.plot_trajectory": RK4,
    "adaptive_dd.identification.records.simulate_record": RK4,
    "adaptive_dd.identification.records.Record": RK4,
    "adaptive_dd.identification.output_error.fit_output_error": RK4,
    "adaptive_dd.identification.output_error.OutputErrorResult": RK4,
    "adaptive_dd.identification.excitation.design_excitation": "an optimisation",
    "adaptive_dd.identification.two_link_online.online_step": ESTIMATOR,
    "adaptive_dd.identification.two_link_online.run_two_link_online": ESTIMATOR,
    "adaptive_dd.identification.detection_limit.detection_limit": CLOSED_LOOP,
    "adaptive_dd.sweep.run_sweep": CLOSED_LOOP + " on Dask",
    "adaptive_dd.arena.leaderboard.leaderboard": CLOSED_LOOP,
    "adaptive_dd.gym.make_env": RK4,
    "adaptive_dd.gym.env.PayloadSwapEnv": RK4,
    "adaptive_dd.gym.score.evaluate": CLOSED_LOOP,
    "adaptive_dd.identification.reproduce.run_reproduce": RK4,
}
"""Listed objects whose Examples compile kernels (minutes on a cold cache): their doctests run
under the slow marker (``pytest -m slow tests/test_doctests.py``), the others in every run."""


def listed_params():
    """Every listed name, the ones of :data:`SLOW` marked slow."""
    return [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in listed()]


def resolve(name: str):
    module, _, attr = name.rpartition(".")
    return getattr(importlib.import_module(module), attr)


def missing_sections(obj) -> list[str]:
    """The numpydoc sections ``obj``'s docstring lacks (Examples apart).

    Parameters
    ----------
    obj : class or callable
        A listed object.

    Returns
    -------
    list of str
        Section names, empty when complete.
    """
    if not inspect.getdoc(obj):
        return ["a docstring"]
    if inspect.isclass(obj):
        if issubclass(obj, BaseException):
            return []
        doc = ClassDoc(obj, config={"show_class_members": False})
        return [] if doc["Parameters"] or doc["Attributes"] else ["Parameters or Attributes"]
    doc = FunctionDoc(obj)
    sig = inspect.signature(obj)
    out = []
    if sig.parameters and not doc["Parameters"]:
        out.append("Parameters")
    returns_none = sig.return_annotation in (None, "None")
    if not returns_none and not (doc["Returns"] or doc["Yields"]):
        out.append("Returns")
    return out


def run_examples(obj, name: str) -> doctest.TestResults:
    """Run the doctests of ``obj``'s own docstring (not its members'), in a fresh namespace.

    Parameters
    ----------
    obj : object
        A listed object.
    name : str
        Its dotted name, for the report.

    Returns
    -------
    doctest.TestResults
        Failed and attempted counts.
    """
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for test in finder.find(obj, name, globs={}):
        runner.run(test)
    return runner.summarize(verbose=False)


def test_the_list_is_curated():
    names = listed()
    assert len(names) == len(set(names)), "a name listed twice"
    assert 50 <= len(names) <= 150
    assert set(SLOW) <= set(names)
    assert all(summary.endswith(".") for _, summary, _ in GROUPS)


@pytest.mark.parametrize("name", listed())
def test_listed_object_is_documented(name):
    obj = resolve(name)
    assert not missing_sections(obj), f"{name}'s docstring lacks {missing_sections(obj)}"


@pytest.mark.parametrize("name", listed_params())
def test_listed_object_examples_run(name):
    obj = resolve(name)
    has_examples = "Examples\n--------" in (inspect.getdoc(obj) or "")
    assert has_examples, f"{name} has no Examples section"
    failed, attempted = run_examples(obj, name)
    assert attempted > 0
    assert failed == 0, f"{failed} of {attempted} examples of {name} failed (printed above)"


def _planted(a, b):
    """Add two numbers.

    Parameters
    ----------
    a, b : float
        The numbers.

    Examples
    --------
    >>> _planted(1, 2)
    4
    """
    return a + b


def _no_returns(a):
    """Add one.

    Parameters
    ----------
    a : float
        A number.
    """
    return a + 1


def test_the_checks_catch_planted_faults():
    failed, attempted = run_examples(_planted, "_planted")
    assert (failed, attempted) == (1, 1)  # a wrong expected output fails
    assert missing_sections(_no_returns) == ["Returns"]
    assert missing_sections(_planted) == ["Returns"]
    assert missing_sections(lambda x: x) == ["a docstring"]
