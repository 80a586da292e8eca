"""The ClosedFormTwoLink object, scenario [arm]/[plant] tables, smooth plant friction, chunked noise."""

import dataclasses
import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.cli import main
from adaptive_dd.errors import ParameterError, ScenarioError
from adaptive_dd.experiments import table2_torque, trial_rngs
from adaptive_dd.plant import (
    TABLE1_PHYSICAL,
    TABLE1_SIGMA,
    ActuatorConfig,
    ArmSimulator,
    ClosedFormTwoLink,
    Payload,
    PayloadSchedule,
    PhysicalParameters,
    SensorConfig,
    inverse_dynamics,
    mass_matrix,
    simulate_open_loop,
    two_link_plant_step,
)
from adaptive_dd.plant.arm_tables import arm_from_tables
from adaptive_dd.plant.pinocchio_model import two_link_cross_check
from adaptive_dd.plant.simulator import NOISE_CHUNK
from adaptive_dd.plant.two_link import closed_form_view

SCENARIOS = Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios"
CLEAN = SensorConfig(quantize=False, position_variance=(0, 0), velocity_variance=(0, 0))
IDEAL = ActuatorConfig((70.0, 15.0), saturate=False, quantize=False)
OTHER = PhysicalParameters(
    I1=0.02, I2=0.03, m1=2.0, m2=6.0, a1=0.15, a2=0.1, b1=4.0, b2=1.0, d1=2.5, d2=0.6, l1=0.3, l2=0.25
)
OTHER_TABLE = {
    "l1": 0.3,
    "l2": 0.25,
    "m1": 2.0,
    "m2": 6.0,
    "a1": 0.15,
    "a2": 0.1,
    "I1": 0.02,
    "I2": 0.03,
    "b": [4.0, 1.0],
    "d": [2.5, 0.6],
    "payload_radius": 0.04,
}


# ----------------------------------------------------------------------- ClosedFormTwoLink
def test_sice_arm_is_table_1():
    arm = ClosedFormTwoLink.sice()
    np.testing.assert_array_equal(arm.sigma, TABLE1_SIGMA)
    assert (arm.l1, arm.l2, arm.payload_radius) == (0.2, 0.2, 0.05)
    assert arm.physical == TABLE1_PHYSICAL and arm.actuator.torque_limit == (70.0, 15.0)
    assert arm.actuator.dac_bits == 12 and arm.sensor.encoder_counts == (614400, 507904)
    assert arm.friction == "stick-slip" and arm.n_joints == 2
    np.testing.assert_allclose(arm.nominal_inertia(), np.diagonal(mass_matrix([0.0, 0.0], TABLE1_SIGMA)))
    assert not arm.sigma.flags.writeable


@pytest.mark.parametrize("mass, radius", [(0.0, None), (2.0, None), (3.5, 0.08), (1.0, 0.0)])
def test_payload_effect_is_the_parallel_axis_result(mass, radius):
    arm = ClosedFormTwoLink.from_physical(OTHER, payload_radius=0.04)
    r = arm.payload_radius if radius is None else radius
    np.testing.assert_allclose(
        arm.sigma_with_payload(mass, radius), OTHER.with_payload(Payload(mass, r)).to_sigma(), rtol=1e-12
    )
    np.testing.assert_allclose(
        arm.payload_direction(radius) * mass, arm.sigma_with_payload(mass, radius) - arm.sigma
    )
    assert arm.payload_mass_from_sigma(arm.sigma_with_payload(mass, radius)) == pytest.approx(mass, abs=1e-12)


def test_payload_effect_broadcasts_over_trials():
    arm = ClosedFormTwoLink.from_physical(OTHER)
    m = np.array([[0.0, 1.0], [2.0, 3.0]])
    s = arm.sigma_with_payload(m)
    assert s.shape == (2, 2, 7)
    np.testing.assert_allclose(arm.payload_mass_from_sigma(s), m, atol=1e-12)


@pytest.mark.parametrize("mass", [0.0, 2.0])
def test_second_arm_agrees_with_pinocchio(mass):
    arm = ClosedFormTwoLink.from_physical(OTHER, payload_radius=0.06)
    results = two_link_cross_check(arm, Payload(mass, 0.06) if mass else None, n_states=30)
    assert all(r.passed for r in results), [str(r) for r in results if not r.passed]


