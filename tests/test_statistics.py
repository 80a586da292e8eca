"""The headline statistics on small hand-made inputs: every number worked out by hand.

Each test pins one figure the report prints (per-seed ratios, mean / median / p90 / max / 95 %
interval, worst seed index, false alarms and the window's edges, missed swaps, detection
delays, the floor's saturation); a fault planted in any of them in ``benchmark/metrics.py``
fails here.
"""

import dataclasses

import numpy as np
import pytest

from adaptive_dd.benchmark.intervals import BOOTSTRAP_RESAMPLES, mean_interval
from adaptive_dd.benchmark.metrics import (
    FALSE_ALARM_WINDOW,
    compute_metrics,
    detection_delays,
    false_alarm_counts,
    ratio_statistics,
    segment_failed,
)
from adaptive_dd.benchmark.report import format_report
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.benchmark.streaming import segment_bounds
from adaptive_dd.benchmark.types import BenchmarkResult, ControllerRun

T = 0.001
SWAP = 1.0


def test_ratio_statistics_by_hand():
    r = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0])
    seeds = np.arange(100, 110)
    st = ratio_statistics(r[::-1].copy(), seeds)  # worst (10) at position 0, seed 100
    assert st["mean"] == pytest.approx(5.5)
    assert st["median"] == pytest.approx(5.5)
    assert st["p90"] == pytest.approx(9.1)  # 9 + 0.1 (10 - 9): linear interpolation
    assert st["max"] == 10.0
    assert st["worst_seed"] == 100 and st["n"] == 10
    # the percentile bootstrap of the mean, drawn by hand from the seeded generator over the sorted
    # ratios (the interval of the set, whatever the seeds' order)
    draws = np.random.default_rng(0).integers(0, 10, (BOOTSTRAP_RESAMPLES, 10))
    np.testing.assert_allclose(st["ci95"], np.percentile(r[draws].mean(axis=1), [2.5, 97.5]), rtol=1e-12)
    # about the normal interval of the mean: sd of 1..10 = sqrt(110 / 12) (ddof 1), x sqrt(9 / 10)
    half = 1.96 * np.sqrt(110 / 12) * np.sqrt(0.9) / np.sqrt(10)
    np.testing.assert_allclose(st["ci95"], [5.5 - half, 5.5 + half], rtol=0.05)


def test_one_interval_for_the_report_and_the_leaderboard():
    """The report's ci95 and the leaderboard's columns were two methods (Student t and the
    bootstrap) for one statistic; now both are ``intervals.mean_interval``, a function of the set of
    ratios and the seed: the same trials in another order give the same interval (a review found
    the report's run order and the figure's seed order disagreeing)."""
    from adaptive_dd.arena.leaderboard import ratio_columns

    r = np.random.default_rng(3).lognormal(0.1, 0.3, 12)
    c = ratio_columns(r[::-1])
    assert ratio_statistics(r)["ci95"] == [c["ratio_ci95_low"], c["ratio_ci95_high"]]
    assert mean_interval(r) == mean_interval(np.random.default_rng(5).permutation(r))
    assert mean_interval(r, 1) != mean_interval(r)  # another seed, other draws


def test_ratio_statistics_skips_nan_and_names_the_seed_not_the_position():
    r = np.array([1.0, np.nan, 1.2, 3.0, 1.1])
    st = ratio_statistics(r, seeds=[7, 8, 9, 42, 11])
    assert st["n"] == 4 and st["worst_seed"] == 42 and st["max"] == 3.0
    assert st["median"] == pytest.approx(1.15)  # (1.1 + 1.2) / 2: even count
    assert st["mean"] == pytest.approx(6.3 / 4)
    assert ratio_statistics(np.array([2.0]))["ci95"] is None  # one seed: no interval
    assert ratio_statistics(np.array([np.nan, np.nan])) is None


def test_false_alarm_window_edges():
    w = FALSE_ALARM_WINDOW
    assert w == 0.3
    trials = [
        [SWAP],  # exactly at the swap: detected, delay 0
        [SWAP + 0.29],  # inside the window
        [SWAP + 0.31],  # just past the window: false alarm, swap missed
        [SWAP - 0.001],  # just before the swap: false alarm, swap missed
        [],  # nothing: missed, no false alarm
        [SWAP + 0.02, SWAP + 0.05, 0.5],  # two in the window (first counts), one false
    ]
    assert false_alarm_counts(trials, (SWAP,)) == [0, 0, 1, 1, 0, 1]
    d = detection_delays(trials, SWAP)
    assert d[0] == 0.0 and d[1] == pytest.approx(0.29) and d[5] == pytest.approx(0.02)
    assert d[2] is None and d[3] is None and d[4] is None


