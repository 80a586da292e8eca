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


@pytest.mark.parametrize("fill", [np.nan, 1e300])
def test_the_steps_kernels_with_dirty_scratch_equal_the_allocating_forms(fill):
    """The estimator's step is compiled without reference counting (it may allocate nothing): the
    eigen-decomposition, the ball's bound and the re-opening take their scratch; with it dirty
    they give the allocating forms' numbers to the bit, and the eigen-decomposition numpy's."""
    from adaptive_dd.identification.pseudo_inertia import (
        _bound_ball,
        _bound_ball_in,
        _eigh4,
        _eigh4_in,
        pseudo_inertia,
    )

    rng = np.random.default_rng(5)
    for raw in _payloads(rng):
        J = np.zeros((4, 4))
        pseudo_inertia(raw, J)
        lam, V = _eigh4(J)
        lam2, V2, A = np.full(4, fill), np.full((4, 4), fill), np.full((4, 4), fill)
        _eigh4_in(J, A, V2, lam2)
        assert np.array_equal(lam, lam2) and np.array_equal(V, V2)
        np.testing.assert_allclose(np.sort(lam), np.linalg.eigvalsh(J), atol=1e-12 * max(1.0, abs(J).max()))
        np.testing.assert_allclose(V @ np.diag(lam) @ V.T, J, atol=1e-12 * max(1.0, abs(J).max()))
        for radius in (0.02, 0.1):
            want, got = raw.copy(), raw.copy()
            _bound_ball(want, radius)
            _bound_ball_in(got, radius, np.full((3, 3), fill), np.full(3, fill))
            assert np.array_equal(got, want, equal_nan=True)


@pytest.mark.parametrize("fill", [np.nan, 1e300])
def test_the_reopening_and_the_alarm_with_dirty_scratch_equal_the_allocating_forms(fill):
    from adaptive_dd.identification import online
    from adaptive_dd.identification import online_kernel as K
    from adaptive_dd.identification.arm_prior import ArmUncertainty
    from adaptive_dd.identification.online_detector import _alarm_in, _reopen_in
    from adaptive_dd.identification.online_slots import est_work
    from adaptive_dd.plant.arm import Arm
    from adaptive_dd.robots import ROBOTS, robot_urdf

    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    rng = np.random.default_rng(6)
    for mode in ("payload", "arm"):
        kw = {} if mode == "payload" else {"arm_uncertainty": ArmUncertainty()}
        c, s = online.est_init(online.OnlineConfig(**kw), arm, 2)
        p = s.theta.shape[1]
        a = rng.normal(size=(p, p))
        s.P[:] = a @ a.T * 1e-2 + np.eye(p)
        s.theta[:] = rng.normal(size=p) * 0.1
        for arr in (s.long, s.plong, s.nlong):
            arr[:] = rng.uniform(0.1, 1.0, size=arr.shape)
        s.learned[:], s.seen[:] = 500, 500
        want = s.P[0].copy()
        K._reopen(c, s.P[0])
        w = est_work(c.w.shape[0], p)
        for arr in (w.rq, w.rs, w.raw, w.Pc, w.pphi, w.row, w.d, w.cov):
            arr[:] = fill
        _reopen_in(c, want, w.rq, w.rs)
        assert np.array_equal(want, s.P[0]), mode
        for x in s:  # trial 1 the same as trial 0
            x[1] = x[0]
        K._alarm(c, s, 0, 100)  # trial 0 the allocating form, trial 1 the scratch's
        _alarm_in(c, s, 1, 100, w)
        for name, x in zip(s._fields, s, strict=True):
            assert np.array_equal(x[0], x[1], equal_nan=True), (mode, name)
