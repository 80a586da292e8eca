"""``benchmarks/detector_setting.py`` (judge an N-joint detector setting on the shipped scenarios
and drawn arms): its ``--detector`` pairs are typed as the defaults, an unknown key is refused by
name, and the settings reach ``adaptive_ct``'s estimator (a setting that never arrived would
compare the defaults with themselves)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from adaptive_dd import load_scenario
from adaptive_dd.benchmark.scenario_settings import with_settings
from adaptive_dd.closed_loop.runner import make_controllers

ROOT = Path(__file__).resolve().parents[1]


def _script():
    spec = importlib.util.spec_from_file_location(
        "detector_setting", ROOT / "benchmarks" / "detector_setting.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_pairs_are_typed_and_checked():
    mod = _script()
    assert mod.detector_settings(["fast_threshold=6.5", "reopen_again=false"]) == {
        "fast_threshold": 6.5,
        "reopen_again": False,
    }
    with pytest.raises(SystemExit, match="bogus"):
        mod.detector_settings(["bogus=1"])
    with pytest.raises(SystemExit, match="reopen_again"):
        mod.detector_settings(["reopen_again=1"])  # not silently false
    with pytest.raises(SystemExit, match="min_learned"):
        mod.detector_settings(["min_learned=many"])
    with pytest.raises(Exception, match="fast_threshold"):
        mod.detector_settings(["fast_threshold=0.5"])  # must be > 1


def test_the_settings_reach_the_controller():
    mod = _script()
    sc = load_scenario(ROOT / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml")
    sc = with_settings(sc, "adaptive_ct", {"detector": mod.detector_settings(["fast_threshold=6.5"])})
    assert make_controllers(sc)["adaptive_ct"].online.detector.fast_threshold == 6.5
    for name in mod.SCENARIOS:  # every default scenario exists
        assert (ROOT / name).is_file(), name
