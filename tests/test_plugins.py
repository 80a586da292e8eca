"""Controllers by import path with their settings, the worked example plug-in, the registry's errors."""

import dataclasses
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.metrics import compute_metrics
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.cli import main
from adaptive_dd.controllers import AdaptiveCT, ComputedTorque, Controller, make_controller
from adaptive_dd.errors import ParameterError

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_the_example_plugin_runs_from_a_scenario_with_its_settings():
    sc = load_scenario(EXAMPLES / "plugin.toml")
    sc = dataclasses.replace(sc, seeds=2, duration=4.0, swap_times=(2.0,), swap_masses=(3.0,))
    res = run_benchmark(sc, progress=False)
    assert "payload_gradient" in res.runs  # the label from [controllers.PayloadGradient]
    run = res.runs["payload_gradient"]
    assert run.engine == "python" and not run.failed.any() and run.floor == "slotine_li_oracle"
    m = compute_metrics(res)["controllers"]
    seg = m["payload_gradient"]["segments"][1]
    assert seg["ratio_to_floor"] is not None
    assert 1.0 < seg["mass_estimate"] < 4.0  # it learns the 3 kg disk (from 0)
    # gamma from the table reached the object: a run with another gamma gives other numbers
    from adaptive_dd.benchmark.scenario_checks import freeze

    other = dataclasses.replace(sc, controller_options=(("PayloadGradient", freeze({"gamma": 1.0})),))
    res2 = run_benchmark(dataclasses.replace(other, controllers=sc.controllers[2:3]), progress=False)
    # without a label the results carry the class's declared name (docs/controllers.md)
    assert not np.allclose(res2.runs["payload_gradient"].acc.sum_e2, run.acc.sum_e2)


def test_builtin_settings_reach_the_controller():
    c = make_controller("adaptive_ct", options={"boost_duration": 0.05, "estimator": {"tau_f": 0.02}})
    assert isinstance(c, AdaptiveCT) and c.boost_duration == 0.05 and c.online.tau_f == 0.02
    c = make_controller("adaptive_ct", options={"detector": False, "boost_bandwidth": None})
    assert c.online.detector is None
    c = make_controller("ct_oracle", options={"bandwidth": 20.0, "label": "slow_oracle"})
    assert c.gains.bandwidth == 20.0 and c.name == "slow_oracle"


@pytest.mark.parametrize(
    ("spec", "options", "match"),
    [
        ("adaptive_ct", {"tauf": 0.02}, "unknown setting"),
        ("adaptive_ct", {"estimator": {"tau": 1}}, "unknown setting"),
        ("adaptive_ct", {"detector": {"slow_factor": 1.5}}, r"unknown setting\(s\) \['slow_factor'\]"),
        # a built-in's sub-table takes no common setting, and is named as such
        (
            "adaptive_ct",
            {"estimator": {"label": "x"}},
            r"controllers\.adaptive_ct\.estimator: unknown setting",
        ),
        ("adaptive_ct", {"detector": {"threshold": 0.5}}, "threshold"),
        ("slotine_li", {"gamma": [1.0, 2.0]}, "gamma"),
        ("ct_oracle", {"bandwidth": -1.0}, "bandwidth"),
        ("nope", {}, "unknown controller"),
        ("no_such_module_xyz:Ctrl", {}, "cannot import"),
        ("adaptive_dd.controllers:NoSuchClass", {}, "has no"),
        ("adaptive_dd.plant:TABLE1_SIGMA", {}, "not a controller class"),
        ("adaptive_dd.controllers:ComputedTorque", {"unknown_key": 1}, "unknown setting"),
        (
            "adaptive_dd.controllers:ComputedTorque",
            {"dampng": 1.0},
            r"unknown setting\(s\) \['dampng'\] \('dampng': did you mean 'damping'\?\)",
        ),
    ],
)
def test_bad_controller_specs_and_settings_are_named(spec, options, match):
    with pytest.raises(ParameterError, match=match):
        make_controller(spec, options=options)


