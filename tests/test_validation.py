"""Scenario validation (issue 13): every problem at once, no bypass, no crash on any input."""

import dataclasses
import math
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from adaptive_dd.benchmark.scenario import format_scenario, load_scenario, parse_scenario
from adaptive_dd.errors import ScenarioError
from adaptive_dd.io import read_recording

BASE = """
[run]
duration = 2.0
sample_period = 0.001
seeds = 2
controllers = ["pd", "adaptive_ct"]
[reference]
joint1 = { offset = 0.1, amplitude = [0.3], frequency = [0.5], phase = [0.0] }
joint2 = { amplitude = [0.3], frequency = [0.7] }
[[payload]]
at = 1.0
mass = 1.0
"""


def parse(text, src="F.toml"):
    return parse_scenario(tomllib.loads(text), src)


def test_all_errors_at_once_each_naming_file_and_key():
    bad = BASE.replace("seeds = 2", "seeds = 0\nseed = -1").replace("mass = 1.0", "mass = nan")
    with pytest.raises(ScenarioError) as e:
        parse(bad)
    msg = str(e.value)
    assert "3 errors" in msg
    for key in ("F.toml: run.seeds:", "F.toml: run.seed:", "F.toml: payload[0].mass: must be finite"):
        assert key in msg


@pytest.mark.parametrize(
    "edit, match",
    [
        (("frequency = [0.5]", "frequency = [500.0]"), r"joint1.frequency: 500.0 Hz is above 100 Hz"),
        (("frequency = [0.5]", "frequency = [101.0]"), r"above 100 Hz"),
        (("seeds = 2", "seeds = 2\nseed = 18446744073709551616"), r"run.seed: must be in \[0, 922337203685"),
        (("seeds = 2", "seeds = 1000000000"), r"run.seeds: must be in \[1, 10000\]"),
        (("at = 1.0", "at = 1.9995"), r"payload\[0\].at: must be in \(0, 1.999\], got 1.9995"),
        (("at = 1.0", "at = 0.0000001"), r"less than one sample"),
        (("mass = 1.0", "mass = 1e300"), r"payload\[0\].mass: must be in \[0, 50\]"),
        (("duration = 2.0", "duration = 1e9"), r"run: too large: .* GiB"),
        (("sample_period = 0.001", "sample_period = 1e-300"), r"run.sample_period: must be in"),
        (("amplitude = [0.3], frequency = [0.7]", "amplitude = [1e300], frequency = [0.7]"), "amplitude"),
        (
            ("amplitude = [0.3], frequency = [0.7]", "amplitude = [23.0], frequency = [0.7]"),
            r"joint2.amplitude: must be in \[-10, 10\], got 23.0 \(radians: an angle in degrees\?\)",
        ),
        (("offset = 0.1", "offset = 45.0"), r"joint1.offset: must be in .* \(radians: an angle in degrees"),
        (("seeds = 2", "seeds = 2\nspeed = 1"), r"run.speed: unknown key"),
        (('"adaptive_ct"]', '"not a module:x"]'), r"unknown controller 'not a module:x'"),
        (("[[payload]]", "[controllers.slotine_li]\nx = 1\n[[payload]]"), r"controllers.slotine_li: not a"),
        (("[[payload]]", "[controllers.pd]\nx = nan\n[[payload]]"), r"controllers.pd.x: must be finite"),
        (("[run]", "[control]\nbandwidth = 400.0\n[run]"), r"bandwidth \* T = 0.4 > 0.2"),
    ],
)
def test_meaningless_values_are_refused(edit, match):
    with pytest.raises(ScenarioError, match=match):
        parse(BASE.replace(*edit))


def test_replace_cannot_bypass_validation_and_scenario_is_hashable():
    sc = load_scenario()
    hash(sc)
    for kw in ({"seeds": -1}, {"sample_period": 0.0}, {"swap_times": (5.0, 10.0, 10.0001)}):
        with pytest.raises(ScenarioError):
            dataclasses.replace(sc, **kw)
    assert not hasattr(sc, "extra")


