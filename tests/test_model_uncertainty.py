"""The model's uncertainty belongs to the model (``[model] uncertainty``,
adaptive_dd.plant.uncertainty.model_uncertainty): checked like every key, the plant's draw levels
when the scenario states none and draws one, exact otherwise, and adaptive_ct's arm prior follows
it whatever the plant is (drawn, a URDF of its own, the [arm] itself)."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.closed_loop.runner import make_controller_of
from adaptive_dd.errors import ScenarioError
from adaptive_dd.identification.arm_prior import ArmUncertainty, draw_parameters, prior_covariance
from adaptive_dd.identification.online import est_init
from adaptive_dd.plant.uncertainty import Uncertainty
from adaptive_dd.plant.urdf_write import write_urdf_links

ROOT = Path(__file__).resolve().parents[1]
LEVELS = {"mass": 0.1, "com": 0.01, "inertia": 0.2, "viscous": 0.5, "coulomb": 0.5, "armature": 0.3}


def _data(**tables) -> dict:
    """The shipped exact UR5 scenario as a dict (adaptive_ct and its floor), with ``tables``."""
    path = resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap_exact.toml")
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    data["run"] = {**data["run"], "duration": 2.0, "seeds": 1, "controllers": ["ct_oracle", "adaptive_ct"]}
    data["payload"] = data["payload"][:1]
    data["payload"][0]["at"] = 1.0
    data.pop("controllers", None)
    return {**data, **tables}


def _arm_prior(sc) -> np.ndarray:
    """adaptive_ct's start-up covariance of the arm's base parameters, as the run builds it."""
    _, ctrl = make_controller_of(sc, "adaptive_ct")
    assert ctrl.online.mode == "arm"
    _, s = est_init(ctrl.online, sc.arm, 1)
    pb = sc.arm.base.count
    return s.P[0][:pb, :pb] - ctrl.online.p0_arm * np.eye(pb)


def _stated_prior(arm, levels: dict) -> np.ndarray:
    B = arm.base.B
    return B @ prior_covariance(arm, ArmUncertainty(**levels)) @ B.T


@pytest.mark.parametrize(
    ("model", "match"),
    [
        ({"uncertainty": 0.1}, r"u\.toml: \[model\.uncertainty\] must be a table of levels .*got 0\.1"),
        (
            {"uncertainty": {"masss": 0.1}},
            r"u\.toml: unknown key 'model\.uncertainty\.masss' \(did you mean 'mass'\?\); allowed",
        ),
        (
            {"uncertainty": {"mass": 1.0}},
            r"u\.toml: key 'model\.uncertainty\.mass' must be in \[0, 1\), got 1",
        ),
        ({"uncertainty": {"com": -0.01}}, r"key 'model\.uncertainty\.com' must be in \[0, 0\.5\], got -0"),
        ({"uncertainty": {"inertia": "20 %"}}, r"key 'model\.uncertainty\.inertia' must be a finite number"),
        (
            {"uncertainty": {"mass": 0.5, "distribution": "normal"}},
            r"key 'model\.uncertainty\.mass' must be in \[0, 0\.333\)",
        ),
        ({"uncertainty": {"distribution": "cauchy"}}, r"'model\.uncertainty\.distribution'.*'cauchy'"),
        ({"uncertain": {}}, r"unknown key 'model\.uncertain'; allowed: \['from', 'uncertainty'\]"),
    ],
)
def test_model_uncertainty_is_checked(model, match):
    with pytest.raises(ScenarioError, match=match):
        parse_scenario(_data(model=model), "u.toml")


def test_the_model_uncertainty_defaults_to_the_draw_then_to_exact():
    assert parse_scenario(_data(), "u.toml").model_uncertainty is None
    drawn = {"mass": 0.05, "com": 0.02, "distribution": "normal"}
    sc = parse_scenario(_data(plant={"uncertainty": drawn}), "u.toml")
    assert sc.model_uncertainty == Uncertainty(**drawn) == sc.plant.uncertainty
    stated = {"mass": 0.02, "inertia": 0.05}
    sc = parse_scenario(_data(plant={"uncertainty": drawn}, model={"uncertainty": stated}), "u.toml")
    assert sc.model_uncertainty == Uncertainty(**stated) and sc.plant.uncertainty == Uncertainty(**drawn)


def test_a_model_stated_exact_keeps_the_payload_estimator():
    drawn = parse_scenario(_data(plant={"uncertainty": LEVELS}), "u.toml")
    assert make_controller_of(drawn, "adaptive_ct")[1].online.mode == "arm"
    sc = parse_scenario(_data(plant={"uncertainty": LEVELS}, model={"uncertainty": {}}), "u.toml")
    assert sc.model_uncertainty == Uncertainty()
    assert make_controller_of(sc, "adaptive_ct")[1].online.mode == "payload"
    assert make_controller_of(parse_scenario(_data(), "u.toml"), "adaptive_ct")[1].online.mode == "payload"


def test_the_arm_prior_follows_the_stated_uncertainty_when_the_plant_is_a_urdf_of_its_own(tmp_path):
    """The plant a URDF of its own (no draw): adaptive_ct's arm prior is the covariance of the
    model's stated levels, whichever they are."""
    sc = parse_scenario(_data(), "u.toml")
    arm, n = sc.arm, sc.arm.n_joints
    pi = draw_parameters(arm, ArmUncertainty(), np.random.default_rng(3))
    urdf = write_urdf_links(arm, pi[: 10 * n], tmp_path / "plant.urdf")
    plant = {"urdf": str(urdf), "armature": [float(x) for x in pi[12 * n :]]}
    cad = parse_scenario(_data(plant=plant, model={"uncertainty": LEVELS}), "u.toml")
    assert cad.plant is not None and cad.plant.uncertainty is None and cad.plant.urdf == str(urdf)
    np.testing.assert_allclose(_arm_prior(cad), _stated_prior(arm, LEVELS), rtol=1e-9, atol=1e-15)
    stated = {"mass": 0.03, "com": 0.002, "inertia": 0.05, "viscous": 0.2, "coulomb": 0.1, "armature": 0.1}
    own = parse_scenario(_data(plant=plant, model={"uncertainty": stated}), "u.toml")
    P = _arm_prior(own)
    np.testing.assert_allclose(P, _stated_prior(arm, stated), rtol=1e-9, atol=1e-15)
    assert np.trace(P) < 0.5 * np.trace(_arm_prior(cad))


