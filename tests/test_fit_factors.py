"""The weighted least squares on per-channel triangular factors and the single-output filtering
give the numbers of the direct computations they replace."""

import numpy as np

from adaptive_dd.identification.filters import design_filter_bank, filter_record
from adaptive_dd.identification.log_fit import _channel_factors, _solve


def _tall_qr_solve(phi, y, w):
    """The weighted least squares by a QR of the tall weighted regressor (the direct way)."""
    r = phi.shape[-1]
    A = (phi * w[None, :, None]).reshape(-1, r)
    scale = np.linalg.norm(A, axis=0)
    R = np.linalg.qr(np.column_stack([A / scale, (y * w).reshape(-1)]), mode="r")
    sol, *_ = np.linalg.lstsq(R[:r, :r], R[:r, r], rcond=A.shape[0] * np.finfo(float).eps)
    return sol / scale, scale


def test_channel_factored_solve_matches_the_tall_qr():
    rng = np.random.default_rng(3)
    N, m, r = 400, 3, 7
    # columns of very different sizes and two nearly collinear ones, as a base regressor has
    phi = rng.standard_normal((N, m, r)) * np.logspace(-4, 3, r)
    phi[..., 5] = phi[..., 4] * 1e-3 * 1.0001 + 1e-9 * rng.standard_normal((N, m))
    y = phi @ rng.standard_normal(r) + 0.1 * rng.standard_normal((N, m))
    factors = _channel_factors(phi, y)
    for w in (np.ones(m), np.array([3.0, 0.2, 11.0])):
        x_ref, s_ref = _tall_qr_solve(phi, y, w)
        x, s = _solve(phi, y, w, factors)
        np.testing.assert_allclose(s, s_ref, rtol=1e-12)
        # the same fit: the same weighted residual norm (the minimum) and residuals (the estimate
        # along the near-collinear pair is fixed only to the conditioning, about 1e10)
        res, res_ref = (y - phi @ x) * w, (y - phi @ x_ref) * w
        np.testing.assert_allclose(np.linalg.norm(res), np.linalg.norm(res_ref), rtol=1e-10)
        np.testing.assert_allclose(res, res_ref, rtol=0, atol=1e-6 * np.abs(res_ref).max())
        np.testing.assert_allclose(x[[0, 1, 2, 3, 6]], x_ref[[0, 1, 2, 3, 6]], rtol=1e-7)
    # a wrong weight changes the estimate: the factors do carry the weighting
    x1, _ = _solve(phi, y, np.ones(m), factors)
    x2, _ = _solve(phi, y, np.array([1.0, 1.0, 100.0]), factors)
    assert np.max(np.abs(x1 - x2)) > 1e-6


def test_filter_record_outputs_are_the_banks_columns():
    rng = np.random.default_rng(4)
    bank = design_filter_bank("M2", 0.02, 1e-3)
    u = rng.standard_normal((500, 3, 2))
    full = filter_record(bank, u, axis=0, initial=u[0])
    for k in range(len(bank.num)):
        one = filter_record(bank, u, axis=0, initial=u[0], outputs=(k,))
        assert one.shape == (*u.shape, 1)
        np.testing.assert_array_equal(one[..., 0], full[..., k])
    both = filter_record(bank, u, axis=0, outputs=(1, 0))
    np.testing.assert_array_equal(both, filter_record(bank, u, axis=0)[..., [1, 0]])
