"""Scenario files: the shipped default, the reference, and every error naming file and key."""

from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import default_scenario_path, load_scenario, parse_scenario
from adaptive_dd.errors import ScenarioError

GOOD = """
[run]
duration = 4.0
sample_period = 0.001
seeds = 2
controllers = ["ct_oracle", "adaptive_ct"]

[reference]
joint1 = { offset = 0.1, amplitude = [0.3], frequency = [0.5], phase = [0.0] }
joint2 = { offset = 0.0, amplitude = [0.3], frequency = [0.7], phase = [0.5] }

[[payload]]
at = 2.0
mass = 1.0
"""


def write(tmp_path, text):
    p = tmp_path / "s.toml"
    p.write_text(text)
    return p


def test_default_scenario_is_the_issue_s():
    sc = load_scenario()
    assert default_scenario_path().is_file()
    assert sc.duration == 20.0 and sc.sample_period == 0.001 and sc.seeds == 10
    assert sc.segments() == [(0.0, 5.0, 0.0), (5.0, 10.0, 3.0), (10.0, 15.0, 1.0), (15.0, 20.0, 0.0)]
    assert len(sc.controllers) == 7 and "slotine_li_oracle" in sc.controllers


def test_reference_derivatives_and_ramp():
    sc = load_scenario()
    t = np.arange(0, 6, 1e-3)
    q, qd, qdd = sc.reference.sample(t)
    np.testing.assert_allclose(
        np.gradient(q, 1e-3, axis=0)[5:-5], qd[5:-5], atol=5e-5
    )  # O(h^2) error of np.gradient
    # the quintic ramp is C^2: its third derivative jumps at t = 1 s, where the numerical
    # derivative of qd is off by O(h jump); leave those few samples out
    keep = np.ones(t.size, bool)
    keep[:5], keep[-5:], keep[990:1010] = False, False, False
    np.testing.assert_allclose(np.gradient(qd, 1e-3, axis=0)[keep], qdd[keep], atol=1e-3)
    np.testing.assert_allclose(q[0], 0.0)
    np.testing.assert_allclose(qd[0], 0.0)  # starts at rest: the ramp


def test_good_file(tmp_path):
    sc = load_scenario(write(tmp_path, GOOD))
    assert sc.controllers == ("ct_oracle", "adaptive_ct")
    assert sc.segments() == [(0.0, 2.0, 0.0), (2.0, 4.0, 1.0)]
    assert sc.reference.sample(np.zeros(1))[0][0, 0] == pytest.approx(0.1)


@pytest.mark.parametrize(
    "edit, match",
    [
        (("seeds = 2", "seeds = 2\nspeed = 3"), "run.speed: unknown key"),
        (("[run]", "[runs]\n[run]"), "\\[runs\\]: unknown table"),
        (('"adaptive_ct"]', '"adaptive_cta"]'), "unknown controller 'adaptive_cta'"),
        (("mass = 1.0", "mass = -1.0"), "payload\\[0\\].mass: must be in \\[0, 50\\]"),
        (("at = 2.0", "at = 5.0"), "payload\\[0\\].at: must be in \\(0, 3.999\\]"),
        (
            ("at = 2.0\nmass = 1.0", "at = 2.0\nmass = 1.0\n[[payload]]\nat = 1.0\nmass = 3.0"),
            "must increase",
        ),
        (
            ("amplitude = [0.3], frequency = [0.5]", "amplitude = [0.3, 0.1], frequency = [0.5]"),
            "equal lengths",
        ),
        (("duration = 4.0", "duration = -4.0"), "run.duration: must be in \\(0, inf\\]"),
        (("seeds = 2", "seeds = 2.5"), "run.seeds: must be an integer"),
        (("duration = 4.0", "duration = 4.0 ="), "not valid TOML"),
    ],
)
def test_scenario_errors_name_file_and_key(tmp_path, edit, match):
    p = write(tmp_path, GOOD.replace(*edit))
    with pytest.raises(ScenarioError, match=match) as e:
        load_scenario(p)
    assert str(p) in str(e.value)


def test_a_payload_key_misspelt_is_one_error_with_its_index(tmp_path):
    """A typo in one [[payload]] entry is named with the entry's index and the key meant, and
    its com/inertia do not go on to misalign every other payload's (the entry is not a change)."""
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml

    data = read_toml(default_scenario_path().parent / "ur5_tool_swap.toml")
    data["payload"][1]["mas"] = data["payload"][1].pop("mass")
    with pytest.raises(ScenarioError) as e:
        parse_scenario(data, "u.toml")
    msg = str(e.value)
    assert "payload[1].mas: unknown key (did you mean 'mass'?)" in msg
    assert "payload[1].mass: missing" in msg
    assert "swap_com" not in msg and "swap_inertia" not in msg and "2 errors" in msg


@pytest.mark.parametrize("first", ["joint1", "shoulder_pan_joint"])
def test_a_joint_given_by_number_and_by_name_is_named_once(first):
    """Either order: the error names the pair, not 'not a joint of this arm'."""
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml

    data = read_toml(default_scenario_path().parent / "ur5_tool_swap.toml")
    spec = data["reference"].pop("joint1")
    other = "shoulder_pan_joint" if first == "joint1" else "joint1"
    data["reference"] = {first: spec, other: dict(spec), **data["reference"]}
    with pytest.raises(ScenarioError) as e:
        parse_scenario(data, "u.toml")
    msg = str(e.value)
    assert "reference.shoulder_pan_joint: the same joint as reference.joint1" in msg
    assert "not a joint" not in msg


