"""Real arms' URDFs named "example-robot-data:PATH" in a scenario (adaptive_dd.robots.example_robot_data),
and the shipped scenarios of arms nobody here tuned for (benchmarks/scenarios/example_robot_data)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import load_scenario, parse_scenario, read_toml
from adaptive_dd.errors import ParameterError, ScenarioError
from adaptive_dd.robots import example_robot_data as E

ROOT = Path(__file__).resolve().parent.parent
FOLDER = ROOT / "benchmarks" / "scenarios" / "example_robot_data"
SCENARIOS = sorted(FOLDER.glob("*.toml"))


@pytest.fixture(scope="module")
def robots():
    try:
        return E.robots_folder()
    except ParameterError as exc:  # the optional package (the robots and test extras)
        pytest.skip(str(exc))


def test_a_name_resolves_to_the_packages_file(robots):
    path = E.urdf_path("example-robot-data:z1_description/urdf/z1.urdf")
    assert path == robots / "z1_description" / "urdf" / "z1.urdf" and path.is_file()


@pytest.mark.parametrize(
    ("name", "listed", "not_listed"),
    [
        (
            "xarm_description/urdf/xarm8.urdf",
            "the URDFs of xarm_description: xarm_description/urdf/xarm7.urdf",
            "z1",
        ),
        ("nope/x.urdf", "its description folders: ", "z1_description/urdf/z1.urdf"),  # the folders
        ("xarm_description/urdf", "xarm7.urdf", None),  # a folder is no file
        ("", "its description folders: ", None),
    ],
)
def test_an_unknown_name_lists_what_there_is(robots, name, listed, not_listed):
    with pytest.raises(ParameterError, match="no such URDF in example-robot-data") as exc:
        E.urdf_path(f"example-robot-data:{name}")
    assert repr(f"example-robot-data:{name}") in str(exc.value) and listed in str(exc.value)
    if not_listed:
        assert not_listed not in str(exc.value)
    if "folders" in listed:  # every folder with a URDF, e.g. kinova's (its URDFs under robots/)
        assert "z1_description" in str(exc.value) and "kinova_description" in str(exc.value)


@pytest.mark.parametrize("name", ["../package.xml", "/etc/hostname", "C:/x.urdf", "..\\package.xml"])
def test_a_name_never_leaves_the_robots_folder(robots, name):
    """Each of these is an existing file (or a drive) outside the folder if joined as it is."""
    assert (robots.parent / "package.xml").is_file()
    with pytest.raises(ParameterError, match="no such URDF in example-robot-data"):
        E.urdf_path(f"example-robot-data:{name}")


def test_without_the_package_the_error_says_how_to_install_it(monkeypatch):
    import importlib.metadata
    import sys

    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "distribution", missing)
    monkeypatch.setitem(sys.modules, "example_robot_data", None)  # an import of it fails
    with pytest.raises(ParameterError, match=r"example-robot-data is not installed: pip install"):
        E.urdf_path("example-robot-data:z1_description/urdf/z1.urdf")
    data = {"arm": {"urdf": "example-robot-data:z1_description/urdf/z1.urdf"}}
    with pytest.raises(ScenarioError, match=r"s\.toml: key 'arm\.urdf': example-robot-data is not installed"):
        parse_scenario(data, "s.toml")


def test_only_the_prefix_names_the_package():
    assert E.is_example_robot_data("example-robot-data:a.urdf")
    assert not E.is_example_robot_data("robots/example-robot-data:a.urdf") and not E.is_example_robot_data(3)
    with pytest.raises(ParameterError, match="does not start with"):
        E.urdf_path("z1.urdf")


def test_a_scenario_names_a_bad_one_by_file_and_key(robots):
    data = read_toml(FOLDER / "z1.toml")
    data["arm"]["urdf"] = "example-robot-data:z1_description/urdf/z2.urdf"
    with pytest.raises(
        ScenarioError, match=r"s\.toml: key 'arm\.urdf': .*z2\.urdf.*z1_description/urdf/z1\.urdf"
    ):
        parse_scenario(data, "s.toml")
    data = read_toml(FOLDER / "z1_drawn.toml")
    data["plant"]["urdf"] = "example-robot-data:nope.urdf"
    with pytest.raises(ScenarioError, match=r"s\.toml: key 'plant\.urdf': 'example-robot-data:nope\.urdf'"):
        parse_scenario(data, "s.toml")


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_the_shipped_scenarios_load(robots, path):
    sc = load_scenario(str(path))
    assert sc.arm.urdf is not None and Path(sc.arm.urdf).is_relative_to(robots)
    assert sc.n_joints == {"ur3": 6, "ur10": 6, "xarm7": 7, "z1": 6}[path.stem.removesuffix("_drawn")]
    assert sc.arm.payload_capacity > 0 and (sc.excite > 0) == path.stem.endswith("_drawn")


def test_both_variants_are_the_same_task():
    """Each arm's exact and drawn scenarios differ only by the drawn plant and the excitation phase."""
    stems = {p.stem for p in SCENARIOS}
    assert {f"{s}_drawn" for s in stems if not s.endswith("_drawn")} == {
        s for s in stems if s.endswith("_drawn")
    }
    for stem in (s for s in stems if not s.endswith("_drawn")):
        a, b = read_toml(FOLDER / f"{stem}.toml"), read_toml(FOLDER / f"{stem}_drawn.toml")
        b.pop("plant")
        b["run"].pop("excite")
        assert a == b, stem


