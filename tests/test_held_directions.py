"""Directions of the base parameters a record cannot see are held at the URDF's values
(:mod:`adaptive_dd.identification.held_directions`), on every route that estimates base
parameters: ``adaptive-dd identify --arm`` (weighted least squares, output error kept off them,
``model.json`` for ``[model] from``) and the excitation phase (``identify_record``).

The records are computed by inverse dynamics (no simulation: fast): vertical3 with its third joint
nearly still (its viscous friction barely seen: the plain estimate lands 6-7 of the prior's
standard deviations off), and, marked slow, the Kinova Gen3 whose rounded right angles leave
three base parameters seen only through the rounding (the plain estimate 1e4-1e5 of them off).
"""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.types import io_of
from adaptive_dd.identification import held_directions
from adaptive_dd.identification.arm_prior import ArmUncertainty, draw_parameters
from adaptive_dd.identification.held_directions import base_prior_std, hold_unseen, unit_class
from adaptive_dd.identification.log_fit import fit_log
from adaptive_dd.identification.model import arm_model, base_regressor


def _shipped(name: str) -> Path:
    return Path(str(resources.files("adaptive_dd.scenarios").joinpath(f"{name}.toml")))


@pytest.fixture(scope="module")
def still_joint():
    """(scenario, model, plant base parameters, q, qd measured, tau) of vertical3, joint 3 within
    +-0.012 rad, 4 s: its viscous friction is barely seen."""
    src = _shipped("vertical3_payload_exact")
    sc = parse_scenario(read_toml(src), str(src), "v")
    arm, n, T = sc.arm, sc.n_joints, sc.sample_period
    model = arm_model(arm)
    rng = np.random.default_rng([7, 0])
    sigma = model.B @ draw_parameters(arm, ArmUncertainty(), rng)
    t = np.arange(0.0, 4.0, T)[:, None]
    w = 2 * np.pi * np.array([[0.3, 0.5, 0.4], [0.7, 1.1, 0.9], [1.3, 1.7, 1.9]])
    a = np.array([[0.5, 0.4, 0.006], [0.2, 0.2, 0.003], [0.1, 0.1, 0.003]])
    ph = rng.uniform(0, 2 * np.pi, (3, n))
    q = sum(a[k] * np.sin(w[k] * t + ph[k]) for k in range(3))
    qd = sum(a[k] * w[k] * np.cos(w[k] * t + ph[k]) for k in range(3))
    qdd = sum(-a[k] * w[k] ** 2 * np.sin(w[k] * t + ph[k]) for k in range(3))
    tau = base_regressor(model, q, qd, qdd) @ sigma
    std = io_of(sc).std
    qm = q + std[:n] * rng.standard_normal(q.shape)
    qdm = qd + std[n:] * rng.standard_normal(qd.shape)
    return sc, model, sigma, qm, qdm, tau


def test_hold_unseen_holds_what_a_regression_cannot_see_and_keeps_the_rest():
    """Three parameters, the last two columns equal but for 1e-7: their difference is held at the
    prior (its error within the prior's), their sum and the first are the least squares'. A
    hold_unseen that estimates the held direction anyway leaves it 1e4 prior std off."""
    rng = np.random.default_rng(3)
    N = 400
    a, b = rng.standard_normal(N), rng.standard_normal(N)
    phi = np.column_stack([a, b, b + 1e-7 * rng.standard_normal(N)])
    ref, s0 = np.array([1.0, 2.0, 3.0]), np.array([0.1, 0.2, 0.2])
    truth = ref + s0 * rng.uniform(-1, 1, 3)
    y = phi @ truth + 0.01 * rng.standard_normal(N)
    x = np.linalg.lstsq(phi, y, rcond=None)[0]
    cov = 1e-4 * np.linalg.inv(phi.T @ phi)
    assert np.abs(x - truth).max() > 100 * s0.max()  # the plain estimate: wild
    out, C, held = hold_unseen(x, cov, ref, s0)
    assert held.count == 1 and held.ratio[0] > 1e4
    assert np.allclose(held.directions[0] ** 2, [0.0, 0.5, 0.5], atol=1e-3)
    assert np.all(np.abs(out - truth) < 2 * s0)
    assert out[0] == pytest.approx(x[0], abs=1e-3) and out[1] + out[2] == pytest.approx(x[1] + x[2], abs=1e-3)
    d = held.directions[0] * s0  # the held direction in the parameters' units
    assert d @ np.linalg.solve(np.diag(s0**2), d) == pytest.approx(1.0)
    v = d / s0
    assert v @ (C / np.outer(s0, s0)) @ v == pytest.approx(1.0, rel=1e-6)  # the prior's variance
    assert held.share[1:].min() > 0.99 and held.share[0] < 1e-6
    assert np.allclose(held.apply(x, ref), out)


