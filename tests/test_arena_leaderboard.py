"""The leaderboard (adaptive_dd.arena): its statistics, and the command on one short scenario."""

from __future__ import annotations

import json
import tomllib
import warnings
from importlib import resources

import numpy as np
import pandas as pd
import pytest

from adaptive_dd.arena.leaderboard import COLUMNS, leaderboard, ratio_columns
from adaptive_dd.cli import main
from adaptive_dd.errors import ParameterError


def test_ratio_columns_by_hand():
    r = np.array([1.0, 2.0, 3.0, 4.0, 10.0, np.nan])  # the NaN (a failed trial) is left out
    c = ratio_columns(r, 1)
    assert c["ratio_mean"] == pytest.approx(4.0)
    assert c["ratio_max"] == 10.0
    assert c["ratio_cvar10"] == 10.0  # ceil(0.1 * 5) = 1 worst seed
    assert c["ratio_p90"] == pytest.approx(np.percentile([1, 2, 3, 4, 10], 90))
    assert 1.0 <= c["ratio_ci95_low"] < 4.0 < c["ratio_ci95_high"] <= 10.0
    twenty = ratio_columns(np.arange(1.0, 21.0), 1)
    assert twenty["ratio_cvar10"] == pytest.approx(19.5)  # the two worst of twenty
    assert np.isnan(ratio_columns(np.full(3, np.nan), 1)["ratio_mean"])
    one = ratio_columns(np.array([1.7, np.nan]), 1)  # one seed: no interval
    assert one["ratio_mean"] == 1.7 and np.isnan(one["ratio_ci95_low"]) and np.isnan(one["ratio_ci95_high"])


def test_the_two_link_closed_form_runtime_is_refused_with_the_route_that_works():
    with pytest.raises(ParameterError, match=r"sice_drawn\.toml"):
        leaderboard([None], ["pd_gravity"])


PLUGIN = '''
import numpy as np


class FloorlessPD:
    """PD with a floor nobody ships: the leaderboard must say why its row has no ratio."""

    floor = "no_such_law"

    def __init__(self, arm, gains):
        self.n, self.kp, self.kd = arm.n_joints, gains.kp * 5.0, gains.kd * 5.0

    def reset(self, n_trials, sample_period):
        pass

    def command(self, q, qd, q_d, qd_d, qdd_d):
        return self.kp * (q_d - q) + self.kd * (qd_d - qd)

    def observe(self, q, qd, tau):
        pass
'''


def _short_vertical3(tmp_path):
    src = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload.toml")
    text = src.read_text(encoding="utf-8")
    text = text.replace("duration = 16.0", "duration = 1.6").replace("ramp = 1.0", "ramp = 0.2")
    head, _, _ = text.partition("[[payload]]")
    p = tmp_path / "v3short.toml"
    p.write_text(head + "[[payload]]\nat = 0.8\nmass = 1.0\n", encoding="utf-8")
    (tmp_path / "floorless.py").write_text(PLUGIN, encoding="utf-8")
    assert tomllib.loads(p.read_text(encoding="utf-8"))["run"]["duration"] == 1.6  # the edit took
    return p


