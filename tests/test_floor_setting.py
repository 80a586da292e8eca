"""``[controllers.NAME] floor``: a controller measured against another of the run, named as its
results are (a label, a built-in's name, a plug-in's declared name), through the command line."""

from pathlib import Path

import pytest

from adaptive_dd.cli import main
from adaptive_dd.errors import ScenarioError

ROOT = Path(__file__).resolve().parent.parent
LABELLED = """
[run]
duration = 1.0
seeds = 1
controllers = ["ct_oracle", "ct_nominal"]
[controllers.ct_oracle]
label = "oracle"
[controllers.ct_nominal]
floor = "oracle"
[[payload]]
at = 0.5
mass = 1.0
"""


@pytest.mark.slow  # a cold compile of its own path; the rest of the file covers the check
def test_a_floor_named_by_its_label_runs_from_the_command_line(tmp_path, capsys):
    """The command line compared the floor with run.controllers' entries: it added 'oracle' as a
    controller to run, then failed on it as unknown."""
    path = tmp_path / "lab.toml"
    path.write_text(LABELLED)
    assert main(["benchmark", str(path), "--no-progress", "--out", str(tmp_path / "o")]) == 0
    out, err = capsys.readouterr()
    assert "(floor: oracle)" in out and "added" not in err
    assert (
        main(
            [
                "benchmark",
                str(path),
                "--controllers",
                "ct_nominal",
                "--no-progress",
                "--out",
                str(tmp_path / "p"),
            ]
        )
        == 0
    )
    assert "--controllers: ct_oracle added (the floor of ct_nominal)" in capsys.readouterr().err


def test_a_floor_named_by_an_entry_of_the_list_says_the_name_results_carry(tmp_path):
    from adaptive_dd.benchmark.scenario import load_scenario

    path = tmp_path / "spec.toml"
    path.write_text(LABELLED.replace('floor = "oracle"', 'floor = "ct_oracle"'))
    with pytest.raises(
        ScenarioError,
        match=r"controllers.ct_nominal.floor: name 'ct_oracle' by the name its results carry, 'oracle'",
    ):
        load_scenario(path)


def test_a_plug_in_that_does_not_import_is_a_problem_of_validate_not_an_internal_error(tmp_path, capsys):
    """Reading a scenario imported every plug-in to learn its name, even with no floor set: a module
    raising on import escaped as an internal error."""
    (tmp_path / "gpuplug.py").write_text('raise RuntimeError("needs a GPU")\n')
    path = tmp_path / "gp.toml"
    path.write_text(
        LABELLED.replace('"ct_nominal"]', '"gpuplug:Law"]').replace(
            '[controllers.ct_nominal]\nfloor = "oracle"', ""
        )
    )
    assert main(["validate", str(path)]) == 1
    out, err = capsys.readouterr()
    assert "controller 'gpuplug:Law': RuntimeError: needs a GPU" in err and "internal error" not in out + err


def test_a_sweep_varying_a_controller_keeps_its_floor(tmp_path):
    """A cell runs one controller of the list: its floor was judged on the cell, and refused."""
    from adaptive_dd.sweep_spec import load_sweep

    (tmp_path / "base.toml").write_text(
        LABELLED.replace('floor = "oracle"', 'floor = "oracle"\nbandwidth = 30.0')
    )
    (tmp_path / "sw.toml").write_text(
        '[sweep]\nscenario = "base.toml"\nseeds = 1\ncontrollers = ["ct_oracle", "ct_nominal"]\n'
        "[grid]\npayload_mass = [1.0]\n[grid.controller.ct_nominal]\nbandwidth = [30.0, 40.0]\n"
    )
    assert len(load_sweep(tmp_path / "sw.toml").points) == 2