@pytest.mark.slow
def test_an_arm_nobody_tuned_for_meets_the_targets(robots):
    """The xArm 7 as its URDF, defaults only, 4 seeds: adaptive_ct within 1.1x its floor per segment
    on average (1.3x per seed), no false alarm, no missed swap."""
    import dataclasses

    from adaptive_dd.benchmark.runner import run_benchmark

    sc = load_scenario(str(FOLDER / "xarm7.toml"))

    res = run_benchmark(dataclasses.replace(sc, seeds=4), progress=False, keep_trajectories=0)
    a, o = res.runs["adaptive_ct"], res.runs["ct_oracle"]
    ratio = np.sqrt(a.acc.sum_e2 / o.acc.sum_e2)  # (seeds, segments)
    assert ratio.shape == (4, 4)
    assert np.all(ratio.mean(axis=0) <= 1.1) and np.all(ratio <= 1.3), ratio
    swaps = [t for t, _, _ in sc.segments()[1:]]
    for s in range(4):
        alarms = np.asarray(a.alarm_times[s], float)
        assert all(np.any((alarms >= t) & (alarms < t + 0.3)) for t in swaps), (s, alarms)
        assert all(any(t <= x < t + 0.3 for t in swaps) for x in alarms), (s, alarms)  # no false alarm


def test_validate_prints_what_the_vendors_file_had_that_is_unusual(robots, capsys):
    from adaptive_dd.cli import main

    assert main(["validate", str(FOLDER / "ur3.toml")]) == 0
    out = capsys.readouterr().out
    assert "# note: link 'tool0': mass 0 kg and no inertia: a massless frame (kept)" in out
    assert f"# arm: {robots / 'ur_description' / 'urdf' / 'ur3_robot.urdf'} (6 joints" in out


@pytest.mark.parametrize(
    "value", ["example_robot_data:z1_description/urdf/z1.urdf", "example-robot-data/z1.urdf"]
)
def test_a_misspelt_prefix_is_told_the_right_one(value):
    with pytest.raises(
        ScenarioError, match=r"s\.toml: key 'arm\.urdf' = .*no such file; .*\"example-robot-data:PATH\""
    ):
        parse_scenario({"arm": {"urdf": value}}, "s.toml")


def test_plant_and_model_take_the_prefix_too(robots):
    """[plant] urdf and [model] from name example-robot-data's files as [arm] urdf does (here the arm's
    own URDF: the same joints and frames); a wrong one is an error naming its key."""
    ur3 = "example-robot-data:ur_description/urdf/ur3_robot.urdf"
    data = read_toml(FOLDER / "ur3.toml")
    data["plant"] = {"urdf": ur3}
    data["model"] = {"from": ur3}
    sc = parse_scenario(data, "s.toml")
    assert sc.n_joints == 6
    data["model"] = {"from": "example-robot-data:ur_description/urdf/ur3.json"}
    with pytest.raises(
        ScenarioError, match=r"s\.toml: key 'model\.from': .*ur3\.json.*the URDFs of ur_description"
    ):
        parse_scenario(data, "s.toml")
    data["model"] = {"from": "example-robot-data:ur_description/urdf/ur10_robot.urdf"}
    with pytest.raises(ScenarioError, match=r"s\.toml: key 'model\.from'.*same joints and frames"):
        parse_scenario(data, "s.toml")


@pytest.mark.parametrize("table", ["plant", "model"])
def test_validate_prints_the_plants_urdf_notes_too(robots, table):
    """The plant's URDF is read and checked like the [arm]'s, and what it had that is unusual is said:
    a [plant] urdf, or the [arm]'s own file when [model] from gives the controllers another (the [arm]
    then is the plant). A plant from the [arm] itself adds nothing (its notes are the arm's)."""
    from adaptive_dd.benchmark.scenario import format_scenario

    ur3 = "example-robot-data:ur_description/urdf/ur3_robot.urdf"
    data = read_toml(FOLDER / "ur3.toml")
    data.pop("plant", None)
    plain = format_scenario(parse_scenario(data, "s.toml"))
    data["plant" if table == "plant" else "model"] = {"urdf": ur3} if table == "plant" else {"from": ur3}
    text = format_scenario(parse_scenario(data, "s.toml"))
    assert "# plant note: link 'tool0': mass 0 kg and no inertia: a massless frame (kept)" in text
    assert "# plant note:" not in plain