def test_missing_scenario_file(tmp_path):
    with pytest.raises(ScenarioError, match="no such scenario file"):
        load_scenario(tmp_path / "none.toml")
    with pytest.raises(ScenarioError, match="is a folder, not a scenario file"):
        load_scenario(tmp_path)


def test_a_urdf_arm_s_sensors_carry_the_scenario_s_noise():
    """What reads ``arm.sensor`` (the detector's noise rise, identification on the arm) reads the
    ``[noise]`` the run draws, not the URDF arm's defaults (5e-5 (rad/s)^2): the paper's
    arm drawn states 1e-4 for joint 2. Fails if parse_scenario keeps the URDF's sensors."""
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
    from adaptive_dd.identification.online import OnlineConfig, est_init

    src = default_scenario_path().parent / "ur5_tool_swap.toml"
    data = read_toml(src)
    data["run"]["controllers"] = ["adaptive_ct"]
    vv = [5e-5, 4e-4, 5e-5, 5e-5, 5e-5, 5e-5]
    data["noise"] = {"position_variance": [1e-7] * 6, "velocity_variance": vv}
    sc = parse_scenario(data, str(src))
    assert sc.arm.sensor.velocity_variance == (5e-5, 4e-4, 5e-5, 5e-5, 5e-5, 5e-5)
    assert sc.arm.sensor.position_variance == (1e-7,) * 6
    c, _ = est_init(OnlineConfig(sample_period=sc.sample_period), sc.arm, 1)
    assert np.array_equal(c.vdet, vv)  # the detector's noise rise reads the stated noise
    root = Path(__file__).resolve().parents[1]
    drawn = load_scenario(root / "benchmarks" / "scenarios" / "sice_drawn.toml")
    assert drawn.arm.sensor.velocity_variance == tuple(drawn.velocity_variance) == (5e-5, 1e-4)


@pytest.mark.parametrize(
    ("setting", "named"),
    [
        (
            {"estimator": {"whiten": True}},
            r"controllers.adaptive_ct.estimator: not a scenario key: .*\[model\]",
        ),
        ({"estimator": {"mode": "full"}}, "controllers.adaptive_ct.estimator: not a scenario key"),
        ({"detector": {"learn_below": 0.5}}, "controllers.adaptive_ct.detector: not a scenario key"),
        ({"observer_trip": True}, r"controllers.adaptive_ct: unknown setting\(s\) \['observer_trip'\]"),
        ({"observer_momentum_test": "reopen"}, r"unknown setting\(s\) \['observer_momentum_test'\]"),
    ],
)
def test_a_removed_option_in_a_scenario_is_an_error_naming_file_and_key(setting, named):
    """The options measured and removed (docs/changelog.md) are not silently ignored when an older
    scenario still sets them: building adaptive_ct names the file and the key."""
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
    from adaptive_dd.controllers.registry import scenario_controller

    src = default_scenario_path().parent / "ur5_tool_swap.toml"
    data = read_toml(src)
    data.setdefault("controllers", {}).setdefault("adaptive_ct", {}).update(setting)
    with pytest.raises(ScenarioError, match=named) as err:
        scenario_controller(parse_scenario(data, str(src)), "adaptive_ct")
    assert str(err.value).startswith(f"{src}: controllers.adaptive_ct"), err.value


def test_an_arm_without_a_reference_is_told_what_one_looks_like(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[arm]\nrobot = "ur5"\n')
    with pytest.raises(
        ScenarioError, match=r"joint1 \.\. joint6, each as joint1 = \{ offset = 0\.0, amplitude"
    ):
        load_scenario(str(path))


@pytest.mark.parametrize("data", [None, [1, 2], "run.duration = 2"])
def test_a_scenario_that_is_not_a_dict_of_tables_is_named(data):
    from adaptive_dd.errors import ScenarioError

    with pytest.raises(ScenarioError, match=r"s\.toml: a scenario is a dict of tables"):
        parse_scenario(data, "s.toml")


def test_a_payload_change_is_told_its_real_range():
    """A change must leave its last segment a sample: the range printed is (0, duration - T]."""
    from adaptive_dd.errors import ScenarioError

    with pytest.raises(ScenarioError, match=r"payload\[0\]\.at: must be in \(0, 1\.999\], got 2\.0"):
        parse_scenario({"run": {"duration": 2.0}, "payload": [{"at": 2.0, "mass": 1.0}]}, "s.toml")
    assert parse_scenario({"run": {"duration": 2.0}, "payload": [{"at": 1.999, "mass": 1.0}]}).swap_times == (
        1.999,
    )


def test_a_misspelt_key_names_every_key_as_near():
    """``seedz`` was "did you mean 'seed'?": the base seed, whose change alters the noise silently,
    not the count of seeds meant."""
    from adaptive_dd.benchmark.scenario import parse_scenario

    with pytest.raises(ScenarioError, match=r"run\.seedz: unknown key \(did you mean 'seed' or 'seeds'\?\)"):
        parse_scenario({"run": {"seedz": 3}}, "s.toml")


def test_two_entries_sharing_a_name_or_a_settings_table_are_named():
    """Two plug-ins of one class name from two files were "a controller (or label) is listed twice:
    [every controller]", naming neither the entries nor what they share."""
    from adaptive_dd.benchmark.scenario import parse_scenario

    ctrls = ["pd", "a_mod:MyLaw", "b_mod:MyLaw", "pd"]
    with pytest.raises(ScenarioError) as e:
        parse_scenario({"run": {"controllers": ctrls}}, "s.toml")
    msg = str(e.value)
    assert "'pd' twice" in msg
    assert "'a_mod:MyLaw' and 'b_mod:MyLaw' share the settings table [controllers.MyLaw]" in msg