def test_controller_options_and_import_paths():
    text = BASE.replace('"adaptive_ct"]', '"mypkg.ctrl:Fancy"]') + (
        "[controllers.Fancy]\ngain = [1, 2]\nmode = { a = 1.5 }\n[controllers.pd]\nbandwidth = 30.0\n"
    )
    sc = parse(text)
    hash(sc)
    assert sc.controllers == ("pd", "mypkg.ctrl:Fancy")
    assert sc.options("Fancy") == {"gain": [1, 2], "mode": {"a": 1.5}}  # a plug-in's settings: as given
    assert sc.options("pd") == {"bandwidth": 30.0} and sc.options("none") == {}
    # a built-in's settings are checked when the file is read, not when the run starts
    with pytest.raises(ScenarioError, match=r"F.toml: controllers.pd: unknown setting\(s\) \['kp'\]"):
        parse(text.replace("bandwidth = 30.0", "kp = 3"))


def test_encodings(tmp_path):
    p = tmp_path / "s.toml"
    p.write_bytes(b"\xef\xbb\xbf" + BASE.encode())
    assert load_scenario(p).seeds == 2  # BOM accepted
    p.write_bytes(BASE.encode().replace(b"seeds = 2", b"seeds = 2 # \xff"))
    with pytest.raises(ScenarioError, match=r"s.toml: not UTF-8 text: byte 0xff at offset \d+"):
        load_scenario(p)
    c = tmp_path / "r.csv"
    c.write_bytes(b"t,q1,q2,tau1,tau2\n0,0,0,0,\xe9\n")
    with pytest.raises(ValueError, match=r"r.csv: not UTF-8 text: byte 0xe9 at offset 26"):
        read_recording(c)


def test_format_marks_defaults():
    text = format_scenario(parse(BASE))
    assert "run.seeds = 2\n" in text
    assert "run.substeps = 2   (default)" in text and "control.bandwidth = 40.0   (default)" in text
    assert "1000 samples" in text  # two segments of 1 s at 1 kHz
    assert "payload.com" not in text  # the two-link arm's payload is a disk at the tip


def test_format_shows_each_payloads_centre_and_inertia_on_a_urdf_arm():
    """validate prints every field: on a URDF arm each payload's centre of mass and inertia too,
    the defaults said (a payload without them was invisible)."""
    text = format_scenario(load_scenario("adaptive_dd/scenarios/ur5_tool_swap.toml"))
    assert (
        "payload.com = [(0.04, 0.0, 0.06), (0.0, 0.03, 0.08), None]   (None: the payload frame's origin)"
        in text
    )
    assert (
        "payload.inertia = [(0.004, 0.004, 0.003, 0.0, 0.0, 0.0), (0.015, 0.015, 0.01, 0.0, 0.0, 0.0), None]"
        in text
    )


# --- property tests ------------------------------------------------------------------

ANY = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.booleans(),
    st.text(max_size=5),
    st.lists(st.floats(-1e3, 1e3), max_size=3),
    st.just([]),
)
KEYS = [
    ("run", "duration"), ("run", "sample_period"), ("run", "seeds"), ("run", "seed"),
    ("run", "substeps"), ("run", "controllers"), ("control", "bandwidth"), ("control", "damping"),
    ("noise", "position_variance"), ("reference", "ramp"),
]  # fmt: skip


@st.composite
def scenario_dicts(draw):
    data = tomllib.loads(BASE)
    for table, key in draw(st.lists(st.sampled_from(KEYS), max_size=4)):
        data.setdefault(table, {})[key] = draw(ANY)
    if draw(st.booleans()):
        n = draw(st.integers(0, 4))
        times = draw(st.lists(st.one_of(st.floats(-1, 3), st.just(math.nan)), min_size=n, max_size=n))
        masses = draw(st.lists(st.floats(-1, 60), min_size=n, max_size=n))
        data["payload"] = [{"at": t, "mass": m} for t, m in zip(times, masses, strict=True)]
    if draw(st.booleans()):
        data["reference"]["joint1"]["frequency"] = [draw(st.one_of(st.floats(-10, 2000), st.just(math.nan)))]
    return data


def check_valid_or_precise(data):
    try:
        sc = parse_scenario(data, "F.toml")
    except ScenarioError as exc:
        assert str(exc).startswith("F.toml: ")
        return
    T = sc.sample_period
    assert sc.n_samples >= 10 and min(sc.segment_samples()) >= 1
    assert all(0 < f < 0.5 / T for fs in sc.reference.frequency for f in fs)
    assert 0 <= sc.seed < 2**63 and 1 <= sc.seeds <= 10_000
    assert all(math.isfinite(x) for x in (sc.duration, T, sc.bandwidth, *sc.swap_times, *sc.swap_masses))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenario_dicts())
