"""Derivative filter banks (eqs. 17-21) and the filtered regressions."""

import sys

import numpy as np
import pytest

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.experiments import table2_torque
from adaptive_dd.identification import filters
from adaptive_dd.identification.estimators import align_torque
from adaptive_dd.identification.filters import (
    StreamingFilter,
    design_filter_bank,
    filter_record,
    summing_realisation,
)
from adaptive_dd.identification.regressors import OnlineRegressor, two_link_filtered_regression
from adaptive_dd.plant import TABLE1_SIGMA, ActuatorConfig, SensorConfig, simulate_open_loop

CLEAN = SensorConfig(quantize=False, position_variance=(0, 0), velocity_variance=(0, 0))


@pytest.mark.parametrize("method", ["M1", "M2"])
@pytest.mark.parametrize("tau_f", [0.002, 0.006, 0.02])
def test_streaming_equals_whole_record(method, tau_f, rng):
    bank = design_filter_bank(method, tau_f)
    u = rng.normal(size=(3, 1500)).cumsum(axis=-1) * 0.01 + 0.3
    y_rec = filter_record(bank, u, axis=-1, initial=u[:, 0])
    sf = StreamingFilter(bank, (3,), initial=u[:, 0])
    y_str = np.stack([sf(u[:, k]) for k in range(u.shape[1])], axis=1)
    np.testing.assert_allclose(y_str, y_rec, rtol=1e-9, atol=1e-9 * np.abs(y_rec).max())


@pytest.mark.parametrize("method", ["M1", "M2"])
@pytest.mark.parametrize("tau_f", [0.002, 0.02])
def test_summing_realisation_is_the_sum_of_the_banks_outputs(method, tau_f, rng):
    """One state driven by u_k through G_k: the sum of the bank's outputs, to round-off, from rest
    and from the steady state of constant inputs (the restart of the momentum form)."""
    bank = design_filter_bank(method, tau_f)
    A, B, C, D = summing_realisation(bank)
    k_out = bank.n_outputs
    u = rng.normal(size=(k_out, 2, 800)).cumsum(axis=-1) * 0.01 + rng.normal(size=(k_out, 2, 1))
    for steady in (False, True):
        want = np.zeros(u.shape[1:])  # (2, N): the bank's own state space, one state per input
        for k in range(k_out):
            sf = StreamingFilter(bank, (2,), initial=u[k, :, 0] if steady else None)
            for t in range(u.shape[-1]):
                want[:, t] += sf(u[k, :, t])[:, k]
        x = np.linalg.solve(np.eye(bank.order) - A, B @ u[:, :, 0]).T if steady else np.zeros((2, bank.order))
        got = np.empty_like(want)
        for t in range(u.shape[-1]):
            got[:, t] = x @ C + u[:, :, t].T @ D
            x = x @ A.T + u[:, :, t].T @ B.T
        scale = np.abs(want).max()
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * scale)
        assert scale > 0.1


@pytest.mark.parametrize("method", ["M1", "M2"])
def test_filters_are_derivative_filters(method):
    bank = design_filter_bank(method, 0.01)
    t = np.arange(4000) * 1e-3
    # a ramp: G0 passes it with a delay of n*tau_f, G1 gives its slope, G2 gives 0
    y = filter_record(bank, 2.0 * t)
    n = bank.order
    np.testing.assert_allclose(y[-1, 0], 2.0 * (t[-1] - n * 0.01), rtol=1e-6)
    np.testing.assert_allclose(y[-1, 1], 2.0, rtol=1e-6)
    if method == "M1":
        assert abs(y[-1, 2]) < 1e-6
    # the magnitude at 1 Hz matches |G_k(j w)| of eq. (18) / (20)
    w = 2 * np.pi
    y = filter_record(bank, np.sin(w * t))
    g0 = abs(1 / (1 + 1j * w * 0.01) ** n)
    np.testing.assert_allclose(np.abs(y[-1000:, 0]).max(), g0, rtol=1e-3)
    np.testing.assert_allclose(np.abs(y[-1000:, 1]).max(), w * g0, rtol=1e-3)


def test_bad_filter_parameters():
    with pytest.raises(ParameterError, match="tau_f must be > 0"):
        design_filter_bank("M2", 0.0)
    with pytest.raises(ParameterError, match="method"):
        design_filter_bank("M3", 0.01)
    with pytest.raises(ParameterError, match="sample_period"):
        design_filter_bank("M2", 0.01, -1e-3)
    with pytest.raises(SignalError, match="shape"):
        StreamingFilter(design_filter_bank("M2", 0.01), (2,))(np.zeros(3))


@pytest.fixture(scope="module")
def smooth_record():
    """Noise-free, no Coulomb friction: the equation of motion holds at every sample."""
    sigma = TABLE1_SIGMA.copy()
    sigma[5:] = 0.0
    res = simulate_open_loop(
        table2_torque(1, 4000),
        np.random.default_rng(0),
        sigma0=sigma,
        sensor=CLEAN,
        actuator=ActuatorConfig((70.0, 15.0), quantize=False),
        substeps=4,
    )
    return res, sigma


