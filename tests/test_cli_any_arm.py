"""The command line on both kinds of arm (issue 27): every option that does not apply to the
arm's kind is an error naming it, ``--debug`` after the command, ``excite`` on a two-link URDF."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

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
        (["simulate", "--arm", UR5, "--no-saturate"], "--no-saturate"),
        (["simulate", "--com", "0", "0", "0.1"], "--com"),
        (["simulate", "--plant", "serial"], "--plant"),
        (["simulate", "--arm", SICE_URDF, "--plant", "model"], "--plant"),
        (["identify", "rec.csv", "--arm", UR5, "--online"], "--online"),
        (["identify", "rec.csv", "--arm", UR5, "--method", "M1"], "--method"),
        (["identify", "rec.csv", "--arm", UR5, "--estimator", "paper"], "--estimator"),
        (["identify", "rec.csv", "--arm", UR5, "--split", "16"], "--split"),
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
    assert "2-joint arm of" in capsys.readouterr().out
    text = out.read_text()
    assert "[reference]" in text and 'robot = "sice_arm"' in text
    err = _error(capsys, ["excite", "--arm", str(ROOT / "adaptive_dd" / "scenarios" / "payload_swap.toml")])
    assert "excite needs an [arm] from a URDF" in err and 'robot = "sice_arm"' in err