def test_property_scenarios_valid_or_precise_error(data):
    check_valid_or_precise(data)


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenario_dicts())
def test_property_scenarios_many(data):
    check_valid_or_precise(data)


CELL = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-5, 5).map(str),
    st.sampled_from(["", "x", "1e400", " 1", "nan"]),
)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    header=st.lists(st.sampled_from(["t", "q1", "q2", "qd1", "qd2", "tau1", "tau2", "x"]), max_size=8),
    rows=st.lists(st.lists(CELL, min_size=5, max_size=7), max_size=15),
    uniform=st.booleans(),
)
def test_property_csv_valid_or_precise_error(tmp_path, header, rows, uniform):
    from adaptive_dd.errors import DataError

    if uniform:
        header = ["t", "q1", "q2", "tau1", "tau2"]
        rows = [[str(k * 0.001), *r[1:5]] for k, r in enumerate(rows)]
    p = tmp_path / "rec.csv"
    p.write_text("\n".join(",".join(r) for r in [header, *rows]))
    try:
        rec = read_recording(p)
    except DataError as exc:
        assert str(exc).startswith(str(p))
        return
    assert rec.t.size >= 10 and rec.sample_period > 0
    assert all(map(math.isfinite, rec.q.ravel())) and all(map(math.isfinite, rec.tau.ravel()))


def test_overflowing_sample_count_is_an_error_not_a_crash():
    # found by the slow hypothesis profile: duration / T overflowed to inf
    with pytest.raises(ScenarioError, match=r"run: too large: inf samples per trial"):
        parse(BASE.replace("duration = 2.0", "duration = 1.797693134862316e+305"))


def test_an_empty_scenario_file_is_refused(tmp_path):
    for raw in (b"", b"# only a comment\n", b"\xef\xbb\xbf"):
        p = tmp_path / "empty.toml"
        p.write_bytes(raw)
        with pytest.raises(ScenarioError, match=r"empty.toml: empty scenario"):
            load_scenario(p)


ARM = """
[arm]
l1 = 0.3
l2 = 0.25
m1 = 2.0
m2 = 6.0
a1 = 0.15
a2 = 0.1
I1 = 0.02
I2 = 0.03
b = [4.0, 1.0]
d = [2.5, 0.6]
"""


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("l1 = 0.3", "l1 = 1e300", r"arm.l1' must be <= 2"),  # overflowed in parameters.py before
        ("a1 = 0.15", "a1 = 1.7e308", r"arm.a1' must be <= 3"),
        ("a2 = 0.1", "a2 = 1e300", r"arm.a2' must be <= 3"),
        ("l2 = 0.25", "l2 = 1e9", r"arm.l2' must be <= 2"),
        ("m2 = 6.0", "m2 = 1e17", r"arm.m2' must be <= 500"),
        ("I1 = 0.02", "I1 = -0.02", r"arm.I1' must be > 0"),
        ("b = [4.0, 1.0]", "b = [4.0, -1.0]", r"arm.b\[1\]' must be >= 0"),
    ],
)
def test_arm_tables_have_physical_bounds(old, new, match):
    assert parse(BASE + ARM).closed_forms.l1 == 0.3
    with pytest.raises(ScenarioError, match=r"F.toml: .*" + match):
        parse(BASE + ARM.replace(old, new))


@pytest.mark.parametrize(
    ("table", "match"),
    [
        (
            "[controllers.adaptive_ct]\nbandwidth = -40.0",
            r"controllers.adaptive_ct.bandwidth: must be in \(0",
        ),
        ("[controllers.adaptive_ct]\nbandwidth = 400.0", r"bandwidth \* T = 0.4 > 0.2"),
        ("[controllers.adaptive_ct]\nboost_bandwidth = 1e300", r"boost_bandwidth: must be in \(0"),
        ("[controllers.adaptive_ct]\nboost_duration = 1e300", r"boost_duration: must be in \[0, 2\]"),
        ("[controllers.adaptive_ct]\ndamping = 1.7e308", r"controllers.adaptive_ct.damping: must be in"),
        (
            "[controllers.adaptive_ct]\ndetector = { threshold = 1e300 }",
            r"controllers.adaptive_ct.detector: not a scenario key: .*payload_capacity.*; remove it",
        ),
        ("[controllers.pd]\nsigma = [0.5, 0.04, 0.05, 3.0, 0.6, 2.0, -0.5]", r"controllers.pd"),
    ],
)
def test_builtin_controller_settings_are_checked_on_reading(table, match):
    with pytest.raises(ScenarioError, match=r"F.toml: .*" + match):
        parse(BASE + table + "\n")