def test_an_unknown_setting_lists_what_a_scenario_may_set():
    """The settings a scenario may not set (derived: adaptive_ct's estimator and detector) are not
    listed as allowed; the message says where they are set."""
    with pytest.raises(ParameterError) as e:
        make_controller("adaptive_ct", options={"boost_bandwith": 200.0})
    msg = str(e.value)
    allowed = msg.split("allowed: ")[1].split("]")[0]
    assert "'boost_bandwidth'" in allowed and "detector" not in allowed and "estimator" not in allowed
    assert "['detector', 'estimator']: derived from the scenario, set in code only" in msg
    from adaptive_dd.benchmark.scenario_settings import DERIVED
    from adaptive_dd.controllers.registry import CONTROLLERS

    code_only = {n: {k for k, x in e.settings.items() if not x.scenario_key} for n, e in CONTROLLERS.items()}
    assert {n: set(d) for n, d in DERIVED.items()} == {n: k for n, k in code_only.items() if k}


def test_a_plugin_written_against_the_old_interface_still_works():
    """reset / command(q, qd, q_d, qd_d, qdd_d, sigma_true=None) / observe, no new attributes."""
    from adaptive_dd.controllers import Controller

    class OldPD(Controller):
        name = "old_pd"

        def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
            assert sigma_true is None  # only oracles see the true model
            return 100.0 * (q_d - q) + 10.0 * (qd_d - qd)

    sc = dataclasses.replace(load_scenario(), seeds=1, duration=0.5, swap_times=(), swap_masses=())
    res = run_benchmark(sc, progress=False, controllers={"old_pd": OldPD()})
    assert not res.runs["old_pd"].failed.any() and not res.runs["old_pd"].error


class BarePD:
    """A plain PD written against reset / command / observe alone: no base class, no attributes."""

    def reset(self, n_trials, sample_period):
        self.n = n_trials

    def command(self, q, qd, q_d, qd_d, qdd_d):
        return 100.0 * (q_d - q) + 10.0 * (qd_d - qd)

    def observe(self, q, qd, tau):
        pass


def test_a_bare_class_without_base_runs_as_the_docs_say(tmp_path, capsys):
    """docs/controllers.md: a class written against reset / command / observe alone works."""
    assert not isinstance(BarePD(), Controller)
    sc = dataclasses.replace(load_scenario(), seeds=2, duration=0.5, swap_times=(0.25,), swap_masses=(1.0,))
    res = run_benchmark(
        sc, progress=False, controllers={"bare": BarePD(), "ct_oracle": ComputedTorque(oracle=True)}
    )
    run = res.runs["bare"]
    assert not run.failed.any() and not run.error
    assert run.floor == "ct_oracle" and run.sigma_hat is None and run.alarm_times is None
    m = res.metrics()["controllers"]["bare"]
    assert m["failed_trials"] == 0 and m["segments"][1]["ratio_to_floor"]["n"] == 2
    # and from a scenario file, through the CLI
    (tmp_path / "bare_mod.py").write_text(
        "class BarePD:\n"
        "    def reset(self, n, T):\n        pass\n"
        "    def command(self, q, qd, q_d, qd_d, qdd_d):\n"
        "        return 100.0 * (q_d - q) + 10.0 * (qd_d - qd)\n"
        "    def observe(self, q, qd, tau):\n        pass\n"
    )
    (tmp_path / "bare.toml").write_text(
        '[run]\nduration = 0.5\nseeds = 1\ncontrollers = ["bare_mod:BarePD"]\n'
    )
    assert (
        main(["benchmark", str(tmp_path / "bare.toml"), "--out", str(tmp_path / "out"), "--no-progress"]) == 0
    )
    out = capsys.readouterr().out
    assert "failed trials: none" in out


# ---- plug-ins on any arm (issue 27) ---------------------------------------------------------


