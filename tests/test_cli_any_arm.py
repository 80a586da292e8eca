"""The command line on both kinds of arm (issue 27): every option that does not apply to the
arm's kind is an error naming it, the options both kinds share mean the same on both (``simulate
--no-saturate``, ``--experiment reference``, ``identify --online --arm``, ``--tau-f``'s default),
``--debug`` after the command, ``excite`` on a two-link URDF."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from adaptive_dd.cli import main

ROOT = Path(__file__).resolve().parent.parent
SICE_URDF = str(ROOT / "benchmarks" / "scenarios" / "sice_urdf.toml")
UR5 = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml"))


def _error(capsys, argv) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err  # one line, no traceback
    return err


@pytest.mark.parametrize(
    "argv, named",
    [
        (["simulate", "--arm", UR5, "--experiment", "table2"], "--experiment table2"),
        (["simulate", "--arm", SICE_URDF, "--experiment", "table2", "--com", "0", "0", "0.1"], "--com"),
        (["simulate", "--com", "0", "0", "0.1"], "--com"),
        (["simulate", "--plant", "benchmark"], "--plant"),
        (["simulate", "--arm", SICE_URDF, "--plant", "model"], "--plant"),
        (["identify", "rec.csv", "--arm", UR5, "--online"], "--online"),
        (["identify", "rec.csv", "--arm", UR5, "--method", "M1"], "--method"),
        (["identify", "rec.csv", "--arm", UR5, "--estimator", "paper"], "--estimator"),
        (["identify", "rec.csv", "--arm", UR5, "--split", "16"], "--split"),
        (["identify", "rec.csv", "--arm", UR5, "--estimator", "exact"], "--estimator"),  # its default
        (["identify", "rec.csv", "--output-error", "auto"], "--output-error"),  # its default
        (["identify", "rec.csv", "--arm", SICE_URDF, "--window", "0", "1"], "--window"),
        (["identify", "rec.csv", "--arm", UR5, "--true", *["1"] * 7], "--true"),
        (["identify", "rec.csv", "--baseline", "b.csv"], "--baseline"),
        (["identify", "rec.csv", "--payload-only"], "--payload-only"),
        (["identify", "rec.csv", "--arm", SICE_URDF, "--segment-length", "100"], "--segment-length"),
        (["identify", "rec.csv", "--max-iter", "3"], "--max-iter"),
    ],
)
def test_an_option_for_the_other_kind_of_arm_is_an_error_naming_it(tmp_path, capsys, argv, named):
    err = _error(capsys, [*argv, "--out", str(tmp_path / "out")])
    assert f"error: {named}" in err and ("URDF" in err or "two-link" in err), err
    assert not (tmp_path / "out").exists()  # refused before anything runs


def test_debug_is_accepted_after_the_command(capsys, monkeypatch):
    import adaptive_dd.cli.validate as cli_validate

    def broken(args):
        raise RuntimeError("planted")

    monkeypatch.setattr(cli_validate, "run", broken)
    assert main(["validate"]) == 3
    assert "Traceback" not in capsys.readouterr().err
    assert main(["validate", "--debug"]) == 3
    assert "Traceback" in capsys.readouterr().err
    assert main(["--debug", "validate"]) == 3
    assert "Traceback" in capsys.readouterr().err


def test_excite_works_on_the_two_link_urdf_arm(tmp_path, capsys):
    """Issue 27: 'excite needs an [arm] from a URDF' on sice_urdf.toml (which is one)."""
    out = tmp_path / "designed.toml"
    argv = ["excite", "--arm", SICE_URDF, "--harmonics", "1", "--maxiter", "1", "--duration", "1.0"]
    assert main([*argv, "--out", str(out)]) == 0
    printed = capsys.readouterr()
    assert "2-joint arm of" in printed.out
    assert "scenario's reference" in printed.out and "against the scenario's own reference" in printed.out
    # what it is doing goes to stderr as it goes (minutes on a 7-joint arm), not to the result
    assert "designing the excitation of the 2-joint arm" in printed.err
    assert "bounding the designed" in printed.err
    assert "designing" not in printed.out
    text = out.read_text()
    assert "[reference]" in text and 'robot = "sice_arm"' in text
    err = _error(capsys, ["excite", "--arm", str(ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml")])
    assert "excite needs an [arm] from a URDF" in err and 'robot = "sice_arm"' in err


def _capture(monkeypatch, module, name: str) -> dict:
    """Replace ``module.name`` by a function that keeps its arguments and stops the command."""
    seen: dict = {}

    def stop(*args, **kwargs):
        seen["args"], seen["kwargs"] = args, kwargs
        raise RuntimeError("captured")

    monkeypatch.setattr(module, name, stop)
    return seen


@pytest.mark.parametrize("no_saturate", [False, True])
def test_no_saturate_applies_to_a_urdf_arm(tmp_path, capsys, monkeypatch, no_saturate):
    """--no-saturate was refused on an arm from a URDF: the record's actuator now saturates or not."""
    import adaptive_dd.identification.records as records

    seen = _capture(monkeypatch, records, "simulate_record")
    argv = ["simulate", "--arm", UR5, "--duration", "0.1", "--out", str(tmp_path / "o")]
    assert main(argv + ["--no-saturate"] * no_saturate) == 3
    assert seen["args"][0].actuator.saturate is not no_saturate


