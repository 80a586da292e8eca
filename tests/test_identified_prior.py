"""The prior an identification hands to adaptive_ct (``[run] excite``, ``[model] from = "model.json"``)
must cover what the identification got wrong when the model is not the plant's law.

A record of the vertical three-joint arm computed by inverse dynamics (no simulation: fast), the
plant's parameters drawn around its URDF and its Coulomb friction with a Stribeck rise at low
speed, which the model's ``fc tanh(qd / v_f)`` cannot fit; sensor noise at the scenario's levels.
The identified base parameters' errors against the plant's, in units of the prior's standard
deviations, must look like draws of that prior (the white-residual formula the excitation phase
used before gave errors of 5-10 of its standard deviations in the median on the drawn iiwa).
"""

from __future__ import annotations

import dataclasses
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.excitation_phase import identify_record
from adaptive_dd.closed_loop.types import io_of
from adaptive_dd.errors import ParameterError, ScenarioError
from adaptive_dd.identification.arm_prior import (
    ArmUncertainty,
    draw_parameters,
    identified_prior_cov,
    identified_prior_std,
)
from adaptive_dd.identification.model import arm_model, base_regressor


def _shipped(name: str) -> Path:
    return Path(str(resources.files("adaptive_dd.scenarios").joinpath(f"{name}.toml")))


def _record(seed: int, stribeck: float, duration: float = 8.0, noise: float = 1.0):
    """(model, plant base parameters, q, qd, tau measured) of the vertical3 arm on a multi-sine."""
    src = _shipped("vertical3_payload_exact")
    sc = parse_scenario(read_toml(src), str(src), "v")
    arm = sc.arm
    rng = np.random.default_rng([2026, seed])
    pi_true = draw_parameters(arm, ArmUncertainty(), rng)
    model = arm_model(arm)
    n, T = arm.n_joints, sc.sample_period
    t = np.arange(0.0, duration, T)[:, None]
    f = np.array([[0.3, 0.5, 0.4], [0.7, 1.1, 0.9], [1.3, 1.7, 1.9]])
    a = np.array([[0.5, 0.4, 0.5], [0.2, 0.2, 0.3], [0.1, 0.1, 0.1]])
    ph = rng.uniform(0, 2 * np.pi, (3, n))
    w = 2 * np.pi * f
    q = sum(a[k] * np.sin(w[k] * t + ph[k]) for k in range(3))
    qd = sum(a[k] * w[k] * np.cos(w[k] * t + ph[k]) for k in range(3))
    qdd = sum(-a[k] * w[k] ** 2 * np.sin(w[k] * t + ph[k]) for k in range(3))
    sigma_true = model.B @ pi_true
    fc = pi_true[11 * n : 12 * n]
    # the plant's Coulomb law: a Stribeck rise at low speed on a sign, not the model's tanh
    law = fc * np.sign(qd) * (1.0 + stribeck * np.exp(-((qd / 0.1) ** 2)))
    tau = base_regressor(model, q, qd, qdd) @ sigma_true + law - fc * np.tanh(qd / model.friction_velocity)
    std = noise * io_of(sc).std  # the scenario's sensor noise (n positions, n velocities)
    qm = q + std[:n] * rng.standard_normal(q.shape)
    qdm = qd + std[n:] * rng.standard_normal(qd.shape)
    return model, sigma_true, qm, qdm, tau, T


@pytest.mark.parametrize("seed", [0, 1])
def test_the_identified_prior_covers_the_error_of_a_misspecified_model(seed):
    model, sigma_true, q, qd, tau, T = _record(seed, stribeck=1.0)
    one = identify_record(model, q, qd, tau, T)
    z = (one.fit - sigma_true) / one.std
    assert np.all(np.isfinite(z))
    # draws of the prior: about 0.67 in the median of |z|, rarely beyond 4
    assert np.median(np.abs(z)) < 1.5, np.round(z, 1)
    assert np.max(np.abs(z)) < 6.0, (model.names[int(np.argmax(np.abs(z)))], np.round(z, 1))


