"""The report and ``adaptive-dd validate`` say which kernels a run takes and why
(``benchmark.scenario.runtime_line``): an arm of the paper's geometry silently took the closed
forms before; ``metrics.json`` records the same choice (``provenance.runtime``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from adaptive_dd import load_scenario
from adaptive_dd.benchmark.provenance import provenance
from adaptive_dd.benchmark.scenario import runtime_line
from adaptive_dd.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "benchmarks" / "scenarios"


@pytest.mark.parametrize(
    ("path", "expected"),
    [
        (None, "the paper's two-link closed forms"),
        (SCENARIOS / "sice_urdf.toml", "the paper's two-link closed forms"),
        (SCENARIOS / "sice_general.toml", "general N-joint kernels (2 joints; [arm] general = true)"),
        (
            SCENARIOS / "sice_drawn.toml",
            "general N-joint kernels (2 joints; [arm] general = true; a plant apart from the arm ([plant]))",
        ),
        (
            ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml",
            "(6 joints; the arm is not of the paper's geometry)",
        ),
        (
            SCENARIOS / "cad_error" / "ur5_cad_error.toml",
            "(6 joints; the arm is not of the paper's geometry; a plant apart from the arm ([plant]))",
        ),
    ],
)
def test_the_line_names_the_kernels_and_why(path, expected):
    sc = load_scenario(path) if path else load_scenario()
    line = runtime_line(sc)
    assert line.startswith("runtime: ") and expected in line
    # the line follows the choice the scenario made (a planted fault: the line from the arm alone)
    assert ("closed forms" in line) == (sc.closed_forms is not None)


def test_validate_prints_it(capsys):
    assert main(["validate", str(SCENARIOS / "sice_urdf.toml")]) == 0
    out = capsys.readouterr().out
    assert "# runtime: the paper's two-link closed forms" in out and 'add `robot = "sice_arm"`' in out


def test_the_provenance_records_it():
    class _Res:  # what provenance reads of a result
        def __init__(self, sc):
            self.scenario, self.seed_indices, self.wall_time, self.runs = sc, [0], 0.0, {}

    default = load_scenario()
    general = dataclasses.replace(load_scenario(SCENARIOS / "sice_general.toml"), seeds=1)
    assert provenance(_Res(default))["runtime"] == "closed_forms"
    assert provenance(_Res(general))["runtime"] == "general"
