"""A plug-in's floor is added to the run as a built-in's is: the documented default (``ct_oracle``)
for a plug-in that declares none, and a built-in floor named in its table though the run does not
list it. Both were left out by ``adaptive-dd benchmark`` (the plug-in vanished from every ratio
table with a warning) or refused by the scenario's checks."""

from pathlib import Path

import pytest

from adaptive_dd.benchmark.preflight import missing_floors
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.errors import ScenarioError

PLUGINS = Path(__file__).resolve().parent.parent / "examples" / "plugins"


@pytest.fixture
def folder(tmp_path):
    """A folder with a copy of examples/plugins' compiled plug-in whose class declares no floor (the
    module forgotten before and after: each test imports its own file)."""
    import sys

    lines = (PLUGINS / "pd_gravity_plugin.py").read_text().splitlines(keepends=True)
    kept = [x for x in lines if not x.startswith('    floor = "pd_gravity_oracle"')]
    assert len(kept) == len(lines) - 1
    (tmp_path / "nofloor_plugin.py").write_text("".join(kept))
    sys.modules.pop("nofloor_plugin", None)
    yield tmp_path
    sys.modules.pop("nofloor_plugin", None)


def _scenario(folder, table: str = ""):
    """examples/plugins/pd_gravity.toml (vertical3) with the plug-in alone, written beside it."""
    text = (PLUGINS / "pd_gravity.toml").read_text()
    start = text.index("controllers = [")
    end = text.index("\n", start)
    text = text[:start] + 'controllers = ["nofloor_plugin:PDGravityPlugin"]' + text[end:]
    text = text.replace("[controllers.PDGravityPlugin]\n", f"[controllers.PDGravityPlugin]\n{table}\n")
    path = folder / "scenario.toml"
    path.write_text(text)
    return load_scenario(str(path))


def test_a_plugin_without_a_floor_gets_ct_oracle_added(folder):
    sc = _scenario(folder)
    add, cannot = missing_floors(sc)
    assert add == {"ct_oracle": ["nofloor_plugin:PDGravityPlugin"]} and not cannot


def test_a_builtin_floor_in_the_table_is_added_not_refused(folder):
    sc = _scenario(folder, 'floor = "pd_gravity_oracle"')
    assert missing_floors(sc)[0] == {"pd_gravity_oracle": ["nofloor_plugin:PDGravityPlugin"]}
    with pytest.raises(ScenarioError, match=r"floor: 'nosuch' is not one of the run's controllers"):
        _scenario(folder, 'floor = "nosuch"')


def test_a_plugin_file_shadowed_by_an_installed_module_is_named(tmp_path):
    """control.py beside a scenario naming "control:GlobLaw" read "module 'control' has no 'GlobLaw'":
    python-control, a dependency, is found first, and the message did not say which file it read."""
    from adaptive_dd.controllers.plugins import load_controller_class
    from adaptive_dd.errors import ParameterError

    (tmp_path / "control.py").write_text("class GlobLaw:\n    pass\n")
    with pytest.raises(ParameterError) as exc:
        load_controller_class("control:GlobLaw", (tmp_path,))
    text = str(exc.value)
    assert "site-packages" in text and "module 'control'" in text
    assert f"before your {tmp_path / 'control.py'}" in text and "rename your file, e.g. my_control.py" in text


def test_validate_reads_a_compiled_plugins_parameters_as_the_run_does(folder):
    """A compiled plug-in whose parameters() returns a dict passed validate ("valid", exit 0) and was
    refused by benchmark (exit 2): validate builds each controller as the run does, its declarations too."""
    from adaptive_dd.benchmark.preflight import controller_problems

    src = (PLUGINS / "pd_gravity_plugin.py").read_text()
    assert "    def parameters(self, sample_period):\n" in src
    bad = src.replace(
        "    def parameters(self, sample_period):\n",
        "    def parameters(self, sample_period):\n        return {'kp': 1.0}\n\n"
        "    def _old(self, sample_period):\n",
    )
    (folder / "nofloor_plugin.py").write_text(bad)
    (problem,) = controller_problems(_scenario(folder))
    assert "parameters(0.001) returned a dict, which numba cannot compile" in problem