def _model_file(tmp_path: Path, **changes) -> tuple[Path, object, np.ndarray]:
    """A model.json (what ``identify --out`` writes) on the vertical3 arm: its estimate off the
    consistent fit, a covariance, the last base parameter held at the URDF's."""
    from adaptive_dd.identification.identified_model import IdentifiedModel, save_identified_model

    src = _shipped("vertical3_payload")
    arm = parse_scenario(read_toml(src), str(src), "v").arm
    names, p, n = list(arm.base.names), arm.base.count, arm.n_joints
    rng = np.random.default_rng(5)
    L = rng.standard_normal((p, p)) * 1e-3
    cov = L @ L.T
    K = np.ones(p, bool)
    K[-1] = False
    cov[~K, :] = 0.0
    cov[:, ~K] = 0.0
    sigma = arm.sigma + np.sqrt(np.diag(cov)) * rng.standard_normal(p)
    (tmp_path / "model.urdf").write_text(Path(arm.urdf).read_text())
    m = IdentifiedModel(
        urdf=str(arm.urdf), payload_frame=arm.payload_frame, gravity=list(arm.gravity),
        repair_inertia=False, joint_names=list(arm.joint_names), friction_velocity=arm.friction_velocity,
        names=names, sigma=sigma.tolist(), sigma_urdf=arm.sigma.tolist(), std=np.sqrt(np.diag(cov)).tolist(),
        identified=K.tolist(), covariance=cov.tolist(), used=[True] * n, residual_rms=[0.1] * n,
        noise_rms=[0.01] * n, viscous=list(arm.viscous), coulomb=list(arm.coulomb),
        armature=list(arm.armature), consistent_sigma=arm.sigma.tolist(), consistent_distance=1.0,
        fitted_urdf="model.urdf", record={"model_error_var": (0.5 * np.diag(cov)).tolist()},
    )  # fmt: skip
    m = dataclasses.replace(m, **changes)
    return save_identified_model(tmp_path / "model.json", m), m, cov


def test_a_model_file_gives_adaptive_ct_the_same_prior_rule(tmp_path):
    """[model] from = "model.json": adaptive_ct's arm prior is the file's sandwich covariance plus
    the consistent fit's step (the rule of the excitation phase), the stated uncertainty where the
    file held a parameter at the URDF's; a table that states its own prior is left alone."""
    from adaptive_dd.closed_loop.model_prior import _stated_variance
    from adaptive_dd.closed_loop.runner import make_controller_of

    path, m, cov = _model_file(tmp_path)
    data = read_toml(_shipped("vertical3_payload"))
    data["model"] = {"from": str(path)}
    sc = parse_scenario(data, "m.toml")
    _, ctrl = make_controller_of(sc, "adaptive_ct")
    stated = _stated_variance(sc, sc.arm)
    step = np.asarray(m.consistent_sigma) - np.asarray(m.sigma)
    want = np.sqrt(1.5 * np.diag(cov) + step**2)  # the sandwich, the step, the model error
    want[-1] = np.sqrt(stated[-1])
    assert ctrl.online.mode == "arm" and ctrl.online.arm_uncertainty is None
    P = np.asarray(ctrl.online.arm_prior_cov)
    np.testing.assert_allclose(np.sqrt(np.diag(P)), want, rtol=1e-12)
    # the sandwich's correlations handed on; none for the parameter held at the URDF's
    off = ~np.eye(len(want), dtype=bool)
    np.testing.assert_allclose(P[:-1, :-1][off[:-1, :-1]], cov[:-1, :-1][off[:-1, :-1]], rtol=1e-12)
    assert np.all(P[-1, :-1] == 0.0) and np.all(P[:-1, -1] == 0.0)
    # the payload block starts with what the identification knows of a mass at the payload frame
    b = sc.arm.payload_basis[:, 0]
    known = 1.0 / np.sqrt(b @ np.linalg.pinv(P, rcond=1e-15) @ b)
    assert ctrl.online.payload_mass_std == pytest.approx(known, rel=1e-6) and known < 5.0
    data["controllers"] = {"adaptive_ct": {"estimator": {"mode": "payload"}}}  # derived, not a key
    with pytest.raises(
        ScenarioError, match=r"m\.toml: controllers\.adaptive_ct\.estimator: .*\[model\] from"
    ):
        parse_scenario(data, "m.toml")