def test_segment_failed_rule():
    end = np.array([1000, 2000])
    bad = segment_failed(np.array([False, True, True, True]), np.array([-1, 1500, 100, -1]), end)
    assert bad.tolist() == [[False, False], [False, True], [True, True], [True, True]]


def _fake_result(seed_indices=(10, 11, 12, 13), sat_oracle=(0.0, 0.0), friction=None):
    """Two controllers x 4 seeds x 2 segments (swap to 1 kg at 1 s) with hand-set streamed sums;
    ``friction``: the plant's friction law (default the scenario's, stick-slip)."""
    sc = dataclasses.replace(
        load_scenario(),
        seeds=len(seed_indices),
        duration=2.0,
        swap_times=(SWAP,),
        swap_masses=(1.0,),
        controllers=("ct_oracle", "adaptive_ct"),
    )
    if friction is not None:
        sc = dataclasses.replace(sc, arm=dataclasses.replace(sc.arm, friction=friction))
    N = sc.n_samples
    start, end, settled = segment_bounds(sc.segments(), T, 0.5)
    n = (end - start).astype(float)
    S = len(seed_indices)

    def run(name, rms, alarms, floor, sat):
        from adaptive_dd.closed_loop.types import StreamedSums

        rms = np.asarray(rms, float)
        e2 = rms**2 * n
        acc = StreamedSums(
            sum_e2=e2,
            sum_e2_joint=np.stack([e2 / 2, e2 / 2], axis=-1),
            max_e=2 * rms,
            sum_tau2=np.broadcast_to(n, (S, 2)).copy(),
            n_saturated=np.broadcast_to(np.asarray(sat)[None, :] * n, (S, 2)).copy(),
            sum_e2_settled=rms**2 * (end - settled),
            e_norm=np.zeros((S, N), dtype=np.float32),
        )
        return ControllerRun(
            name=name,
            acc=acc,
            e_norm=acc.e_norm,
            sigma_end=None,
            failed=np.zeros(S, dtype=bool),
            failed_at=np.full(S, -1),
            alarm_times=alarms,
            floor=floor,
        )

    oracle = np.array([[1.0, 1.0], [1.0, 2.0], [2.0, 1.0], [1.0, 1.0]]) * 1e-4
    ratio = np.array([[1.0, 1.1], [1.0, 1.2], [1.0, 3.0], [1.0, 1.05]])
    alarms = [[SWAP + 0.02], [SWAP + 0.04, 0.4], [SWAP + 0.31], []]
    res = BenchmarkResult(sc, np.arange(N) * T, np.zeros((N, 2)), np.zeros((N, 7)), np.zeros(N))
    res.seed_indices = tuple(seed_indices)
    res.runs["ct_oracle"] = run("ct_oracle", oracle, None, None, sat_oracle)
    res.runs["adaptive_ct"] = run("adaptive_ct", oracle * ratio, alarms, "ct_oracle", (0.0, 0.0))
    return res, ratio


def test_compute_metrics_per_seed_ratios_alarms_and_missed_swaps():
    res, ratio = _fake_result()
    m = compute_metrics(res)["controllers"]
    a = m["adaptive_ct"]
    assert a["floor"] == "ct_oracle"
    st = a["segments"][1]["ratio_to_floor"]
    assert st["mean"] == pytest.approx(ratio[:, 1].mean())
    assert st["median"] == pytest.approx(1.15)
    assert st["p90"] == pytest.approx(np.percentile([1.05, 1.1, 1.2, 3.0], 90))
    assert st["p90"] == pytest.approx(1.2 + 0.7 * 1.8)  # by hand: 0.9 * 3 = 2.7 -> 1.2 + 0.7 (3.0 - 1.2)
    assert st["max"] == pytest.approx(3.0) and st["worst_seed"] == 12 and st["n"] == 4
    assert a["segments"][0]["ratio_to_floor"]["max"] == pytest.approx(1.0)
    # per-seed RMS in the JSON is the hand-set one
    np.testing.assert_allclose(a["segments"][1]["rms_error_per_seed"], [1.1e-4, 2.4e-4, 3e-4, 1.05e-4])
    # alarms: seed 0 detects at 20 ms, seed 1 at 40 ms plus a false alarm at 0.4 s, seed 2's alarm
    # is 10 ms past the window (false, and the swap missed), seed 3 raises none (missed)
    assert a["false_alarms_per_seed"] == [0, 1, 1, 0]
    assert a["trials_with_false_alarms"] == 2
    assert a["missed_swaps_per_seed"] == [0, 0, 1, 1] and a["missed_swaps"] == 2
    seg = a["segments"][1]
    assert seg["detection_delay_per_seed"][:2] == pytest.approx([0.02, 0.04])
    assert seg["detection_delay_per_seed"][2:] == [None, None]
    assert seg["detection_delay"] == pytest.approx(0.03) and seg["detected"] == 2 and seg["missed"] == 2
    assert a["segments"][0]["detection_delay"] is None
    assert m["ct_oracle"]["false_alarms_per_seed"] is None  # no detector: None, never absent


