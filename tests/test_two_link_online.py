"""The online estimator's pure step: agreement with the numpy pipeline, stepping vs whole
record, detection of a swap, no alarm without one, a correct start kept, bad settings."""

import dataclasses

import numpy as np
import pytest

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.experiments import table2_torque, trial_rngs
from adaptive_dd.identification.estimators import SplitRLS
from adaptive_dd.identification.regressors import OnlineRegressor
from adaptive_dd.identification.rls import RLSConfig
from adaptive_dd.identification.two_link_online import (
    ChangeDetector,
    OnlineEstimator,
    TwoLinkOnlineConfig,
    online_init,
    online_step,
    run_two_link_online,
)
from adaptive_dd.plant import TABLE1_SIGMA, PayloadSchedule, payload_mass_from_sigma, simulate_open_loop


@pytest.fixture(scope="module")
def swap_record():
    """Table 2 torques, 2 trials, 8 s, a 3 kg disk from 4 s on."""
    sched = PayloadSchedule(times=(4.0,), masses=(3.0,))
    return simulate_open_loop(table2_torque(2, 8000), trial_rngs(5, 2), payload=sched)


def _reference(r, cfg, n):
    """The same estimator from the numpy pieces: streaming regression + SplitRLS."""
    reg = OnlineRegressor((2,), construction=cfg.construction, tau_f=cfg.tau_f)
    rls = SplitRLS(cfg.split, cfg.rls, (2,), TABLE1_SIGMA)
    since = np.zeros((2, 2), dtype=int)
    mem = cfg.samples(cfg.selection[1]) if cfg.selection else 0
    out, prev = np.empty((2, n, 7)), None
    for k in range(n):
        tau = r.tau[:, k]
        t_used = 0.5 * (tau + (tau if prev is None else prev)) if cfg.align else tau
        prev = tau
        phi, y = reg(r.q_meas[:, k], t_used, r.qd_meas[:, k])
        act = None
        if cfg.selection:
            since = np.where(np.abs(r.qd_meas[:, k]) <= cfg.selection[0], 0, since + 1)
            act = since > mem
        out[:, k] = rls.step(phi, y, act)
    return out


@pytest.mark.parametrize("split", ["full", "15", "16"])
@pytest.mark.parametrize("construction", ["exact", "paper"])
def test_compiled_step_equals_the_numpy_pipeline(swap_record, split, construction):
    n = 2500
    cfg = TwoLinkOnlineConfig(
        construction=construction,
        split=split,
        rls=RLSConfig(lam0=0.999, mu=0.001, p0=1.0),
        p0_payload=0.0,
        p0_j2=0.0,
        align=construction == "exact",
        selection=(0.05, 6.0) if construction == "exact" else None,
        detector=None,
        project="none",
    )
    rec = run_two_link_online(
        swap_record.q_meas[:, :n], swap_record.qd_meas[:, :n], swap_record.tau[:, :n], cfg, TABLE1_SIGMA
    )
    np.testing.assert_allclose(rec.theta, _reference(swap_record, cfg, n), rtol=1e-9, atol=1e-10)


def test_stepping_equals_the_whole_record_alarms_included(swap_record):
    r, n = swap_record, 5000
    cfg = TwoLinkOnlineConfig()
    rec = run_two_link_online(r.q_meas[:, :n], r.qd_meas[:, :n], r.tau[:, :n], cfg, TABLE1_SIGMA)
    state = online_init(cfg, 2, TABLE1_SIGMA)
    alarms = []
    for k in range(n):
        before = state.theta.copy()
        state, info = online_step(state, r.q_meas[:, k], r.qd_meas[:, k], r.tau[:, k], cfg)
        np.testing.assert_array_equal(state.theta, rec.theta[:, k])
        np.testing.assert_array_equal(state.sigma_model, rec.sigma_model[:, k])
        alarms.append(info.alarm)
        assert before is not state.theta  # pure: a new state
    np.testing.assert_array_equal(np.stack(alarms, 1), rec.alarm)
    assert rec.alarm.any()
    est = OnlineEstimator(cfg, 2, TABLE1_SIGMA)
    for k in range(n):
        est.update(r.q_meas[:, k], r.qd_meas[:, k], r.tau[:, k])
    np.testing.assert_array_equal(est.theta, rec.theta[:, -1])
    assert est.alarm_times == rec.alarm_times()