def test_a_model_file_of_other_base_parameters_is_refused(tmp_path):
    path, _, _ = _model_file(tmp_path, names=["a", "b"], sigma=[1.0, 1.0], sigma_urdf=[1.0, 1.0],
                             std=[0.1, 0.1], identified=[True, True], covariance=np.eye(2).tolist(),
                             consistent_sigma=[1.0, 1.0], record={})  # fmt: skip
    data = read_toml(_shipped("vertical3_payload"))
    data["model"] = {"from": str(path)}
    with pytest.raises(ScenarioError, match=r"m\.toml.*model\.from.*model\.json.*2 base parameters are not"):
        parse_scenario(data, "m.toml")


def test_the_prior_rule_refuses_bad_input():
    p = 3
    ok = identified_prior_std(np.eye(p), np.zeros(p), np.ones(p))
    np.testing.assert_allclose(ok, np.sqrt(2.0))
    with pytest.raises(ParameterError, match="covariance"):
        identified_prior_std(np.eye(2), np.zeros(p), np.ones(p))
    with pytest.raises(ParameterError, match="not finite"):
        identified_prior_std(np.full((p, p), np.nan), np.zeros(p), np.ones(p))
    with pytest.raises(ParameterError, match="no stated uncertainty"):
        identified_prior_std(np.eye(p), np.zeros(p), np.ones(p), identified=[True, False, True])
    with pytest.raises(ParameterError, match="model_error_var"):
        identified_prior_std(np.eye(p), np.zeros(p), np.ones(p), model_error_var=[1.0, -1.0, 0.0])
    more = identified_prior_std(np.eye(p), np.zeros(p), np.ones(p), model_error_var=[2.0, 0.0, 0.0])
    np.testing.assert_allclose(more, [2.0, np.sqrt(2.0), np.sqrt(2.0)])


def test_the_prior_with_correlations_keeps_the_sandwich_and_the_diagonal_rule():
    """identified_prior_cov: the sandwich's off-diagonal terms, the diagonal of identified_prior_std
    (the step and the model error stay there), positive semidefinite."""
    rng = np.random.default_rng(3)
    p = 5
    L = rng.standard_normal((p, p))
    C = L @ L.T
    wls, fit, extra = rng.standard_normal(p), rng.standard_normal(p), rng.uniform(0, 1, p)
    P = identified_prior_cov(C, wls, fit, model_error_var=extra)
    np.testing.assert_allclose(np.diag(P), identified_prior_std(C, wls, fit, model_error_var=extra) ** 2)
    off = ~np.eye(p, dtype=bool)
    np.testing.assert_allclose(P[off], C[off])
    assert np.linalg.eigvalsh(P).min() >= -1e-12
    K = np.array([True, True, False, True, True])
    P = identified_prior_cov(C, wls, fit, identified=K, stated_var=np.full(p, 7.0))
    assert np.isclose(P[2, 2], 7.0) and np.all(P[2, K] == 0.0) and np.all(P[K, 2] == 0.0)


def test_the_estimator_starts_its_arm_block_at_the_given_covariance():
    """OnlineConfig.arm_prior_cov is the arm block of P0 (plus p0_arm); bad tables are refused."""
    from adaptive_dd.identification.online import OnlineConfig, _pack

    src = _shipped("vertical3_payload")
    arm = parse_scenario(read_toml(src), str(src), "v").arm
    p = arm.base.count
    L = np.random.default_rng(1).standard_normal((p, p)) * 1e-2
    C = L @ L.T
    cfg = OnlineConfig(arm_prior_cov=C.tolist())
    assert cfg.mode == "arm"
    _, P0 = _pack(cfg, arm)
    np.testing.assert_allclose(P0[:p, :p], C + cfg.p0_arm * np.eye(p), rtol=1e-12, atol=1e-15)
    with pytest.raises(ParameterError, match="arm_prior_cov must be a symmetric"):
        OnlineConfig(arm_prior_cov=(C + np.triu(np.ones((p, p)), 1)).tolist())
    with pytest.raises(ParameterError, match="give arm_uncertainty or arm_prior_cov, not both"):
        OnlineConfig(arm_prior_cov=C.tolist(), arm_uncertainty={})
    with pytest.raises(ParameterError, match=f"this arm has {p} base parameters"):
        _pack(OnlineConfig(arm_prior_cov=np.eye(p + 1).tolist()), arm)