def test_sigma_only_arm_builds_an_equivalent_physical_set_for_pinocchio():
    arm = ClosedFormTwoLink.from_sigma(OTHER.to_sigma(), l1=0.3, l2=0.25)
    phys = arm.equivalent_physical()
    np.testing.assert_allclose(phys.to_sigma(), arm.sigma, rtol=1e-12)
    assert min(phys.I1, phys.I2, phys.m1, phys.m2) > 0
    assert all(r.passed for r in two_link_cross_check(arm, Payload(2.0, 0.05), n_states=20))


def test_cross_check_catches_a_wrong_payload_effect(monkeypatch):
    arm = ClosedFormTwoLink.from_physical(OTHER)
    monkeypatch.setattr(
        ClosedFormTwoLink, "sigma_with_payload", lambda self, m, r=None, s0=None: self.sigma + 0.01 * m
    )
    assert not all(r.passed for r in two_link_cross_check(arm, Payload(2.0, 0.05), n_states=10))


def test_arm_is_hashable_comparable_and_json_able():
    a, b = ClosedFormTwoLink.sice(), ClosedFormTwoLink.sice()
    assert a == b and hash(a) == hash(b) and a != ClosedFormTwoLink.sice(friction="tanh")
    d = json.loads(json.dumps(a.to_dict()))
    assert d["l1"] == 0.2 and d["sigma"] == TABLE1_SIGMA.tolist() and d["physical"]["m2"] == 10.125
    assert d["actuator"]["torque_limit"] == [70.0, 15.0] and d["friction"] == "stick-slip"


def _bad_physical(**kw):
    return dataclasses.replace(OTHER, **kw)


