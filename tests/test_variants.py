"""One law twice with two settings (an ablation): an entry of ``run.controllers`` of the user's own
name whose ``[controllers.NAME]`` table names its ``law``. Its results carry its name, its floor is
its law's, and a variant that changes nothing gives its law's numbers bit for bit."""

import json
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.report import format_report
from adaptive_dd.benchmark.scenario import load_scenario, parse_scenario
from adaptive_dd.controllers import make_controller
from adaptive_dd.controllers.registry import law_of
from adaptive_dd.errors import ParameterError, ScenarioError
from adaptive_dd.sweep_spec import load_sweep

ABLATION = """
[run]
duration = 2.0
seeds = 2
controllers = ["ct_oracle", "adaptive_ct", "no_observer", "as_is"]

[[payload]]
at = 1.0
mass = 2.0

[controllers.no_observer]
law = "adaptive_ct"
observer = false

[controllers.as_is]
law = "adaptive_ct"
"""


def _write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_law_of_reads_the_table_and_refuses_a_law_on_a_law():
    assert law_of("x", {"law": "pd", "bandwidth": 30.0}) == "pd"
    assert law_of("pd", None) == "pd" and law_of("m:C", {}) == "m:C"
    with pytest.raises(ParameterError, match=r"adaptive_ct\.law: 'adaptive_ct' is a law already"):
        law_of("adaptive_ct", {"law": "pd"})
    with pytest.raises(ParameterError, match=r"controllers\.x\.law: .* got 'nope'"):
        law_of("x", {"law": "nope"})


def test_make_controller_builds_the_law_under_the_variants_name():
    c = make_controller("no_obs", options={"law": "adaptive_ct", "observer": False})
    base = make_controller("adaptive_ct")
    assert type(c) is type(base) and c.name == "no_obs" and c.floor == base.floor == "ct_oracle"
    labelled = make_controller("no_obs", options={"law": "adaptive_ct", "label": "AC-noobs"})
    assert labelled.name == "AC-noobs"
    with pytest.raises(ParameterError, match=r"controllers\.no_obs: unknown setting"):  # its table named
        make_controller("no_obs", options={"law": "adaptive_ct", "observr": False})


@pytest.mark.parametrize(
    ("table", "says"),
    [
        ("", "a name of your own whose [controllers.NAME] table names its law"),
        ('[controllers.x]\nlaw = "nope"\n', "controllers.x.law: must be a built-in name"),
        ('[controllers.x]\nlaw = "adaptive_ct"\nbandwidth = -3.0\n', "controllers.x.bandwidth"),
        ('[controllers.ct_oracle]\nlaw = "pd"\n', "controllers.ct_oracle.law: 'ct_oracle' is a law already"),
        ('[controllers.x]\nlaw = "foo:"\n', "controllers.x.law: must be a built-in name"),
        ('[controllers.x]\nlaw = "Adaptive_CT"\n', "did you mean 'adaptive_ct'?"),
        (
            '[controllers.x]\nlaw = "adaptive_ct"\ndetector = { threshold = 7.0 }\n',
            "x.detector: not a scenario key",
        ),
        (
            '[controllers.x]\nlaw = "adaptive_ct"\nlabel = "ct_oracle"\n',
            "would both carry the name 'ct_oracle'",
        ),
        (
            '[controllers.x]\nlaw = "adaptive_ct"\nlabel = 5\n',
            "controllers.x.label: the name its results carry",
        ),
        (
            '[controllers.x]\nlaw = "adaptive_ct"\nfloor = "x"\n',
            "controllers.x.floor: 'x' is this controller itself",
        ),
        (
            '[controllers.x]\nlaw = "adaptive_ct"\nlabel = "pd"\n',
            "controllers.x.label: 'pd' is a built-in's name",
        ),
    ],
)
def test_a_wrong_variant_is_an_error_of_the_file_naming_its_table(tmp_path, table, says):
    text = '[run]\nduration = 2.0\nseeds = 1\ncontrollers = ["ct_oracle", "x"]\n' + table
    with pytest.raises(ScenarioError) as err:
        load_scenario(str(_write(tmp_path, text)))
    assert says in str(err.value)