@pytest.mark.parametrize("scenario", [SICE_URDF, None])
def test_the_reference_experiment_runs_on_the_two_link_arm(tmp_path, capsys, scenario):
    """simulate --experiment reference: the scenario's reference tracked on the paper's arm too (its
    general model); without --arm the SICE arm tracks the shipped payload_swap's reference."""
    out = tmp_path / "o"
    argv = ["simulate", "--experiment", "reference", "--duration", "0.2", "--out", str(out)]
    assert main(argv + (["--arm", scenario] if scenario else [])) == 0
    text = capsys.readouterr().out
    assert "the scenario's reference tracked by computed torque" in text
    assert ("2-joint arm of" if scenario else "the SICE arm (2 joints") in text
    head = (out / "trajectory.csv").read_text().splitlines()
    assert head[0] == "t,q1,q2,qd1,qd2,tau1,tau2" and len(head) == 201
    assert np.load(out / "trajectory.npz")["q_true"].shape == (1, 200, 2)


def test_the_reference_experiment_needs_a_urdf(tmp_path, capsys):
    lugre = str(ROOT / "benchmarks" / "scenarios" / "lugre_friction.toml")
    err = _error(capsys, ["simulate", "--arm", lugre, "--experiment", "reference", "--out", str(tmp_path)])
    assert "--experiment reference needs an [arm] from a URDF" in err and lugre in err


def _two_link_record(path, T: float, n: int):
    from adaptive_dd.io import write_recording

    t = np.arange(n) * T
    q = np.sin(t[:, None] * np.array([1.0, 1.3]))
    tau = np.sin(2.0 * t[:, None] * np.array([1.0, 1.3]))  # a varying torque (a constant one is refused)
    return write_recording(path, t, q, np.cos(t[:, None] * np.array([1.0, 1.3])), tau)


def test_identify_online_starts_from_the_scenario_arm(tmp_path, capsys, monkeypatch):
    """identify --online --arm TWO_LINK.toml started from the SICE arm whatever the scenario said."""
    import adaptive_dd.identification.two_link_online as online
    from adaptive_dd.cli import _common
    from adaptive_dd.cli._common import load_arm
    from adaptive_dd.plant.two_link import ClosedFormTwoLink

    sice = ClosedFormTwoLink.sice()
    arm_toml = tmp_path / "arm.toml"
    sigma = ", ".join(repr(1.2 * float(v)) for v in sice.sigma)
    arm_toml.write_text(f"[arm]\nsigma = [{sigma}]\nl1 = {sice.l1}\nl2 = {sice.l2}\n")
    rec = _two_link_record(tmp_path / "rec.csv", 1e-3, 2000)
    seen = _capture(monkeypatch, online, "run_two_link_online")
    argv = ["identify", str(rec), "--online", "--out", str(tmp_path / "id")]
    assert main([*argv, "--arm", str(arm_toml)]) == 3
    np.testing.assert_array_equal(seen["args"][4], _common.closed_form_view(load_arm(str(arm_toml))).sigma)
    assert not np.allclose(seen["args"][4], sice.sigma)
    assert main(argv) == 3  # without --arm: the SICE arm (Table 1)
    np.testing.assert_array_equal(seen["args"][4], sice.sigma)