def test_a_setting_beyond_its_own_bound_is_refused_once():
    """1e7 rad/s of boost_bandwidth was refused twice in one line, by its bound ((0, 1e5]) and by
    the generic one (+-1e6), two limits that read as a contradiction."""
    with pytest.raises(ScenarioError) as exc:
        parse(BASE + "[controllers.adaptive_ct]\nboost_bandwidth = 1e7\n")
    assert str(exc.value).count("boost_bandwidth") == 1 and "must be in (0, 100000]" in str(exc.value)


def test_sweep_and_arm_files_read_toml_like_scenarios(tmp_path):
    """One TOML reader: a BOM is accepted everywhere, errors name the file."""
    from adaptive_dd.cli._common import closed_form_view as _closed_form_view
    from adaptive_dd.cli._common import load_arm
    from adaptive_dd.io import read_toml

    p = tmp_path / "arm.toml"
    p.write_bytes(b"\xef\xbb\xbf" + ARM.encode())
    assert _closed_form_view(load_arm(str(p))).l1 == 0.3
    p.write_bytes(b"[arm\n")
    with pytest.raises(ScenarioError, match=r"arm.toml: not valid TOML"):
        load_arm(str(p))
    with pytest.raises(ValueError, match=r"nope.toml: no such file"):
        read_toml(tmp_path / "nope.toml")


def test_fuzzer_small_configuration_finds_no_crash_and_no_meaningless_scenario():
    """benchmarks/fuzz_scenarios.py in a small configuration (the README prints the 2000-mutation
    one), run as a user runs it (a script, not imported by its path)."""
    import os
    import re
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    env = {**os.environ, "PYTHONPATH": str(root)}
    script = root / "benchmarks" / "fuzz_scenarios.py"
    out = subprocess.run(
        [sys.executable, str(script), "--n", "300", "--seed", "7"], capture_output=True, text=True, env=env
    )
    assert out.returncode == 0, out.stderr
    counts = {k: int(v) for k, v in re.findall(r"^  ([a-z ]+?)\s{2,}(\d+)$", out.stdout, re.M)}
    assert counts["crash"] == 0 and counts["meaningless accepted"] == 0, out.stdout
    assert counts["error not naming the file"] == 0
    assert counts["precise error"] > 100 and counts["valid accepted"] > 20


def test_closed_form_parameters_of_no_physical_arm_are_a_scenario_error():
    """Each of sigma, l1, l2 within its bounds, together an arm whose link 1 weighs 1.6e7 kg: the
    equivalent arm's URDF (written to the cache) is refused, and the error names the scenario and
    the keys, not the cache's file (the fuzzer found it as a crash)."""
    table = {"arm": {"sigma": [10.0, 0.5, 0.5, 1.0, 1.0, 1.0, 1.0], "l1": 1e-3, "l2": 0.3}}
    with pytest.raises(
        ScenarioError, match=r"^mine.toml: \[arm\]: the two-link arm that sigma, l1 and l2"
    ) as e:
        parse_scenario(table, "mine.toml")
    assert "cache" not in str(e.value) and "above 10000 kg" in str(e.value)


def test_a_scenario_built_in_code_checks_its_payloads_centres_and_inertias():
    """``swap_com`` and ``swap_inertia`` follow ``swap_times``: a Scenario changed in code with
    another number of swaps, or a centre that is not three numbers, is refused when built."""
    import dataclasses

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.errors import ScenarioError

    sc = load_scenario("adaptive_dd/scenarios/ur5_tool_swap.toml")
    assert len(sc.swap_com) == 3
    with pytest.raises(ScenarioError, match=r"swap_com: one entry per payload change \(4"):
        dataclasses.replace(sc, swap_times=(4, 10, 16, 18), swap_masses=(2, 5, 0, 1))
    with pytest.raises(ScenarioError, match=r"swap_com\[0\]: must be None or 3 finite numbers"):
        dataclasses.replace(sc, swap_com=((0, 0, "x"), None, None))
    with pytest.raises(ScenarioError, match=r"swap_inertia\[1\]"):
        dataclasses.replace(sc, swap_inertia=(None, (1.0, 0.0), None))
    one = dataclasses.replace(
        sc, swap_times=(4.0,), swap_masses=(2.0,), swap_com=sc.swap_com[:1], swap_inertia=sc.swap_inertia[:1]
    )
    assert one.payload_of(0)["com"] == sc.swap_com[0]


