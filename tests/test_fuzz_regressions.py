"""What the scenario fuzzer (benchmarks/fuzz_scenarios.py --n 2000) found, held fixed (issue 27):
at --seed 0 three crashes ``TypeError: unhashable type: 'list'`` (``[arm] robot = [...]``), at
--seed 1 ``controllers.slotine_li.gamma = {threshold = -1.0}`` accepted on a URDF arm."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import pytest

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.errors import ScenarioError

ROOT = Path(__file__).resolve().parent.parent
UR5 = Path(str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml")))


@pytest.mark.parametrize("value", ["[]", "[1, 2, 3]", "{ a = 1 }", "3", "true"])
def test_a_robot_that_is_not_a_name_is_a_scenario_error(tmp_path, value):
    path = tmp_path / "s.toml"
    path.write_text(UR5.read_text().replace('robot = "ur5"', f"robot = {value}"))
    with pytest.raises(ScenarioError, match=r"s\.toml: key 'arm\.robot' = .* is not a shipped robot"):
        load_scenario(path)


@pytest.mark.parametrize(
    "gamma",
    [
        "{ threshold = -1.0 }",
        "[1.0, 2.0]",
        "[" + ", ".join(["1.0"] * 9) + ", -1.0]",
        '"fast"',
        "[true" + ", 1" * 9 + "]",
    ],
)
@pytest.mark.parametrize("arm", ["urdf", "two_link"])
def test_a_slotine_li_gamma_that_is_not_positive_gains_is_a_scenario_error(tmp_path, gamma, arm):
    src = UR5 if arm == "urdf" else ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml"
    path = tmp_path / "s.toml"
    path.write_text(src.read_text() + f"\n[controllers.slotine_li]\ngamma = {gamma}\n")
    with pytest.raises(ScenarioError, match=r"s\.toml: controllers\.slotine_li.*gamma"):
        load_scenario(path)


def test_slotine_li_settings_that_are_numbers_still_load(tmp_path):
    path = tmp_path / "s.toml"
    gains = ", ".join(["1.0"] * 10)
    path.write_text(UR5.read_text() + f"\n[controllers.slotine_li]\ngamma = [{gains}]\nmax_mass = 8\n")
    assert load_scenario(path).options("slotine_li") == {"gamma": [1.0] * 10, "max_mass": 8}