@pytest.mark.slow  # runs six controllers' closed loops: minutes of compiling, cold
def test_leaderboard_command_writes_the_table_the_json_and_the_figure(tmp_path, capsys):
    sc = _short_vertical3(tmp_path)
    out = tmp_path / "out"
    argv = ["leaderboard", str(sc), "--seeds", "2", "--controllers", "pd_gravity", "sliding_mode"]
    argv += ["--plugin", "floorless:FloorlessPD", "--out", str(out), "--no-progress"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(argv) == 0
    # the floor that cannot run is the row's floor_note, not also run_benchmark's raw warning
    assert not [w for w in caught if "did not run" in str(w.message)]
    df = pd.read_csv(out / "leaderboard.csv", keep_default_na=False, na_values=[""])
    assert list(df.columns) == list(COLUMNS)
    runs = ["pd_gravity", "sliding_mode", "FloorlessPD", "pd_gravity_oracle", "slotine_li_oracle"]
    assert set(df["controller"]) == set(runs)
    assert len(df) == len(runs) * 2  # two segments: 0 kg, then 1 kg
    ranked = df[df["controller"].isin(["pd_gravity", "sliding_mode"])]
    assert set(ranked["floor"]) == {"pd_gravity_oracle", "slotine_li_oracle"}
    assert np.all(np.isfinite(ranked["ratio_mean"])) and np.all(ranked["ratio_mean"] > 0)
    assert np.all(ranked["ratio_ci95_low"] <= ranked["ratio_mean"])
    assert np.all(ranked["ratio_mean"] <= ranked["ratio_ci95_high"])
    assert np.all(ranked["ratio_p90"] <= ranked["ratio_max"] + 1e-12)
    assert np.all(ranked["seeds"] + ranked["failures"] == 2)
    # the ratio is the law's mean error over the floor's only when both have the same seeds: check
    # it against the two error columns within the seeds' spread
    assert np.all(ranked["rms_error_mrad"] > 0) and np.all(ranked["floor_rms_error_mrad"] > 0)
    oracle = df[df["controller"] == "pd_gravity_oracle"]
    assert np.all(oracle["floor_note"].str.contains("oracle")) and np.all(np.isnan(oracle["ratio_mean"]))
    mine = df[df["controller"] == "FloorlessPD"]
    assert np.all(mine["floor_note"].str.contains("no_such_law cannot run here"))
    assert np.all(np.isnan(mine["ratio_mean"])) and np.all(mine["rms_error_mrad"] > 0)
    doc = json.loads((out / "leaderboard.json").read_text(encoding="utf-8"))
    assert doc["columns"]["rms_torque_Nm"]["unit"] == "N m" and len(doc["rows"]) == len(df)
    from adaptive_dd import __version__

    assert (
        doc["provenance"]["version"] == __version__ and "git_commit" in doc["provenance"]
    )  # as metrics.json
    assert (out / "leaderboard.png").stat().st_size > 1000
    # the command as typed, and what it ran (it recorded a command rebuilt from the rows: a template's
    # folder, a plug-in's --plugin and the scenarios' paths were lost)
    import shlex

    from adaptive_dd.arena.latex import latex_table
    from adaptive_dd.arena.page import read_table

    assert doc["command"] == shlex.join(["adaptive-dd", *argv]) and doc["scenarios"] == [str(sc)]
    assert doc["controllers"] == ["pd_gravity", "sliding_mode", "floorless:FloorlessPD"]
    assert doc["bootstrap_seed"] == 0 and doc["template"] is None
    tex = (out / "leaderboard.tex").read_text(encoding="utf-8")  # the paper's table, of the CSV's figures
    assert tex == latex_table(read_table(out / "leaderboard.csv"), command=doc["command"])
    assert tex.startswith(f"% {doc['command']}\n") and "\\texttt{sliding\\_mode}" in tex
    assert "pd_gravity_oracle" in capsys.readouterr().out


def test_every_column_and_its_unit_is_on_the_docs_page():
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "leaderboard.md").read_text(encoding="utf-8")
    for name, (unit, meaning) in COLUMNS.items():
        assert f"| `{name}` | {unit} | {meaning} |" in page, name


