"""Estimators against the bound: rows, table, reproduce JSON and the CLI."""

import json

import numpy as np
import pytest

from adaptive_dd.cli import main
from adaptive_dd.experiments import table2_torque
from adaptive_dd.identification.fisher import crb_from_fisher, fisher_information
from adaptive_dd.identification.limits import bound_rows, format_bound_table, table2_bound
from adaptive_dd.identification.reproduce import format_bounds, run_reproduce
from adaptive_dd.plant.parameters import TABLE1_SIGMA


@pytest.fixture
def fake_crb():
    # F = diag(1 / std^2) with std = 0.01 % of sigma
    std = 1e-4 * TABLE1_SIGMA
    return crb_from_fisher(np.diag(1 / std**2), TABLE1_SIGMA, "test", 10)


def test_bound_rows_ratio_bias_and_targets(fake_crb, rng):
    z = rng.standard_normal((50, 7))
    z = (z - z.mean(0)) / z.std(0, ddof=1)  # exactly zero mean, unit std
    est = {
        "output_error": TABLE1_SIGMA * (1 + 2e-4 * z),  # std 0.02 % = 2 bounds: met (3x)
        "exact_batch_ls": TABLE1_SIGMA * (1 + 5e-4 * z + 1e-4),  # 5 bounds: NOT met, bias 1 bound
        "akf": TABLE1_SIGMA * (1 + 5e-4 * z),  # 5 bounds, online target 10x: met
    }
    rows = {(r["estimator"], r["param"]): r for r in bound_rows(fake_crb, est)}
    r = rows[("output_error", "J1")]
    assert r["crb_std_pct"] == pytest.approx(0.01)
    assert r["est_std_pct"] == pytest.approx(0.02)
    assert r["std_over_crb"] == pytest.approx(2.0)
    assert r["met"] is True
    assert rows[("exact_batch_ls", "d2")]["met"] is False
    assert rows[("exact_batch_ls", "r")]["bias_over_crb"] == pytest.approx(1.0)
    assert rows[("akf", "b1")]["met"] is True
    text = format_bound_table(fake_crb, est)
    verdicts = {line.split()[0]: line.endswith("NOT met") for line in text.splitlines()[-3:]}
    assert verdicts == {"output_error": False, "exact_batch_ls": True, "akf": False}


def test_table2_bound_is_the_fisher_bound_with_quantization():
    tau = table2_torque(1, 1500)[0]
    a = table2_bound(tau)
    b = fisher_information(TABLE1_SIGMA, tau, encoder_counts=(614400, 507904))
    np.testing.assert_allclose(a.crb_std_pct, b.crb_std_pct)


def test_reproduce_rows_carry_the_bound(tmp_path):
    res = run_reproduce(
        seeds=2, tau_f=(0.02,), methods=("M2",), estimators=("exact",), n_samples=1500, progress=False
    )
    assert res.crb is not None
    np.testing.assert_allclose(res.crb.crb_std_pct, table2_bound(res.sim.tau[0]).crb_std_pct)
    rows = json.loads(res.write_json(tmp_path / "r.json").read_text())
    j1 = next(r for r in rows if r["param"] == "J1")
    signed = res.signed[("M2", "full", "exact")][0, :, 0]
    assert j1["crb_std_pct"] == pytest.approx(res.crb.crb_std_pct[0])
    assert j1["est_std_pct"] == pytest.approx(np.std(signed, ddof=1))
    assert j1["bias_pct"] == pytest.approx(signed.mean())
    assert j1["mean_pct"] == pytest.approx(np.abs(signed).mean())  # the existing key keeps its meaning
    assert j1["std_over_crb"] == pytest.approx(j1["est_std_pct"] / j1["crb_std_pct"])
    assert "M2 exact tau_f=0.02" in format_bounds(res)
    noiseless = run_reproduce(
        seeds=1,
        tau_f=(0.02,),
        methods=("M2",),
        estimators=("exact",),
        n_samples=500,
        progress=False,
        noise=False,
    )
    assert noiseless.crb is None and "no bound" in format_bounds(noiseless)


def test_cli_identify_prints_the_bound_for_the_stated_noise(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "--duration", "1.5", "--out", str(out)]) == 0
    csv = str(out / "trajectory.csv")

    def crb_column(extra):
        capsys.readouterr()
        assert main(["identify", csv, "--out", str(tmp_path / "id"), *extra]) == 0
        text = capsys.readouterr().out
        assert "CRB" in text
        return np.array(
            [
                float(line.split()[3])
                for line in text.splitlines()
                if line.split() and line.split()[0] in ("J1", "J2", "r", "b1", "b2", "d1", "d2")
            ]
        )

    base = crb_column([])
    quad = crb_column(["--position-variance", "4e-8", "4e-7", "--velocity-variance", "2e-4", "4e-4"])
    np.testing.assert_allclose(quad, 2 * base, rtol=0.07)  # printed to 2 digits


@pytest.mark.slow
def test_cli_identify_output_error_is_near_the_bound(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "--duration", "1.5", "--out", str(out)]) == 0
    csv = str(out / "trajectory.csv")
    capsys.readouterr()
    assert main(["identify", csv, "--estimator", "output_error", "--out", str(tmp_path / "oe")]) == 0
    text = capsys.readouterr().out
    assert "output error:" in text
    ratios = [float(line.split()[-1]) for line in text.splitlines() if line.split()[:1] == ["J1"]]
    assert len(ratios) == 1 and 0.5 < ratios[0] < 4  # maximum likelihood: near the bound