def test_the_prior_std_has_a_floor_per_unit_and_none_without_one():
    src = _shipped("vertical3_payload_exact")
    model = arm_model(parse_scenario(read_toml(src), str(src), "v").arm)
    s0 = base_prior_std(model)
    assert np.all(s0 > 0)
    assert [unit_class(x) for x in ("m2", "mx1", "my2 - 0.2*m3", "Ixy2", "Ia3", "fv1", "fc2")] == [
        "kg", "kg m", "kg m", "kg m^2", "kg m^2", "N m s", "N m",
    ]  # fmt: skip
    frictionless = arm_model(parse_scenario(read_toml(src), str(src), "v").arm.with_(viscous=np.zeros(3)))
    s1 = base_prior_std(frictionless)
    fv = [k for k, nm in enumerate(frictionless.names) if nm.startswith("fv")]
    assert np.all(np.isinf(s1[fv]))  # a URDF without viscous friction states no prior on it: never held


def test_fit_log_holds_the_still_joints_friction(still_joint):
    """The plain weighted least squares puts joint 3's viscous friction several prior std off; held,
    every base parameter is within 2 of them, the held direction is fv3's and its std the prior's."""
    _sc, model, sigma, q, qd, tau = still_joint
    n, p = model.n, model.p
    s0 = base_prior_std(model)
    kw = dict(tau_f=0.02, sample_period=0.001, torque_held=False)
    plain = fit_log(model, q, qd, tau, np.ones(n, bool), np.ones(p, bool), hold=False, **kw)
    fit = fit_log(model, q, qd, tau, np.ones(n, bool), np.ones(p, bool), **kw)
    fv3 = model.names.index("fv3")
    assert np.abs(plain.sigma - sigma)[fv3] > 4 * s0[fv3]
    err = np.abs(fit.sigma - sigma) / s0
    assert np.all(err < 2), model.names[int(np.argmax(err))]
    assert fit.held.count >= 1 and fit.held.directions[0, fv3] ** 2 > 0.9
    assert fit.std[fv3] == pytest.approx(s0[fv3], rel=0.05)
    assert "fv3" in fit.held.describe(model.names)[0]


def test_identify_cli_reports_the_held_direction_and_hands_on_the_prior(still_joint, tmp_path, capsys):
    """``adaptive-dd identify --arm`` says which direction it held and why, marks it 'held' in the
    table, and model.json (what ``[model] from`` reads) carries the prior's variance there."""
    from adaptive_dd.cli import main
    from adaptive_dd.io import write_recording

    sc, _model, sigma, q, qd, tau = still_joint
    path = write_recording(tmp_path / "r.csv", 0.001 * np.arange(len(q)), q, qd, tau)
    scen = tmp_path / "v3.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n')
    out = tmp_path / "id"
    assert main(["identify", "--arm", str(scen), str(path), "--out", str(out), "--output-error", "off"]) == 0
    text = capsys.readouterr().out
    assert "direction(s) the record cannot see" in text
    line = next(x for x in text.splitlines() if x.startswith("  fv3 ("))
    assert "the record's std" in line
    row = next(x for x in text.splitlines() if x.startswith("fv3 "))
    assert row.split()[3] == "held"
    import pandas as pd

    est = pd.read_csv(out / "estimates.csv")  # the file marks it as the table does
    assert est.set_index("name").loc["fv3", "held"] == 1 and est["held"].sum() < len(est)
    m = json.loads((out / "model.json").read_text())
    k = m["names"].index("fv3")
    s0 = base_prior_std(arm_model(sc.arm))
    held = m["record"]["held_directions"]
    assert held and held[0].startswith("fv3 (")
    kappa = m["record"]["prior_scale"]  # the prior widened by what the well-seen directions show
    assert 1.0 <= kappa < 1.5
    assert m["std"][k] == pytest.approx(kappa * s0[k], rel=0.05)
    assert abs(m["sigma"][k] - sigma[k]) < 2 * s0[k]
    # output error moves the other directions only; its Cramér-Rao column says 'held' for fv3
    argv = ["identify", "--arm", str(scen), str(path), "--out", str(tmp_path / "oe"), "--max-iter", "1"]
    assert main([*argv, "--output-error", "on"]) == 0
    text = capsys.readouterr().out
    rows = [x for x in text.splitlines() if x.startswith("fv3 ")]
    assert len(rows) == 2 and rows[1].split()[3:] == ["held", "-"], rows
    wls, oe = (float(x) for x in rows[1].split()[1:3])
    assert oe == pytest.approx(wls, rel=0.01)  # not moved off the URDF's value (a fault: by 190 %)
    assert "output error kept the" in text