def test_the_n_joint_example_receives_the_arm_and_the_scenario():
    from adaptive_dd.plant import Arm  # issue 27: this import failed

    sc = load_scenario(EXAMPLES / "plugin_urdf.toml")
    sc = dataclasses.replace(sc, seeds=1, duration=0.6, swap_times=(0.3,), swap_masses=(2.0,), swap_com=())
    assert isinstance(sc.arm, Arm)
    ctrl = make_controller(
        "assumed_payload:AssumedPayload", options={"label": "x"}, arm=sc.arm, search=(EXAMPLES,), scenario=sc
    )
    assert ctrl.arm is sc.arm and ctrl.mass == 1.0  # the mean of the scenario's masses 0 and 2 kg
    res = run_benchmark(sc, progress=False)
    run = res.runs["assumed_2kg"]
    assert run.engine == "python" and not run.failed.any() and not run.error
    assert run.sigma_hat.shape == (1, sc.n_samples, sc.arm.base.count)
    np.testing.assert_allclose(run.sigma_end[0, 0], sc.arm.sigma_with_payload(2.0))
    with pytest.raises(ParameterError, match=r"\['arm'\] are given by the runner"):
        make_controller("assumed_payload:AssumedPayload", options={"arm": 1}, arm=sc.arm, search=(EXAMPLES,))


class LateEstimate(Controller):
    """A PD whose estimate appears only after its first observe (issue 27: it was not reported)."""

    name = "late"

    def reset(self, n_trials, sample_period):
        super().reset(n_trials, sample_period)
        self.seen, self.est = 0, None

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        return 400.0 * (q_d - q) + 40.0 * (qd_d - qd)

    def observe(self, q, qd, tau):
        self.seen += 1
        if self.seen == 3:
            self.est = np.full(self.p, 1.5)

    @property
    def sigma_hat(self):
        return self.est


class AssignedEstimate(Controller):
    """The same estimate set as a plain attribute, as docs/controllers.md's table describes it
    (the base class's ``sigma_hat`` was a read-only property: every trial failed in ``reset``)."""

    name = "late"
    command = LateEstimate.command

    def reset(self, n_trials, sample_period):
        super().reset(n_trials, sample_period)
        self.seen, self.sigma_hat = 0, None

    def observe(self, q, qd, tau):
        self.seen += 1
        if self.seen == 3:
            self.sigma_hat = np.full(self.p, 1.5)


@pytest.mark.parametrize("cls", [LateEstimate, AssignedEstimate])
@pytest.mark.parametrize("arm_kind", ["two_link", "urdf"])
def test_an_estimate_set_after_the_first_sample_is_reported(arm_kind, cls):
    sc = load_scenario() if arm_kind == "two_link" else load_scenario(EXAMPLES / "plugin_urdf.toml")
    sc = dataclasses.replace(sc, seeds=2, duration=0.2, swap_times=(0.1,), swap_masses=(1.0,), swap_com=())
    ctrl = cls()
    ctrl.p = (sc.closed_forms or sc.arm).sigma.shape[0]  # the run's parameters: the paper's sigma on its arm
    run = run_benchmark(sc, progress=False, controllers={"late": ctrl}).runs["late"]
    assert not run.error and run.sigma_end is not None
    assert np.all(run.sigma_end == 1.5)  # both segments' ends, both trials
    assert np.isnan(run.sigma_hat[:, :2]).all() and np.all(run.sigma_hat[:, 2:] == 1.5)
    # a controller that never estimates reports none
    run = run_benchmark(sc, progress=False, controllers={"bare": BarePD()}).runs["bare"]
    assert run.sigma_end is None and run.sigma_hat is None


class NaNEstimate(LateEstimate):
    """A PD whose estimator breaks in seed 1 after 0.15 s: its estimate turns NaN, its torque stays
    finite (the trial does not fail)."""

    name = "nan_est"

    def observe(self, q, qd, tau):
        self.seen += 1
        self.est = np.full((len(q), self.p), 1.5) if np.ndim(q) > 1 else np.full(self.p, 1.5)
        if self.seen > 150 and self.est.ndim > 1:
            self.est[1] = np.nan