def test_a_variant_run_controllers_does_not_list_is_said_to_be_one(tmp_path):
    """A variant's table beside a run.controllers without it read "not a controller of
    run.controllers", as a misspelt table does: it says how to run it."""
    text = (
        '[run]\nduration = 2.0\nseeds = 1\ncontrollers = ["ct_oracle", "adaptive_ct"]\n'
        '[controllers.fast]\nlaw = "adaptive_ct"\nboost_bandwidth = 200.0\n'
    )
    with pytest.raises(ScenarioError, match=r"controllers\.fast: a variant of 'adaptive_ct'.*add 'fast'"):
        load_scenario(str(_write(tmp_path, text)))


def test_a_variant_runs_beside_its_law_and_one_that_changes_nothing_gives_its_numbers(tmp_path):
    from adaptive_dd import run_benchmark

    sc = load_scenario(str(_write(tmp_path, ABLATION)))
    res = run_benchmark(sc, progress=False)
    df = res.to_frame()
    df = df.sort_values(["seed", "segment"])
    per = {c: g["rms_error_rad"].to_numpy() for c, g in df.groupby("controller")}
    assert set(per) == {"ct_oracle", "adaptive_ct", "no_observer", "as_is"}
    np.testing.assert_array_equal(per["as_is"], per["adaptive_ct"])  # the same law, the same settings
    assert not np.array_equal(per["no_observer"], per["adaptive_ct"])  # its setting reached the law
    assert set(df.loc[df["controller"] == "no_observer", "floor"]) == {"ct_oracle"}
    text = format_report(res.metrics(), res)
    said = "variants: no_observer = adaptive_ct with observer = false; as_is = adaptive_ct (its defaults)"
    assert said in text


def test_a_sweep_runs_a_variant_of_its_scenario(tmp_path):
    _write(tmp_path, ABLATION, "base.toml")
    sweep = _write(
        tmp_path,
        '[sweep]\nscenario = "base.toml"\nseeds = 1\ncontrollers = ["ct_oracle", "no_observer"]\n'
        "[grid]\npayload_mass = [1.0, 2.0]\n",
        "sweep.toml",
    )
    spec = load_sweep(str(sweep))
    assert "no_observer" in spec.controllers
    from adaptive_dd.sweep import run_cell

    point = spec.points[0]  # 1 kg: the cell runs the variant, its table's setting applied
    rows = run_cell(point.scenario, "no_observer", [0], point.settings_for("no_observer"))
    same = run_cell(point.scenario, "adaptive_ct", [0], {"observer": False})
    base = run_cell(point.scenario, "adaptive_ct", [0])
    assert [r["rms_error"] for r in rows] == [r["rms_error"] for r in same]
    assert [r["rms_error"] for r in rows] != [r["rms_error"] for r in base]
    grid_law = _write(
        tmp_path,
        '[sweep]\nscenario = "base.toml"\n[grid]\npayload_mass = [1.0]\n[grid.controller.adaptive_ct]\n'
        'law = ["pd"]\n',
        "law.toml",
    )
    with pytest.raises(ScenarioError, match=r"grid\.controller\.adaptive_ct\.law': a law is not a grid axis"):
        load_sweep(str(grid_law))


def test_a_variant_is_not_a_law_outside_a_scenario_that_names_it():
    with pytest.raises(ScenarioError, match="unknown controller 'no_observer'"):
        parse_scenario({"run": {"duration": 1.0, "controllers": ["ct_oracle", "no_observer"]}})


def test_law_on_a_plugins_own_table_is_an_error_of_the_file(tmp_path):
    text = (
        '[run]\nduration = 2.0\nseeds = 1\ncontrollers = ["ct_oracle", "my_laws:MyPD"]\n'
        '[controllers.MyPD]\nlaw = "adaptive_ct"\n'
    )
    with pytest.raises(ScenarioError, match=r"controllers\.MyPD\.law: 'my_laws:MyPD' is a law already"):
        load_scenario(str(_write(tmp_path, text)))