def test_the_generators_check_reads_numbers_to_their_last_digits_only():
    """``--check`` compared the text: the draw's inertias differ in their last digit between BLAS
    thread counts (a user's shell against the test suite's one thread), and it said "differs"."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("cad", ROOT / "tools" / "make_cad_error_plants.py")
    cad = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(cad)
    line = '<inertia ixx="0.02387077681658869" ixy="-1.5e-05" iyy="2"/>'
    assert cad.same_text(line, line.replace("0.02387077681658869", "0.023870776816588675"))
    assert not cad.same_text(line, line.replace("0.02387077681658869", "0.0238707768165887"[:9]))
    assert not cad.same_text(line, line.replace('iyy="2"', 'izz="2"'))
    assert not cad.same_text(line, line + " 1")


@pytest.mark.slow  # a subprocess that loads two arms and writes their URDFs
def test_the_shipped_cad_error_scenarios_are_the_generators_output():
    out = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "make_cad_error_plants.py"), "--check"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert out.returncode == 0, out.stderr
    for robot in ("ur5", "panda"):
        sc = parse_scenario(
            tomllib.loads((ROOT / "benchmarks/scenarios/cad_error" / f"{robot}_cad_error.toml").read_text()),
            str(ROOT / "benchmarks/scenarios/cad_error" / f"{robot}_cad_error.toml"),
        )
        assert sc.plant.urdf.endswith(f"{robot}_plant.urdf") and sc.plant.uncertainty is None
        assert sc.model_uncertainty == Uncertainty(**LEVELS) and sc.excite == 0.0
        rel = np.abs(np.asarray(sc.plant.pi_links) - sc.arm.pi_links)[::10] / sc.arm.pi_links[::10]
        assert 0.0 < rel.max() <= 0.1 + 1e-9  # the link masses off, within 10 %