def test_an_unknown_controller_is_a_user_error_naming_it(tmp_path, capsys):
    sc = _short_vertical3(tmp_path)
    assert main(["leaderboard", str(sc), "--controllers", "no_such_law", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    # named by the option that gave it (it was blamed on the scenario file the run would fail on)
    assert "--controllers: unknown controller 'no_such_law'" in err and "v3short.toml" not in err
    assert main(["leaderboard", str(sc), "--plugin", "my_laws", "--out", str(tmp_path / "o")]) == 2
    assert "--plugin my_laws: expects MODULE:CLASS" in capsys.readouterr().err
    # two values after one --plugin: the second is read as a SCENARIO, and said so
    two = ["leaderboard", "--no-scenarios", "--arms", "2", "--plugin", "a:A", "b:B"]
    assert main([*two, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "SCENARIO 'b:B': no such file, and it reads as a plug-in" in err
    assert "--plugin a:A --plugin b:B" in err


def test_a_scenario_with_a_table_for_a_controller_not_ranked_runs(tmp_path, monkeypatch):
    """A scenario with a plug-in's settings table, ranked on built-ins only: its run drops that
    table (it failed: ``controllers.PayloadGradient: not a controller of run.controllers``)."""
    import adaptive_dd.benchmark.runner as runner
    from adaptive_dd.arena.leaderboard import _run_cells
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = load_scenario(resources.files("adaptive_dd").parent / "examples" / "plugin.toml")
    ran = []

    class Ran(Exception):
        pass

    def run_benchmark(scenario, **kw):
        ran.append(scenario)
        raise Ran

    monkeypatch.setattr(runner, "run_benchmark", run_benchmark)
    with pytest.raises(Ran):
        _run_cells(sc, "two_link", ["ct_nominal"], 1, False)
    assert ran[0].controllers == ("ct_nominal", "ct_oracle") and ran[0].controller_options == ()


def _ee_agrees(board: pd.DataFrame, per_seed: pd.DataFrame) -> bool:
    """Every scenario row's ``ee_*`` columns are the aggregate of ``per_seed.csv``'s figures of
    its controller and segment: the mean over the seeds (the peak's largest too)."""
    cols = {
        "ee_position_rms_mm": ("ee_position_rms_mm", "mean"),
        "ee_position_peak_mm": ("ee_position_max_mm", "mean"),
        "ee_position_peak_max_mm": ("ee_position_max_mm", "max"),
        "ee_orientation_rms_deg": ("ee_orientation_rms_deg", "mean"),
    }
    checked = 0
    for r in board[board["kind"] == "scenario"].itertuples():
        seeds = per_seed[(per_seed["controller"] == r.controller) & (per_seed["segment"] == r.segment)]
        if seeds.empty:
            continue
        for col, (src, how) in cols.items():
            want = getattr(seeds[src].dropna(), how)()
            if not np.isclose(getattr(r, col), want, rtol=1e-5, atol=0.0):
                return False
            checked += 1
    return checked > 0


@pytest.mark.slow  # two runs of a short scenario's closed loops: minutes of compiling, cold
def test_the_end_effector_columns_are_the_per_seed_figures_they_aggregate(tmp_path):
    """The leaderboard's tool-frame columns against ``adaptive-dd benchmark``'s ``per_seed.csv`` of
    the same scenario, seeds and law (common random numbers: the same trials); an off-by-one
    segment (the per-seed figures moved to the next segment) fails the check."""
    sc = _short_vertical3(tmp_path)
    args = [str(sc), "--seeds", "2", "--controllers", "slotine_li", "--no-progress"]
    assert main(["benchmark", *args, "--out", str(tmp_path / "b")]) == 0
    assert main(["leaderboard", *args, "--out", str(tmp_path / "l")]) == 0
    per_seed = pd.read_csv(tmp_path / "b" / "per_seed.csv")
    board = pd.read_csv(tmp_path / "l" / "leaderboard.csv", keep_default_na=False, na_values=[""])
    assert set(board["controller"]) == {"slotine_li", "slotine_li_oracle"}
    mine = board[board["controller"] == "slotine_li"]
    assert len(mine) == 2 and np.all(mine["ee_position_rms_mm"] > 0)
    assert np.all(mine["ee_position_rms_mm"] <= mine["ee_position_peak_mm"])
    assert np.all(mine["ee_position_peak_mm"] <= mine["ee_position_peak_max_mm"])
    assert _ee_agrees(board, per_seed)
    n_seg = int(per_seed["segment"].max()) + 1
    assert not _ee_agrees(board, per_seed.assign(segment=(per_seed["segment"] + 1) % n_seg))
    doc = json.loads((tmp_path / "l" / "leaderboard.json").read_text(encoding="utf-8"))
    assert doc["columns"]["ee_position_rms_mm"]["unit"] == "mm"
    assert doc["columns"]["ee_orientation_rms_deg"]["unit"] == "deg"


@pytest.mark.slow  # two runs of a 10 s excitation phase, its design and identification (about a minute)
def test_the_leaderboards_lean_run_streams_the_same_sums_as_a_full_run():
    """The leaderboard runs its units keeping no trajectory and without the excitation report's
    scale check (it reads neither): every streamed sum, failure and end-of-segment estimate is
    the same as a default run's, bit for bit; only the report's ``estimator_scale`` is left out."""
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.closed_loop.types import StreamedSums

    text = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload.toml").read_text("utf-8")
    data = tomllib.loads(text)
    names = ["ct_oracle", "adaptive_ct", "slotine_li", "slotine_li_oracle"]
    data["run"] = {**data["run"], "duration": 2.0, "seeds": 2, "excite": 10.0, "controllers": names}
    data["payload"] = [{"at": 1.0, "mass": 1.0}]
    data.pop("controllers", None)
    sc = parse_scenario(data, "test.toml", name="v3_excite")
    full = run_benchmark(sc, progress=False)
    lean = run_benchmark(sc, progress=False, keep_trajectories=0, scale_check=False)
    assert full.runs["adaptive_ct"].q.shape[0] == 2 and lean.runs["adaptive_ct"].q.shape[0] == 0
    for name, a in full.runs.items():
        b = lean.runs[name]
        for f in StreamedSums._fields:
            np.testing.assert_array_equal(getattr(a.acc, f), getattr(b.acc, f), err_msg=f"{name} {f}")
        np.testing.assert_array_equal(a.failed, b.failed)
        if a.sigma_end is not None:
            np.testing.assert_array_equal(a.sigma_end, b.sigma_end)
    rep_full, rep_lean = full.cache["excitation_report"], lean.cache["excitation_report"]
    assert rep_lean.estimator_scale is None and np.all(np.isfinite(rep_full.estimator_scale))
    for f in ("sigma_fit", "sigma_cov"):
        np.testing.assert_array_equal(getattr(rep_full, f), getattr(rep_lean, f))
    assert "estimator_scale" not in json.dumps(lean.excitation)


def test_the_metrics_segment_bounds_are_the_loops():
    """The metrics count each segment's samples with :func:`sample_bounds` (no reference sampled,
    no tool frame's table): the bounds the closed loop ran with (``run_constants``)."""
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.closed_loop.types import run_constants, sample_bounds

    text = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload.toml").read_text("utf-8")
    data = tomllib.loads(text)
    data["run"]["duration"] = 3.0
    data["payload"] = [{"at": 1.2, "mass": 1.0}, {"at": 1.6, "mass": 0.0}, {"at": 2.5, "mass": 0.5}]
    rc = run_constants(parse_scenario(data, "test.toml", name="v3"))
    got = sample_bounds(parse_scenario(data, "test.toml", name="v3"))
    for a, b in zip(got, (rc.seg_start, rc.seg_end, rc.seg_settled), strict=True):
        np.testing.assert_array_equal(a, b)
    assert list(rc.seg_start) == [0, 1200, 1600, 2500] and list(rc.seg_settled) == [500, 1599, 2100, 2999]


def test_unit_costs_order_the_drawn_arms_by_joints_without_drawing_them(monkeypatch):
    """A drawn arm's cost is its joints squared, three times with an excitation phase; counted
    without drawing the arm (``random_arm`` is not called: the parent would draw every arm once
    more before the workers start)."""
    import importlib

    from adaptive_dd.arena.leaderboard import unit_costs

    ra = importlib.import_module(
        "adaptive_dd.robots.random_arm"
    )  # the module (the package exports the function)

    joints = {s: ra.random_arm(s).n_joints for s in (0, 1, 2)}

    def refuse(*_):
        raise AssertionError("unit_costs drew an arm")

    monkeypatch.setattr(ra, "random_arm", refuse)
    units = [("arm", ({"run": {"excite": 20.0}}, "t.toml", 0)), ("arm", ({}, "t.toml", 1)),
             ("arm", ({"run": {"excite": 0.0}}, "t.toml", 2))]  # fmt: skip
    assert unit_costs(units) == [3.0 * joints[0] ** 2, float(joints[1] ** 2), float(joints[2] ** 2)]


def _run_with_alarms(alarm_times, failed_at=None):
    from types import SimpleNamespace

    n = len(alarm_times)
    fa = np.full(n, -1) if failed_at is None else np.asarray(failed_at)
    return SimpleNamespace(alarm_times=alarm_times, failed=fa >= 0, failed_at=fa)


def test_the_alarm_columns_by_hand():
    """Swaps at 1 and 3 s of a 4-s run at 1 kHz: an alarm with no swap in the 0.3 s before counts
    in the segment it falls in, a swap with no alarm in the 0.3 s after is missed (not by a trial
    that failed before that window ended), a failed trial's alarms are not counted (as the
    benchmark's report: they counted, even 4 s after the arm was stopped), a swap the run ends
    within 0.3 s of is not judged, and a law without a detector has no count."""
    from types import SimpleNamespace

    from adaptive_dd.arena.leaderboard import _alarms

    sc = SimpleNamespace(swap_times=(1.0, 3.0), sample_period=1e-3, duration=4.0)
    t0 = np.array([0.0, 1.0, 3.0])
    run = _run_with_alarms([[0.05, 1.02, 2.5], [1.29, 3.1], [1.01, 2.5]], failed_at=[-1, -1, 2000])
    fa, missed = _alarms(run, sc, t0)
    np.testing.assert_array_equal(fa, [[1, 1, 0], [0, 0, 0], [np.nan] * 3])
    np.testing.assert_array_equal(missed, [[0, 0, 1], [0, 0, 0], [np.nan] * 3])
    _, missed = _alarms(run, SimpleNamespace(swap_times=(1.0, 3.0), sample_period=1e-3, duration=3.2), t0)
    np.testing.assert_array_equal(missed, [[0, 0, 0], [0, 0, 0], [np.nan] * 3])  # 3 s: not judged
    # two trials failing late with no alarm: their misses are not counted against the survivors
    late = _run_with_alarms([[1.01, 3.02], [], []], failed_at=[-1, 3900, 3900])
    _, missed = _alarms(late, SimpleNamespace(swap_times=(1.0, 3.0), sample_period=1e-3, duration=4.0), t0)
    assert np.nansum(missed) == 0 and np.all(np.isnan(missed[1:]))
    fa, missed = _alarms(SimpleNamespace(alarm_times=None, failed=np.zeros(2, bool)), sc, t0)
    assert fa.shape == missed.shape == (2, 3) and np.all(np.isnan(fa)) and np.all(np.isnan(missed))


def test_the_alarm_columns_agree_with_the_benchmark_reports_counts():
    """Over random alarms, the per-segment columns say what the benchmark's report counts per
    trial (:func:`false_alarm_counts`, :func:`missed_swap_counts`): a trial has a false alarm in
    some segment exactly when it has one, and its missed swaps are the segments' sum."""
    from types import SimpleNamespace

    from adaptive_dd.arena.leaderboard import _alarms
    from adaptive_dd.benchmark.metrics import false_alarm_counts, missed_swap_counts

    rng = np.random.default_rng(3)
    swaps = (2.0, 4.5, 7.0)
    sc = SimpleNamespace(swap_times=swaps, sample_period=1e-3, duration=9.0)
    times = [sorted(rng.uniform(0.0, 9.0, rng.integers(0, 5)).tolist()) for _ in range(300)]
    times += [[s + rng.uniform(0, 0.35) for s in swaps if rng.random() < 0.8] for _ in range(300)]
    fa, missed = _alarms(_run_with_alarms(times), sc, np.array([0.0, *swaps]))
    np.testing.assert_array_equal(fa.max(axis=1) > 0, np.asarray(false_alarm_counts(times, swaps)) > 0)
    np.testing.assert_array_equal(missed.sum(axis=1), missed_swap_counts(times, swaps, np.zeros(600, bool)))
    assert 0 < fa.sum() < fa.size and 0 < missed.sum() < missed.size  # both kinds were drawn


def test_the_printed_winners_say_when_there_is_no_law_to_rank(capsys):
    """``--controllers ct_oracle`` alone printed the winners' header with nothing under it."""
    from adaptive_dd.cli.leaderboard import _print_winners

    df = pd.DataFrame(
        {"scenario": ["s"], "segment": [0], "controller": ["ct_oracle"], "floor": [""], "failures": [0],
         "rms_error_mrad": [0.1], "payload_kg": [0.0]}
    )  # fmt: skip
    _print_winners(df)
    assert "no law to rank" in capsys.readouterr().out
    _print_winners(df.assign(controller="pd", floor="pd_gravity_oracle"))
    assert "s:0 (0 kg): pd 0.1 mrad" in capsys.readouterr().out


def test_alarm_windows_decide_ties_and_the_runs_end_alike():
    """An alarm 0.3 s after a swap to the sample was a detection for some swap times and a false alarm
    plus a miss for others (float rounding: 2.8 - 2.5 vs 5.3 - 5.0); it is outside the window for
    every one. A swap the run ends within 0.3 s of is not judged missed."""
    from adaptive_dd.benchmark.metrics import detection_delays, false_alarm_counts, missed_swap_counts

    for k in (2500, 5000, 7300, 11100):
        s, x = k * 0.001, (k + 300) * 0.001
        assert false_alarm_counts([[x]], [s]) == [1] and detection_delays([[x]], s) == [None]
        y = (k + 299) * 0.001
        assert false_alarm_counts([[y]], [s]) == [0] and detection_delays([[y]], s)[0] is not None
    assert missed_swap_counts([[]], [2.99], [False], duration=3.0).tolist() == [0]
    assert missed_swap_counts([[]], [2.5], [False], duration=3.0).tolist() == [1]


def test_capped_alarm_lists_are_warned_of():
    """More alarms than the buffer holds were cut to the first 256 in silence (a compiled plug-in
    alarming every sample read 512 false alarms and every swap missed)."""
    from adaptive_dd.closed_loop.glue import Alarms, alarm_lists

    a = Alarms(np.zeros((2, 4)), np.array([3, 9]))
    with pytest.warns(UserWarning, match=r"trial\(s\) \[1\] raised up to 9 change alarms; the first 4"):
        out = alarm_lists(a)
    assert [len(x) for x in out] == [3, 4]


def test_a_law_told_the_model_is_shown_in_the_table_and_figure_as_a_reference():
    """``ct_oracle_late`` (a floor, told the true model) was dropped from the figure and the LaTeX
    table without a word, while the CSV and the printed table held it; it is shown, marked, and
    ranked with none (no bold). The figure's colours are one scale for every leaderboard."""
    from adaptive_dd.arena.latex import latex_table
    from adaptive_dd.arena.plot import RATIO_SCALE, plot_leaderboard

    rows = [
        dict(scenario="s", kind="scenario", controller=c, floor=f, segment=1, payload_kg=3.0, seeds=4,
             ratio_mean=m, ratio_p90=m, failures=0, rms_error_mrad=e, rms_rank=r, floor_saturation_pct=0.0)
        for c, f, m, e, r in [("adaptive_ct", "ct_oracle", 1.03, 0.2, 1.0),
                              ("ct_oracle_late", "ct_oracle", 2.4, 0.5, np.nan),
                              ("ct_oracle", "", np.nan, 0.19, np.nan)]
    ]  # fmt: skip
    df = pd.DataFrame(rows)
    tex = latex_table(df, command="adaptive-dd leaderboard x")
    late = next(line for line in tex.splitlines() if "oracle\\_late" in line)
    assert late.startswith("\\texttt{ct\\_oracle\\_late}$^\\dagger$") and "textbf" not in late
    assert "$\\dagger$: told the true model" in tex and "\\textbf{1.030}" in tex
    fig = plot_leaderboard(df)
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert labels == ["adaptive_ct / ct_oracle", "ct_oracle_late / ct_oracle (told the model; a reference)"]
    norm = fig.axes[0].images[0].norm
    assert (norm.vmin, norm.vmax) == RATIO_SCALE  # 1.03 is not drawn red because it is the largest here
    no_late = latex_table(df[df["controller"] != "ct_oracle_late"])
    assert "dagger" not in no_late  # an oracle (told, no floor) is no row and no mark


def test_a_scenarios_own_table_is_said_not_to_reach_the_drawn_arms(tmp_path, capsys):
    """A plug-in labelled in the given scenario ran under its class name on the drawn arms (two
    half-empty rows) and its settings did not reach them, without a word."""
    from adaptive_dd.cli.leaderboard import _say_tables_not_on_the_arms

    sc = _short_vertical3(tmp_path)
    sc.write_text(sc.read_text(encoding="utf-8") + '\n[controllers.pd]\nlabel = "my_pd"\n', encoding="utf-8")
    _say_tables_not_on_the_arms([str(sc)], ["pd", "adaptive_ct"], None)
    err = capsys.readouterr().err
    assert "[controllers.pd] (label) sets pd for that scenario only" in err
    assert "population.toml's tables" in err and "adaptive_ct" not in err


def test_a_law_with_another_floor_in_another_scenario_is_two_rows():
    """A scenario's floor setting can give a law another floor in one scenario: the figure crashed
    (its rows keyed by the law, its labels by law and floor) and the table named one floor for both."""
    from adaptive_dd.arena.latex import latex_table
    from adaptive_dd.arena.plot import plot_leaderboard

    rows = [
        dict(scenario=s, kind="scenario", controller="pd", floor=f, segment=1, payload_kg=1.0, seeds=2,
             ratio_mean=m, ratio_p90=m, failures=0, rms_error_mrad=1.0, rms_rank=1.0,
             floor_saturation_pct=0.0)
        for s, f, m in [("a", "ct_nominal", 0.9), ("b", "ct_oracle", 40.0)]
    ]  # fmt: skip
    df = pd.DataFrame(rows)
    labels = [t.get_text() for t in plot_leaderboard(df).axes[0].get_yticklabels()]
    assert labels == ["pd / ct_nominal", "pd / ct_oracle"]
    tex = latex_table(df, command="x")
    assert "\\texttt{pd} & \\texttt{ct\\_nominal} & \\textbf{0.900} (0.900) & -- \\\\" in tex
    assert "\\texttt{pd} & \\texttt{ct\\_oracle} & -- & \\textbf{40} (40) \\\\" in tex


def test_a_law_at_another_bandwidth_than_its_floor_is_noted_not_ranked_silently(tmp_path, capsys):
    """``[controllers.pd_gravity] bandwidth = 20`` against a floor at 40: benchmark and validate
    warned, the leaderboard ranked its ratio (3.6 on an exact arm, unloaded) without a word. Its
    rows' floor_note says so, and the command prints it. A plug-in's own table is read too (its
    class name: the check looked its entry up and found nothing)."""
    from adaptive_dd.arena.leaderboard import _run_cells
    from adaptive_dd.benchmark.preflight import floor_mismatches
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = _short_vertical3(tmp_path)
    text = sc.read_text(encoding="utf-8").replace(
        'controllers = ["pd",', 'controllers = ["pd_gravity", "pd",'
    )
    sc.write_text(text + "\n[controllers.pd_gravity]\nbandwidth = 20.0\n", encoding="utf-8")
    cells = _run_cells(load_scenario(sc), "scenario", ["pd_gravity"], 1, False)
    notes = {c["floor_note"] for c in cells if c["controller"] == "pd_gravity"}
    assert (
        len(notes) == 1
        and "pd_gravity.bandwidth = 20.0 but its floor pd_gravity_oracle runs at 40" in notes.pop()
    )
    assert not any(
        "but its floor" in c["floor_note"] for c in cells if c["controller"] == "pd_gravity_oracle"
    )
    assert main(["leaderboard", str(sc), "--seeds", "1", "--controllers", "pd_gravity", "--no-progress",
                 "--out", str(tmp_path / "out")]) == 0  # fmt: skip
    err = capsys.readouterr().err
    assert err.count("warning: v3short: pd_gravity: controllers.pd_gravity.bandwidth = 20.0") == 1

    plug = resources.files("adaptive_dd").parent / "examples" / "plugins" / "pd_gravity.toml"
    text = plug.read_text(encoding="utf-8").replace(
        'label = "pd_gravity_plugin"', 'label = "pd_gravity_plugin"\nbandwidth = 20.0'
    )
    (tmp_path / "plug.toml").write_text(text, encoding="utf-8")
    (tmp_path / "pd_gravity_plugin.py").write_text(
        (plug.parent / "pd_gravity_plugin.py").read_text(), encoding="utf-8"
    )
    (tmp_path / "pd_gravity_python.py").write_text(
        (plug.parent / "pd_gravity_python.py").read_text(), encoding="utf-8"
    )
    differ = floor_mismatches(load_scenario(tmp_path / "plug.toml"))
    assert list(differ) == ["pd_gravity_plugin:PDGravityPlugin"]
    assert differ["pd_gravity_plugin:PDGravityPlugin"][0].startswith(
        "controllers.PDGravityPlugin.bandwidth = 20.0 but"
    )
