"""The compact payload prior weighed against the estimator's covariance in the units of the
equations' learned noise (``OnlineConfig.prior_noise``): the mechanism on a hand-set state, and
the drawn arm whose loaded segment it brings from 4.4x its floor to within 2x."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.online import (
    OnlineConfig,
    est_init,
    est_payload_trial,
)
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.robots import ROBOTS, robot_urdf

ROOT = Path(__file__).resolve().parents[1]
RHO = 0.05


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def _sphere_inertia(pay, rho):
    m, h = pay[0], pay[1:4]
    full = (h @ h * np.eye(3) - np.outer(h, h)) / m + 0.4 * m * rho**2 * np.eye(3)
    return full[[0, 0, 1, 0, 1, 2], [0, 1, 1, 2, 2, 2]]  # Ixx, Ixy, Iyy, Ixz, Iyz, Izz


def _control_payload(arm, prior_noise, level):
    """The control model's payload of a state whose covariance holds the inertia at 1e-8 kg^2 m^4
    (what the recursive least squares claim after a few hundred samples) while every row has
    learned the noise level ``level`` (None: no level learned yet)."""
    c, s = est_init(OnlineConfig(prior_noise=prior_noise, project=False, prior_radius=RHO), arm, 1)
    c = c._replace(com_size=0.0)  # the compact prior alone (the centred one: tests/test_centred_prior.py)
    raw = payload_parameters(2.5, [0.03, 0.0, 0.08], radius=0.05)
    raw[4:] = [0.05, 0.01, -0.03, 0.005, 0.02, 0.04]  # an inertia no compact 2.5 kg body has
    s.theta[0] = raw
    s.P[0] = np.diag(np.r_[np.full(4, 1e-6), np.full(6, 1e-8)])
    if level is not None:
        s.learned[0, :] = 100_000
        s.long[0, :] = level
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)
    return raw, pay


def test_the_prior_weighs_against_the_covariance_scaled_by_the_learned_noise(ur5):
    raw, off = _control_payload(ur5, 0.0, 1e6)
    sphere = _sphere_inertia(raw, RHO)
    assert np.allclose(off, raw, rtol=0, atol=2e-3)  # unscaled, the covariance claims the inertia known
    _, noisy = _control_payload(ur5, 10.0, 1e6)  # rows 1e6 times noisier than the RLS assume
    assert np.array_equal(noisy[:4], raw[:4])  # the mass and first moments are the data's
    assert np.allclose(noisy[4:], sphere, rtol=0, atol=2e-4), (noisy[4:], sphere)
    _, quiet = _control_payload(ur5, 10.0, 1e-6)  # quiet rows: the data are believed
    assert np.allclose(quiet, raw, rtol=0, atol=1e-4)
    _, none = _control_payload(ur5, 10.0, None)  # no level learned: the covariance times prior_noise
    assert np.allclose(none, raw, rtol=0, atol=2e-3)


def test_the_default_is_the_filters_memory_and_a_bad_value_is_refused():
    assert OnlineConfig().prior_noise == pytest.approx(10.0)  # tau_f 10 ms at 1 kHz
    assert OnlineConfig(tau_f=0.02, sample_period=0.002).prior_noise == pytest.approx(10.0)
    assert OnlineConfig(tau_f=0.03).prior_noise == pytest.approx(30.0)
    assert OnlineConfig(prior_noise=None).prior_noise == 0.0
    assert OnlineConfig(arm_uncertainty={}).prior_noise == 0.0  # mode "arm": no compact prior
    for bad in (-1.0, float("nan"), float("inf"), "10"):
        with pytest.raises(ParameterError, match="prior_noise"):
            OnlineConfig(prior_noise=bad)


@pytest.mark.slow
def test_a_drawn_arms_loaded_segment_near_its_floor_and_not_without():
    """random:14 (5 joints), seed 2 of the population template, its 30 % segment (2.24 kg): with
    the compact prior off it is 1.85x its floor, with the default 1.12x. (The trial this test first
    held, random:19 seed 2, no longer needs the prior since the centred prior: 1.04x either way.)"""
    from adaptive_dd.benchmark.population import population_scenario
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import read_toml
    from adaptive_dd.benchmark.scenario_settings import with_settings

    tpl = ROOT / "benchmarks" / "scenarios" / "population.toml"
    sc = population_scenario(read_toml(tpl), str(tpl), 14)
    sc = dataclasses.replace(sc, seeds=3, controllers=("ct_oracle", "adaptive_ct"))
    ratio = {}
    for noise in ("auto", 0.0):
        s = with_settings(sc, "adaptive_ct", {"estimator": {"prior_noise": noise}})
        f = run_benchmark(s, progress=False, seed_indices=[2], keep_trajectories=0).to_frame()
        row = f[(f.controller == "adaptive_ct") & (f.segment == 2)]
        ratio[noise] = float(row.ratio_to_floor.iloc[0])
    assert ratio["auto"] < 1.3 < 1.6 < ratio[0.0], ratio