def test_a_sweep_names_a_plugins_variant_as_a_plugin(tmp_path):
    plugin = (
        "class P:\n    def reset(self, n, T): pass\n    def command(self, q, qd, a, b, c): return 0 * q\n"
    )
    plugin += "    def observe(self, q, qd, tau): pass\n"
    (tmp_path / "p_mod.py").write_text(plugin)
    base = '[run]\nduration = 2.0\nseeds = 1\ncontrollers = ["ct_oracle", "pv"]\n'
    base += '[controllers.pv]\nlaw = "p_mod:P"\n'
    _write(tmp_path, base, "base.toml")
    sweep = _write(tmp_path, '[sweep]\nscenario = "base.toml"\n[grid]\npayload_mass = [1.0]\n', "sweep.toml")
    with pytest.raises(ScenarioError, match=r"'pv' is a plug-in \(p_mod:P\); a sweep runs built-in"):
        load_sweep(str(sweep))


def test_with_settings_adds_a_variant_and_judges_its_law():
    from adaptive_dd.benchmark.scenario_settings import with_settings

    sc = parse_scenario({"run": {"duration": 1.0, "controllers": ["ct_oracle", "adaptive_ct"]}})
    out = with_settings(sc, "no_boost", {"law": "adaptive_ct", "boost_duration": 0.0})
    assert out.controllers == ("ct_oracle", "adaptive_ct", "no_boost")
    assert out.options("no_boost") == {"law": "adaptive_ct", "boost_duration": 0.0}
    with pytest.raises(ScenarioError, match=r"controllers\.nb\.law: .*got 'nope'"):
        with_settings(sc, "nb", {"law": "nope"})


def test_the_leaderboard_ranks_a_variant_every_scenario_defines_and_says_one_it_does_not(tmp_path, capsys):
    from adaptive_dd.cli import main

    path = _write(tmp_path, ABLATION)
    # a variant no given scenario defines: refused before any run
    assert (
        main(["leaderboard", str(path), "--controllers", "adaptive_ct", "nope", "--out", str(tmp_path)]) == 2
    )
    err = capsys.readouterr().err
    assert "--controllers: unknown controller 'nope'" in err
    assert "define(s) the variant 'no_observer', not ranked" in err


def _short_vertical3_with_a_variant(tmp_path):
    from importlib import resources

    text = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload_exact.toml").read_text()
    text = text.replace("duration = 16.0", "duration = 1.6").replace("ramp = 1.0", "ramp = 0.2")
    head, _, _ = text.partition("[[payload]]")
    body = (
        '[[payload]]\nat = 0.8\nmass = 1.0\n\n[controllers.no_obs]\nlaw = "adaptive_ct"\nobserver = false\n'
    )
    import re

    head = re.sub(r"(?m)^controllers = \[.*\]$", 'controllers = ["ct_oracle", "adaptive_ct", "no_obs"]', head)
    path = tmp_path / "v3.toml"
    path.write_text(head + body)
    return path


def test_the_leaderboard_ranks_a_variant_its_scenario_defines(tmp_path, capsys):
    from adaptive_dd.cli import main

    path = _short_vertical3_with_a_variant(tmp_path)
    out = tmp_path / "lb"
    argv = ["leaderboard", str(path), "--seeds", "1", "--workers", "1", "--no-progress", "--out", str(out)]
    assert main([*argv, "--controllers", "adaptive_ct", "no_obs"]) == 0
    rows = json.loads((out / "leaderboard.json").read_text())["rows"]
    ranked = {(r["controller"], r["floor"]) for r in rows}
    assert ("no_obs", "ct_oracle") in ranked and ("adaptive_ct", "ct_oracle") in ranked
    capsys.readouterr()
    # with --arms the drawn arms run the template's tables, which do not define it: refused at once
    assert main([*argv, "--controllers", "no_obs", "--arms", "1"]) == 2
    err = capsys.readouterr().err
    assert "unknown controller 'no_obs'" in err  # and which file lacks it, with the remedy
    assert "population.toml do(es) not define it; the drawn arms' template is --template FILE" in err
    assert main([*argv, "--controllers", "adaptive_cd"]) == 2  # a typo: the nearest name
    assert "unknown controller 'adaptive_cd' (did you mean 'adaptive_ct'?)" in capsys.readouterr().err