def test_report_prints_missed_swaps_false_alarms_and_worst_seed_index():
    res, _ = _fake_result()
    text = format_report(compute_metrics(res), res)
    assert "adaptive_ct missed swaps: 2 of 4 (target 0: NOT met)" in text
    assert "adaptive_ct trials with a false alarm: 2 of 4 (50.0 %)" in text
    assert "p90 2.460, max 3.000 (seed 12)" in text  # max as p90: "p90 1.023, max 1.02" read as max < p90
    assert "#12" in text


def test_a_saturated_floor_gets_no_verdict():
    res, _ = _fake_result(sat_oracle=(0.0, 0.029))
    m = compute_metrics(res)
    seg = m["controllers"]["adaptive_ct"]["segments"]
    assert seg[1]["floor_saturated"] and not seg[0]["floor_saturated"]
    assert seg[1]["floor_saturation"] == pytest.approx(0.029)
    assert m["controllers"]["ct_oracle"]["segments"][1]["floor_saturated"]
    text = format_report(m, res)
    assert "no verdict, ct_oracle saturates 2.90 % of samples" in text
    assert "ct_oracle saturated fraction (max over segments): 2.900 %" in text
    assert "NOT met: the saturated segments have no verdict" in text
    # the per-seed tables mark the saturated segment's ratio, for every law against that floor
    assert "! the floor (ct_oracle) saturates in more than 1 % of the segment's samples: no verdict" in text
    table = text.split("Per-seed RMS error ratio to the floor")[1]
    mean_row = next(x for x in table.splitlines() if x.startswith("adaptive_ct"))
    first, second = mean_row.split()[1:3]
    assert not first.endswith("!") and second.endswith("!") and float(second[:-1]) > 0
    plain = format_report(compute_metrics(_fake_result()[0]), res)
    assert "! the floor" not in plain


def test_a_floor_on_a_plant_friction_outside_the_model_is_called_a_reference():
    plain = compute_metrics(_fake_result()[0])
    assert plain["floor_caveat"] is None
    assert "note:" not in format_report(plain, _fake_result()[0])
    for law in ("tanh", "stribeck", "lugre"):
        res, _ = _fake_result(friction=law)
        m = compute_metrics(res)
        assert f"friction law ({law}) is not the controllers' model's" in m["floor_caveat"]
        text = format_report(m, res)
        # in the per-seed tables and above the targets' verdicts
        assert text.count(f"  note: the plant's friction law ({law})") == 2
        # the ratios themselves are still there
        assert m["controllers"]["adaptive_ct"]["segments"][1]["ratio_to_floor"]["max"] == pytest.approx(3.0)


def test_a_failed_trial_is_left_out_after_its_failure_only():
    res, _ = _fake_result()
    run = res.runs["adaptive_ct"]
    run.failed[3], run.failed_at[3] = True, 1500  # diverged in segment 1
    m = compute_metrics(res)["controllers"]["adaptive_ct"]
    assert m["segments"][0]["ratio_to_floor"]["n"] == 4
    assert m["segments"][1]["ratio_to_floor"]["n"] == 3
    assert m["segments"][1]["rms_error_per_seed"][3] is None
    assert m["false_alarms_per_seed"][3] is None and m["missed_swaps_per_seed"][3] is None
    assert m["missed_swaps"] == 1


def test_one_conversion_of_seconds_to_samples():
    """A swap at 2.5005 s with T = 1 ms: the plant changes at sample 2501 and so does the segment."""
    from adaptive_dd.benchmark.trials import true_sigma
    from adaptive_dd.plant.sampling import first_sample

    assert first_sample(2.5005, 1e-3) == 2501 and first_sample(2.0, 1e-3) == 2000
    start, end, _ = segment_bounds([(0.0, 2.5005, 0.0), (2.5005, 5.0, 1.0)], 1e-3, 0.5)
    assert start.tolist() == [0, 2501] and end.tolist() == [2501, 5000]
    sc = dataclasses.replace(load_scenario(), seeds=1, duration=5.0, swap_times=(2.5005,), swap_masses=(1.0,))
    _, mass = true_sigma(sc, np.arange(sc.n_samples) * T)
    assert mass[2500] == 0.0 and mass[2501] == 1.0