def test_a_nan_estimate_is_said_not_read_as_no_estimate():
    """A plug-in's estimate that is NaN at a segment's end in a trial that did not fail was left out of
    the mass column in silence (it read as no estimate): metrics.json lists each (seed, segment),
    the report says it."""
    from adaptive_dd.benchmark.report import format_report

    sc = dataclasses.replace(load_scenario(), seeds=3, duration=0.2, swap_times=(0.1,), swap_masses=(1.0,))
    ctrl = NaNEstimate()
    ctrl.p = sc.closed_forms.sigma.shape[0]
    res = run_benchmark(
        sc,
        progress=False,
        controllers={"ct_oracle": make_controller("ct_oracle"), "nan_est": ctrl, "bare": BarePD()},
    )
    m = res.metrics()["controllers"]
    assert not res.runs["nan_est"].failed.any()
    assert m["nan_est"]["nonfinite_estimates"] == [[1, 1]] and m["bare"]["nonfinite_estimates"] is None
    text = format_report(res.metrics(), res)
    assert (
        "nan_est: its estimate is not finite at the end of 1 segment(s) of trials that did not fail (seeds 1)"
        in text
    )


# ---- a plug-in's name; settings tables of controllers left out by --controllers --------------

NAMED_PD = (
    "class NamedPD:\n"
    "    name = 'gravity_pd'\n"
    "    def reset(self, n, T):\n        pass\n"
    "    def command(self, q, qd, q_d, qd_d, qdd_d):\n"
    "        return 100.0 * (q_d - q) + 10.0 * (qd_d - qd)\n"
    "    def observe(self, q, qd, tau):\n        pass\n"
    "class Unnamed(NamedPD):\n"
    "    name = None\n"
)


def _named_scenario(tmp_path, tables: str = "", controllers: str = '"named_mod:NamedPD"'):
    (tmp_path / "named_mod.py").write_text(NAMED_PD)
    path = tmp_path / "named.toml"
    path.write_text(f"[run]\nduration = 0.4\nseeds = 1\ncontrollers = [{controllers}]\n{tables}")
    return load_scenario(path)


def test_a_plugins_declared_name_is_the_name_its_results_carry(tmp_path):
    """docs/controllers.md: a controller's ``name`` is the name its results carry, a ``label``
    setting overrides it; without either, the class name. Two controllers that would carry the
    same name are an error naming both (a dict of runs would keep one silently)."""
    from adaptive_dd.controllers.registry import scenario_controller, scenario_controllers

    sc = _named_scenario(tmp_path)
    assert scenario_controller(sc, "named_mod:NamedPD")[0] == "gravity_pd"
    res = run_benchmark(dataclasses.replace(sc, swap_times=(), swap_masses=()), progress=False)
    assert list(res.runs) == ["gravity_pd"] and not res.runs["gravity_pd"].error
    labelled = _named_scenario(tmp_path, '[controllers.NamedPD]\nlabel = "mine"\n')
    assert scenario_controller(labelled, "named_mod:NamedPD")[0] == "mine"
    unnamed = _named_scenario(tmp_path, controllers='"named_mod:Unnamed"')
    assert scenario_controller(unnamed, "named_mod:Unnamed")[0] == "Unnamed"
    with pytest.raises(  # a label's clash: an error of the file, when it is read
        ValueError, match="'named_mod:NamedPD' and 'ct_oracle' would both carry the name 'ct_oracle'"
    ):
        _named_scenario(tmp_path, '[controllers.NamedPD]\nlabel = "ct_oracle"\n',
                        '"named_mod:NamedPD", "ct_oracle"')  # fmt: skip
    # a plug-in's declared name: when the run builds it (the file does not import it)
    (tmp_path / "twin_mod.py").write_text("from named_mod import NamedPD\nclass Twin(NamedPD):\n    pass\n")
    clash = _named_scenario(tmp_path, controllers='"named_mod:NamedPD", "twin_mod:Twin"')
    with pytest.raises(ParameterError, match="both carry the name 'gravity_pd'"):
        scenario_controllers(clash)