def test_a_variant_of_a_law_told_the_true_model_is_a_reference_not_a_contender():
    """ct_oracle_late told 5 ms late as a variant: its row has a floor, and it is told the true model
    by its law (the leaderboard's ``law`` column), so it is shown beside the contenders, not ranked."""
    import pandas as pd

    from adaptive_dd.arena.columns import contenders, told_the_model

    df = pd.DataFrame(
        {
            "controller": ["ct_oracle_late", "late_5ms", "no_boost"],
            "law": ["ct_oracle_late", "ct_oracle_late", "adaptive_ct"],
            "floor": ["ct_oracle", "ct_oracle", "ct_oracle"],
        }
    )
    assert told_the_model(df).tolist() == [True, True, False]
    assert contenders(df).tolist() == [False, False, True]
    assert told_the_model(df.drop(columns="law")).tolist() == [True, False, False]  # by name alone


def test_an_identified_prior_reaches_every_variant_of_adaptive_ct(tmp_path):
    """After an excitation phase or [model] from, the identified prior went to the entry named
    adaptive_ct alone: a variant that changes nothing then ran with another prior."""
    from adaptive_dd.closed_loop.model_prior import identified_prior

    sc = load_scenario(str(_short_vertical3_with_a_variant(tmp_path)))
    opts = dict(identified_prior(sc, 1e-6 * np.eye(sc.arm.base.count)))
    for name in ("adaptive_ct", "no_obs"):
        est = dict(dict(opts[name])["estimator"])
        assert {"arm_prior_cov", "p0_arm", "payload_mass_std"} <= set(est), name
    assert "ct_oracle" not in opts


def test_the_variants_line_names_what_differs_from_the_law_as_it_runs_here(tmp_path):
    from adaptive_dd.benchmark.controller_entries import variants_line

    text = (
        '[run]\nduration = 2.0\nseeds = 1\ncontrollers = ["ct_oracle", "adaptive_ct", "nb", "same", "bare"]\n'
        "[controllers.adaptive_ct]\nobserver = false\n"
        '[controllers.nb]\nlaw = "adaptive_ct"\nobserver = false\nboost_duration = 0.0\n'
        '[controllers.same]\nlaw = "adaptive_ct"\nobserver = false\n'
        '[controllers.bare]\nlaw = "adaptive_ct"\n'
    )
    line = variants_line(load_scenario(str(_write(tmp_path, text))))
    assert "nb = adaptive_ct with boost_duration = 0.0;" in line
    assert "same = adaptive_ct (as adaptive_ct runs here)" in line
    assert "bare = adaptive_ct with observer = its default" in line


def test_the_leaderboard_refuses_a_variant_the_shipped_scenarios_lack(tmp_path, capsys):
    """No scenario given: the shipped ones run, which define no variant; one only the template
    defines is refused before any run (it failed on the first shipped scenario)."""
    from adaptive_dd.cli import main

    root = Path(__file__).resolve().parents[1]
    text = (root / "benchmarks" / "scenarios" / "population.toml").read_text()
    text = text.replace(
        'controllers = ["ct_oracle", "adaptive_ct"]', 'controllers = ["ct_oracle", "adaptive_ct", "nob"]'
    )
    tmpl = _write(tmp_path, text + '\n[controllers.nob]\nlaw = "adaptive_ct"\n', "tmpl.toml")
    argv = [
        "leaderboard",
        "--arms",
        "1",
        "--template",
        str(tmpl),
        "--seeds",
        "1",
        "--out",
        str(tmp_path / "o"),
    ]
    assert main([*argv, "--controllers", "nob"]) == 2
    assert "--controllers: unknown controller 'nob'" in capsys.readouterr().err
    bad = _write(tmp_path, "run = 5\n", "bad.toml")  # a malformed scenario: its own error, not a crash
    assert main(["leaderboard", str(bad), "--out", str(tmp_path / "o2")]) == 2
    assert "run: must be a table" in capsys.readouterr().err


def test_the_docs_variants_snippet_is_a_scenario_that_loads(tmp_path):
    """docs/controllers.md's TOML of "One law twice: variants" (it listed a variant without its table)."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "controllers.md").read_text()
    start = text.index("```toml", text.index("## One law twice: variants")) + len("```toml")
    sc = load_scenario(str(_write(tmp_path, text[start : text.index("```", start)])))
    assert sc.controllers[-3:] == ("no_observer", "no_boost", "long_boost")