@pytest.mark.parametrize(
    ("com", "match"),
    [
        ([40.0, 0.0, 0.0], r"payload\[0\]\.com: \[40\.0, 0\.0, 0\.0\] is 40 m from the payload frame, "
         r"beyond 2 m: give it in metres"),
        ([0.04, 0.0], r"payload\[0\]\.com: must be a list of 3 finite numbers"),
    ],
)  # fmt: skip
def test_a_payloads_centre_in_the_wrong_unit_or_shape_is_one_error_naming_it(com, match):
    """A centre of mass in mm (40 m from the flange) is refused, not warned about as a torque the
    reference cannot give; a malformed one is one error, not a second about the Scenario's field."""
    with open("adaptive_dd/scenarios/ur5_tool_swap.toml", "rb") as f:
        table = tomllib.load(f)
    table["payload"][0]["com"] = com
    with pytest.raises(ScenarioError, match=match) as e:
        parse_scenario(table, "mine.toml")
    assert str(e.value).startswith("mine.toml: payload[0].com") and "swap_com" not in str(e.value)


@pytest.mark.parametrize("kind", ["two_link", "chain"])
def test_stating_a_builtin_controllers_default_settings_is_valid(kind):
    """Every built-in's settings table written out at its defaults passes the file's checks on its
    kind of arm (a default refused by a bound, as a boost of 300 rad/s by the control bandwidth's
    0.2 / T once was, would make the documented value unusable)."""
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.controllers.builtins import ABSENT, CONTROLLERS

    arm = {} if kind == "two_link" else {"arm": {"robot": "vertical3", "payload_capacity": 1.5}}
    ref = {
        f"joint{j}": {"offset": o, "amplitude": [0.3], "frequency": [0.3]}
        for j, o in ((1, 0.3), (2, -0.6), (3, 0.4))
    }
    checked = 0
    for name, b in CONTROLLERS.items():
        if not b.applies_to(kind):
            continue
        table = {
            k: s.default(kind)
            for k, s in b.settings.items()
            if s.default(kind) is not None and s.default(kind) is not ABSENT
        }
        if not table:
            continue
        data = {**arm, "run": {"duration": 2.0, "seeds": 1, "controllers": [name]}}
        data["controllers"] = {name: table}
        if kind == "chain":
            data["reference"] = ref
        parse_scenario(data, f"{name}.toml")
        checked += 1
    assert checked >= 2, checked


def test_a_too_large_n_joint_run_is_refused_with_its_own_estimate():
    """The refusal's estimate is the N-joint arm's (its rate per joint), not the two-link arm's."""
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.benchmark.scenario_base import run_estimate
    from adaptive_dd.errors import ScenarioError

    ref = {
        f"joint{j}": {"offset": o, "amplitude": [0.3], "frequency": [0.3]}
        for j, o in ((1, 0.3), (2, -0.6), (3, 0.4))
    }
    data = {
        "arm": {"robot": "vertical3"},
        "run": {"duration": 20000.0, "seeds": 1000, "controllers": ["ct_oracle", "pd"]},
        "reference": ref,
    }
    with pytest.raises(ScenarioError, match="run: too large") as e:
        parse_scenario(data, "big.toml")
    assert str(run_estimate(20_000_000, 1000, 2, n_joints=3)) in str(e.value)
    assert str(run_estimate(20_000_000, 1000, 2)) not in str(e.value)


def test_the_reports_centre_of_mass_shows_each_axis_the_data_determine():
    from adaptive_dd.benchmark.report import _xyz

    assert _xyz((0.03, None, 0.0)) == "30,-,0"  # a planar arm: y is not determined
    assert _xyz((None, None, None)) == "—" and _xyz(None) == "—"
    assert _xyz((0.001, 0.002, 0.003)) == "1,2,3"


