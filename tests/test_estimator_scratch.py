"""The estimator's model kernels with their scratch given equal the allocating forms bit for bit,
whatever the scratch held before (the closed loop reuses one scratch from sample to sample)."""

from __future__ import annotations

import numpy as np
import pytest

from adaptive_dd.identification.online_control_model import (
    centred_prior,
    centred_prior_in,
    compact_prior,
    compact_prior_in,
)
from adaptive_dd.identification.pseudo_inertia import project_payload, project_payload_in


def _payloads(rng):
    """Consistent and inconsistent payloads, a zero and a negative mass among them."""
    out = [np.zeros(10), np.r_[-0.5, 0.01, 0.0, 0.02, np.zeros(6)]]
    for _ in range(30):
        m = rng.uniform(0.0, 5.0)
        x = np.r_[m, m * rng.normal(0.0, 0.1, 3), rng.normal(0.0, 0.05, 6)]
        out.append(x)
    return out


def _cov(rng):
    a = rng.normal(size=(10, 10))
    return a @ a.T * 1e-3 + np.eye(10) * 1e-4


@pytest.mark.parametrize("fill", [np.nan, 1e300])
def test_priors_and_projection_with_dirty_scratch_equal_the_allocating_forms(fill):
    rng = np.random.default_rng(3)
    for raw in _payloads(rng):
        Pc = _cov(rng)
        for prior, prior_in, arg, scratch in (
            (compact_prior, compact_prior_in, 0.05, (6, 10, 10)),
            (centred_prior, centred_prior_in, 0.1, (4, 4)),
        ):
            want_raw, want_P = raw.copy(), Pc.copy()
            prior(want_raw, want_P, arg)
            got_raw, got_P = raw.copy(), Pc.copy()
            prior_in(got_raw, got_P, arg, *(np.full(k, fill) for k in scratch))
            assert np.array_equal(got_raw, want_raw) and np.array_equal(got_P, want_P), prior.__name__
        for radius in (0.0, 0.1):
            want, got = np.empty(10), np.empty(10)
            project_payload(raw, want, 1e-8, radius)
            project_payload_in(raw, got, 1e-8, radius, np.full((10, 10), fill))
            assert np.array_equal(got, want, equal_nan=True)
