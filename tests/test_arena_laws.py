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
NEW += ["slotine_li", "composite", "slotine_li_oracle", "ct_oracle"]
NEW += ["icl", "natural_adaptive", "craig_hsu_sastry", "ct_oracle_textbook"]


def _vertical3(duration: float, swap: float, controllers: list, seeds: int = 2):
    src = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload.toml")
    data = tomllib.loads(src.read_text(encoding="utf-8"))
    data["run"] = {**data["run"], "duration": duration, "seeds": seeds, "controllers": controllers}
    data["payload"] = [{**data["payload"][0], "at": swap}]
    data["controllers"] = {}
    return parse_scenario(data, "test.toml", name="vertical3_payload")


@pytest.fixture(scope="module")
def vertical3_run():
    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.closed_loop.types import run_constants

    sc = _vertical3(2.0, 1.2, NEW)  # the shipped 1 s ramp, then 0.8 s with the 1 kg payload
    res = run_closed_loop(sc)
    seg = np.diff(np.r_[run_constants(sc).seg_start, sc.n_samples])
    return {n: (r, np.sqrt(r.acc.sum_e2 / seg)) for n, r in res.runs.items()}


@pytest.mark.slow  # the closed loop of every arena law on a drawn arm: minutes of compiling, cold
def test_every_arena_law_runs_on_a_drawn_arm_without_failure_or_nan(vertical3_run):
    assert set(ARENA_CONTROLLERS) <= set(vertical3_run)
    for name, (run, rms) in vertical3_run.items():
        assert not run.failed.any(), name
        assert np.all(np.isfinite(rms)) and np.all(rms > 0), (name, rms)


@pytest.mark.slow  # the closed loop of every arena law on a drawn arm: minutes of compiling, cold
def test_gravity_compensation_the_observer_the_robust_term_and_composite_each_help(vertical3_run):
    """On the drawn vertical3 (2 seeds; 1 kg from 1.2 s): each law's added term does what it is for."""
    rms = {n: r for n, (_, r) in vertical3_run.items()}
    # vertical3 lifts every link: gravity compensation beats plain PD, with or without payload
    assert np.all(rms["pd_gravity"] < 0.7 * rms["pd"]), rms
    loaded = {n: r[:, 1] for n, r in rms.items()}
    # the observer feeds back the torque the nominal model lacks (the payload's, the drawn arm's)
    assert np.all(rms["momentum_observer_ct"] < 0.8 * rms["ct_nominal"]), rms
    assert np.all(loaded["momentum_observer_ct"] < 0.2 * loaded["ct_nominal"]), loaded
    # the robust term bounds the payload's torque
    assert np.all(loaded["sliding_mode"] < 0.6 * loaded["ct_nominal"]), loaded
    # the prediction-error term learns the payload faster than the tracking error alone
    assert np.all(loaded["composite"] < loaded["slotine_li"]), loaded


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


def test_composite_prediction_error_vanishes_at_the_true_payload(rng):
    """The composite term's filtered torque and regressor agree (momentum form, no acceleration):
    on a smooth motion of the loaded arm its prediction error ``eps = F tau_r - W theta`` is about
    zero at the true payload and about ``W theta_true`` at none."""
    from adaptive_dd.closed_loop.arena_laws import Composite
    from adaptive_dd.closed_loop.composite import C_TF, C_W, composite_term
    from adaptive_dd.closed_loop.laws import OBS_ROWS, law_work
    from adaptive_dd.closed_loop.residual_observer import O_COUNT, O_TAU
    from adaptive_dd.plant.chain_batch import rnea_batch
    from adaptive_dd.plant.payload import payload_parameters

    arm = _arm()
    n, j, T = arm.n_joints, arm.payload_joint, 1e-3
    cfg = Composite(arm).law_config(T)
    theta = payload_parameters(1.0, [0.03, 0.0, 0.02], radius=0.05)
    pi = arm.pi.copy()
    pi[10 * j : 10 * j + 10] += arm.payload_map @ theta
    w, ph, amp = rng.uniform(1, 3, n), rng.uniform(0, 6, n), rng.uniform(0.2, 0.5, n)

    def motion(t):
        x = w * t + ph
        return arm_q0 + amp * np.sin(x), amp * w * np.cos(x), -amp * w * w * np.sin(x)

    def torque(t):
        q, qd, qdd = motion(t)
        tau = rnea_batch(arm.chain, pi[: 10 * n], q[None], qd[None], qdd[None])[0]
        return tau + arm.viscous * qd + arm.coulomb * np.sign(qd) + arm.armature * qdd

    arm_q0 = np.mean(arm.position_limits, axis=1)
    obs, work, gx = np.zeros((OBS_ROWS, n)), law_work(n), np.zeros(10)
    for k in range(600):
        t = k * T
        if k > 0:  # the mean torque over the sample before (Simpson), as the closed loop sums it
            obs[O_TAU] = (torque(t - T) + 4 * torque(t - T / 2) + torque(t)) / 6
            obs[O_COUNT, 1] = 1.0
        q, qd, _ = motion(t)
        composite_term(arm.chain, cfg, q, qd, theta, obs, work, gx)
    W = obs[C_W : C_W + 10].T  # (n, 10)
    tf = obs[C_TF]
    assert np.linalg.norm(W @ theta) > 0.1  # the payload's torque, filtered: well above rounding
    assert np.linalg.norm(tf - W @ theta) < 2e-3 * np.linalg.norm(tf)
    assert np.all(np.isfinite(gx)) and np.linalg.norm(gx) < 1e-2 * np.linalg.norm(
        W.T @ (cfg.comp_weight * tf)
    )


@pytest.mark.slow  # the closed loop of every arena law on a drawn arm: minutes of compiling, cold
def test_compiled_and_python_paths_agree_for_the_laws_that_read_the_applied_torque():
    """The observer's and the composite term's applied torque reaches them on both paths alike (a
    dropout holds a measurement: the held-sample rule too)."""
    import dataclasses

    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.controllers import gains_for

    names = ["momentum_observer_ct", "composite", "sliding_mode"]
    sc = dataclasses.replace(_vertical3(1.0, 0.6, names, seeds=1), dropout=0.002)
    arm = sc.arm

    def ctrls():
        g = gains_for(arm, sc.bandwidth, sc.damping)
        return {n: make_controller(n, g, arm=arm) for n in names}

    comp = run_closed_loop(sc, ctrls(), engine="compiled")
    py = run_closed_loop(sc, ctrls(), engine="python")
    for n in names:
        a, b = comp.runs[n], py.runs[n]
        assert a.engine.startswith("compiled") and b.engine.startswith("python")
        np.testing.assert_allclose(a.acc.sum_e2, b.acc.sum_e2, rtol=1e-12)
        np.testing.assert_allclose(a.q, b.q, rtol=1e-12, atol=1e-13)
        assert a.dropped.sum() > 0