@pytest.mark.parametrize("T, tau_f", [(1e-3, 0.02), (0.02, 0.04)])
def test_identify_tau_f_default_is_sized_to_the_sample_rate_on_the_two_link_arm(
    tmp_path, capsys, monkeypatch, T, tau_f
):
    """One default on every arm: two sample periods, at least 0.02 s (was 0.02 s whatever T)."""
    import adaptive_dd.identification.estimators as est

    class Few:
        n_used, split, final, std = 12, "full", np.ones(7), np.ones(7)

    monkeypatch.setattr(est, "estimate", lambda *a, **k: Few())
    rec = _two_link_record(tmp_path / "rec.csv", T, 400)
    assert main(["identify", str(rec), "--out", str(tmp_path / "id")]) == 2  # too few equations
    assert f"tau_f = {tau_f}\n" in capsys.readouterr().out


def test_sweep_workers_with_a_scheduler_is_an_error(tmp_path, capsys):
    argv = ["sweep", str(tmp_path / "none.toml"), "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"]
    err = _error(capsys, argv)
    assert "error: --workers: sizes the local cluster" in err


def test_the_arm_kind_is_asked_in_one_place():
    """The CLI asks whether an arm has the paper's closed forms through
    :func:`adaptive_dd.plant.two_link.closed_form_view` (the package's one place, imported by
    ``cli/_common.py``), never reads ``closed_form`` itself nor tests the arm's class (issue 27: the
    type tests on the arm's class go)."""
    import ast

    from adaptive_dd.cli import _common
    from adaptive_dd.plant import two_link
    from adaptive_dd.plant.arm import Arm

    assert _common.closed_form_view is two_link.closed_form_view
    arm, general = _common.load_arm(SICE_URDF), _common.load_arm(SICE_URDF, general="test")
    assert isinstance(arm, Arm) and isinstance(general, Arm)  # one arm type
    assert _common.closed_form_view(arm) is not None and _common.closed_form_view(general) is None
    for f in sorted((ROOT / "adaptive_dd" / "cli").glob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            assert not (isinstance(node, ast.Attribute) and node.attr == "closed_form"), f.name
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance":
                assert "Arm" not in ast.unparse(node.args[1]), f"{f.name}: {ast.unparse(node)}"
            if isinstance(node, ast.FunctionDef):
                assert node.name not in ("is_two_link", "is_chain"), f"{f.name}: a second {node.name}"


@pytest.mark.parametrize("scenario", [None, "adaptive_dd/scenarios/ur5_tool_swap.toml"])
def test_benchmark_controllers_option_keeps_the_floor(scenario, capsys):
    """``benchmark --controllers adaptive_ct`` runs adaptive_ct and its floor ct_oracle (said on
    stderr), in the scenario's order, on either arm; a name the scenario lacks is a usage error."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.cli import main
    from adaptive_dd.cli.benchmark import only_controllers

    root = Path(__file__).resolve().parents[1]
    sc = load_scenario(None if scenario is None else root / scenario)
    assert only_controllers(sc, ["adaptive_ct"]) == ("ct_oracle", "adaptive_ct")
    assert "ct_oracle added (the floor of adaptive_ct)" in capsys.readouterr().err
    assert only_controllers(sc, ["pd", "ct_oracle"]) == ("pd", "ct_oracle")
    args = ["benchmark"] + ([] if scenario is None else [str(root / scenario)])
    assert main([*args, "--controllers", "adaptive_ct", "no_such_law", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "no_such_law not among" in err and "adaptive_ct" in err
    assert main([*args, "--controllers", "adaptive_ct", "ct_orcale", "--no-progress"]) == 2
    assert "ct_orcale (did you mean 'ct_oracle'?) not among" in capsys.readouterr().err


def test_plant_serial_is_read_as_benchmark_with_a_warning(capsys):
    """The ``serial_`` prefix went everywhere else; ``--plant serial`` is its old name: read as
    ``benchmark``, the warning naming the new one."""
    from adaptive_dd.cli import build_parser

    assert build_parser().parse_args(["simulate", "--plant", "serial"]).plant == "benchmark"
    assert "--plant serial is deprecated; use --plant benchmark" in capsys.readouterr().err
    assert build_parser().parse_args(["simulate", "--plant", "benchmark"]).plant == "benchmark"
    assert capsys.readouterr().err == ""
    with pytest.raises(SystemExit):
        build_parser().parse_args(["simulate", "--plant", "rk4"])
    assert "invalid choice: 'rk4'" in capsys.readouterr().err


def test_benchmark_warns_of_a_reference_beyond_the_joint_limits(tmp_path, capsys, monkeypatch):
    """A reference that leaves a joint's position limit is said before the run (``validate``
    alone used to say it: a user who ran ``benchmark`` first learnt nothing), and the run goes on."""
    import adaptive_dd.cli.benchmark as cli_benchmark

    ran = []
    no_run = SimpleNamespace(runs={})
    monkeypatch.setattr(cli_benchmark, "_benchmark", lambda args, sc, outputs: (ran.append(sc) or [], no_run))
    assert main(["benchmark", UR5, "--out", str(tmp_path / "ok"), "--no-progress"]) == 0
    assert "warning:" not in capsys.readouterr().err  # a shipped scenario: within its limits
    text = (ROOT / "adaptive_dd" / "scenarios" / "vertical3_payload_exact.toml").read_text()
    bad = tmp_path / "beyond.toml"
    bad.write_text(text.replace("joint2 = { offset = -0.6,", "joint2 = { offset = -2.9,"))
    assert main(["benchmark", str(bad), "--out", str(tmp_path / "bad"), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert f"warning: {bad}: reference.joint2: q = -3.542 rad" in err, err
    assert "below the joint's lower limit -3.142 rad" in err
    assert len(ran) == 2  # warned, and ran


@pytest.mark.parametrize("opt", [["--method", "M1"], ["--split", "15"], ["--estimator", "paper"]])
def test_online_refuses_the_batch_estimators_options(tmp_path, capsys, opt):
    """``identify REC --online`` runs adaptive_ct's online estimator with its own settings: a batch
    estimator's option given beside it was silently ignored."""
    err = _error(capsys, ["identify", "rec.csv", "--online", *opt, "--out", str(tmp_path / "out")])
    assert f"error: {opt[0]}: options of the batch estimators; --online runs" in err, err


