"""N-joint identification (issue 20): regression identities, the bound, estimators held to it, payload,
consistency, excitation, records and CLI errors. Most on the shipped three-joint vertical arm."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import Reference
from adaptive_dd.errors import DataError, ParameterError
from adaptive_dd.identification.consistency import (
    consistent_fit,
    is_physical,
    params_from_pseudo_inertia,
    pseudo_inertia,
)
from adaptive_dd.identification.excitation import (
    FINE,
    ExcitationLimits,
    FourierTrajectory,
    _constraints,
    _within_limits,
    design_excitation,
    multisine,
    reference_toml,
    relative_bounds,
)
from adaptive_dd.identification.model import (
    arm_model,
    base_regressor,
    pi_from_sigma,
)
from adaptive_dd.identification.output_error import (
    cramer_rao_bound,
    fit_output_error,
    measurement_std,
    schur_information,
    segment_sensitivities,
    simulate_segments,
)
from adaptive_dd.identification.payload_pair import payload_from_pair
from adaptive_dd.identification.records import simulate_record
from adaptive_dd.identification.regression import (
    check_excitation,
    filtered_regression,
    weighted_least_squares,
)
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.robots import ROBOTS, robot_urdf

REF3 = Reference(
    offset=(0.2, -0.4, 0.5),
    amplitude=((0.8, 0.3), (0.6, 0.3), (0.7, 0.3)),
    frequency=((0.3, 0.9), (0.4, 1.1), (0.5, 1.3)),
    phase=((0.0, 1.0), (0.5, 2.0), (1.0, 0.3)),
    ramp=0.2,
)


@pytest.fixture(scope="module")
def arm3():
    return Arm.from_urdf(robot_urdf("vertical3"), ROBOTS["vertical3"].payload_frame)


@pytest.fixture(scope="module")
def model3(arm3):
    return arm_model(arm3)


@pytest.fixture(scope="module")
def clean3(arm3):
    return simulate_record(arm3, REF3, 2.0, [np.random.default_rng(0)], noise=False, quantize=False)


def test_base_regressor_equals_the_arms(arm3, model3):
    rng = np.random.default_rng(1)
    q = rng.uniform(-2, 2, (20, 3))
    qd = rng.choice([-1, 1], (20, 3)) * rng.uniform(2, 3, (20, 3))  # tanh(qd / 0.02) == sign(qd)
    qdd = rng.uniform(-5, 5, (20, 3))
    np.testing.assert_allclose(base_regressor(model3, q, qd, qdd), arm3.regressor(q, qd, qdd), atol=1e-10)
    np.testing.assert_allclose(pi_from_sigma(model3, arm3.sigma) @ model3.B.T, arm3.sigma, atol=1e-12)


def test_exact_filtered_regression_holds_on_clean_records(model3, clean3):
    reg = filtered_regression(model3, clean3.q_true[0], clean3.qd_true[0], clean3.tau[0])
    err = reg.y - np.einsum("knp,p->kn", reg.phi, clean3.sigma_true)
    # exact up to the filters' discretisation: 1e-4 of the torque
    assert np.abs(err).max() < 1e-3 * np.abs(reg.y).max()
    sol = weighted_least_squares(reg, model3.names)
    np.testing.assert_allclose(sol.sigma, clean3.sigma_true, rtol=2e-3, atol=1e-3)


def test_unexcited_parameter_is_named(arm3, model3):
    still = Reference(
        offset=(0.2, -0.4, 0.5),
        amplitude=((0.8,), (0.6,), (0.0,)),
        frequency=((0.3,), (0.4,), (0.5,)),
        phase=((0.0,), (0.5,), (1.0,)),
    )
    rec = simulate_record(arm3, still, 2.0, [np.random.default_rng(0)])
    with pytest.raises(DataError, match=r"does not excite base parameter.*'fv3'.*joint 3 moves only"):
        filtered_regression(model3, rec.q[0], rec.qd[0], rec.tau[0])
    # two parameters that the record sees only together: collinear columns
    phi = np.random.default_rng(0).normal(size=(500, 3, model3.p))
    phi[..., 4] = 2.0 * phi[..., 2]
    with pytest.raises(DataError, match=r"does not excite base parameter '(mz2|m3)"):
        check_excitation(phi, model3.names)


def test_schur_bound_equals_least_squares_monte_carlo():
    """Linear-Gaussian case: y_j = A_j theta + C_j x_j + e; LS std over 2000 draws = sqrt(diag S^-1)."""
    rng = np.random.default_rng(2)
    nseg, R, m, s = 6, 30, 3, 2
    A, C = rng.normal(size=(nseg, R, m)), rng.normal(size=(nseg, R, s))
    S, _, _, _ = schur_information(A, C)
    bound = np.sqrt(np.diag(np.linalg.inv(S)))
    big = np.zeros((nseg * R, m + nseg * s))
    for j in range(nseg):
        big[j * R : (j + 1) * R, :m] = A[j]
        big[j * R : (j + 1) * R, m + j * s : m + (j + 1) * s] = C[j]
    e = rng.normal(size=(2000, nseg * R))
    est = np.linalg.lstsq(big, e.T, rcond=None)[0][:m].T
    np.testing.assert_allclose(est.std(axis=0), bound, rtol=0.08)


def _first_segment(arm, duration: float, samples: int):
    """``(model, record, pi, x0, tau, xs, Z)``: a clean record of ``arm`` tracking REF3 from rest, and
    the simulated states and sensitivities of one segment of its first ``samples`` from its start."""
    model = arm_model(arm)
    rec = simulate_record(arm, REF3, duration, [np.random.default_rng(0)], noise=False, quantize=False)
    pi = pi_from_sigma(model, rec.sigma_true)
    x0 = np.concatenate([rec.q_true[0, :1], rec.qd_true[0, :1]], axis=1)
    tau = rec.tau[:, :samples]
    xs = simulate_segments(model, pi, x0, tau, 1e-3)
    return model, rec, pi, x0, tau, xs, segment_sensitivities(model, pi, xs, tau, 1e-3)


def test_sensitivities_match_finite_differences(arm3):
    """Against finite differences through the RK4 model, where the Coulomb law is not steep
    (v_f = 0.2 rad/s: the Jacobians frozen over a sample are then accurate; see the module docstring)."""
    model3, clean3, pi, x0, tau, xs, Z = _first_segment(arm3.with_(friction_velocity=0.2), 0.5, 300)
    for col in (1, 4, 6 + 0, 6 + 5, 6 + 11):  # two states, three parameters
        h = 1e-6
        if col < 6:
            dx = np.zeros(6)
            dx[col] = h
            xp = simulate_segments(model3, pi, x0 + dx, tau, 1e-3)
        else:
            ds = np.zeros(model3.p)
            ds[col - 6] = h * max(1.0, abs(clean3.sigma_true[col - 6]))
            xp = simulate_segments(model3, pi_from_sigma(model3, clean3.sigma_true + ds), x0, tau, 1e-3)
            h = ds[col - 6]
        fd = (xp - xs)[0, -1] / h
        np.testing.assert_allclose(Z[0, -1, :, col], fd, rtol=1e-2, atol=1e-2 * np.abs(fd).max())


def test_sample_exponential_holds_on_stiff_steps():
    """exp(T F) and int_0^T exp(sF) ds against scipy's expm of the augmented matrix, on a mild step
    and on a stiff one (T F = -16 on a velocity: a light joint's Coulomb slope at a standstill),
    where the plain fourth-order series gives 2161 for exp(-16)."""
    from scipy.linalg import expm

    from adaptive_dd.identification.output_error import _expm_terms

    rng = np.random.default_rng(3)
    for scale in (0.3, 16.0):
        F = rng.normal(size=(2, 4, 4))
        F[:, 3, 3] = -scale / 1e-3
        phi, gam = _expm_terms(F, 1e-3)
        for b in range(2):
            aug = np.zeros((8, 8))
            aug[:4, :4], aug[:4, 4:] = F[b], np.eye(4)
            ex = expm(1e-3 * aug)
            np.testing.assert_allclose(phi[b], ex[:4, :4], atol=1e-4)
            np.testing.assert_allclose(gam[b], ex[:4, 4:], atol=1e-7)


def test_sensitivities_stay_bounded_from_a_standstill(arm3):
    """A segment that starts at rest under a steep smooth Coulomb law (v_f = 2 mrad/s): the
    sensitivities stay of the order of the motion's. The unscaled series grew them to 1e12 on
    the SICE URDF and the Cramér-Rao bound it fed was 1e-15 of the parameters."""
    *_, Z = _first_segment(arm3.with_(friction_velocity=0.002), 0.4, 200)
    assert np.all(np.isfinite(Z)) and np.abs(Z).max() < 1e3


def test_model_records_hold_on_a_stiff_friction_law():
    """The SICE arm's light second link under its smooth Coulomb law (h rho = 5 at 2 substeps,
    past RK4's 2.79): the record with the default substeps is the one with 16 (h rho 0.6). Unsplit, joint 2
    ran backwards from rest and the error to the fine record reached 0.39 rad/s."""
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = load_scenario(Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "sice_urdf.toml")
    rec = {
        s: simulate_record(sc.arm, sc.reference, 0.2, [np.random.default_rng(0)], substeps=s, noise=False)
        for s in (2, 16)
    }
    np.testing.assert_allclose(rec[2].qd_true, rec[16].qd_true, atol=1e-5)


@pytest.mark.slow  # 10 s in a cold run
def test_output_error_is_held_to_the_bound(arm3, model3):
    """Three seeds of a 2.5 s record: every parameter's error within 4 bounds; the bound's scale is right
    (the normalised errors' RMS is between 0.5 and 2)."""
    rec = simulate_record(arm3, REF3, 2.5, [np.random.default_rng([5, i]) for i in range(3)])
    std = measurement_std(arm3)
    crb, _ = cramer_rao_bound(model3, rec.sigma_true, rec.q_true[0], rec.qd_true[0], rec.tau[0], std)
    z = []
    for s in range(3):
        wls = weighted_least_squares(filtered_regression(model3, rec.q[s], rec.qd[s], rec.tau[s]))
        oe = fit_output_error(model3, rec.q[s], rec.qd[s], rec.tau[s], wls.sigma, std)
        assert oe.converged
        assert 0.9 < 2 * oe.cost / oe.n_residuals < 1.1  # residuals at the noise level
        np.testing.assert_allclose(oe.std, crb, rtol=0.05)  # bound at the estimate ~ at the truth
        z.append((oe.sigma - rec.sigma_true) / crb)
    z = np.array(z)
    assert np.abs(z).max() < 4.0
    assert 0.5 < np.sqrt(np.mean(z**2)) < 2.0


def test_pseudo_inertia_roundtrip_and_constrained_fit():
    pp = payload_parameters(1.5, [0.01, -0.02, 0.05], [0.002, 0.003, 0.004, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(params_from_pseudo_inertia(pseudo_inertia(pp)), pp, atol=1e-15)
    assert is_physical(pp)
    F = np.diag(1.0 / np.maximum(np.abs(pp), 1e-4) ** 2)
    same = consistent_fit(pp, F)
    assert same.was_physical and same.distance == 0.0
    bad = payload_parameters(0.05, [0.03, 0.0, 0.02], radius=0.0)
    bad[9] -= 2e-5  # Izz below what a point mass at that place has: no rigid body
    assert not is_physical(bad)
    fit = consistent_fit(bad, np.diag(1.0 / np.full(10, 1e-4) ** 2))
    assert not fit.was_physical and fit.min_eigenvalue < 0
    assert is_physical(fit.params, atol=1e-12) and fit.distance > 0


def test_payload_from_pair_recovers_a_linear_case():
    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    pp = payload_parameters(2.0, [0.01, -0.02, 0.06], radius=0.04)
    su = arm.sigma
    sl = su + arm.payload_basis @ pp
    cov = np.eye(arm.base.count) * 1e-10
    pr = payload_from_pair(arm, sl, cov, su, cov)
    assert pr.mass == pytest.approx(2.0, rel=1e-6)
    np.testing.assert_allclose(pr.com, [0.01, -0.02, 0.06], atol=1e-6)
    assert pr.consistent.was_physical


def test_payload_json_is_a_scenario_payload_entry():
    """``identify``'s payload.json: its ``scenario_payload``, pasted as a [[payload]] entry, is the
    payload identified (the same ten parameters), through the scenario's own checks."""
    from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
    from adaptive_dd.identification.payload_pair import payload_from_params, payload_record

    pp = payload_parameters(2.0, [0.01, -0.02, 0.06], [0.004, 0.005, 0.003, 0.0002, -0.0001, 0.0003])
    rec = json.loads(json.dumps(payload_record(payload_from_params(pp, np.eye(10) * 1e-12), "r.csv")))
    entry = rec["scenario_payload"]
    assert rec["mass_kg"] == pytest.approx(2.0) and rec["com_m"] == pytest.approx([0.01, -0.02, 0.06])
    data = read_toml(Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "ur5_tool_swap.toml")
    data["payload"][0] = {"at": data["payload"][0]["at"], **entry}
    sc = parse_scenario(data, "u.toml")
    got = payload_parameters(sc.swap_masses[0], sc.swap_com[0], sc.swap_inertia[0])
    np.testing.assert_allclose(got, pp, atol=1e-6)


def test_a_pair_on_a_planar_arm_gives_what_the_arm_determines_and_says_the_rest(arm3):
    """vertical3's base parameters determine 4 of the payload's 10 (m, mx, mz, Iyy): the pair gives
    those (the pair was refused), the others NaN, no consistent fit; a full arm's result is as it was."""
    pp = payload_parameters(2.0, [0.03, 0.01, 0.05], [0.004, 0.005, 0.003, 0.0, 0.0, 0.0])
    cov = 1e-12 * np.eye(arm3.base.count)
    pr = payload_from_pair(arm3, arm3.sigma + arm3.payload_basis @ pp, cov, arm3.sigma, cov)
    assert pr.determined.tolist() == [True, True, False, True, False, False, True, False, False, False]
    assert pr.mass == pytest.approx(2.0) and pr.consistent is None
    np.testing.assert_allclose(pr.com[[0, 2]], [0.03, 0.05], atol=1e-9)
    assert np.isnan(pr.com[1]) and np.isnan(pr.com_std[1]) and np.isfinite(pr.com_std[[0, 2]]).all()
    # Iyy about the centre of mass from the determined ones alone (the out-of-plane cy not needed)
    assert pr.inertia_com[1, 1] == pytest.approx(0.005, abs=1e-9)
    assert np.isnan(pr.inertia_com[[0, 2], [0, 2]]).all() and np.isnan(pr.inertia_com[0, 1])


def test_a_planar_payload_writes_a_scenario_entry_the_arm_takes(arm3):
    """payload.json of a partly determined payload: nulls where not determined, the list of those
    determined, and a [[payload]] entry filled to a valid body that a scenario of the arm accepts."""
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.identification.payload_pair import payload_record

    pp = payload_parameters(1.0, [0.02, 0.0, 0.04], [0.002, 0.003, 0.001, 0.0, 0.0, 0.0])
    cov = 1e-12 * np.eye(arm3.base.count)
    pr = payload_from_pair(arm3, arm3.sigma + arm3.payload_basis @ pp, cov, arm3.sigma, cov)
    rec = json.loads(json.dumps(payload_record(pr, "r.csv")))  # strict JSON: no NaN
    assert rec["determined"] == ["m", "mx", "mz", "Iyy"] and rec["com_m"][1] is None
    assert rec["physical_as_estimated"] is None and rec["params"][2] is None
    entry = rec["scenario_payload"]
    assert entry["com"][1] == 0.0 and entry["inertia"][1] == pytest.approx(0.003, abs=1e-9)
    assert entry["inertia"][0] == entry["inertia"][2] == entry["inertia"][1]  # filled: a valid body
    from adaptive_dd.io import read_toml

    data = read_toml(
        Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "vertical3_payload.toml"
    )
    data["payload"] = [{"at": data["payload"][0]["at"], **entry}]
    sc = parse_scenario(data, "v.toml")
    assert sc.swap_masses[0] == pytest.approx(1.0)


def test_payload_seen_refuses_directions_that_mix_parameters():
    """An arm whose base parameters see a payload combination of a determined and an undetermined
    parameter cannot give them one by one: refused, naming them."""
    from types import SimpleNamespace

    from adaptive_dd.identification.payload_pair import payload_seen

    P = np.zeros((3, 10))
    P[0, 0] = 1.0  # the mass alone
    P[1, 1] = P[1, 4] = 1.0  # mx and Ixx only together
    fake = SimpleNamespace(payload_basis=P, payload_rank=2)
    fake.payload_identifiable = np.array([True] + [False] * 9)
    with pytest.raises(ParameterError, match=r"2 combinations .* mix \['mx', 'my'"):
        payload_seen(fake, "a pair of records")


def test_fourier_reference_roundtrip(arm3):
    tr = FourierTrajectory(np.array([0.1, -0.2, 0.3]), np.full((3, 2), 0.2), np.full((3, 2), -0.1), 0.2)
    t = np.linspace(0, 5, 101)
    for a, b in zip(tr.sample(t), tr.reference().sample(t), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)
    assert reference_toml(tr.reference()).count("joint") == 3


def test_designed_excitation_keeps_limits_and_beats_the_multisine(arm3, model3):
    lim = ExcitationLimits.of_arm(arm3, acceleration=5.0)
    plain = multisine(arm3, lim, harmonics=3, f0=0.2, grid=60)
    best, _ = design_excitation(arm3, lim, harmonics=3, f0=0.2, grid=60, maxiter=40)
    checked = np.linspace(0, 5, 60 * FINE, endpoint=False)  # the design's own check
    assert np.min(_constraints(model3, best, checked, lim)) >= 0
    t = np.linspace(0, 5, 4000, endpoint=False)
    assert np.min(_constraints(model3, best, t, lim)) > -1e-3
    assert np.min(_constraints(model3, plain, t, lim)) > -0.01

    def logdet(tr):  # of the limit-weighted information
        A = (base_regressor(model3, *tr.sample(t)) / lim.torque[None, :, None]).reshape(-1, model3.p)
        return np.linalg.slogdet(A.T @ A + 1e-9 * np.eye(model3.p))[1]

    assert logdet(best) > logdet(plain) + 5


def test_an_optimum_crossing_a_limit_between_grid_points_is_shrunk_within_it(model3):
    """The iiwa's designed excitation crossed a limit by 1.1 % between the optimiser's grid points
    and the excitation phase was refused; the oscillation is now shrunk within the limits."""
    tr = FourierTrajectory(np.zeros(3), np.full((3, 2), 0.2), np.full((3, 2), -0.1), 0.2)
    fine = np.linspace(0, 5, 2000, endpoint=False)
    peak = np.abs(tr.sample(fine)[1]).max(axis=0)
    wide = ExcitationLimits(np.full(3, -3.0), np.full(3, 3.0), peak / 0.98, np.full(3, 1e3), np.full(3, 1e6))
    assert _within_limits(model3, tr, fine, wide) is tr  # within: untouched
    lim = dataclasses.replace(wide, velocity=peak * 0.98)  # 2 % over on every joint
    assert np.min(_constraints(model3, tr, fine, lim)) < -0.019
    shrunk = _within_limits(model3, tr, fine, lim)
    assert np.min(_constraints(model3, shrunk, fine, lim)) >= 0
    assert shrunk.a[0, 0] / tr.a[0, 0] == pytest.approx(0.98, abs=2e-3)  # no more than needed
    np.testing.assert_array_equal(shrunk.q0, tr.q0)
    with pytest.raises(ParameterError, match=r"still does with its oscillation shrunk to 0\.8"):
        _within_limits(model3, tr, fine, dataclasses.replace(wide, velocity=peak * 0.7))


def test_read_recording_of_n_joints_names_the_problem(tmp_path, arm3, clean3):
    from adaptive_dd.cli import main
    from adaptive_dd.io import read_recording, write_recording

    path = write_recording(tmp_path / "r.csv", clean3.t, clean3.q[0], clean3.qd[0], clean3.tau[0])
    rec = read_recording(path, 3)
    assert rec.q.shape == (2000, 3) and rec.sample_period == pytest.approx(1e-3)
    with pytest.raises(DataError, match=r"do not fit an arm of 6 joints: missing column\(s\) \['q4'"):
        read_recording(path, 6)
    lines = path.read_text().splitlines()
    lines[5] = lines[5].replace(lines[5].split(",")[2], "nan", 1)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"line 6, column 'q2': non-finite"):
        read_recording(bad, 3)
    scen = tmp_path / "s.toml"
    scen.write_text('[arm]\nrobot = "ur5"\n')
    assert main(["identify", "--arm", str(scen), str(path), "--out", str(tmp_path / "o")]) == 2


@pytest.mark.slow
def test_cli_simulate_and_identify_end_to_end(tmp_path, capsys):
    """simulate --arm writes an N-joint record; identify --arm reads it back, with and without qd."""
    from adaptive_dd.cli import main
    from adaptive_dd.identification.excitation import reference_toml

    scen = tmp_path / "v3.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n\n' + reference_toml(REF3))
    assert main(["simulate", "--arm", str(scen), "--duration", "2.5", "--out", str(tmp_path / "sim")]) == 0
    csv = tmp_path / "sim" / "trajectory.csv"
    assert csv.read_text().splitlines()[0] == "t,q1,q2,q3,qd1,qd2,qd3,tau1,tau2,tau3"
    assert main(["identify", "--arm", str(scen), str(csv), "--out", str(tmp_path / "id")]) == 0
    out = capsys.readouterr().out
    assert "output error:" in out and "converged" in out and "CRB std" in out
    # announced before it runs (minutes on a 7-joint arm's long record), not only reported after
    announced = out.index("output error: maximum likelihood from the WLS estimate, up to 30 iterations")
    assert announced < out.index("converged")
    assert (tmp_path / "id" / "torque_fit.png").is_file()
    # positions only: output error fits q alone
    lines = csv.read_text().splitlines()
    cols = lines[0].split(",")
    keep = [i for i, c in enumerate(cols) if not c.startswith("qd")]
    nq = tmp_path / "noqd.csv"
    nq.write_text("\n".join(",".join(r.split(",")[i] for i in keep) for r in lines) + "\n")
    assert main(["identify", "--arm", str(scen), str(nq), "--out", str(tmp_path / "id2")]) == 0
    out = capsys.readouterr().out
    assert "derived from the positions" in out
    # no trajectory.json beside it: the law is not stated, so its width is estimated (the noise's
    # width of the derived velocities was 23x the plant's 0.02 rad/s too narrow: output error stalled)
    assert "v per joint from the record's profile likelihood" in out
    # the payload of a planar arm is not fully identifiable from base parameters: what the pair does
    # not see is named, the rest reported (the record against itself: no mass)
    assert (
        main(["identify", "--arm", str(scen), str(csv), "--baseline", str(csv), "--out", str(tmp_path / "x")])
        == 0
    )
    out = capsys.readouterr().out
    assert "'-': not determined on this arm" in out and "centre of mass undefined" in out
    # torque offsets fitted by WLS come off the torques output error simulates (it ignored them:
    # normalised residual 28, estimates thousands of bounds off, "converged")
    off = tmp_path / "off.csv"
    rows = [r.split(",") for r in lines]
    j = rows[0].index("tau1")
    off.write_text(
        "\n".join([lines[0], *(",".join([*r[:j], repr(float(r[j]) - 0.8), *r[j + 1 :]]) for r in rows[1:])])
        + "\n"
    )
    # the law the record was simulated with, as its trajectory.json would state it
    args = [
        "identify",
        "--arm",
        str(scen),
        str(off),
        "--out",
        str(tmp_path / "off"),
        "--coulomb-width",
        "0.02",
    ]
    assert main([*args, "--torque-offset", "on"]) == 0
    out = capsys.readouterr().out
    res = float(out.split("normalised residual ")[1].split()[0])
    assert (
        res < 1.5 and "torque offsets fitted by WLS taken off" in out and "warning: the normalised" not in out
    )
    assert main([*args, "--torque-offset", "off"]) == 0  # the offset left in: said, not "converged" alone
    assert "warning: the normalised residual is" in capsys.readouterr().out


@pytest.mark.slow  # a kernel no other default test compiles (about 20-60 CPU-s cold)
def test_benchmark_plant_with_smooth_friction_is_the_model(arm3):
    """plant="benchmark" (the compiled benchmark plant) under the tanh law equals the identification model."""
    a = simulate_record(
        arm3.with_(friction="tanh"), REF3, 0.5, [np.random.default_rng(0)], noise=False, plant="benchmark"
    )
    b = simulate_record(arm3, REF3, 0.5, [np.random.default_rng(0)], noise=False)
    np.testing.assert_allclose(a.q_true, b.q_true, atol=1e-10)
    np.testing.assert_allclose(a.tau, b.tau, atol=1e-8)
    # "serial", the old name, is the same plant, with a warning naming the new one
    with pytest.warns(FutureWarning, match="use plant='benchmark'"):
        c = simulate_record(
            arm3.with_(friction="tanh"), REF3, 0.5, [np.random.default_rng(0)], noise=False, plant="serial"
        )
    np.testing.assert_array_equal(c.q_true, a.q_true)
    with pytest.raises(ParameterError, match="plant must be 'model' or 'benchmark'"):
        simulate_record(arm3, REF3, 0.5, [np.random.default_rng(0)], plant="rk4")


def test_relative_bounds_leave_out_a_kind_that_is_zero(arm3, model3):
    """An arm whose URDF gives no friction (UR3, UR10 of example-robot-data): its friction bounds
    have no magnitude to be relative to; they were divided by 1e-300 (1e297 relative), now NaN."""
    sigma = model3.sigma_ref.copy()
    fric = np.array([n.startswith(("fv", "fc")) for n in model3.names])
    sigma[fric] = 0.0
    rb = relative_bounds(np.full(model3.p, 1e-3), sigma, model3.names)
    assert np.all(np.isnan(rb[fric])) and np.all(np.isfinite(rb[~fric])) and np.nanmax(rb) < 1e3


def test_two_link_output_error_refuses_a_smooth_law_record(tmp_path, capsys):
    """A record simulate made on the general model (tanh Coulomb, said in its trajectory.json): the
    closed forms' output error fitted it as stick-slip and landed 60-340 bounds off, silently."""
    from adaptive_dd.cli import main

    out = tmp_path / "sim"
    assert main(["simulate", "--experiment", "reference", "--duration", "3", "--out", str(out)]) == 0
    csv = str(out / "trajectory.csv")
    capsys.readouterr()
    args = ["identify", csv, "--out", str(tmp_path / "id")]
    assert main([*args, "--estimator", "output_error"]) == 2
    assert 'robot = "sice_arm" and general = true' in capsys.readouterr().err
    assert main(args) == 0
    assert "the Cramér-Rao bound below is that of the stick-slip plant" in capsys.readouterr().out


def test_several_simulated_records_keep_the_width_they_were_made_with(tmp_path, capsys):
    """Two records of simulate --arm: their trajectory.json files give the Coulomb width (one record
    did; two looked for 'a; b.json' and took the velocity noise's width, 0.0073 for 0.02 rad/s)."""
    from adaptive_dd.cli import main
    from adaptive_dd.identification.excitation import reference_toml

    scen = tmp_path / "v3.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n\n' + reference_toml(REF3))
    csvs = []
    for seed in (1, 2):
        out = tmp_path / f"sim{seed}"
        assert (
            main(
                ["simulate", "--arm", str(scen), "--duration", "2.5", "--seed", str(seed), "--out", str(out)]
            )
            == 0
        )
        csvs.append(str(out / "trajectory.csv"))
    capsys.readouterr()
    assert (
        main(["identify", "--arm", str(scen), *csvs, "--output-error", "off", "--out", str(tmp_path / "id")])
        == 0
    )
    assert "v = 0.02 rad/s: the width the record was simulated with" in capsys.readouterr().out


def test_excite_writes_a_scenario_whose_paths_and_reference_still_read(tmp_path):
    """Written to another folder (results/excite/ by default), the scenario's relative URDF named
    nothing; a [reference] of sub-tables was kept beside the new one (invalid TOML)."""
    import shutil

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.cli import main

    shutil.copy(robot_urdf("vertical3"), tmp_path / "my_arm.urdf")
    scen = tmp_path / "my_arm.toml"
    joints = "\n".join(
        f"[reference.joint{j + 1}]\noffset = {o}\namplitude = [0.3]\nfrequency = [0.4]\n"
        for j, o in enumerate((0.2, -0.5, 0.3))
    )
    scen.write_text(f'[arm]\nurdf = "my_arm.urdf"\n\n[reference]\nramp = 0.5\n\n{joints}')
    load_scenario(scen)
    out = tmp_path / "results" / "excite" / "scenario.toml"
    assert (
        main(
            [
                "excite",
                "--arm",
                str(scen),
                "--maxiter",
                "2",
                "--harmonics",
                "2",
                "--duration",
                "1",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    text = out.read_text()
    assert 'urdf = "../../my_arm.urdf"' in text and "[reference.joint1]" not in text
    sc = load_scenario(out)
    assert sc.arm.n_joints == 3 and len(sc.reference.amplitude[0]) == 2


def test_excite_rebases_the_paths_of_an_array_over_several_lines(tmp_path):
    """A ``files = [...]`` written over several lines kept its relative paths as they were (the
    rewrite went line by line and the array's lines carry no key): the written scenario named
    nothing. Comments in the array (a bracket, a lone quote), a key that only ends in ``from``, an
    empty string and a nested array's line in the [reference] left out (taken for a table's header:
    invalid TOML) are read as what they are."""
    import tomllib

    from adaptive_dd.cli.excite import _replace_reference

    for name in ("a.csv", "b.csv", "m.json"):
        (tmp_path / name).write_text("")
    src = (
        '[model]\nfrom = "m.json"\nplatform-from = "m.json"\n[record]\nfiles = [ # see [record]\n'
        '  "a.csv", # 5" rows\n  "b.csv",\n]\nempty = ""\n\n'
        "[reference]\namplitude = [\n  [0.1, 0.2],\n  [0.3, 0.4]\n]\n[run]\nseeds = 2\n"
    )
    out = _replace_reference(src, "[reference]\n", tmp_path / "s.toml", tmp_path / "x" / "y" / "s.toml")
    data = tomllib.loads(out)
    assert data["record"]["files"] == ["../../a.csv", "../../b.csv"], out
    assert data["model"] == {"from": "../../m.json", "platform-from": "m.json"}, out
    assert data["record"]["empty"] == "" and data["run"] == {"seeds": 2} and data["reference"] == {}


@pytest.mark.slow  # the UR5's kernels (about 20 s cold)
def test_payload_only_says_whether_its_fit_converged(tmp_path, capsys):
    """--payload-only printed a mass 168 of its std off the truth after 2 iterations with no word that
    the fit had stopped; its +- now says 1 std."""
    from adaptive_dd.cli import main

    scen = str(Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "ident_ur5.toml")
    out = tmp_path / "loaded"
    assert main(["simulate", "--arm", scen, "--duration", "4", "--payload", "2", "--out", str(out)]) == 0
    capsys.readouterr()
    assert (
        main(["identify", "--arm", scen, str(out / "trajectory.csv"), "--payload-only", "--max-iter", "1"])
        == 0
    )
    text = capsys.readouterr().out
    assert "NOT converged" in text and "warning: output error stopped at --max-iter 1" in text
    assert "payload (one record, arm known) [+- 1 std]: mass" in text
    assert not (tmp_path / "fit").exists()  # printed only, without --out
    argv = ["identify", "--arm", scen, str(out / "trajectory.csv"), "--payload-only", "--max-iter", "1"]
    assert main([*argv, "--out", str(tmp_path / "fit")]) == 0
    written = json.loads((tmp_path / "fit" / "payload.json").read_text())
    assert written["output_error"]["converged"] is False and written["scenario_payload"]["mass"] >= 0


def test_identify_warns_where_output_error_leaves_the_wls_bound(capsys):
    """On a simulated Kinova record the WLS bounds missed 13 of 35 parameters that output error,
    converged with its noise model, put on the truth; nothing said so. A warning names how many and
    the farthest; none when they agree, when output error did not converge or its residual is off."""
    from types import SimpleNamespace

    from adaptive_dd.cli._identify_log import _disagreement

    model = SimpleNamespace(names=("a", "b", "c"))
    fit = SimpleNamespace(sigma=np.array([1.0, 2.0, 3.0]), std=np.array([0.1, 0.1, 0.1]), quantile=2.1)
    share = np.array([0.0, 0.0, 0.9])  # c held at the URDF's value: not judged
    oe = SimpleNamespace(sigma=np.array([1.5, 2.05, 9.0]), converged=True, cost=50.0, n_residuals=100)
    _disagreement(model, fit, oe, share)
    out = capsys.readouterr().out
    assert "outside the WLS estimate's 95 % bound on 1 of 2 parameters (the farthest a: 5.0" in out
    for other in ({"converged": False}, {"cost": 500.0}, {"sigma": np.array([1.1, 2.0, 9.0])}):
        _disagreement(model, fit, SimpleNamespace(**{**vars(oe), **other}), share)
        assert capsys.readouterr().out == ""


def test_identify_writes_output_errors_estimate_when_it_converged(tmp_path, capsys):
    """The warning said to prefer output error's column, and nothing could read it: model.json and
    estimates.csv held the least squares' estimate always. Where output error converged with its noise
    model they hold its estimate with its Cramér-Rao std (95 % bound +- 1.96 std); the pair
    (--baseline) still differences two WLS fits."""
    import json

    import pandas as pd

    from adaptive_dd.cli import main

    scen = Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "ident_vertical3.toml"
    sim = tmp_path / "sim"
    assert main(["simulate", "--arm", str(scen), "--seed", "3", "--duration", "6", "--out", str(sim)]) == 0
    out = tmp_path / "id"
    assert main(["identify", "--arm", str(scen), str(sim / "trajectory.csv"), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "converged, normalised residual" in text and "the model written (model.json" in text
    assert "is output error's, with its Cramér-Rao std" in text
    table = text.split("|WLS-OE|/CRB\n")[1].split("CRB: ")[0].strip().splitlines()
    oe = {
        line.split()[0]: (float(line.split()[-3]), float(line.split()[-2]))
        for line in table
        if "held" not in line
    }
    m = json.loads((out / "model.json").read_text())
    est = pd.read_csv(out / "estimates.csv").set_index("name")
    for name, (value, crb) in oe.items():
        k = m["names"].index(next(n for n in m["names"] if n.split()[0] == name))
        assert m["sigma"][k] == pytest.approx(value, rel=1e-4, abs=1e-9)  # as printed (5 digits)
        assert m["std"][k] == pytest.approx(crb, rel=0.05)
    assert m["record"]["quantile_95"] == 1.96
    np.testing.assert_allclose(est["half_width_95"], 1.96 * est["std"], rtol=2e-3)  # as written (4 digits)


def test_output_errors_model_with_a_held_direction(tmp_path, capsys):
    """A record too weak for a direction (held at the URDF's values): writing output error's model
    multiplied its (r, r) information by E as if it were (p, p) and failed every such record (exit 2,
    nothing written); the held directions keep the least squares' prior through the fit's own
    (oblique) projector."""
    import json

    import pandas as pd

    from adaptive_dd.cli import main

    text = (
        '[arm]\nrobot = "vertical3"\n[reference]\nramp = 1.0\n'
        "joint1 = { offset = 0.3, amplitude = [0.05], frequency = [0.3] }\n"
        "joint2 = { offset = -0.6, amplitude = [0.05], frequency = [0.4] }\n"
        "joint3 = { offset = 0.4, amplitude = [0.05], frequency = [0.5] }\n"
    )
    scen = tmp_path / "weak.toml"
    scen.write_text(text)
    sim = tmp_path / "sim"
    assert main(["simulate", "--arm", str(scen), "--seed", "3", "--out", str(sim)]) == 0
    outs = {}
    for how, extra in (("written", []), ("wls", ["--output-error", "off"])):
        out = tmp_path / how
        assert (
            main(["identify", "--arm", str(scen), str(sim / "trajectory.csv"), "--out", str(out), *extra])
            == 0
        )
        outs[how] = (json.loads((out / "model.json").read_text()), pd.read_csv(out / "estimates.csv"))
    text = capsys.readouterr().out
    assert "held at the URDF's values" in text
    m, est = outs["written"]
    assert m["record"]["estimator"] == "output_error" and outs["wls"][0]["record"]["estimator"] == "wls"
    held = est["held"].to_numpy(bool)
    assert held.any() and np.all(np.isfinite(m["std"])) and min(m["std"]) > 0
    ratio = est["std"][held].to_numpy() / outs["wls"][1]["std"][held].to_numpy()
    assert np.all((ratio > 0.3) & (ratio < 3.0)), ratio  # the prior's scale, not the CRB's


def test_a_planar_payload_within_its_noise_has_no_centre_of_mass_and_a_valid_entry(arm3):
    """A payload whose mass is within its noise (none, or a tiny one): the centre of mass is
    undefined (it printed a meaningless one); an inertia below 0 (noise) is 0 in the entry, which a
    scenario of the arm accepts (it was refused)."""
    from adaptive_dd.identification.payload_pair import payload_from_params, payload_record

    seen = np.array([True, True, False, True, False, False, True, False, False, False])
    cov = np.diag(np.where(seen, 1e-6, 0.0))
    none = payload_from_params(np.array([1e-4, 1e-4, 0, 1e-4, 0, 0, -1e-5, 0, 0, 0]), cov, seen)
    assert not none.com_defined and np.isnan(none.inertia_com).all()
    small = payload_from_params(np.array([0.05, 0.0015, 0, 0.0025, 0, 0, -0.0003, 0, 0, 0]), cov, seen)
    assert small.com_defined and small.inertia_com[1, 1] < 0
    assert np.isfinite(small.inertia_com_std[1, 1]) and np.isnan(small.inertia_com_std[0, 0])
    entry = payload_record(small, "r.csv")["scenario_payload"]
    assert entry["inertia"][:3] == [0.0, 0.0, 0.0]
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.io import read_toml

    data = read_toml(Path(__file__).resolve().parents[1] / "adaptive_dd/scenarios/vertical3_payload.toml")
    data["payload"] = [{"at": data["payload"][0]["at"], **entry}]
    assert parse_scenario(data, "v.toml").swap_masses[0] == pytest.approx(0.05)


def test_the_inertia_about_the_centre_of_mass_has_its_first_order_std(arm3):
    """The inertia's std (the docs promised one; none was given): from the parameters' covariance,
    checked against the spread of the inertia over draws of the parameters."""
    from adaptive_dd.identification.payload_pair import _inertia_about_com, payload_from_params

    seen = np.array([True, True, False, True, False, False, True, False, False, False])
    pp = payload_parameters(1.0, [0.02, 0.0, 0.04], [0.002, 0.003, 0.001, 0.0, 0.0, 0.0])
    C = np.diag(np.where(seen, [1e-6, 1e-8, 0, 1e-8, 0, 0, 1e-9, 0, 0, 0], 0.0))
    pr = payload_from_params(pp, C, seen)
    rng = np.random.default_rng(0)
    draws = rng.multivariate_normal(pp, C, 4000)
    spread = np.std([_inertia_about_com(np.where(seen, d, np.nan))[1, 1] for d in draws])
    assert pr.inertia_com_std[1, 1] == pytest.approx(spread, rel=0.05)