def test_the_excitation_phase_holds_too(still_joint):
    """``identify_record`` (the excitation phase's identification) holds the same direction and its
    consistent fit, the model handed to the controllers, keeps within the prior there."""
    from adaptive_dd.closed_loop.excitation_phase import identify_record

    _sc, model, sigma, q, qd, tau = still_joint
    one = identify_record(model, q, qd, tau, 0.001, torque_held=False)
    fv3 = model.names.index("fv3")
    s0 = base_prior_std(model)
    assert one.held >= 1
    assert abs(one.hat[fv3] - sigma[fv3]) < 2 * s0[fv3] and abs(one.fit[fv3] - sigma[fv3]) < 2 * s0[fv3]


def test_a_hold_ratio_of_infinity_is_the_plain_fit(monkeypatch):
    """The rule's threshold is what holds: with it at infinity nothing is held (the planted fault the
    tests above catch)."""
    monkeypatch.setattr(held_directions, "HOLD_RATIO", np.inf)
    x, cov = np.array([5.0, -3.0]), np.diag([1e6, 1e-6])
    out, C, held = hold_unseen(x, cov, np.zeros(2), np.ones(2))
    assert held.count == 0 and np.allclose(out, x) and np.allclose(C, cov)


@pytest.mark.slow
def test_the_gen3s_rounded_angles_are_held():
    """The Gen3's URDF writes its right angles rounded: ``mx1``, ``my1``'s group and ``Ia2`` are seen
    only through the rounding. On a 12 s multi-sine the plain fit puts some base parameter thousands of
    prior std off; held, every one is within 3, and those three are among the held directions."""
    from adaptive_dd.identification.log_fit import predict_torque
    from adaptive_dd.plant.arm import Arm
    from adaptive_dd.record import derivatives
    from adaptive_dd.robots import robot_urdf

    arm = Arm.from_urdf(robot_urdf("gen3"), "end_effector_link", armature=[0.2] * 4 + [0.05] * 3)
    model = arm_model(arm)
    n, T = model.n, 0.002
    t = np.arange(6000) * T
    rng = np.random.default_rng(1)
    w, ph = rng.uniform(0.5, 2.5, (n, 3)), rng.uniform(0, 6, (n, 3))
    home = np.array([0.0, 0.15, 3.14, -2.25, 0.0, 1.0, 1.57])
    q = sum(0.4 * np.sin(w[:, k] * t[:, None] + ph[:, k]) for k in range(3)) + home
    qd, qdd = derivatives(q, T)
    s0 = base_prior_std(model)
    truth = model.sigma_ref + s0 * rng.uniform(-1, 1, model.p)
    tau = predict_torque(model, truth, q, qd, qdd) + 0.05 * rng.standard_normal(q.shape)
    kw = dict(tau_f=0.02, sample_period=T, torque_held=False, prior_std=s0)
    plain = fit_log(model, q, qd, tau, np.ones(n, bool), np.ones(model.p, bool), hold=False, **kw)
    fit = fit_log(model, q, qd, tau, np.ones(n, bool), np.ones(model.p, bool), **kw)
    assert (np.abs(plain.sigma - truth) / s0).max() > 1e3
    assert (np.abs(fit.sigma - truth) / s0).max() < 3
    weight = (fit.held.directions**2).sum(axis=0)
    for name in ("mx1", "Ia2"):
        k = next(i for i, nm in enumerate(model.names) if nm.split(" ")[0] == name)  # "Ia2 - 1e-10*mz3 ..."
        assert weight[k] > 0.15, name
    assert weight[1] > 0.9  # my1's group


