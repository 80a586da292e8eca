"""The arena's N-joint laws (adaptive_dd.closed_loop.arena_laws): each runs in the compiled loop
on a shipped drawn arm without a failure or a NaN, does what its equation says, and is refused on
the two-link closed-form runtime with the route that works."""

from __future__ import annotations

import tomllib
from importlib import resources

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.closed_loop.arena_laws import (
    ARENA_CONTROLLERS,
    SlidingMode,
    parameter_error_bound,
    payload_bound,
)
from adaptive_dd.closed_loop.laws import LawState, law_batch
from adaptive_dd.controllers import make_controller
from adaptive_dd.errors import ParameterError

NEW = ["pd", "pd_gravity", "pd_gravity_oracle", "ct_nominal", "momentum_observer_ct", "sliding_mode"]
NEW += ["slotine_li_oracle", "ct_oracle"]


def _vertical3(duration: float, swap: float, controllers: list, seeds: int = 2):
    src = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload.toml")
    data = tomllib.loads(src.read_text(encoding="utf-8"))
    data["run"] = {**data["run"], "duration": duration, "seeds": seeds, "controllers": controllers}
    data["payload"] = [{**data["payload"][0], "at": swap}]
    data["reference"]["ramp"] = 0.2
    data["controllers"] = {}
    return parse_scenario(data, "test.toml", name="vertical3_payload")


@pytest.fixture(scope="module")
def vertical3_run():
    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.closed_loop.types import run_constants

    sc = _vertical3(1.6, 0.8, NEW)
    res = run_closed_loop(sc)
    seg = np.diff(np.r_[run_constants(sc).seg_start, sc.n_samples])
    return {n: (r, np.sqrt(r.acc.sum_e2 / seg)) for n, r in res.runs.items()}


def test_every_arena_law_runs_on_a_drawn_arm_without_failure_or_nan(vertical3_run):
    assert set(ARENA_CONTROLLERS) <= set(vertical3_run)
    for name, (run, rms) in vertical3_run.items():
        assert not run.failed.any(), name
        assert np.all(np.isfinite(rms)) and np.all(rms > 0), (name, rms)


def test_gravity_compensation_and_the_observer_and_the_robust_term_each_help(vertical3_run):
    rms = {n: r for n, (_, r) in vertical3_run.items()}
    # vertical3 lifts every link: gravity compensation beats plain PD, with or without payload
    assert np.all(rms["pd_gravity"] < 0.7 * rms["pd"]), rms
    # the oracle's gravity includes the 1 kg payload: better than the nominal's in the loaded segment
    assert np.all(rms["pd_gravity_oracle"][:, 1] < rms["pd_gravity"][:, 1]), rms
    # the observer feeds back the payload's torque the nominal model lacks; the robust term bounds it
    assert np.all(rms["momentum_observer_ct"][:, 1] < 0.7 * rms["ct_nominal"][:, 1]), rms
    assert np.all(rms["sliding_mode"][:, 1] < 0.7 * rms["ct_nominal"][:, 1]), rms


def _arm():
    return _vertical3(1.0, 0.5, ["pd"]).arm


def test_sliding_term_is_the_clipped_boundary_layer_of_the_regressor_bound(rng):
    """The kernel's robust term against a second writing in numpy: ``clip(lam M0_jj s, +-rho)``,
    ``rho = |Y| dpi + |Y_j P| dtheta + friction``, Y from the batch Slotine-Li regressor."""
    from adaptive_dd.plant.chain_batch import slotine_li_regressor_batch

    arm = _arm()
    n = arm.n_joints
    law = SlidingMode(arm, 30.0, 1.2, uncertainty={"mass": 0.1, "com": 0.01, "inertia": 0.2, "viscous": 0.5})
    cfg = law.law_config(1e-3)
    plain = cfg._replace(robust=False)
    q, qd = rng.uniform(-1, 1, (3, n)), rng.uniform(-1, 1, (3, n))
    q_d, qd_d, qdd_d = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
    diff = law_batch(law.ch, cfg, LawState.start(cfg, 3), q, qd, q_d, qd_d, qdd_d)
    diff -= law_batch(law.ch, plain, LawState.start(plain, 3), q, qd, q_d, qd_d, qdd_d)
    lam = cfg.lam
    e, ed = q_d - q, qd_d - qd
    qdr, a = qd_d + lam * e, qdd_d + lam * ed
    Y = slotine_li_regressor_batch(arm.chain, q, qd, qdr, np.broadcast_to(a, q.shape))
    d = cfg.rho_pi
    rho = np.abs(Y) @ d[: 10 * n] + np.abs(qdr) * d[10 * n : 11 * n] + d[11 * n : 12 * n]
    rho += np.abs(a) * d[12 * n :]
    j = arm.payload_joint
    rho += np.abs(Y[:, :, 10 * j : 10 * j + 10] @ arm.payload_map) @ cfg.rho_payload
    m0 = np.stack([np.diag(arm.mass_matrix(x, arm.sigma)) for x in q]) + arm.armature
    want = np.clip(m0 * lam * (ed + lam * e), -rho, rho)
    np.testing.assert_allclose(diff, want, rtol=1e-9, atol=1e-9)
    assert np.all(np.abs(want) > 0) and np.any(np.abs(want) == rho)  # both sides of the layer seen


def test_parameter_error_bound_of_the_stated_levels():
    arm = _arm()
    n = arm.n_joints
    assert np.all(parameter_error_bound(arm, None) == 0.0)
    b = parameter_error_bound(arm, {"mass": 0.1})
    masses = arm.pi[0 : 10 * n : 10]
    np.testing.assert_allclose(b[0 : 10 * n : 10], 0.1 * masses, rtol=1e-6)
    normal = parameter_error_bound(arm, {"mass": 0.1, "distribution": "normal"})
    np.testing.assert_allclose(normal, 3.0 * b, rtol=1e-9)
    np.testing.assert_allclose(payload_bound(2.0, 0.1)[:4], [2.0, 0.2, 0.2, 0.2])


@pytest.mark.parametrize("name", sorted(ARENA_CONTROLLERS))
def test_two_link_runtime_refuses_with_the_route_that_works(name):
    with pytest.raises(ParameterError, match=r"N-joint arms only.*sice_drawn\.toml"):
        make_controller(name)


def test_sliding_mode_bad_settings_name_the_key():
    with pytest.raises(ParameterError, match=r"sliding_mode\.max_mass"):
        SlidingMode(_arm(), max_mass=-1.0)
    with pytest.raises(ParameterError, match=r"sliding_mode\.uncertainty"):
        SlidingMode(_arm(), uncertainty={"mass": 2.0})