def test_validate_names_the_plant_friction_law_on_both_runtimes():
    from pathlib import Path

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.benchmark.scenario_format import format_scenario

    two_link = load_scenario(
        str(Path(__file__).resolve().parents[1] / "benchmarks/scenarios/lugre_friction.toml")
    )
    assert two_link.closed_forms is not None
    text = format_scenario(two_link)
    assert "plant.friction = 'lugre'" in text and "each floor is a reference, not a floor" in text
    assert "plant.friction" not in format_scenario(load_scenario())  # stick-slip: the model's own law


def test_settling_time_in_a_short_segment_is_not_set_by_its_own_transient():
    from adaptive_dd.benchmark.metrics import _settling_times

    T = 1e-3
    e = np.full((1, 1800), 1e-4)
    e[0, 1000:1100] = 3e-3  # 100 ms off after the swap at 1 s, in a 0.8 s segment
    t = _settling_times(e, [0, 1000], [1000, 1800], T)
    assert np.isnan(t[0, 0])  # the first segment has none
    # the 50 ms moving RMS leaves the spike 50 ms after it ends: about 0.15 s after the swap
    assert 0.14 <= t[0, 1] <= 0.16
    # a 2 s segment, as before: the band from its last second
    e2 = np.full((1, 3000), 1e-4)
    e2[0, 1000:1100] = 3e-3
    assert 0.14 <= _settling_times(e2, [0, 1000], [1000, 3000], T)[0, 1] <= 0.16


def test_settling_time_after_a_short_segment_is_not_set_by_that_segment_s_transient():
    from adaptive_dd.benchmark.metrics import _settling_times

    e = np.full((1, 3700), 1e-4)
    e[0, 1000:1100] = e[0, 1700:1800] = 3e-3  # swaps at 1.0 s and 1.7 s, each 100 ms off
    t = _settling_times(e, [0, 1000, 1700], [1000, 1700, 3700], 1e-3)
    assert 0.14 <= t[0, 1] <= 0.16 and 0.14 <= t[0, 2] <= 0.16  # the 1.7 s swap's read 0 before


def test_every_planted_fault_of_the_benchmark_script_still_applies():
    """``benchmarks/planted_faults.py`` plants each fault by replacing a line of metrics.py: a line that
    changed made it print "fault not applicable" and count that fault as not caught, unnoticed."""
    import importlib.util
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location("planted_faults", root / "benchmarks" / "planted_faults.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    text = (root / mod.METRICS).read_text()
    stale = [name for name, (old, _new) in mod.FAULTS.items() if text.count(old) != 1]
    assert not stale, f"faults whose line is not in {mod.METRICS} once: {stale}"


def test_a_trial_whose_alarm_record_filled_before_the_swap_is_not_called_missed():
    """A detector alarming at every sample filled its record (MAX_ALARMS) before the swap and read
    "missed swaps 3 of 3": whether it saw the swap is not known, so it is not counted missed."""
    from adaptive_dd.benchmark.metrics import missed_swap_counts
    from adaptive_dd.benchmark.types import MAX_ALARMS
    from adaptive_dd.closed_loop.glue import AlarmTimes

    res, _ = _fake_result()
    run = res.runs["adaptive_ct"]
    run.alarm_times[3] = AlarmTimes([0.001 * k for k in range(MAX_ALARMS)], truncated=True)  # full before
    a = compute_metrics(res)["controllers"]["adaptive_ct"]
    assert a["missed_swaps_per_seed"] == [0, 0, 1, 0] and a["segments"][1]["missed"] == 1
    # the leaderboard's count is the same rule
    args = (res.scenario.swap_times, run.failed, res.scenario.duration)
    assert missed_swap_counts(run.alarm_times, *args).tolist() == [0, 0, 1, 0]
    # a record that kept every alarm (the Python path keeps them all; exactly MAX_ALARMS raised on the
    # compiled one) still says the swap was missed
    for times in ([0.001 * k for k in range(300)], AlarmTimes([0.001 * k for k in range(MAX_ALARMS)])):
        run.alarm_times[3] = times
        a = compute_metrics(res)["controllers"]["adaptive_ct"]
        assert a["missed_swaps_per_seed"] == [0, 0, 1, 1]
        assert missed_swap_counts(run.alarm_times, *args).tolist() == [0, 0, 1, 1]
