"""Recorded-data reader and the command line."""

from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.cli import main
from adaptive_dd.errors import DataError
from adaptive_dd.io import read_recording, write_recording

ROOT = Path(__file__).resolve().parent.parent


def write(tmp_path, text, name="rec.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def good_csv(n=20, T=1e-3):
    rows = ["t,q1,q2,qd1,qd2,tau1,tau2"] + [f"{k * T},{k},0,1,0,0.5,0.1" for k in range(n)]
    return "\n".join(rows) + "\n"


def test_round_trip(tmp_path):
    t = np.arange(50) * 1e-3
    q = np.random.default_rng(0).normal(size=(50, 2))
    p = write_recording(tmp_path / "x.csv", t, q, q * 2, q * 3)
    rec = read_recording(p)
    np.testing.assert_allclose(rec.q, q, rtol=1e-9)
    np.testing.assert_allclose(rec.tau, q * 3, rtol=1e-9)
    assert rec.sample_period == pytest.approx(1e-3)


def test_one_record_format_for_every_arm(tmp_path):
    t = np.arange(30) * 2e-3
    q = np.random.default_rng(1).normal(size=(30, 3))
    p = write_recording(tmp_path / "n3.csv", t, q, None, -q)  # no velocities
    assert p.read_text().splitlines()[0] == "t,q1,q2,q3,tau1,tau2,tau3"
    rec = read_recording(p, 3)
    assert rec.qd is None and rec.sample_period == pytest.approx(2e-3)
    np.testing.assert_allclose(rec.tau, -q, rtol=1e-9)
    with pytest.raises(DataError, match=r"arm of 2 joints: unknown column\(s\) \['q3', 'tau3'\]"):
        read_recording(p)  # the paper's arm by default
    import adaptive_dd.io as io_module

    with pytest.warns(FutureWarning, match="read_serial_recording is now read_recording"):
        old = io_module.read_serial_recording
    assert old is read_recording


@pytest.mark.parametrize(
    "text, match",
    [
        ("t,q1,q2,tau1\n1,2,3,4\n", "missing column\\(s\\) \\['tau2'\\]"),
        ("t,q1,q2,tau1,tau2,foo\n", "unknown column"),
        ("t,q1,q2,qd1,tau1,tau2\n", "missing column\\(s\\) \\['qd2'\\].*the qd columns all or none"),
        (good_csv().replace("0.5,0.1\n0.002", "0.5,abc\n0.002", 1), "line 3, column 'tau2': not a number"),
        (good_csv().replace("0.005,5,0", "0.0057,5,0"), "line 7, column 't': non-uniform sampling"),
        (good_csv().replace("0.004,4,0", "0.004,nan,0"), "line 6, column 'q1': non-finite"),
        ("t,q1,q2,tau1,tau2\n0,0,0,0,0\n", "need at least 10"),
        ("", "empty file"),
    ],
)
def test_bad_recordings_name_file_line_and_column(tmp_path, text, match):
    p = write(tmp_path, text)
    with pytest.raises(DataError, match=match) as e:
        read_recording(p)
    assert str(p) in str(e.value)


def test_missing_file(tmp_path):
    with pytest.raises(DataError, match="no such file"):
        read_recording(tmp_path / "nope.csv")


def test_cli_check_passes_and_reports(capsys):
    assert main(["check", "--states", "20"]) == 0
    out = capsys.readouterr().out
    assert "9 passed, 0 failed" in out and "pin.crba" in out


def test_cli_check_fails_on_a_wrong_model(monkeypatch, capsys):
    import adaptive_dd.plant.pinocchio_model as pm
    from adaptive_dd.plant.parameters import TABLE1_PHYSICAL, PhysicalParameters

    wrong = PhysicalParameters(**{**TABLE1_PHYSICAL.__dict__, "a2": 0.09})
    real = pm.build_model
    monkeypatch.setattr(pm, "build_model", lambda params, payload=None: real(wrong, payload))
    assert main(["check", "--states", "10"]) == 1
    assert "FAIL" in capsys.readouterr().out


def test_cli_simulate_then_identify(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "--duration", "4", "--out", str(out)]) == 0
    for f in ("trajectory.npz", "trajectory.csv", "trajectory.png"):
        assert (out / f).is_file()
    assert main(["identify", str(out / "trajectory.csv"), "--out", str(tmp_path / "id")]) == 0
    text = capsys.readouterr().out
    j1 = float(next(line.split()[1] for line in text.splitlines() if line.strip().startswith("J1")))
    assert abs(j1 / 0.429 - 1) < 0.05
    assert (tmp_path / "id" / "convergence.png").is_file()