@pytest.mark.parametrize("split", ["full", "15", "16"])
def test_a_swap_is_detected_once_and_the_mass_follows_on_every_split(swap_record, split):
    r = swap_record
    cfg = TwoLinkOnlineConfig(split=split)
    rec = run_two_link_online(r.q_meas, r.qd_meas, r.tau, cfg, TABLE1_SIGMA)
    for times in rec.alarm_times():
        assert len(times) == 1 and 4.0 < times[0] < 4.15, times
    m = payload_mass_from_sigma(rec.sigma_model[:, [3999, -1]])
    np.testing.assert_allclose(m[:, 0], 0.0, atol=0.05 if split == "full" else 0.15)
    np.testing.assert_allclose(m[:, 1], 3.0, rtol=0.05 if split == "full" else 0.15)


def test_no_alarm_on_a_constant_payload_over_a_long_run():
    r = simulate_open_loop(table2_torque(3, 30_000), trial_rngs(11, 3))
    rec = run_two_link_online(r.q_meas, r.qd_meas, r.tau, TwoLinkOnlineConfig(), TABLE1_SIGMA)
    assert not rec.alarm.any()


def test_a_correct_start_is_not_degraded():
    """Started at the true model, the model for control stays within 1 % once the first
    0.5 s of data are in (before that the prior allows an unknown tip mass: within 10 %)."""
    r = simulate_open_loop(table2_torque(2, 6000), trial_rngs(2, 2))
    rec = run_two_link_online(r.q_meas, r.qd_meas, r.tau, TwoLinkOnlineConfig(), TABLE1_SIGMA)
    rel = np.abs(rec.sigma_model[..., :3] / TABLE1_SIGMA[:3] - 1)
    assert rel[:, 500:].max() < 0.01 and rel.max() < 0.1
    # the paper's isotropic large start throws the correct model away at once
    bad = dataclasses.replace(
        TwoLinkOnlineConfig(), rls=RLSConfig(lam0=0.99, mu=0.002, p0=100.0), p0_payload=0.0
    )
    rec_bad = run_two_link_online(r.q_meas, r.qd_meas, r.tau, bad, TABLE1_SIGMA)
    assert np.abs(rec_bad.sigma_model[:, 500:, :3] / TABLE1_SIGMA[:3] - 1).max() > 0.1


def test_a_dropout_is_skipped_and_counted_not_spread(swap_record):
    r = swap_record
    q, qd = r.q_meas.copy(), r.qd_meas.copy()
    q[0, 2000, 1] = np.nan
    qd[1, 3000, 0] = np.inf
    rec = run_two_link_online(q, qd, r.tau, TwoLinkOnlineConfig(), TABLE1_SIGMA)
    assert np.all(np.isfinite(rec.theta)) and np.all(np.isfinite(rec.sigma_model))
    assert np.all(rec.n_skipped > 0)
    clean = run_two_link_online(r.q_meas, r.qd_meas, r.tau, TwoLinkOnlineConfig(), TABLE1_SIGMA)
    np.testing.assert_allclose(rec.sigma_model[:, -1], clean.sigma_model[:, -1], rtol=0.01)


