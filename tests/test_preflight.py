"""``validate`` checks what the run will meet; a failed trial says why and when; outputs are
checked before a run (issue 27)."""

from __future__ import annotations

import dataclasses
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.benchmark.types import ControllerRun
from adaptive_dd.cli import main

ROOT = Path(__file__).resolve().parent.parent
PANDA = Path(str(resources.files("adaptive_dd.scenarios").joinpath("panda_payload.toml")))


def test_validate_catches_a_reference_beyond_position_and_velocity_limits(tmp_path, capsys):
    """Issue 27: a reference through joint 4's limit at twice its speed was accepted."""
    text = PANDA.read_text().replace(
        "joint4 = { offset = -1.8, amplitude = [0.5, 0.15], frequency = [0.3, 0.85]",
        "joint4 = { offset = -0.1, amplitude = [0.5, 0.15], frequency = [0.6, 1.7]",
    )
    bad = tmp_path / "panda.toml"
    bad.write_text(text)
    assert main(["validate", str(PANDA)]) == 0
    capsys.readouterr()
    assert main(["validate", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "2 problem(s)" in err
    assert "reference.joint4: q = 0.5489 rad at t = 13.682 s" in err
    assert "above the joint's upper limit -0.0698 rad" in err
    assert "reference.joint4: |qd| = " in err and "velocity limit 2.175 rad/s" in err


def test_validate_warns_of_a_torque_beyond_the_limit_along_the_reference(capsys):
    path = ROOT / "benchmarks" / "scenarios" / "alternating.toml"
    assert main(["validate", str(path)]) == 0  # the benchmark runs through saturation and says so
    err = capsys.readouterr().err
    assert "warning: reference.joint2: inverse dynamics along the reference with the 3 kg payload" in err
    assert "(carried from 7.5 to 12 s; each is checked along the whole reference)" in err
    assert "torque limit 15 N m" in err and "joint1" not in err


def test_a_torque_beyond_the_limit_without_payload_blames_the_arm_not_a_payload(tmp_path, capsys):
    """An arm that cannot follow its reference unloaded (a link's mass in g, an effort limit too
    small) is named as such: the warning said "with the 2 kg payload" at a time it was not carried."""
    text = (ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml").read_text()
    limits = 'robot = "ur5"\ntorque_limit = [150.0, 20.0, 150.0, 28.0, 28.0, 28.0]'
    text = text.replace('robot = "ur5"', limits)
    path = tmp_path / "weak.toml"
    path.write_text(text)
    assert main(["validate", str(path)]) == 0
    out, err = capsys.readouterr()
    assert "reference.joint2: inverse dynamics along the reference with the arm alone (no payload)" in err
    assert "torque limit 20 N m" in err and "check the URDF's masses and the joint's effort limit" in err
    assert "; with the payloads it needs up to 100.2 N m" in err  # the peak line's figure, said too
    assert "joint1:" not in err
    # the boost is held within the limits at each sample: its caps leave no room for the
    # reference's torque, so a joint the reference saturates does not turn it off
    assert "boost bandwidth per joint = [" in out and "no room on joint(s)" not in out
    # a reference too fast (its frequencies as if in rad/s, 30 and 90 Hz): the motion is named
    fast = tmp_path / "fast.toml"
    text = (ROOT / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml").read_text()
    fast.write_text(text.replace("frequency = [0.4, 1.1]", "frequency = [30.0, 90.0]"))
    assert main(["validate", str(fast)]) == 1  # (its speed beyond the joints' limits: a problem)
    err = capsys.readouterr().err
    assert "reference.joint2: inverse dynamics along the reference with the arm alone" in err
    assert "the reference's motion needs" in err and "([reference] frequency is in Hz)" in err


@pytest.mark.parametrize(
    ("spec", "table", "needle"),
    [
        ("payload_gradient:PayloadGradient", "[controllers.PayloadGradient]\nbogus = 1\n", "['bogus']"),
        ("no_such_module_xyz:Ctrl", "", "cannot import module 'no_such_module_xyz'"),
        ("no_such_module_xyz:Ctrl", "", "put no_such_module_xyz.py beside the scenario file"),
        ("payload_gradient:NoSuchClass", "", "has no 'NoSuchClass'"),
        (
            "payload_gradient:PayloadGradiant",
            "",
            "has no 'PayloadGradiant' (did you mean 'PayloadGradient'?)",
        ),
        ("payload_gradient:PayloadGradient", "[controllers.PayloadGradient]\ngamma = -1\n", "gamma must be"),
    ],
)
def test_validate_builds_plugins_with_their_settings(tmp_path, capsys, monkeypatch, spec, table, needle):
    """Issue 27: a plug-in's unknown setting or bad import path passed validate. (Each case's module
    is its own file: the one imported by an earlier case, from another folder, is forgotten.)"""
    monkeypatch.delitem(sys.modules, "payload_gradient", raising=False)
    (tmp_path / "payload_gradient.py").write_text((ROOT / "examples" / "payload_gradient.py").read_text())
    path = tmp_path / "s.toml"
    path.write_text(f'[run]\nduration = 1.0\ncontrollers = ["ct_oracle", "{spec}"]\n{table}')
    try:
        assert main(["validate", str(path)]) == 1
    finally:  # this folder's module forgotten: a later test imports the examples' own
        sys.modules.pop("payload_gradient", None)
    err = capsys.readouterr().err
    assert "1 problem(s)" in err and needle in err, err


class NanAfter:
    """A plug-in whose command turns NaN on trial 1 from t = 0.05 s."""

    def reset(self, n_trials, sample_period):
        self.k, self.T = 0, sample_period

    def command(self, q, qd, q_d, qd_d, qdd_d):
        tau = 400.0 * (q_d - q) + 40.0 * (qd_d - qd)
        if self.k * self.T >= 0.05 - 1e-12:
            tau[1, 0] = np.nan
        self.k += 1
        return tau

    def observe(self, q, qd, tau):
        pass


@pytest.mark.parametrize("arm", ["two_link", "urdf"])
def test_a_failed_trial_says_why_and_when(arm):
    """Issue 27: a NaN torque failed a trial with no reason and no time."""
    sc = load_scenario() if arm == "two_link" else load_scenario(ROOT / "examples" / "plugin_urdf.toml")
    sc = dataclasses.replace(sc, seeds=2, duration=0.2, swap_times=(0.1,), swap_masses=(1.0,), swap_com=())
    res = run_benchmark(sc, progress=False, controllers={"nan": NanAfter()})
    m = res.metrics()["controllers"]["nan"]
    assert m["failed_trials"] == 1
    (f,) = m["failures"]
    assert f["seed"] == 1 and f["t"] == pytest.approx(0.05)
    assert f["why"] == "non-finite torque command (joint 1: nan) at t = 0.050 s"
    from adaptive_dd.benchmark.report import format_report

    assert "nan, seed 1, t = 0.050 s: non-finite torque command" in format_report(res.metrics(), res)


def test_a_compiled_failure_is_explained_from_the_error_norm():
    e = np.zeros((3, 10), dtype=np.float32)
    e[0, 4], e[1, 6] = 0.9, 0.01
    run = ControllerRun(
        "x", None, e, None, np.array([True, True, False]), np.array([4, 6, -1]), engine="compiled"
    )
    run.explain_failures(max_error=0.5, max_speed=200.0)
    assert run.failed_why[0].startswith("tracking error |e| = 0.9 rad, beyond max_error = 0.5 rad")
    assert run.failed_why[1].startswith("runaway: the arm's state became non-finite or a joint exceeded 200")
    assert 2 not in run.failed_why
    assert run.failures(0.01, (7, 8, 9))[1] == {"seed": 8, "t": 0.06, "why": run.failed_why[1]}


def test_a_payload_above_the_rated_one_is_a_warning(tmp_path, capsys):
    text = (ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml").read_text()
    path = tmp_path / "rated.toml"
    path.write_text(text.replace("payload_capacity = 5.0", "payload_capacity = 3.0"))
    assert main(["validate", str(path)]) == 0
    err = capsys.readouterr().err
    assert "warning: payload[1].mass = 5 kg is above [arm] payload_capacity = 3 kg" in err
    assert "payload[0]" not in err  # 2 kg is within it
    from adaptive_dd.benchmark.preflight import capacity_problems

    assert (
        capacity_problems(load_scenario(ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml"))
        == []
    )


def test_a_duration_that_reads_as_milliseconds_is_a_warning(tmp_path, capsys):
    """12000 written for 12 s: accepted (a long run may be meant), said by validate and by the
    benchmark before it runs; the shipped default says nothing."""
    from adaptive_dd.benchmark.preflight import duration_problems
    from adaptive_dd.cli.benchmark import limit_warnings

    text = (ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml").read_text()
    assert "duration = 20.0" in text
    path = tmp_path / "ms.toml"
    path.write_text(text.replace("duration = 20.0", "duration = 2000.0"))
    assert main(["validate", str(path)]) == 0
    said = "run.duration = 2000 s (0.56 h of simulated time per trial): a duration in ms?"
    assert f"warning: {said}" in capsys.readouterr().err
    assert any(said in w for w in limit_warnings(load_scenario(path)))
    assert duration_problems(load_scenario(ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml")) == []
    path.write_text(text.replace("duration = 20.0", "duration = 999.0"))
    assert duration_problems(load_scenario(path)) == []


def test_a_compiled_non_finite_command_names_its_joint():
    run = ControllerRun(
        "x", None, np.zeros((2, 10), np.float32), None, np.array([True, True]), np.array([4, 6]),
        engine="compiled", failed_cmd=np.array([2, -1]),
    )  # fmt: skip
    run.explain_failures(max_error=0.5, max_speed=200.0)
    assert run.failed_why[0] == "non-finite torque command (joint 3)"
    assert run.failed_why[1].startswith("runaway")


def test_the_reports_failure_lines_group_a_shared_reason_and_cut_a_long_one():
    """A controller that raised fails every trial with one reason: one line for its seeds, not one
    per seed with the reason also in the summary; numba's page of typing errors cut to its gist."""
    from adaptive_dd.benchmark.report import _failure_lines

    typing = (
        "TypingError in the compiled plug-in: Failed in nopython mode\nnon-precise\n\n- argument 18: dict"
    )
    nan = "non-finite torque command (joint 1)"
    raised = [{"seed": s, "t": None, "why": typing} for s in (0, 1, 2)]
    ctrls = {
        "a": {"failed_trials": 3, "error": typing, "failures": raised},
        "b": {"failed_trials": 1, "error": "", "failures": [{"seed": 4, "t": 1.3, "why": nan}]},
    }  # fmt: skip
    lines = _failure_lines(ctrls)
    assert lines[0] == "failed trials: a: 3, b: 1"
    assert lines[1] == (
        "  a, seeds 0, 1, 2, time not recorded: TypingError in the compiled plug-in: Failed in "
        "nopython mode ... - argument 18: dict (the whole message: metrics.json, failures)"
    )
    assert lines[2] == "  b, seed 4, t = 1.300 s: non-finite torque command (joint 1)" and len(lines) == 3


def test_unwritable_outputs_are_reported_before_the_run(tmp_path, capsys):
    """Issue 27: an unwritable --out was found only after the run (excite, sweep)."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    sice = str(ROOT / "benchmarks" / "scenarios" / "sice_urdf.toml")
    assert main(["excite", "--arm", sice, "--out", str(blocker / "x.toml")]) == 2
    cap = capsys.readouterr()
    assert "SLSQP" not in cap.out and f"{blocker} is a file" in cap.err
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('[sweep]\nseeds = 1\ncontrollers = ["ct_oracle"]\n[grid]\npayload_mass = [1.0]\n')
    assert main(["sweep", str(sweep), "--out", str(blocker / "out"), "--no-progress"]) == 2
    cap = capsys.readouterr()
    assert "tasks" not in cap.out and f"{blocker} is a file" in cap.err


def test_a_failed_trial_keeps_its_segments_before_the_failure_on_every_arm():
    """Issue 27: a failed trial blanked every segment on an N-joint arm, only the segments from
    its failure on on the two-link arm; now one rule (metrics.segment_failed) on both."""
    for sc in (load_scenario(), load_scenario(ROOT / "examples" / "plugin_urdf.toml")):
        sc = dataclasses.replace(
            sc, seeds=2, duration=0.2, swap_times=(0.04,), swap_masses=(1.0,), swap_com=()
        )
        res = run_benchmark(sc, progress=False, controllers={"nan": NanAfter()})
        per = res.to_frame()
        trial1 = per[per.seed == 1].sort_values("segment")
        assert np.isfinite(trial1.rms_error_rad.iloc[0]) and np.isnan(trial1.rms_error_rad.iloc[1]), sc.name
        assert np.isfinite(per[per.seed == 0].rms_error_rad).all()


def test_information_time_has_the_same_keys_without_an_oracle_on_every_arm():
    sc = load_scenario(ROOT / "examples" / "plugin_urdf.toml")
    sc = dataclasses.replace(sc, seeds=1, duration=0.2, swap_times=(0.1,), swap_masses=(1.0,), swap_com=())
    seg = res_seg = run_benchmark(sc, progress=False, controllers={"pd": NanAfter()}).metrics()
    seg = res_seg["controllers"]["pd"]["segments"][1]
    from adaptive_dd.closed_loop.information import INFORMATION_KEYS

    # every key of the one schema (tests/test_result_schema.py), None: nothing to compute along
    assert seg["information_time"] == dict.fromkeys(INFORMATION_KEYS) | {"seeds": 0}


@pytest.mark.parametrize("arm", ["two_link", "urdf"])
def test_adaptive_ct_takes_its_detector_table_at_the_top_on_every_arm_and_inside_with_a_warning(arm):
    from adaptive_dd.benchmark.runner import scenario_controller
    from adaptive_dd.benchmark.scenario_checks import freeze
    from adaptive_dd.errors import ParameterError

    base = load_scenario() if arm == "two_link" else load_scenario(ROOT / "examples" / "plugin_urdf.toml")
    key, value = ("glr_threshold", 200.0) if arm == "two_link" else ("threshold", 7.0)  # each reads its own

    def built(opts):
        sc = dataclasses.replace(
            base, controllers=("adaptive_ct",), controller_options=(("adaptive_ct", freeze(opts)),)
        )
        return scenario_controller(sc, "adaptive_ct")[1].online

    top = built({"detector": {key: value}})
    with pytest.warns(FutureWarning, match=r"estimator\.detector: write the detector's table at the top"):
        inside = built({"estimator": {"detector": {key: value}}})
    assert top == inside and getattr(top.detector, key) == value
    with pytest.raises(ParameterError, match="'detector' given twice"):
        built({"detector": {key: value}, "estimator": {"detector": {key: value}}})


def test_validate_says_the_boost_default_of_each_arm(capsys):
    """adaptive_ct's boost_duration defaults differ on purpose (0.2 s two-link, 1 s N-joint):
    validate prints the value the run will use, the default marked."""
    assert main(["validate"]) == 0
    out = capsys.readouterr().out
    assert "controllers.adaptive_ct.boost_duration = 0.2 s   (default)" in out
    assert "adaptive_ct_paper.boost" not in out
    ur5 = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml"))
    assert main(["validate", ur5]) == 0
    assert "controllers.adaptive_ct.boost_duration = 1.0 s   (default)" in capsys.readouterr().out


def test_validate_checks_the_paper_arm_against_its_limits_too(tmp_path, capsys):
    """The paper's arm is an Arm in its scenario (issue 27), with the URDF's limits (+-pi rad,
    2 pi rad/s): ``validate`` checks its reference as it checks any arm's (the closed-form record
    had no limits, so a reference through them passed)."""
    src = ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml"
    bad = tmp_path / "s.toml"
    bad.write_text(
        src.read_text().replace(
            "joint1 = { offset = 0.0, amplitude = [0.5, 0.2]",
            "joint1 = { offset = 3.0, amplitude = [0.5, 0.2]",
        )
    )
    assert main(["validate", str(src)]) == 0
    capsys.readouterr()
    assert main(["validate", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "reference.joint1: q = " in err and "above the joint's upper limit 3.142 rad" in err, err


def test_a_joint_whose_friction_dwarfs_its_inertia_is_warned_of(tmp_path, capsys):
    """The UR5 from its URDF alone (no armature): wrists 2 and 3 carry 1 N m of Coulomb friction
    against 3.8e-3 and 1.3e-4 kg m^2; ``validate`` and ``benchmark`` warn, naming the joint, the
    figures and what to state. The shipped UR5 scenario (armature stated) is quiet."""
    from adaptive_dd.benchmark.preflight import inertia_problems

    p = tmp_path / "ur5_alone.toml"
    p.write_text(
        '[arm]\nrobot = "ur5"\n[run]\nduration = 0.3\nseeds = 1\ncontrollers = ["ct_oracle"]\n'
        "[reference]\nramp = 0.1\n"
        + "".join(
            f"{j} = {{ offset = {o}, amplitude = [0.1], frequency = [0.3] }}\n"
            for j, o in (
                ("shoulder_pan_joint", 0.0),
                ("shoulder_lift_joint", -1.3),
                ("elbow_joint", 1.5),
                ("wrist_1_joint", -1.8),
                ("wrist_2_joint", -1.57),
                ("wrist_3_joint", 0.0),
            )
        )
    )
    assert main(["validate", str(p)]) == 0
    err = capsys.readouterr().err
    assert err.count("warning: arm: joint") == 3 and "'wrist_3_joint': Coulomb friction 1 N m" in err
    assert "'wrist_3_joint': the D/A's step" in err  # its 1.3e-4 kg m^2 behind a 28 N m D/A too
    assert "state [arm] armature" in err
    assert main(["benchmark", str(p), "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    assert "warning: " in capsys.readouterr().err
    shipped = load_scenario(str(resources.files("adaptive_dd.scenarios") / "ur5_tool_swap.toml"))
    assert inertia_problems(shipped) == []


def test_the_centre_of_mass_line_says_when_no_law_estimates_the_payload():
    """It ended in 'information limit 8 ms; ' and nothing else."""
    from adaptive_dd.benchmark.report import _com_information_line

    seg = {"start": 2.0}
    info = {"com_known": 0.008, "com_axes": "xyz"}
    c = {"pd": {"segments": [{}, {"com_learning_time": None}]}}
    line = _com_information_line(c, 1, seg, info, [], set())
    assert line.endswith("information limit 8 ms (no controller of the run estimates the payload)")
    c["adaptive_ct"] = {"segments": [{}, {"com_learning_time": 0.02}]}
    line = _com_information_line(c, 1, seg, info, ["adaptive_ct"], {3})
    assert line.endswith("information limit 8 ms; adaptive_ct 20 ms (median over 3 seed(s))")


def test_a_ratio_below_one_of_adaptive_ct_is_said_to_be_its_boost():
    """A user's arm read adaptive_ct at 0.85x its floor, 'met', without a word that its law differs
    from its floor's by a gain boost after each alarm."""
    from adaptive_dd.benchmark.report import _seed_tables

    st = {"mean": 0.85, "median": 0.85, "p90": 0.9, "max": 0.95, "ci95": (0.8, 0.9), "worst_seed": 1}
    ctrls = {"adaptive_ct": {"floor": "ct_oracle", "segments": [{"ratio_to_floor": st}]}}
    lines = _seed_tables(ctrls, "head")
    assert any("a ratio below 1 is that boost, not a model better than the true one" in x for x in lines)
    st["mean"] = 1.02
    assert not any("boost" in x for x in _seed_tables(ctrls, "head"))
    # sliding_mode's boundary layer is a feedback its floor (slotine_li_oracle) has not either
    st["mean"] = 0.89
    sliding = {"sliding_mode": {"floor": "slotine_li_oracle", "segments": [{"ratio_to_floor": st}]}}
    assert any(
        "sliding_mode adds a robust term" in x and "is that term" in x for x in _seed_tables(sliding, "head")
    )


@pytest.mark.parametrize("name", ["alternating.toml", "weak"])
def test_the_torque_maxima_read_in_chunks_are_the_whole_references(tmp_path, monkeypatch, name):
    """``validate`` built the regressor of the whole reference at once (a run of 8000 s, a typo of
    ms for s, took 24 GB and was killed); it is read in chunks now. Chunks of 7 samples (a swap
    and every peak inside some chunk's interior or at its edge) give the one-chunk figures, and
    the warnings' text is the same."""
    from adaptive_dd.benchmark import preflight

    if name == "weak":  # the unloaded arm beyond its limit: the bare segment's peak and time
        text = (ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml").read_text()
        text = text.replace(
            'robot = "ur5"', 'robot = "ur5"\ntorque_limit = [150.0, 20.0, 150.0, 28.0, 28.0, 28.0]'
        )
        path = tmp_path / "weak.toml"
        path.write_text(text)
    else:
        path = ROOT / "benchmarks" / "scenarios" / name
    sc = load_scenario(path)
    monkeypatch.setattr(preflight, "CHUNK", 10**9)
    whole, problems = preflight._torque_maxima(sc), preflight.torque_problems(sc)
    monkeypatch.setattr(preflight, "CHUNK", 7)
    for a, b in zip(preflight._torque_maxima(sc), whole, strict=True):
        np.testing.assert_array_equal(a, b)
    assert preflight.torque_problems(sc) == problems and problems


def test_a_joint_whose_da_rounding_sets_its_floor_is_warned_of():
    """The SO-100 of example-robot-data: a wrist of 6.5e-5 kg m^2 behind a 35 N m D/A was 3 mrad
    unloaded with no word from validate. The warning's figure is held against the run: vertical3's
    wrist with a 5000 N m limit (0.87 mrad stated, an upper figure) lifts the floor's error of that
    joint beyond the sensors' own (0.057 mrad), and the shipped limits give no warning."""
    from adaptive_dd.benchmark.preflight import inertia_problems
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml

    errors = {}
    for lim in (None, 5000.0):
        d = read_toml(ROOT / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml")
        if lim:
            d["arm"]["torque_limit"] = [lim] * 3
        d["run"].update(duration=2.0, seeds=1, controllers=["ct_oracle"])
        d["payload"] = d["payload"][:1]
        d["payload"][0]["at"] = 1.5
        sc = parse_scenario(d, "v3.toml")
        said = [x for x in inertia_problems(sc) if "no joint has an armature" not in x]
        run = run_benchmark(sc, progress=False).runs["ct_oracle"]
        t = np.arange(sc.n_samples) * sc.sample_period
        e = sc.reference.sample(t)[0][None] - run.q
        errors[lim] = float(np.sqrt(np.mean(e[:, t > 0.5, 2] ** 2)))
        if lim is None:
            assert not said
        else:
            assert len(said) == 1 and "joint 'joint3': the D/A's step 0.153 N m" in said[0]
            stated = float(said[0].split("up to about ")[1].split(" mrad")[0]) * 1e-3
    assert errors[5000.0] > 2.0 * errors[None]  # the rounding shows in the floor
    assert errors[5000.0] < stated  # and the warning's figure bounds it
    # a bandwidth per joint (it stopped validate: float() of a tuple) and noise-free sensors (every
    # joint warned of nanoradians) give no warning on the shipped UR5
    d = read_toml(ROOT / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml")
    d["control"]["bandwidth"] = [40.0, 40.0, 40.0, 30.0, 30.0, 30.0]
    d.setdefault("noise", {})["position_variance"] = [0.0] * 6
    assert inertia_problems(parse_scenario(d, "ur5.toml")) == []


def test_an_arm_with_no_armature_is_warned_of_and_is_the_hard_case_it_says():
    """A URDF without the drives' armature (the Kinova Jaco2 of example-robot-data) passed validate
    without a word and adaptive_ct was 1.64 times its floor unloaded on the exact arm: warned of,
    but not on the paper's direct-drive arm nor an arm that states its armature."""
    from adaptive_dd.benchmark.preflight import inertia_problems
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml

    d = read_toml(ROOT / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml")
    said = [x for x in inertia_problems(parse_scenario(d, "v3.toml")) if "no joint has an armature" in x]
    assert (
        len(said) == 1
        and "state [arm] armature" in said[0]
        and "vertical3_payload_exact.toml 1.482" in said[0]
    )
    d["arm"]["armature"] = [0.05, 0.05, 0.02]
    assert not [x for x in inertia_problems(parse_scenario(d, "v3.toml")) if "armature" in x]
    sice = load_scenario(ROOT / "benchmarks" / "scenarios" / "sice_general.toml")
    assert not [x for x in inertia_problems(sice) if "no joint has an armature" in x]


def test_the_no_armature_warnings_figure_holds_on_vertical3():
    """The warning's figure: on vertical3 (exact) adaptive_ct is far further from its floor in the
    1 kg segment without armature (1.482, 10 seeds) than with [0.05, 0.05, 0.02] (1.119)."""
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml

    means = {}
    for armature in (None, [0.05, 0.05, 0.02]):
        d = read_toml(ROOT / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml")
        d["run"].update(duration=8.0, seeds=4, controllers=["ct_oracle", "adaptive_ct"])
        d["payload"] = d["payload"][:1]
        if armature:
            d["arm"]["armature"] = armature
        res = run_benchmark(parse_scenario(d, "v3.toml"), progress=False)
        e = {c: res.runs[c] for c in ("ct_oracle", "adaptive_ct")}
        t = np.arange(res.scenario.n_samples) * res.scenario.sample_period
        ref = res.scenario.reference.sample(t)[0][None]
        seg = (t >= 3.0) & (t < 8.0)
        rms = {c: np.sqrt(np.mean((ref - r.q)[:, seg] ** 2, axis=(1, 2))) for c, r in e.items()}
        means[bool(armature)] = float(np.mean(rms["adaptive_ct"] / rms["ct_oracle"]))
    assert means[True] < 2.0 and means[False] > 1.2 * means[True], means


def test_a_prismatic_joints_limits_and_effort_are_in_metres_and_newtons(tmp_path):
    """A prismatic joint's reference and torque warnings were in rad, rad/s and N m."""
    from adaptive_dd.benchmark import preflight
    from adaptive_dd.benchmark.scenario import parse_scenario

    urdf = tmp_path / "slide.urdf"
    urdf.write_text(
        '<robot name="slide"><link name="base"/>'
        '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>'
        '<limit effort="20" velocity="3" lower="-3" upper="3"/></joint>'
        '<link name="l1"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>'
        '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="j2" type="prismatic"><parent link="l1"/><child link="tool"/><origin xyz="0.2 0 0"/>'
        '<axis xyz="1 0 0"/><limit effort="1" velocity="0.1" lower="-0.05" upper="0.05"/></joint>'
        '<link name="tool"><inertial><mass value="0.5"/><origin xyz="0.02 0 0"/>'
        '<inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>'
    )
    data = {
        "arm": {"urdf": str(urdf), "payload_frame": "tool", "gravity": [0.0, 0.0, 0.0]},
        "reference": {
            "joint1": {"offset": 0.0, "amplitude": [0.2], "frequency": [0.5]},
            "joint2": {"offset": 0.0, "amplitude": [0.08], "frequency": [2.0]},
        },
        "payload": [{"at": 1.0, "mass": 0.5}],
        "run": {"duration": 2.0},
    }
    sc = parse_scenario(data, str(tmp_path / "s.toml"))
    assert preflight.joint_units(sc.arm) == [("rad", "rad/s", "N m"), ("m", "m/s", "N")]
    ref = preflight.reference_problems(sc)
    above = "upper limit 0.05 m (by 0.03 m)"
    assert any("reference.joint2: q = 0.08 m" in p and above in p for p in ref), ref
    assert any("reference.joint2: |qd| = " in p and "velocity limit 0.1 m/s" in p for p in ref), ref
    torque = preflight.torque_problems(sc)
    assert torque and all(" N at t = " in p and "torque limit 1 N " in p for p in torque), torque


def test_a_ratio_not_met_on_an_arm_without_armature_points_back_to_the_warning():
    """On Baxter (no armature) the report's NOT met lines did not point back to the warning that
    explained them (with an armature the loaded segment went 1.229 -> 1.108)."""
    from adaptive_dd.benchmark.report import _no_armature_note

    path = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload_exact.toml")
    sc = load_scenario(str(path))
    assert not np.any(sc.arm.armature)
    (note,) = _no_armature_note(sc, ["  adaptive_ct / ct_oracle per seed, ...: NOT met)"])
    assert "no joint of this arm has an armature (the warning before the run)" in note
    assert _no_armature_note(sc, ["  adaptive_ct / ct_oracle per seed, ...: met)"]) == []
    geared = dataclasses.replace(sc, arm=sc.arm.with_(armature=[0.05, 0.05, 0.02]))
    assert _no_armature_note(geared, ["  ...: NOT met)"]) == []