def test_controllers_picked_on_the_command_line_drop_the_others_tables(tmp_path):
    """``benchmark --controllers ct_oracle`` on a scenario with a plug-in's settings table runs
    (it failed: ``controllers.PayloadGradient: not a controller of run.controllers``); the tables
    of the controllers kept stay; a table for a controller the file never lists is still an error."""
    from adaptive_dd.benchmark.scenario_checks import freeze
    from adaptive_dd.cli.benchmark import only_controllers
    from adaptive_dd.errors import ScenarioError

    sc = load_scenario(EXAMPLES / "plugin.toml")
    with pytest.raises(
        ScenarioError, match=r"controllers\.PayloadGradient: not a controller of run\.controllers"
    ):
        dataclasses.replace(sc, controllers=("ct_oracle",))  # the selection as the CLI made it before
    picked = sc.with_controllers(only_controllers(sc, ["ct_oracle"]))
    assert picked.controllers == ("ct_oracle",) and picked.controller_options == ()
    kept = sc.with_controllers(only_controllers(sc, ["adaptive_ct"]))  # its floor ct_oracle added
    assert kept.controllers == ("adaptive_ct", "ct_oracle")
    assert kept.controller_options == (("adaptive_ct", freeze({"boost_duration": 0.2})),)
    plug = sc.with_controllers(("payload_gradient:PayloadGradient",))
    assert plug.options("PayloadGradient") == {"gamma": 200.0, "label": "payload_gradient"}
    # named by its label, as its results are (it was refused: not among the controllers)
    assert only_controllers(sc, ["payload_gradient"]) == only_controllers(
        sc, ["payload_gradient:PayloadGradient"]
    )
    assert "payload_gradient:PayloadGradient" in only_controllers(sc, ["payload_gradient"])
    with pytest.raises(ParameterError, match=r"payload_gradiant \(did you mean 'payload_gradient'\?\)"):
        only_controllers(sc, ["payload_gradiant"])
    text = (EXAMPLES / "plugin.toml").read_text().replace('"payload_gradient:PayloadGradient", ', "")
    (tmp_path / "unlisted.toml").write_text(text)
    with pytest.raises(
        ScenarioError, match=r"controllers\.PayloadGradient: not a controller of run\.controllers"
    ):
        load_scenario(tmp_path / "unlisted.toml")
    # through the CLI, as the user ran it
    out = tmp_path / "out"
    argv = ["benchmark", str(EXAMPLES / "plugin.toml"), "--controllers", "ct_oracle", "--seeds", "1"]
    assert main([*argv, "--out", str(out), "--no-progress"]) == 0
    assert (out / "per_seed.csv").exists()


def test_a_plugins_table_is_named_by_its_class_and_its_messages_say_so():
    """A plug-in's unknown setting names the table the user writes (``controllers.Class``, not the
    import path) and lists every setting it takes, the common ones included; a table named by the
    label is told the class name."""
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.errors import ScenarioError

    with pytest.raises(
        ParameterError,
        match=r"^controllers\.ComputedTorque: unknown setting\(s\) \['scael'\].*; allowed: \[.*'bandwidth', "
        r"'damping', .*'label'.*\]",
    ):
        make_controller("adaptive_dd.controllers:ComputedTorque", options={"scael": 1})
    data = {
        "run": {"duration": 1.0, "controllers": ["ct_oracle", "adaptive_dd.controllers:ComputedTorque"]},
        "controllers": {"mine": {"label": "mine"}},
    }
    with pytest.raises(
        ScenarioError, match=r"controllers\.mine: .*named by its class \(\[controllers\.ComputedTorque\]\)"
    ):
        parse_scenario(data, "s.toml")
    # a class misspelt in run.controllers (or the table): either may be wrong, both are named
    data["run"]["controllers"][1] = "adaptive_dd.controllers:ComputedTorqueX"
    data["controllers"] = {"ComputedTorque": {"label": "mine"}}
    with pytest.raises(
        ScenarioError,
        match=r"controllers\.ComputedTorque: not a controller .*; run\.controllers lists "
        r"'adaptive_dd\.controllers:ComputedTorqueX': if its class is ComputedTorque, correct that entry, "
        r"else name the table \[controllers\.ComputedTorqueX\]",
    ):
        parse_scenario(data, "s.toml")