def test_a_prior_the_record_contradicts_holds_nothing():
    """Five well-seen parameters and two nearly equal columns. With the URDF within the stated
    uncertainty the difference is held; with the URDF 30 prior std off along what the record sees
    well (a real robot's URDF: the TIAGo's is about 12 times further than stated) the record
    contradicts the prior, nothing is held and the estimate and its covariance are the plain fit's.
    A hold_unseen without the conflict check holds the difference at a URDF value that is wrong."""
    rng = np.random.default_rng(5)
    N = 600
    cols = rng.standard_normal((N, 6))
    phi = np.column_stack([cols, cols[:, 5] + 1e-7 * rng.standard_normal(N)])
    p = phi.shape[1]
    s0 = np.full(p, 0.1)
    truth = np.arange(1.0, p + 1.0)
    y = phi @ truth + 0.01 * rng.standard_normal(N)
    x = np.linalg.lstsq(phi, y, rcond=None)[0]
    cov = 1e-4 * np.linalg.inv(phi.T @ phi)
    near = truth + s0 * rng.uniform(-1, 1, p)
    _, _, held = hold_unseen(x, cov, near, s0)
    assert not held.conflict and held.count == 1
    far = truth + 30 * s0 * rng.choice([-1.0, 1.0], p)
    out, C, held = hold_unseen(x, cov, far, s0)
    assert held.conflict and held.count == 0 and held.scale2 > 100
    assert np.array_equal(out, x) and np.array_equal(C, cov)
    assert held_directions.prior_conflict(np.full(3, 0.01), np.ones(3)) is False
    assert held_directions.prior_conflict(np.full(3, 0.01), np.full(3, 5.0)) is True


def test_a_window_too_short_for_the_model_error_fails_before_the_fit_is_printed(
    still_joint, tmp_path, capsys, monkeypatch
):
    """The model error's fit at twice tau_f keeps fewer samples of a short window than the fit:
    it failed after the whole estimate table was printed (a fit the command then refused)."""
    from adaptive_dd.cli import main
    from adaptive_dd.errors import DataError
    from adaptive_dd.identification import model_error
    from adaptive_dd.io import write_recording

    _sc, _model, _sigma, q, qd, tau = still_joint
    path = write_recording(tmp_path / "r.csv", 0.001 * np.arange(len(q)), q, qd, tau)
    scen = tmp_path / "v3.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n')

    def short(*a, **k):
        raise DataError("10 samples of 3 channels for 17 parameters: a longer window is needed")

    monkeypatch.setattr(model_error, "model_error_variance", short)
    argv = ["identify", "--arm", str(scen), str(path), "--out", str(tmp_path / "o"), "--output-error", "off"]
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert "estimate       std" not in out and "r.csv: 10 samples of 3 channels" in err
    assert "the model error's estimate at 2 tau_f" in err


def test_a_filter_faster_than_the_samples_is_refused(still_joint, tmp_path, capsys):
    """``--tau-f`` below the sample period was accepted (its transient rounded to one sample)."""
    from adaptive_dd.cli import main
    from adaptive_dd.io import write_recording

    _sc, _model, _sigma, q, qd, tau = still_joint
    path = write_recording(tmp_path / "r.csv", 0.001 * np.arange(len(q)), q, qd, tau)
    scen = tmp_path / "v3.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n')
    assert (
        main(["identify", "--arm", str(scen), str(path), "--tau-f", "0.0005", "--out", str(tmp_path / "o")])
        == 2
    )
    assert "--tau-f: 0.0005 s is shorter than the record's sample period (0.001 s)" in capsys.readouterr().err