def test_a_noise_free_record_recovers_a_planted_inertia_error():
    """The excitation phase's identification (identify_record: weighted least squares, consistent
    fit) on a noise-free record of the model's law recovers a 20 % error planted on link 2's
    inertia, and leaves the other base parameters where the record's plant has them."""
    from adaptive_dd.identification.arm_prior import perturbed_parameters

    src = _shipped("vertical3_payload_exact")
    arm = parse_scenario(read_toml(src), str(src), "v").arm
    model = arm_model(arm)
    n, T = arm.n_joints, 1e-3
    u = np.zeros(8 * n)
    u[5 * 1 + 4] = 1.0  # link 2's inertia about its centre of mass x 1.2
    only = ArmUncertainty(mass=0.0, com=0.0, inertia=0.2, viscous=0.0, coulomb=0.0, armature=0.0)
    sigma_true = model.B @ perturbed_parameters(arm, u, only)
    planted = sigma_true - model.sigma_ref
    k = int(np.argmax(np.abs(planted)))
    assert model.names[k].startswith("Iyy2") and np.count_nonzero(np.abs(planted) > 1e-12) == 1
    t = np.arange(0.0, 8.0, T)[:, None]
    f = np.array([[0.3, 0.5, 0.4], [0.7, 1.1, 0.9], [1.3, 1.7, 1.9]])
    a = np.array([[0.5, 0.4, 0.5], [0.2, 0.2, 0.3], [0.1, 0.1, 0.1]])
    ph = np.random.default_rng(0).uniform(0, 2 * np.pi, (3, n))
    w = 2 * np.pi * f
    q = sum(a[i] * np.sin(w[i] * t + ph[i]) for i in range(3))
    qd = sum(a[i] * w[i] * np.cos(w[i] * t + ph[i]) for i in range(3))
    qdd = sum(-a[i] * w[i] ** 2 * np.sin(w[i] * t + ph[i]) for i in range(3))
    tau = base_regressor(model, q, qd, qdd) @ sigma_true  # a sampled continuous torque
    one = identify_record(model, q, qd, tau, T, torque_held=False)
    for est in (one.hat, one.fit):
        assert abs((est[k] - model.sigma_ref[k]) / planted[k] - 1.0) < 0.01, est[k]
        bad = np.abs(est - sigma_true) > 0.01 * np.abs(sigma_true) + 1e-4
        assert not bad.any(), [model.names[i] for i in np.flatnonzero(bad)]
    # the prior it hands on covers the (tiny) error
    assert np.max(np.abs(one.fit - sigma_true) / one.std) < 6.0


def test_the_excitation_identifies_coulomb_friction_with_the_noise_width():
    """coulomb_width: the identification's Coulomb law tanh(qd / v) with v the record's measured
    velocity noise (rms over joints) for a plant with a sign law, the arm's friction_velocity for a
    tanh plant. On a noise-free record of a sign law (width: the sign itself) it finds the Coulomb
    levels where the arm's 0.02 rad/s did not (with the shipped noise both are within 3 % on this
    record; on the drawn iiwa's excitation the noise's width halved the identified model's torque
    error along the task's path, ``studies/excitation_diagnosis.py`` of commit d41702f)."""
    from adaptive_dd.identification.friction_width import coulomb_width, velocity_noise_std

    src = _shipped("vertical3_payload")
    sc = parse_scenario(read_toml(src), str(src), "v")
    s = float(np.sqrt(np.mean(sc.velocity_variance)))
    model, sigma_true, q, qd, tau, T = _record(0, stribeck=0.0)
    # the record's noise is the scenario's, measured to a few per cent
    assert velocity_noise_std(qd) == pytest.approx(s, rel=0.03) and s < 0.5 * sc.arm.friction_velocity
    assert coulomb_width(qd) == velocity_noise_std(qd)
    assert coulomb_width(qd, "tanh", 0.02) == 0.02
    model, sigma_true, q, qd, tau, T = _record(0, stribeck=0.0, noise=0.0)
    quiet = coulomb_width(qd)
    assert quiet <= 1e-4  # the signal's own second difference: 200x below the arm's 0.02
    fc = [i for i, nm in enumerate(model.names) if nm.startswith("fc")]
    err = {}
    for v in (quiet, model.friction_velocity):
        one = identify_record(
            dataclasses.replace(model, friction_velocity=v), q, qd, tau, T, torque_held=False
        )
        err[v] = np.abs(one.fit[fc] - sigma_true[fc]) / sigma_true[fc]
    assert err[quiet].max() < 0.002 and err[quiet].max() < 0.2 * err[model.friction_velocity].max(), err