def test_projection_applies_to_the_control_model_only(swap_record):
    r, n = swap_record, 3000
    wild = TABLE1_SIGMA * np.array([0.01, 1, 5, 1, 1, 1, 1])  # J1 J2 < r^2: not a valid model
    rec = run_two_link_online(r.q_meas[:, :n], r.qd_meas[:, :n], r.tau[:, :n], TwoLinkOnlineConfig(), wild)
    m = rec.sigma_model
    assert np.all(m[..., 0] * m[..., 1] > m[..., 2] ** 2)
    assert np.any(rec.theta[..., 0] * rec.theta[..., 1] <= rec.theta[..., 2] ** 2)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"split": "17"}, "split"),
        ({"construction": "magic"}, "construction"),
        ({"tau_f": 1e-5}, "tau_f"),
        ({"tau_f": float("nan")}, "tau_f"),
        ({"project": "yes"}, "project"),
        ({"selection": (0.05,)}, "selection"),
        ({"p0_payload": -1.0}, "p0_payload"),
        ({"payload_direction": (1.0, 0, 0, 1.0, 0, 0, 0)}, "payload_direction"),
    ],
)
def test_bad_online_settings_are_named(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        TwoLinkOnlineConfig(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"threshold": float("nan")}, "threshold"),
        ({"threshold": 0.5}, "threshold"),
        ({"short_window": 2.0}, "short_window"),
        ({"min_learned": 0}, "min_learned"),
        ({"p_mass": 0.0}, "p_mass"),
        ({"holdoff": -1.0}, "holdoff"),
        ({"reopen_again": "yes"}, "reopen_again"),
    ],
)
def test_bad_detector_settings_are_named(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        ChangeDetector(**kwargs)


def test_wrong_shapes_are_rejected():
    st = online_init(TwoLinkOnlineConfig(), 2, TABLE1_SIGMA)
    with pytest.raises(SignalError, match="q must have shape"):
        online_step(st, np.zeros((3, 2)), np.zeros((2, 2)), np.zeros((2, 2)), TwoLinkOnlineConfig())
    with pytest.raises(SignalError, match="share a shape"):
        run_two_link_online(
            np.zeros((1, 5, 2)), np.zeros((1, 4, 2)), np.zeros((1, 5, 2)), TwoLinkOnlineConfig(), TABLE1_SIGMA
        )


def test_identify_online_on_a_recorded_csv(tmp_path, swap_record):
    """The same estimator over a CSV: estimates and alarms over time as CSV and a figure."""
    import csv

    from adaptive_dd.cli import main
    from adaptive_dd.io import write_recording

    r = swap_record
    path = tmp_path / "rec.csv"
    write_recording(path, r.t, r.q_meas[0], r.qd_meas[0], r.tau[0])
    assert main(["identify", str(path), "--online", "--tau-f", "0.01", "--out", str(tmp_path / "o")]) == 0
    rows = list(csv.DictReader((tmp_path / "o" / "online.csv").open()))
    assert len(rows) == r.t.size
    alarms = [float(x["t"]) for x in rows if x["alarm"] == "1"]
    assert len(alarms) == 1 and 4.0 < alarms[0] < 4.15
    assert abs(float(rows[-1]["payload_mass"]) - 3.0) < 0.15
    assert (tmp_path / "o" / "online.png").stat().st_size > 10_000


def test_a_small_min_learned_does_not_divide_by_zero():
    """``min_learned`` below 8 (validated from 1) made the relearning weight 0 / 0 at no learned
    sample (a ZeroDivisionError in the compiled kernel) while one joint stood still."""
    from adaptive_dd.plant import ClosedFormTwoLink

    t = np.arange(1500) * 1e-3
    drive = np.stack([0 * t, 1.5 * np.cos(6 * np.pi * t)], axis=-1)[None]  # joint 1 held by friction
    sim = simulate_open_loop(drive, np.random.default_rng(0))
    for ml in (200, 5):
        cfg = TwoLinkOnlineConfig(sample_period=1e-3, detector=ChangeDetector(min_learned=ml))
        rec = run_two_link_online(sim.q_meas, sim.qd_meas, sim.tau, cfg, ClosedFormTwoLink.sice().sigma)
        assert rec.alarm_times() == [[]] and np.all(np.isfinite(rec.theta))