@pytest.mark.parametrize("command", [["check", "--arm"], ["simulate", "--duration", "0.2", "--arm"]])
def test_an_unknown_table_of_an_arm_file_is_refused(tmp_path, capsys, command):
    """``[arms]`` (a typo of ``[arm]``) was read as no ``[arm]``: check and simulate ran the SICE arm
    under the file's name."""
    f = tmp_path / "r5.toml"
    f.write_text('[arms]\nrobot = "ur5"\n')
    err = _error(
        capsys, [*command, str(f), *(["--out", str(tmp_path / "o")] if command[0] == "simulate" else [])]
    )
    assert "r5.toml: [arms]: unknown table" in err, err


def test_reproduce_needs_two_seeds_for_its_std(capsys):
    """``reproduce --seeds 1`` printed numpy's warnings and wrote NaN stds into its JSON."""
    with pytest.raises(SystemExit) as exc:  # argparse's usage error
        main(["reproduce", "--seeds", "1"])
    assert exc.value.code == 2 and "argument --seeds: 1 is outside [2, 10000]" in capsys.readouterr().err


def test_a_record_of_another_arm_is_refused_not_cut(tmp_path, capsys):
    """A 4-joint record given to a 3-joint arm: its extra joints' columns were dropped in silence and
    the fit and prediction ran (one joint's torque error 308 %)."""
    t = np.arange(300) * 0.01
    cols = {"t": t}
    for i in range(1, 5):
        cols |= {f"q{i}": np.sin(t * i), f"tau{i}": np.cos(t * i)}
    path = tmp_path / "four.csv"
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="")
    v3 = str(resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload_exact.toml"))
    err = _error(capsys, ["identify", "--arm", v3, str(path), "--out", str(tmp_path / "o")])
    assert "columns ['q4', 'tau4'] do not fit the 3-joint arm" in err, err


def test_excite_refuses_frequencies_its_scenario_could_not_hold(tmp_path, capsys):
    """``excite --f0 200`` designed (SLSQP failing), wrote a scenario and exited 0; validate then refused
    the scenario's 1000 Hz: refused before the design now."""
    err = _error(capsys, ["excite", "--arm", UR5, "--f0", "200", "--out", str(tmp_path / "x.toml")])
    assert "--f0 200 Hz x --harmonics 5: 1000 Hz is above 0.1 / T = 100 Hz" in err
    assert not (tmp_path / "x.toml").exists()


def test_a_zero_noise_variance_is_refused_by_the_option():
    with pytest.raises(SystemExit):  # argparse's usage error, before any work
        main(["identify", "rec.csv", "--position-variance", "0", "0"])


@pytest.mark.parametrize(
    "argv, named",
    [
        (["identify", "rec.csv", "--arm", UR5, "--output-error", "off", "--max-iter", "5"], "--max-iter"),
        (
            ["identify", "rec.csv", "--arm", UR5, "--output-error", "off", "--segment-length", "50"],
            "--segment-length",
        ),
        (["identify", "rec.csv", "--arm", UR5, "--payload-only", "--output-error", "off"], "--output-error"),
        (["identify", "rec.csv", "--arm", UR5, "--payload-only", "--hold-unseen", "off"], "--hold-unseen"),
    ],
)
def test_an_option_without_effect_is_an_error_naming_it(capsys, argv, named):
    """Accepted and ignored before: output error's settings with it off, --payload-only (always output
    error, nothing held) with --output-error or --hold-unseen."""
    assert f"error: {named}" in _error(capsys, argv)


def test_table2_says_it_leaves_the_scenarios_reference_unused(tmp_path, capsys):
    """simulate --arm of a designed sice_urdf scenario ran Table 2 by default and passed over the
    designed [reference] without a word."""
    assert main(["simulate", "--arm", SICE_URDF, "--duration", "0.5", "--out", str(tmp_path / "o")]) == 0
    assert "[reference] is not used" in capsys.readouterr().out


def test_payload_only_on_a_planar_arm_fits_the_four_it_determines(tmp_path, capsys):
    """vertical3's base parameters determine 4 of the payload's 10: --payload-only was refused; it
    fits those four and prints the others as not determined."""
    arm = str(ROOT / "benchmarks" / "scenarios" / "ident_vertical3.toml")
    rec = tmp_path / "rec"
    sim = ["simulate", "--arm", arm, "--duration", "3", "--payload", "1.5", "--com", "0.03", "0", "0.05"]
    assert main([*sim, "--out", str(rec)]) == 0
    truth = json.loads((rec / "trajectory.json").read_text())["payload"]  # what was simulated, said
    assert truth["mass_kg"] == 1.5 and truth["com_m"] == pytest.approx([0.03, 0.0, 0.05])
    assert truth["inertia_com_kg_m2"][1] == pytest.approx(1.5 * 0.05**2 / 4)  # the default disk's
    assert "inertia about its centre of mass [ixx, iyy, izz]" in capsys.readouterr().out
    assert main(["identify", "--arm", arm, str(rec / "trajectory.csv"), "--payload-only"]) == 0
    out = capsys.readouterr().out
    assert "the 4 of the payload's 10 parameters this arm determines fitted" in out
    line = next(x for x in out.splitlines() if x.startswith("payload (one record, arm known)"))
    mass = float(line.split("mass ")[1].split(" ")[0])
    cx, cy, cz = line.split("centre of mass [")[1].split("]")[0].split(", ")
    assert (
        abs(mass - 1.5) < 0.01 and abs(float(cx) - 30.0) < 1.0 and cy == "-" and abs(float(cz) - 50.0) < 1.0
    )
    assert (
        "not determined on this arm (its motion does not depend on the payload-frame parameters my, Ixx"
        in out
    )


def test_the_loaded_record_of_a_pair_is_not_blamed_for_the_payload(tmp_path, capsys):
    """identify --baseline printed, for the loaded record, that the URDF's prior is "a prior the record
    contradicts" and to state its uncertainty: the payload the URDF lacks is why, not the data."""
    arm = str(ROOT / "benchmarks" / "scenarios" / "ident_vertical3.toml")
    sim = ["simulate", "--arm", arm, "--duration", "4"]
    assert main([*sim, "--payload", "1.5", "--com", "0.03", "0", "0.05", "--out", str(tmp_path / "l")]) == 0
    assert main([*sim, "--seed", "7", "--out", str(tmp_path / "u")]) == 0
    capsys.readouterr()
    loaded, bare = str(tmp_path / "l" / "trajectory.csv"), str(tmp_path / "u" / "trajectory.csv")
    argv = ["identify", "--arm", arm, loaded, "--output-error", "off", "--out", str(tmp_path / "o")]
    assert main(argv) == 0  # alone: the prior the record contradicts, said so
    assert "a prior the record contradicts" in capsys.readouterr().out
    assert main([*argv, "--baseline", bare]) == 0
    out = capsys.readouterr().out
    assert "as the payload this loaded record carries (and the URDF lacks) makes it" in out
    assert "a prior the record contradicts" not in out
    assert "the unloaded record contradicts the URDF's prior too" not in out  # the URDF is right


@pytest.mark.parametrize("extra", [["--com", "0.1", "0", "0"], ["--radius", "0.2"]])
def test_a_payloads_place_without_a_payload_is_refused(tmp_path, capsys, extra):
    """simulate --com or --radius with no --payload (0 kg) placed nothing, in silence."""
    err = _error(capsys, ["simulate", "--arm", UR5, *extra, "--out", str(tmp_path / "o")])
    assert f"error: {extra[0]}" in err and "--payload" in err


def test_predict_help_says_record_is_optional(capsys):
    """predict reads the simulator's CSV through a scenario without [record]
    (tests/test_log_pieces.py runs it): its help says [record] is optional and what it is for."""
    with pytest.raises(SystemExit):
        main(["predict", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "scenario TOML with [arm] and an optional [record]: how a real log's files are read" in text
    assert "without it the record is the simulator's CSV t, q1..qN, [qd1..qdN,] tau1..tauN" in text


def test_benchmark_takes_the_base_seed(tmp_path, capsys):
    """A user changing the base seed had to copy the scenario to add run.seed; --seed does it, and
    metrics.json records it (per_seed.csv's seed column is the index)."""
    run = ["benchmark", "--seeds", "1", "--controllers", "pd", "--no-progress"]
    for out, extra in (("a", ["--seed", "7"]), ("b", ["--seed", "7"]), ("c", [])):
        assert main([*run, *extra, "--out", str(tmp_path / out)]) == 0
    capsys.readouterr()
    text = {k: (tmp_path / k / "per_seed.csv").read_text() for k in "abc"}
    assert text["a"] == text["b"] != text["c"]
    assert json.loads((tmp_path / "a" / "metrics.json").read_text())["provenance"]["seed"] == 7