def test_the_scenarios_own_plug_in_is_taken_before_the_working_directorys(tmp_path, monkeypatch):
    """A plug-in file in the working directory silently replaced the one beside the scenario (the
    results' names were read with the working directory alone, which imported its module first);
    the scenario's folder comes first everywhere, and a module of the same name imported earlier
    from elsewhere is an error naming both files, not a silent swap."""
    import importlib
    import sys
    import uuid

    from adaptive_dd.benchmark.scenario_settings import result_names
    from adaptive_dd.controllers.registry import scenario_controller

    mod = f"shadow_{uuid.uuid4().hex[:8]}"
    (tmp_path / "sub").mkdir()
    for where, name in ((tmp_path, "from_cwd"), (tmp_path / "sub", "from_sub")):
        (where / f"{mod}.py").write_text(NAMED_PD.replace("'gravity_pd'", repr(name)))
    path = tmp_path / "sub" / "s.toml"
    path.write_text(f'[run]\nduration = 0.4\nseeds = 1\ncontrollers = ["{mod}:NamedPD", "ct_oracle"]\n')
    monkeypatch.chdir(tmp_path)
    monkeypatch.delitem(sys.modules, mod, raising=False)
    sc = load_scenario(path)
    assert result_names(sc.controllers, {}, sc.source)[f"{mod}:NamedPD"] == "from_sub"
    assert scenario_controller(sc, f"{mod}:NamedPD")[0] == "from_sub"
    monkeypatch.delitem(sys.modules, mod)
    monkeypatch.syspath_prepend(str(tmp_path))  # the working directory's module found first
    importlib.import_module(mod)
    with pytest.raises(
        ParameterError,
        match=rf"module '{mod}' \({tmp_path / mod}\.py\) is found before your {tmp_path / 'sub' / mod}\.py",
    ):
        scenario_controller(sc, f"{mod}:NamedPD")
    monkeypatch.delitem(sys.modules, mod)


@pytest.mark.parametrize(
    ("table", "needle"),
    [
        (
            "bandwidth = 4000.0",
            "controllers.NamedPD.bandwidth: 4000.0 rad/s at T = 0.001 s gives bandwidth * T = 4 > 0.2",
        ),
        ("damping = -1.0", "controllers.NamedPD.damping"),
    ],
)
def test_a_plug_ins_gains_have_the_bounds_of_a_built_ins(tmp_path, table, needle):
    """``[controllers.PIDGravity] bandwidth = 4000`` passed validate and failed every trial
    (a built-in's is refused when the file is read): a plug-in's table is held to the same bounds."""
    from adaptive_dd.errors import ScenarioError

    with pytest.raises(ScenarioError, match=re.escape(needle)):
        _named_scenario(tmp_path, f"[controllers.NamedPD]\n{table}\n")


def test_a_scenario_read_by_a_relative_path_finds_its_plug_in_from_another_folder(tmp_path, monkeypatch):
    """Read as "myplug.toml" from its folder, then run from another: the plug-in beside it was looked
    for in the new working directory ("looked ... in: /"); the file's folder is kept as it was read."""
    import uuid

    from adaptive_dd.controllers.registry import scenario_controller

    mod = f"rel_{uuid.uuid4().hex[:8]}"
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / f"{mod}.py").write_text(NAMED_PD)
    (tmp_path / "sub" / "s.toml").write_text(
        f'[run]\nduration = 0.4\ncontrollers = ["{mod}:NamedPD", "ct_oracle"]\n'
    )
    monkeypatch.chdir(tmp_path / "sub")
    sc = load_scenario("s.toml")
    assert sc.source == "s.toml" and sc.origin == str(tmp_path / "sub")
    monkeypatch.chdir(tmp_path)
    monkeypatch.delitem(sys.modules, mod, raising=False)
    assert scenario_controller(sc, f"{mod}:NamedPD")[0] == "gravity_pd"
    monkeypatch.delitem(sys.modules, mod)