def test_cli_identify_reports_bad_data(tmp_path, capsys):
    p = write(tmp_path, "t,q1,q2,tau1,tau2\n" + "\n".join(f"{k},0,0,0,0" for k in range(20)))
    assert main(["identify", str(p)]) == 2  # M2 without qd columns
    assert "qd1, qd2" in capsys.readouterr().err
    assert main(["identify", str(tmp_path / "missing.csv")]) == 2


def test_identify_without_arm_names_the_arm_path_for_a_gap_or_a_missing_value(tmp_path, capsys):
    """The paper's estimators refuse a gap or an empty cell; the error names the --arm path, which
    reads the log as it comes (a scenario with robot = "sice_arm", general = true), and that runs."""
    sim = tmp_path / "sim"
    assert main(["simulate", "--duration", "3", "--out", str(sim)]) == 0
    lines = (sim / "trajectory.csv").read_text().splitlines()
    gap = write(tmp_path, "\n".join(lines[:1001] + lines[1201:]) + "\n", "gap.csv")
    cells = lines[500].split(",")
    cells[5] = ""
    empty = write(tmp_path, "\n".join([*lines[:500], ",".join(cells), *lines[501:]]) + "\n", "empty.csv")
    scenario = write(tmp_path, '[arm]\nrobot = "sice_arm"\ngeneral = true\n', "sice_log.toml")
    capsys.readouterr()
    for path, what in ((gap, "line 1002, column 't': non-uniform sampling"), (empty, "column 'tau1': not a")):
        assert main(["identify", str(path), "--out", str(tmp_path / "id")]) == 2
        err = capsys.readouterr().err
        assert what in err and f"identify {path} --arm SCENARIO" in err, err
        assert 'robot = "sice_arm" and general = true' in err and "sice_general.toml" in err
        assert "--window START END" in err
    assert (ROOT / "benchmarks" / "scenarios" / "sice_general.toml").is_file()
    argv = [
        "identify",
        str(gap),
        "--arm",
        str(scenario),
        "--output-error",
        "off",
        "--out",
        str(tmp_path / "a"),
    ]
    assert main(argv) == 0
    assert "split at the gaps into 2 continuous pieces" in capsys.readouterr().out
    argv[1] = str(empty)
    assert main(argv) == 0
    assert "1 row(s) with an empty, non-numeric or non-finite cell" in capsys.readouterr().out


def test_check_arm_with_payload_zero_checks_no_payload(capsys):
    """``check --arm S --payload 0``: one check without payload (the 0 was replaced by 2 kg)."""
    from importlib import resources

    sc = str(resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload_exact.toml"))
    assert main(["check", "--arm", sc, "--payload", "0", "--states", "5"]) == 0
    out = capsys.readouterr().out
    assert "no payload" in out and "payload 2.0 kg" not in out
    assert main(["check", "--arm", sc, "--states", "5"]) == 0
    assert "payload 2.0 kg" in capsys.readouterr().out


def test_identify_says_why_no_bound_where_the_model_at_the_estimate_blows_up(tmp_path, capsys):
    """The paper's estimator with split 16 on a 0.5 s record gives J1 < 0: the Cramér-Rao bound at
    that estimate simulates the record's torque through it and ended in "q has a non-finite value
    nan at index (np.int64(35), ...)", exit 2, the estimate unprinted."""
    sim = tmp_path / "sim"
    assert main(["simulate", "--duration", "0.5", "--out", str(sim)]) == 0
    capsys.readouterr()
    argv = ["identify", str(sim / "trajectory.csv"), "--estimator", "paper", "--split", "16"]
    assert main([*argv, "--out", str(tmp_path / "id")]) == 0
    out, err = capsys.readouterr()
    assert "CRB: not computed" in err and "non-finite" in err and "--estimator exact" in err
    assert "    J1 " in out and "CRB std" not in out