@pytest.mark.parametrize(
    "make, match",
    [
        (
            lambda: ClosedFormTwoLink.from_sigma([0.0, 0.09, 0.18, 4, 1, 2.5, 0.6], 0.3, 0.25),
            "J1 must be > 0",
        ),
        (
            lambda: ClosedFormTwoLink.from_sigma([0.6, 0.09, 0.25, 4, 1, 2.5, 0.6], 0.3, 0.25),
            "J1\\*J2 - r\\^2",
        ),
        (lambda: ClosedFormTwoLink.from_sigma([0.6, np.nan, 0.18, 4, 1, 2.5, 0.6], 0.3, 0.25), "non-finite"),
        (
            lambda: ClosedFormTwoLink.from_sigma(OTHER.to_sigma(), 0.0, 0.25),
            "ClosedFormTwoLink.l1 must be > 0",
        ),
        (
            lambda: ClosedFormTwoLink.from_sigma(OTHER.to_sigma(), 0.3, math.inf),
            "ClosedFormTwoLink.l2 must be finite",
        ),
        (
            lambda: ClosedFormTwoLink.from_sigma(OTHER.to_sigma(), 0.3, 0.25, payload_radius=-0.1),
            "payload_radius",
        ),
        (lambda: ClosedFormTwoLink.from_physical(_bad_physical(a2=0.5)), "physical.a2 = 0.5"),
        (lambda: ClosedFormTwoLink.from_physical(_bad_physical(m2=-1.0)), "m2 must be > 0"),
        (lambda: ClosedFormTwoLink.from_physical(_bad_physical(I1=0.0)), "I1 must be > 0"),
        (
            lambda: ClosedFormTwoLink(sigma=OTHER.to_sigma(), l1=0.2, l2=0.25, physical=OTHER),
            "ClosedFormTwoLink.l1 = 0.2 differs",
        ),
        (
            lambda: ClosedFormTwoLink(sigma=TABLE1_SIGMA, l1=0.3, l2=0.25, physical=OTHER),
            "sigma\\[0\\] \\(J1\\)",
        ),
        (lambda: ClosedFormTwoLink.sice(friction="coulomb"), "friction must be one of"),
        (lambda: ClosedFormTwoLink.sice(friction_velocity=0.0), "friction_velocity must be > 0"),
        (lambda: ClosedFormTwoLink.sice(stribeck_velocity=-1.0), "stribeck_velocity must be > 0"),
        (lambda: ClosedFormTwoLink.sice(stribeck_ratio=0.5), "stribeck_ratio"),
        (lambda: ClosedFormTwoLink.sice(friction_velocity="fast"), "friction_velocity must be a number"),
        (
            lambda: ClosedFormTwoLink.sice(actuator=(70, 15)),
            "ClosedFormTwoLink.actuator must be an ActuatorConfig",
        ),
    ],
)
def test_arm_validation_names_field_and_value(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_payload_arguments_are_checked():
    arm = ClosedFormTwoLink.sice()
    with pytest.raises(ParameterError, match="payload mass"):
        arm.sigma_with_payload(-1.0)
    with pytest.raises(ParameterError, match="payload radius"):
        arm.payload_direction(np.nan)


# ------------------------------------------------------------ scenario tables
def test_arm_from_tables_physical_form():
    arm = closed_form_view(arm_from_tables(OTHER_TABLE, None, "x.toml"))  # an Arm's closed forms (issue 27)
    assert arm == ClosedFormTwoLink.from_physical(OTHER, payload_radius=0.04)


def test_arm_from_tables_sigma_form_and_plant():
    t = {"sigma": OTHER.to_sigma().tolist(), "l1": 0.3, "l2": 0.25, "torque_limit": [100, 20]}
    arm = closed_form_view(arm_from_tables(t, {"friction": "tanh", "friction_velocity": 0.03}, "x.toml"))
    assert arm.physical is None and arm.payload_radius == 0.05 and arm.actuator.torque_limit == (100.0, 20.0)
    np.testing.assert_array_equal(arm.sigma, OTHER.to_sigma())
    assert (arm.friction, arm.friction_velocity, arm.friction_code) == ("tanh", 0.03, 1)


def test_arm_from_tables_without_tables_is_the_sice_arm():
    assert closed_form_view(arm_from_tables(None, None)) == ClosedFormTwoLink.sice()
    stribeck = arm_from_tables(None, {"friction": "stribeck"})
    assert closed_form_view(stribeck) == ClosedFormTwoLink.sice(friction="stribeck")


@pytest.mark.parametrize(
    "arm, plant, match",
    [
        ({**OTHER_TABLE, "sigma": [1, 1, 0.1, 0, 0, 0, 0]}, None, "both 'sigma' and physical keys"),
        ({**OTHER_TABLE, "mass": 1.0}, None, "unknown key 'arm.mass'"),
        ({k: v for k, v in OTHER_TABLE.items() if k != "I2"}, None, "'arm.I2' is missing"),
        ({"sigma": [1, 1, 0.1, 0, 0, 0, 0], "l1": 0.3}, None, "'arm.l2' is missing"),
        ({**OTHER_TABLE, "m1": "2 kg"}, None, "'arm.m1' must be a number"),
        ({**OTHER_TABLE, "m2": math.nan}, None, "'arm.m2' must be finite"),
        ({**OTHER_TABLE, "I1": -0.02}, None, "'arm.I1' must be > 0"),
        ({**OTHER_TABLE, "l1": 0}, None, "'arm.l1' must be > 0"),
        ({**OTHER_TABLE, "b": [4.0]}, None, "'arm.b' must be a list of 2"),
        ({**OTHER_TABLE, "d": [2.5, -0.6]}, None, "'arm.d\\[1\\]' must be >= 0"),
        ({**OTHER_TABLE, "a2": 0.9}, None, "a2 = 0.9"),
        ({"sigma": [0.6, 0.09, 0.25, 4, 1, 2.5, 0.6], "l1": 0.3, "l2": 0.25}, None, "J1\\*J2 - r\\^2"),
        ({"sigma": [1, 2, 3], "l1": 0.3, "l2": 0.25}, None, "'arm.sigma' must be a list of 7"),
        (None, {"friction": "coulomb"}, "'plant.friction' must be one of"),
        (None, {"friction_velocity": 0.0}, "'plant.friction_velocity' must be > 0"),
        (None, {"stribeck_ratio": 0.9}, "'plant.stribeck_ratio' must be >= 1"),
        (None, {"velocity": 0.1}, "unknown key 'plant.velocity'"),
        ([1, 2], None, "\\[arm\\] must be a table"),
    ],
)
def test_arm_from_tables_errors_name_file_key_and_reason(arm, plant, match):
    with pytest.raises(ScenarioError, match=match) as exc:
        arm_from_tables(arm, plant, "my.toml")
    assert str(exc.value).startswith("my.toml:")


def test_scenarios_carry_their_arm(tmp_path):
    assert load_scenario().closed_forms == ClosedFormTwoLink.sice()  # exactly (issue 27: arm is an Arm)
    other = load_scenario(SCENARIOS / "other_arm.toml")
    assert other.closed_forms == ClosedFormTwoLink.from_physical(OTHER, payload_radius=0.05)
    assert other.arm == other.closed_forms.to_arm() and other.arm.n_joints == 2
    assert other.payload_radius == 0.05 and 2.0 in other.swap_masses
    smooth = load_scenario(SCENARIOS / "smooth_friction.toml")
    assert smooth.closed_forms == ClosedFormTwoLink.sice(friction="tanh", friction_velocity=0.02)
    assert smooth.reference == load_scenario().reference
    p = tmp_path / "r.toml"
    p.write_text(
        "[arm]\nsigma = [0.6, 0.09, 0.18, 4, 1, 2.5, 0.6]\nl1 = 0.3\nl2 = 0.25\npayload_radius = 0.07\n"
    )
    assert load_scenario(p).payload_radius == 0.07  # [[payload]] without radius: the arm's
    p.write_text("[plant]\nfriction = 'dry'\n")
    with pytest.raises(ScenarioError, match=r"r\.toml.*plant\.friction"):
        load_scenario(p)


def test_other_arm_reference_is_within_the_actuator_limits():
    sc = load_scenario(SCENARIOS / "other_arm.toml")
    q, qd, qdd = sc.reference.sample(np.arange(sc.n_samples) * sc.sample_period)
    tau = inverse_dynamics(q, qd, qdd, sc.closed_forms.sigma_with_payload(max(sc.swap_masses)))
    peak = np.abs(tau).max(axis=0)
    np.testing.assert_allclose(peak, [27.4, 8.7], atol=0.05)  # the figures in the file's comment
    assert np.all(peak < 0.7 * np.array(sc.arm.actuator.torque_limit))


# ----------------------------------------------------------------- simulator
def test_simulator_takes_payload_physics_from_the_arm():
    arm = ClosedFormTwoLink.from_physical(OTHER, payload_radius=0.04)
    sched = PayloadSchedule(times=(0.002,), masses=(2.0,))
    sim = ArmSimulator(2, 10, trial_rngs(0, 2), arm=arm, payload=sched)
    np.testing.assert_array_equal(sim.sigma, np.broadcast_to(arm.sigma, (2, 7)))
    for _ in range(3):
        sim.measure()
        sim.step(np.zeros((2, 2)))
    np.testing.assert_allclose(sim.sigma[0], OTHER.with_payload(Payload(2.0, 0.04)).to_sigma(), rtol=1e-12)
    wide = ArmSimulator(
        1, 10, trial_rngs(0, 1), arm=arm, payload=PayloadSchedule(initial_mass=2.0, radius=0.1)
    )
    np.testing.assert_allclose(wide.sigma[0], arm.sigma_with_payload(2.0, 0.1))
    assert sim.actuator is arm.actuator and sim.sensor is arm.sensor
    res = simulate_open_loop(np.zeros((1, 5, 2)), np.random.default_rng(0), arm=arm)
    assert res.meta["arm"] == arm.to_dict()


def test_simulator_rejects_a_non_arm():
    with pytest.raises(ParameterError, match="needs an arm of the paper's two-link geometry"):
        ArmSimulator(1, 10, np.random.default_rng(0), arm=TABLE1_SIGMA)


# Hashes of a stick-slip run (payload swap, sticking, both kinds of generator) made
# with the code before the ClosedFormTwoLink and the smooth friction laws (commit 3c9901b).
STICK_SLIP_GOLDEN = [
    {
        "q": "456fbc2c2a2f1fcb",
        "qd": "dfdb3f58ec815c29",
        "q_meas": "96c4aea2825c3951",
        "qd_meas": "48371e4dcbee571c",
    },
    {
        "q": "456fbc2c2a2f1fcb",
        "qd": "dfdb3f58ec815c29",
        "q_meas": "23687ae34992ac14",
        "qd_meas": "e53988be629ea9cc",
    },
]


@pytest.mark.parametrize("shared", [False, True])
def test_stick_slip_plant_is_bit_identical_to_before(shared):
    tau = table2_torque(2, 3000)
    tau[1] *= 0.3  # trial 1 sticks for long stretches
    rng = np.random.default_rng(11) if shared else trial_rngs(11, 2)
    r = simulate_open_loop(tau, rng, payload=PayloadSchedule(times=(1.5,), masses=(2.0,)))
    assert 0.1 < (r.qd == 0).mean() < 0.5  # the run does exercise sticking
    got = {
        k: hashlib.sha256(np.ascontiguousarray(getattr(r, k)).tobytes()).hexdigest()[:16]
        for k in STICK_SLIP_GOLDEN[0]
    }
    assert got == STICK_SLIP_GOLDEN[int(shared)]


def test_noise_is_drawn_in_chunks_with_the_same_numbers():
    n = 2 * NOISE_CHUNK + 300
    sim = ArmSimulator(
        3,
        n,
        trial_rngs(4, 3),
        actuator=IDEAL,
        sensor=dataclasses.replace(CLEAN, position_variance=(1.0, 1.0), velocity_variance=(1.0, 1.0)),
    )
    got = np.zeros((3, n, 4))
    for k in range(n):
        qm, qdm = sim.measure()
        got[:, k] = np.concatenate((qm, qdm), axis=-1)
        assert sim._noise.block.shape[1] <= NOISE_CHUNK
        sim.step(np.zeros((3, 2)))
    up_front = np.stack([g.standard_normal((n, 4)) for g in trial_rngs(4, 3)])
    np.testing.assert_array_equal(got, up_front)  # state stays 0: measurement = noise
    with pytest.raises(Exception, match="built for"):
        sim.measure()


# ------------------------------------------------------------ smooth friction
def _hold(arm, tau, n, q0=(0.0, 0.0), qd0=(0.0, 0.0)):
    taus = np.broadcast_to(np.asarray(tau, float), (1, n, 2))
    return simulate_open_loop(
        taus, np.random.default_rng(0), arm=arm, sensor=CLEAN, actuator=IDEAL, q0=q0, qd0=qd0
    )


@pytest.mark.parametrize("v", [0.02, 0.002])  # 0.002: stiff, RK4 steps refined
def test_tanh_plant_creeps_under_a_torque_below_coulomb_friction(v):
    d2, b2 = TABLE1_SIGMA[6], TABLE1_SIGMA[4]
    tau = [0.0, 0.5 * d2]
    stuck = _hold(ClosedFormTwoLink.sice(), tau, 2000)
    assert np.all(stuck.qd == 0.0)
    smooth = _hold(ClosedFormTwoLink.sice(friction="tanh", friction_velocity=v), tau, 2000)
    # steady creep: d2 tanh(w / v) + b2 w = tau2 (joint 2 alone; joint 1 barely moves)
    w = v * np.arctanh(0.5)
    for _ in range(50):
        w -= (d2 * np.tanh(w / v) + b2 * w - tau[1]) / (d2 / v / np.cosh(w / v) ** 2 + b2)
    assert smooth.q[0, -1, 1] > w  # 2 s of creep at about w
    np.testing.assert_allclose(smooth.qd[0, -1, 1], w, rtol=0.02)
    np.testing.assert_allclose(smooth.qd[0, -100:, 1], w, rtol=0.02)  # steady, no chatter


@pytest.mark.parametrize("law", ["tanh", "stribeck"])
def test_smooth_plants_match_coulomb_far_from_zero_velocity(law):
    a, b = (
        ClosedFormTwoLink.sice(),
        ClosedFormTwoLink.sice(friction=law, friction_velocity=0.01, stribeck_velocity=0.05),
    )
    kw = {"tau": [20.0, 5.0], "n": 300, "qd0": (2.0, 1.5)}
    ref, got = _hold(a, **kw), _hold(b, **kw)
    assert np.abs(ref.qd).min() > 20 * 0.05  # |qd| >> v and v_s throughout
    # the smooth kernel takes finer RK4 steps (stiffness near zero velocity): O(1e-9) apart
    np.testing.assert_allclose(got.q, ref.q, rtol=0, atol=2e-8)
    np.testing.assert_allclose(got.qd, ref.qd, rtol=0, atol=2e-6)


def test_stribeck_plant_holds_near_rest_between_coulomb_and_static_friction():
    d2 = TABLE1_SIGMA[6]
    kw = {"tau": [0.0, 1.2 * d2], "n": 1000}
    tanh = _hold(ClosedFormTwoLink.sice(friction="tanh"), **kw)
    strib = _hold(
        ClosedFormTwoLink.sice(friction="stribeck", stribeck_ratio=1.5, stribeck_velocity=0.1), **kw
    )
    assert tanh.qd[0, -1, 1] > 0.1  # above d: breaks away
    assert 0 < strib.qd[0, -1, 1] < 0.05  # below the static peak 1.5 d: slow creep


def test_tanh_integrator_matches_scipy_on_the_same_ode():
    v, T, n = 0.02, 1e-3, 300
    j1, j2, r, b1, b2, d1, d2 = TABLE1_SIGMA
    tau = table2_torque(1, n)[0] * 0.5

    def f(t, x):  # eq. (3)-(4) written out, tanh Coulomb friction
        k = min(int(t / T + 1e-9), n - 1)
        c, s_ = math.cos(x[1]), math.sin(x[1])
        m11, m12 = j1 + j2 + 2 * r * c, j2 + r * c
        r1 = tau[k, 0] + r * s_ * x[3] * (2 * x[2] + x[3]) - b1 * x[2] - d1 * math.tanh(x[2] / v)
        r2 = tau[k, 1] - r * s_ * x[2] ** 2 - b2 * x[3] - d2 * math.tanh(x[3] / v)
        det = m11 * j2 - m12 * m12
        return [x[2], x[3], (j2 * r1 - m12 * r2) / det, (m11 * r2 - m12 * r1) / det]

    x = np.zeros(4)
    for k in range(n):
        x = solve_ivp(f, (k * T, (k + 1) * T), x, rtol=1e-10, atol=1e-12, method="LSODA").y[:, -1]
    q, qd = np.zeros((1, 2)), np.zeros((1, 2))
    st, sl = np.zeros((1, 2), bool), np.ones((1, 2))
    for k in range(n):
        q, qd, st, sl = two_link_plant_step(
            q, qd, st, sl, tau[k][None], TABLE1_SIGMA[None], T, 2, 1, (v, 1.5, 0.1)
        )
    assert np.abs(x[2:]).max() > 0.1  # it moved
    np.testing.assert_allclose(q[0], x[:2], atol=1e-7)
    np.testing.assert_allclose(qd[0], x[2:], atol=1e-5)


def test_stiff_tanh_plant_stays_stable_and_rejects_bad_codes():
    r = simulate_open_loop(
        table2_torque(2, 2000),
        trial_rngs(0, 2),
        arm=ClosedFormTwoLink.sice(friction="tanh", friction_velocity=0.001),
    )
    assert not r.failed.any() and np.all(np.isfinite(r.q)) and np.abs(r.qd).max() < 5
    z = np.zeros((1, 2))
    with pytest.raises(ParameterError, match="friction_code"):
        two_link_plant_step(z, z, z.astype(bool), z + 1, z, TABLE1_SIGMA[None], 1e-3, 2, 7)


# ------------------------------------------------------------------------ CLI
def test_cli_check_and_simulate_take_an_arm(tmp_path, capsys):
    assert main(["check", "--arm", str(SCENARIOS / "other_arm.toml"), "--states", "10"]) == 0
    out = capsys.readouterr().out
    assert out.count("9 passed, 0 failed") == 2 and "payload 2.0 kg" in out
    sim = tmp_path / "sim"
    argv = [
        "simulate",
        "--arm",
        str(SCENARIOS / "smooth_friction.toml"),
        "--duration",
        "0.5",
        "--out",
        str(sim),
    ]
    assert main(argv) == 0
    assert "plant friction tanh" in capsys.readouterr().out
    bad = tmp_path / "bad.toml"
    bad.write_text("[arm]\nl1 = 0.3\n")
    assert main(["check", "--arm", str(bad)]) == 2
    assert "bad.toml" in capsys.readouterr().err
