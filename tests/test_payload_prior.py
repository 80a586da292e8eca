"""The estimator's payload prior is what the arm states: a payload of unknown mass shaped as
``[arm] payload_radius`` says (its inertia a disk's per kg, moving with the mass), its centre of
mass within ``[arm] payload_offset`` of the payload frame."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.errors import ParameterError, ScenarioError
from adaptive_dd.identification.online import OnlineConfig, est_init
from adaptive_dd.identification.online_config import payload_prior
from adaptive_dd.plant.arm import DEFAULT_PAYLOAD_OFFSET, Arm
from adaptive_dd.plant.payload import payload_parameters

IZZ = 9  # index of Izz in the payload's ten parameters (Pinocchio's order)


def test_the_inertia_moves_with_the_mass_as_the_shape_says():
    d = payload_parameters(1.0, radius=0.05)  # Izz = R^2 / 2 per kg, Ixx = Iyy = R^2 / 4
    P = payload_prior(3.0, 0.0, d)
    np.testing.assert_allclose(P, 9.0 * np.outer(d, d))  # centred on the frame: one direction
    assert np.linalg.matrix_rank(P) == 1
    assert P[0, IZZ] == pytest.approx(9.0 * 0.05**2 / 2)
    # an offset adds an uncertainty of its own to the first moments and the inertias
    Q = payload_prior(3.0, 0.1, d)
    np.testing.assert_allclose(np.diag(Q - P)[1:4], (3.0 * 0.1) ** 2)
    np.testing.assert_allclose(np.diag(Q - P)[4:], (3.0 * 0.01) ** 2)
    assert Q[0, IZZ] == P[0, IZZ]


def test_without_a_shape_the_prior_is_a_point_mass():
    P = payload_prior(2.0, 0.1)
    assert P[0, 0] == 4.0 and np.count_nonzero(P - np.diag(np.diag(P))) == 0


def test_the_estimator_reopens_along_the_arms_stated_payload():
    arm = Arm.sice().with_(payload_capacity=5.0, payload_offset=0.0)
    c, _ = est_init(OnlineConfig(), arm, 1)
    d = payload_parameters(1.0, radius=arm.payload_radius)
    np.testing.assert_allclose(c.P_reopen, c.P_reopen[0, 0] * np.outer(d, d))
    wider, _ = est_init(OnlineConfig(), arm.with_(payload_radius=2 * arm.payload_radius), 1)
    assert wider.P_reopen[0, IZZ] == pytest.approx(4 * c.P_reopen[0, IZZ])
    # the offset is the prior's length scale, and the centred prior's on the control model
    off, _ = est_init(OnlineConfig(), arm.with_(payload_offset=0.05), 1)
    assert off.P_reopen[1, 1] == pytest.approx(c.P_reopen[0, 0] * 0.05**2)


def test_the_default_offset_is_a_tool_off_the_flange():
    """A URDF arm whose data sheet states none: 0.1 m; the paper's arm states its disks centred (eq. 9)."""
    from adaptive_dd.robots import robot_urdf

    assert Arm.from_urdf(robot_urdf("ur5"), "tool0").payload_offset == DEFAULT_PAYLOAD_OFFSET == 0.1
    assert Arm.sice().payload_offset == 0.0


@pytest.mark.parametrize("value", [-0.01, float("nan"), 11.0])
def test_a_bad_offset_is_refused(value):
    with pytest.raises(ParameterError, match="payload_offset"):
        Arm.sice().with_(payload_offset=value)


def _ur5() -> dict:
    return read_toml(Path(str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml"))))


def test_a_scenario_states_the_offset():
    d = _ur5()
    d["arm"]["payload_offset"] = 0.03
    assert parse_scenario(d, "ur5.toml").arm.payload_offset == 0.03


@pytest.mark.parametrize("value", [-0.1, 2.0, "0.1"])
def test_a_bad_offset_in_a_scenario_is_named(value):
    d = _ur5()
    d["arm"]["payload_offset"] = value
    with pytest.raises(ScenarioError, match=r"ur5.toml: key 'arm.payload_offset' must be .* got"):
        parse_scenario(d, "ur5.toml")


def test_validate_prints_the_prior_the_arm_states():
    from adaptive_dd.benchmark.preflight import derived_estimator_settings

    root = Path(__file__).resolve().parents[1]
    stated = derived_estimator_settings(
        parse_scenario(read_toml(root / "benchmarks/scenarios/sice_general.toml"), "s.toml")
    )
    line = [x for x in stated if x.startswith("arm.payload_offset")]
    assert line == [
        "arm.payload_offset = 0 m, arm.payload_radius = 0.05 m   (the estimator's payload prior: a disk of "
        "that radius per kg, its centre of mass within that offset of 'tip')"
    ]


@pytest.mark.parametrize(
    "stated", [{"payload_offset": 0.0}, {"payload_capacity": 5.0, "payload_offset": 0.0}]
)
def test_the_closed_forms_refuse_what_they_would_not_read(stated):
    data = {"arm": {"robot": "sice_arm", **stated}, "payload": [{"at": 1.0, "mass": 1.0}]}
    keys = ", ".join(f"arm.{k}" for k in sorted(stated))
    with pytest.raises(ScenarioError, match=rf"p.toml: {keys}: the paper's closed forms .*`general = true`"):
        parse_scenario(data, "p.toml")
    data["arm"]["general"] = True
    assert parse_scenario(data, "p.toml").arm.payload_offset == 0.0