def test_identify_and_the_excitation_phase_fit_one_friction_on_one_record(tmp_path):
    """`adaptive-dd identify --arm` (whose model.json `[model] from` hands on) and the excitation
    phase of `[run] excite` identify the same record with the same Coulomb law (its width the
    record's velocity noise, identification.friction_width) and so the same friction: identify
    with the arm's 0.02 rad/s (as it did) fails this."""
    import json

    from adaptive_dd.cli import main
    from adaptive_dd.identification.friction_width import identification_model
    from adaptive_dd.io import write_recording

    src = _shipped("vertical3_payload_exact")
    sc = parse_scenario(read_toml(src), str(src), "v")
    _, _, q, qd, tau, T = _record(1, stribeck=0.5, duration=4.0)
    model = identification_model(sc.arm, qd)  # the phase's (excitation_phase.identify_excitation)
    phase = identify_record(model, q, qd, tau, T)
    assert model.friction_velocity < 0.5 * sc.arm.friction_velocity
    t = T * np.arange(len(q))
    path = write_recording(tmp_path / "r.csv", t, q, qd, tau)
    scen = tmp_path / "v3.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n')
    out = tmp_path / "id"
    # the width the excitation phase takes (it knows its plant's law); identify's default on a
    # record whose law is not stated estimates it (profile)
    argv = ["identify", "--arm", str(scen), str(path), "--out", str(out), "--output-error", "off"]
    assert main([*argv, "--coulomb-width", "noise"]) == 0
    m = json.loads((out / "model.json").read_text())
    assert m["friction_velocity"] == pytest.approx(model.friction_velocity, rel=1e-6)  # the CSV's digits
    names = list(m["names"])
    fr = [k for k, nm in enumerate(names) if nm.startswith(("fc", "fv"))]
    assert np.allclose(np.asarray(m["sigma"])[fr], phase.hat[fr], rtol=1e-5, atol=1e-9)


def test_the_identified_prior_is_in_the_online_estimators_units():
    """The identification's covariance, handed to adaptive_ct, counts about as much as the record
    it summarises would in the online estimator (estimator_scale: the median generalised eigenvalue
    of the prior against the estimator's own information from that record; 1.4 on this record,
    0.7 and 2.2 on the drawn iiwa's excitation). A prior in other units is caught: the rows'
    white-noise variance would scale it by about 35 (the estimator's rows are correlated over
    hundreds of samples, so it over-counts its data by about as much)."""
    from adaptive_dd.closed_loop.model_prior import estimator_scale
    from adaptive_dd.identification.online import OnlineConfig

    model, _, q, qd, tau, T = _record(0, stribeck=1.0)
    src = _shipped("vertical3_payload")
    arm = parse_scenario(read_toml(src), str(src), "v").arm
    one = identify_record(model, q, qd, tau, T)
    kappa = estimator_scale(OnlineConfig(sample_period=T), arm, one.prior_cov, q, qd, tau)
    assert 1.0 / 3.0 < kappa < 3.0, kappa


def test_the_estimator_scale_follows_the_estimators_row_units():
    """estimator_scale reads the information the estimator's rows carry: rows divided by twice the
    weights carry a quarter of it, so the same prior is four times as tight in those units; the
    scale is linear in the prior."""
    from adaptive_dd.closed_loop.model_prior import estimator_scale
    from adaptive_dd.identification.online import OnlineConfig

    model, _, q, qd, tau, T = _record(1, stribeck=0.0, duration=4.0)
    src = _shipped("vertical3_payload")
    arm = parse_scenario(read_toml(src), str(src), "v").arm
    P = identify_record(model, q, qd, tau, T).prior_cov
    w = np.array([1.0, 0.4, 0.1])
    one = estimator_scale(OnlineConfig(sample_period=T, row_weights=tuple(w)), arm, P, q, qd, tau)
    two = estimator_scale(OnlineConfig(sample_period=T, row_weights=tuple(2 * w)), arm, P, q, qd, tau)
    assert two / one == pytest.approx(0.25, rel=1e-6)
    more = estimator_scale(OnlineConfig(sample_period=T, row_weights=tuple(w)), arm, 35.0 * P, q, qd, tau)
    assert more / one == pytest.approx(35.0, rel=1e-6)