def test_a_shipped_scenario_loads_by_its_name_from_any_folder(tmp_path, monkeypatch):
    """load_scenario("ur5_tool_swap") (and the CLI's FILE) found the file only from the repository's
    root by its path; a file of that name in the working folder still wins."""
    from adaptive_dd.benchmark.scenario import packaged_scenarios

    monkeypatch.chdir(tmp_path)
    assert load_scenario("ur5_tool_swap").source == str(packaged_scenarios()["ur5_tool_swap"])
    assert load_scenario("panda_payload.toml").n_joints == 7
    (tmp_path / "ur5_tool_swap.toml").write_text("[run]\nduration = 2.0\n")
    assert load_scenario("ur5_tool_swap.toml").duration == 2.0  # the user's own file first
    with pytest.raises(ScenarioError, match=r"no such scenario file .*a shipped one's name: .*ur5_tool_swap"):
        load_scenario("ur5_tool_swp")


@pytest.mark.slow  # a cold compile of its own path; the rest of the file covers the check
def test_simulate_and_identify_take_a_shipped_scenarios_name_as_benchmark_does(tmp_path, monkeypatch):
    """``--arm NAME`` (``simulate``, ``identify``: ``cli._common.load_arm``) and ``benchmark NAME
    --arms`` refused a shipped scenario's name that their own error listed."""
    from adaptive_dd.cli import main
    from adaptive_dd.cli._common import load_arm

    monkeypatch.chdir(tmp_path)
    assert load_arm("vertical3_payload_exact").n_joints == 3
    with pytest.raises(ScenarioError, match=r"no such scenario file .*vertical3_payload_exact"):
        load_arm("vertical3_payload_exac")
    # through the command: it read the name as a file again after the arm (`payload_swap: no such file`)
    assert main(["simulate", "--arm", "payload_swap", "--duration", "0.5", "--out", str(tmp_path / "s")]) == 0


def test_a_bandwidth_per_joint_on_the_closed_forms_says_where_it_runs():
    """It said 'must be a number, got (40, 40)', not that one per joint needs the general kernels."""
    from adaptive_dd.benchmark.scenario import parse_scenario

    with pytest.raises(
        ScenarioError, match=r"control.bandwidth: one number on the paper's two-link closed forms"
    ):
        parse_scenario({"control": {"bandwidth": [40.0, 40.0]}})
    sc = parse_scenario(
        {"control": {"bandwidth": [40.0, 30.0]}, "arm": {"robot": "sice_arm", "general": True}}
    )
    assert sc.closed_forms is None and tuple(sc.bandwidth) == (40.0, 30.0)


def test_a_bandwidth_per_joint_beside_a_wrong_arm_leaves_the_arm_to_its_own_error():
    from adaptive_dd.benchmark.scenario import parse_scenario

    with pytest.raises(ScenarioError) as info:
        parse_scenario({"arm": {"robot": "ur5x"}, "control": {"bandwidth": [40.0] * 6}})
    assert "'ur5x' is not a shipped robot" in str(info.value) and "closed forms" not in str(info.value)


def test_a_misspelt_uncertainty_key_and_a_percentage_level_are_named_with_the_remedy(tmp_path):
    """``[plant.uncertainty] intertia`` listed the allowed keys without the one meant; ``mass = 10``
    (10 %) said its range without saying the level is a fraction; a payload of 1000 (g) likewise."""
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.errors import ScenarioError

    base = {"arm": {"robot": "vertical3"}, "run": {"duration": 2.0}}
    with pytest.raises(ScenarioError, match=r"'plant\.uncertainty\.intertia' \(did you mean 'inertia'\?\)"):
        parse_scenario({**base, "plant": {"uncertainty": {"intertia": 0.2}}}, "s.toml")
    with pytest.raises(ScenarioError, match=r"must be in \[0, 1\), got 10 \(a fraction: 0\.1 for 10 %\)"):
        parse_scenario({**base, "plant": {"uncertainty": {"mass": 10}}}, "s.toml")
    with pytest.raises(
        ScenarioError, match=r"payload\[0\]\.mass: must be in \[0, .*\], got 1500: a mass in g\?"
    ):
        parse_scenario({**base, "payload": [{"at": 1.0, "mass": 1500}]}, "s.toml")
