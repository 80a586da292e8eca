"""The compact prior reads the inertia's covariance given the mass and first moments
(:func:`~adaptive_dd.identification.online_control_model._inertia_cov`): the Schur complement of
the payload covariance, held to numpy's on random covariances, and on a planar arm's confound
(mass, first moment along the link and inertia known only together) it leaves the inertia where
the data put it."""

from __future__ import annotations

import numpy as np

from adaptive_dd.identification.online_control_model import _condition_inertia, compact_prior


def _schur(C: np.ndarray) -> np.ndarray:
    h, i = slice(0, 4), slice(4, 10)
    return C[i, i] - C[i, h] @ np.linalg.solve(C[h, h], C[h, i])


def test_the_inertia_block_is_the_covariance_given_the_mass_and_first_moments():
    rng = np.random.default_rng(3)
    for _ in range(5):
        A = rng.normal(size=(10, 10)) * np.logspace(0, -3, 10)
        C = A @ A.T + 1e-6 * np.eye(10)
        out = C.copy()
        _condition_inertia(out)
        np.testing.assert_allclose(out[4:, 4:], _schur(C), rtol=1e-9, atol=1e-15)
        np.testing.assert_array_equal(out[:4], C[:4])  # the rest as it was


def test_a_mass_and_first_moments_without_variance_condition_nothing():
    C = np.diag(np.r_[np.zeros(4), np.full(6, 0.01)])
    C[0, 4] = C[4, 0] = 0.0
    out = C.copy()
    _condition_inertia(out)
    np.testing.assert_array_equal(out, C)


def test_an_inertia_known_only_with_the_mass_stays_on_the_data():
    """Izz (index 9) and the mass known only through ``Izz + 0.04 m`` (a tip 0.2 m out): a mass
    estimate 1 kg low puts Izz 0.04 kg m^2 high, and the prior, given the mass, keeps the sum."""
    P = np.diag(np.r_[9.0, np.full(3, 1e-8), np.full(6, 1e-2)])
    a = np.zeros(10)
    a[0], a[9] = 0.04, 1.0  # the one combination the data measure, to 1e-8
    S = a @ P @ a + 1e-8
    P = P - np.outer(P @ a, P @ a) / S
    raw = np.zeros(10)
    raw[0], raw[9] = 2.0, 0.04 + 0.0015  # the truth 3 kg and Izz 0.0015: 0.04 m + Izz agrees
    given = P.copy()
    _condition_inertia(given)
    kept = raw.copy()
    compact_prior(kept, given, 0.05)
    np.testing.assert_allclose(0.04 * kept[0] + kept[9], 0.04 * raw[0] + raw[9], rtol=1e-3)
    marginal = raw.copy()
    compact_prior(marginal, P.copy(), 0.05)  # the marginal covariance: the prior moves Izz off it
    assert abs(0.04 * marginal[0] + marginal[9] - (0.04 * raw[0] + raw[9])) > 0.01
