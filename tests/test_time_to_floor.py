"""The first segment's time to come within 1.2x of the floor (adaptive_dd.benchmark.time_to_floor)."""

import dataclasses
import json
import math

import numpy as np
import pytest

from adaptive_dd.benchmark.metrics import compute_metrics
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.benchmark.time_to_floor import LEVEL, WINDOW, quantile_never, time_to_floor


def _direct(e, ef, T, window=WINDOW, level=LEVEL):
    """The definition written out sample by sample: the end of the last window above level."""
    n = round(window / T)
    last = -1
    for k in range(e.size):
        lo = max(0, k + 1 - n)
        a, b = np.sqrt(np.mean(e[lo : k + 1] ** 2)), np.sqrt(np.mean(ef[lo : k + 1] ** 2))
        if a > level * b:
            last = k
    return math.inf if last == e.size - 1 else (last + 1) * T


def test_a_step_down_to_the_floor_is_timed_to_the_sample():
    """3x the floor for 1 s, then the floor: the 0.25 s window holds at most 13 samples of the
    3x part when within 1.2x (8 m / 250 <= 0.44), so the last window above ends at sample 1235."""
    T = 1e-3
    ef = np.ones((1, 3000))
    e = ef.copy()
    e[0, :1000] = 3.0
    assert time_to_floor(e, ef, T)[0] == pytest.approx(1.236)
    assert time_to_floor(ef, ef, T)[0] == 0.0  # never above: 0
    e2 = ef.copy()
    e2[0, -10:] = 5.0  # above at the segment's end: never
    assert np.isinf(time_to_floor(e2, ef, T)[0])
    e3 = e.copy()
    e3[0, 5] = np.nan  # a failed trial
    assert np.isnan(time_to_floor(e3, ef, T)[0])


def test_equals_the_definition_written_out_on_random_errors():
    rng = np.random.default_rng(3)
    T = 0.01
    ef = np.abs(rng.normal(size=(6, 300)))
    decay = 1.0 + 3.0 * np.exp(-np.arange(300) * T / rng.uniform(0.2, 1.5, size=(6, 1)))
    e = ef * decay * rng.uniform(0.9, 1.1, size=(6, 300))
    got = time_to_floor(e, ef, T)
    want = [_direct(e[i], ef[i], T) for i in range(6)]
    np.testing.assert_allclose(got, want)
    assert len(set(np.round(got, 6))) > 2  # the seeds differ: the test discriminates


def test_quantiles_count_never_as_later_than_every_time():
    x = np.array([1.0, 2.0, 3.0, 4.0])
    for q in (0, 50, 90, 100):
        assert quantile_never(x, q) == pytest.approx(np.percentile(x, q))
    y = np.array([1.0, 2.0, np.inf, np.nan])
    assert quantile_never(y, 50) == 2.0
    assert quantile_never(y, 90) == math.inf
    assert quantile_never(np.array([1.0, np.inf]), 0) == 1.0
    assert math.isnan(quantile_never(np.array([np.nan]), 50))


@pytest.fixture(scope="module")
def run():
    sc = dataclasses.replace(
        load_scenario(),
        seeds=3,
        duration=3.0,
        swap_times=(1.5,),
        swap_masses=(3.0,),
        controllers=("ct_oracle", "adaptive_ct"),
    )
    return run_benchmark(sc, progress=False)


def test_the_metrics_carry_it_per_seed_with_its_statistics(run):
    m = compute_metrics(run)
    json.dumps(m)  # machine-readable as it stands
    tf = m["controllers"]["adaptive_ct"]["segments"][0]["time_to_floor"]
    assert m["controllers"]["ct_oracle"]["segments"][0]["time_to_floor"] is None  # its own floor
    T = run.scenario.sample_period
    end = round(1.5 / T)
    e, ef = run.runs["adaptive_ct"].e_norm, run.runs["ct_oracle"].e_norm
    want = [_direct(e[i, :end].astype(float), ef[i, :end].astype(float), T) for i in range(3)]
    got = [math.inf if x == "never" else x for x in tf["per_seed"]]
    np.testing.assert_allclose(got, want)
    assert tf["median"] == pytest.approx(np.median(want)) or tf["median"] == "never"
    assert tf["n"] == 3 and tf["segment_length"] == pytest.approx(1.5)
    assert tf["window"] == WINDOW and tf["level"] == LEVEL
    df = run.to_frame()
    col = df[(df.controller == "adaptive_ct") & (df.segment == 0)].time_to_floor_s.to_numpy()
    np.testing.assert_allclose(col, want)
    assert df[df.segment == 1].time_to_floor_s.isna().all()