def test_exact_construction_removes_the_nonlinear_filtering_error(smooth_record):
    res, sigma = smooth_record
    tau = align_torque(res.tau)
    out = {}
    for c in ("paper", "exact"):
        fr = two_link_filtered_regression(res.q_meas, tau, res.qd_meas, construction=c, tau_f=0.006)
        r = fr.y - fr.phi @ sigma
        out[c] = np.sqrt((r[0, 200:] ** 2).mean(axis=0))
    scale = np.sqrt((res.tau**2).mean(axis=(0, 1)))
    assert np.all(out["exact"] < 1e-4 * scale)  # exact up to discretisation
    assert np.all(out["paper"] > 10 * out["exact"])  # the paper's construction is not


def test_unaligned_torque_leaves_a_half_sample_error(smooth_record):
    res, sigma = smooth_record
    fr = two_link_filtered_regression(res.q_meas, res.tau, res.qd_meas, construction="exact", tau_f=0.006)
    r = np.sqrt(((fr.y - fr.phi @ sigma)[0, 200:] ** 2).mean(axis=0))
    assert np.all(r > 1e-3 * np.sqrt((res.tau**2).mean(axis=(0, 1))))


@pytest.mark.parametrize("construction", ["paper", "exact"])
@pytest.mark.parametrize("method", ["M1", "M2"])
def test_online_regressor_equals_record(construction, method):
    res = simulate_open_loop(table2_torque(2, 600), np.random.default_rng(1))
    fr = two_link_filtered_regression(
        res.q_meas, res.tau, res.qd_meas, method=method, construction=construction, tau_f=0.006
    )
    online = OnlineRegressor((2,), method=method, construction=construction, tau_f=0.006)
    phis, ys = zip(
        *(online(res.q_meas[:, k], res.tau[:, k], res.qd_meas[:, k]) for k in range(600)), strict=True
    )
    np.testing.assert_allclose(np.stack(phis, 1), fr.phi, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(np.stack(ys, 1), fr.y, rtol=1e-8, atol=1e-8)


def test_regression_input_errors():
    q = np.zeros((100, 2))
    with pytest.raises(SignalError, match="M2 needs the measured velocity"):
        two_link_filtered_regression(q, q, None, method="M2")
    with pytest.raises(SignalError, match="equal shapes"):
        two_link_filtered_regression(q, q[:50], q)
    with pytest.raises(ParameterError, match="construction"):
        two_link_filtered_regression(q, q, q, construction="magic")


# ------------------------------------------------------------------- the designs kept on disk
def _same_bank(a, b):
    assert (a.method, a.tau_f, a.sample_period) == (b.method, b.tau_f, b.sample_period)
    for k in ("A", "B", "C", "D"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k
    assert len(a.num) == len(b.num) and len(a.den) == len(b.den)
    for x, y in zip(a.num + a.den, b.num + b.den, strict=True):
        assert np.array_equal(x, y)


@pytest.mark.parametrize("method", ["M1", "M2"])
def test_a_design_read_back_from_the_cache_is_the_design_bit_for_bit(method, tmp_path, monkeypatch):
    """The first design writes its file; a later one reads it without python-control (an import of
    ``control`` made to fail), equal to the design to the last bit."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    fresh = filters._design(method, 0.0123, 1e-3)
    first = design_filter_bank(method, 0.0123, 1e-3)
    _same_bank(first, fresh)
    (path,) = (tmp_path / "adaptive_dd" / "filters").glob(f"{method}-*.npz")
    monkeypatch.setitem(sys.modules, "control", None)  # `import control` raises ImportError
    _same_bank(design_filter_bank(method, 0.0123, 1e-3), fresh)
    with pytest.raises(ImportError):
        design_filter_bank(method, 0.0124, 1e-3)  # not in the cache: designed, so control is needed
    assert path.exists()


def test_a_damaged_cache_file_is_designed_again_and_rewritten(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    fresh = design_filter_bank("M2", 0.02, 1e-3)
    (path,) = (tmp_path / "adaptive_dd" / "filters").glob("M2-*.npz")
    for bad in (b"", b"not a zip file", path.read_bytes()[:40]):
        path.write_bytes(bad)
        _same_bank(design_filter_bank("M2", 0.02, 1e-3), fresh)
        _same_bank(filters._read_cached_bank("M2", 0.02, 1e-3), fresh)  # the file written whole again
    # a file whose numbers are not finite is not used
    np.savez(
        path,
        n_out=2,
        A=np.full((2, 2), np.nan),
        B=fresh.B,
        C=fresh.C,
        D=fresh.D,
        num0=fresh.num[0],
        num1=fresh.num[1],
        den0=fresh.den[0],
        den1=fresh.den[1],
    )
    assert filters._read_cached_bank("M2", 0.02, 1e-3) is None
    _same_bank(design_filter_bank("M2", 0.02, 1e-3), fresh)


def test_an_unwritable_cache_folder_leaves_the_design_uncached(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("a file where the cache folder would be")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocked))
    _same_bank(design_filter_bank("M2", 0.03, 1e-3), filters._design("M2", 0.03, 1e-3))
