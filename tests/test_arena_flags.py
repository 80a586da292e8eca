"""The leaderboard's honesty flags (adaptive_dd.arena.flags), its worker processes
(adaptive_dd.arena.pool) and the one BLAS thread it runs under (threadpoolctl)."""

from __future__ import annotations

import numpy as np
import pytest

from adaptive_dd.arena.flags import LOST_ERROR, lost_times, trial_flags


def _cell(segment, t0, sat, lost_t, fail_t=(np.nan, np.nan), why=("", ""), sat_t=None):
    sat_t = np.where(np.asarray(sat, float) > 0, t0, np.nan) if sat_t is None else sat_t
    return {
        "scenario": "z1", "controller": "slotine_li", "segment": segment, "t0": t0, "seed": np.array([0, 1]),
        "sat": np.asarray(sat, float), "lost_t": np.asarray(lost_t, float), "sat_t": np.asarray(sat_t, float),
        "fail_t": np.asarray(fail_t, float),
        "why": list(why),
    }  # fmt: skip


def test_lost_times_is_the_first_sample_beyond_the_limit_per_segment():
    T = 0.01
    e0 = np.array([[0.0, 0.1, 0.3, 0.5], [0.0, 0.0, 0.0, 0.0]])
    e1 = np.array([[0.1, 0.1], [0.1, LOST_ERROR + 1e-9]])
    t = lost_times([e0, e1, None], [0.0, 2.0, 4.0], T, 2)
    assert t[0, 0] == pytest.approx(0.02) and np.isnan(t[1, 0])
    assert np.isnan(t[0, 1]) and t[1, 1] == pytest.approx(2.01)
    assert np.all(np.isnan(t[:, 2]))


def test_a_trial_saturated_from_the_start_is_flagged_from_the_start_not_at_its_failure():
    """The issue's Z1 trial: 94 % saturated from t = 0, failed at 7.632 s; the other seed reached
    0.54 rad in its last segment without failing. Both flagged from when it began, with reasons."""
    why = ("tracking error |e| = 3.1 rad, beyond max_error = 3 rad", "")
    cells = [
        _cell(0, 0.0, [0.94, 0.0], [np.nan, np.nan], (7.632, np.nan), why),
        _cell(1, 4.0, [0.97, 0.0], [5.5, np.nan], (7.632, np.nan), why),
        _cell(2, 8.0, [np.nan, 0.005], [np.nan, 9.25], (7.632, np.nan), why),  # 0.5 %: not saturated
    ]
    flags = {f["seed"]: f for f in trial_flags(cells)}
    assert set(flags) == {0, 1}
    first = flags[0]
    assert first["flag"] == "saturated" and first["t_s"] == 0.0
    assert "94.0 %" in first["reasons"][0] and "segment 0" in first["reasons"][0]
    assert any("failed at t = 7.632 s" in r and "max_error" in r for r in first["reasons"])
    assert [r.split()[0] for r in first["reasons"]] == ["command", "command", "|q_d", "failed"]  # time order
    second = flags[1]
    assert second["flag"] == "lost tracking" and second["t_s"] == pytest.approx(9.25)
    assert len(second["reasons"]) == 1 and "segment 2" in second["reasons"][0]


def test_a_saturation_flag_is_dated_to_its_first_saturated_sample_not_the_segments_start():
    cells = [
        _cell(0, 0.0, [0.0, 0.0], [np.nan, np.nan]),
        _cell(1, 4.0, [0.3, 0.005], [np.nan, np.nan], sat_t=[5.25, 4.5]),  # seed 1: 0.5 %, not flagged
    ]
    flags = trial_flags(cells)
    assert [(f["seed"], f["flag"], f["t_s"]) for f in flags] == [(0, "saturated", 5.25)]
    assert "from t = 5.250 s" in flags[0]["reasons"][0]


def test_a_trial_saturated_into_its_failure_is_flagged_saturated():
    """Saturated and failed in one segment: its saturation_fraction is blanked (NaN), so it read
    only 'failed'; the flags take the saturation over the samples it ran (``sat_flag``)."""
    cell = _cell(0, 0.0, [np.nan, 0.0], [np.nan, np.nan], (1.3, np.nan), ("runaway", ""), sat_t=[0.2, np.nan])
    cell["sat_flag"] = np.array([0.4, 0.0])
    (flag,) = trial_flags([cell])
    assert (flag["seed"], flag["flag"], flag["t_s"]) == (0, "saturated", 0.2) and "40.0 %" in flag["reasons"][
        0
    ]


def test_the_flags_saturation_counts_a_failed_trials_samples():
    """From a run: a trial that runs away and saturates before it fails has a finite ``sat_flag``
    over the samples it ran, where its blanked saturation_fraction is NaN."""
    import dataclasses

    from adaptive_dd.arena.leaderboard import _per_seed
    from adaptive_dd.benchmark.runner import run_benchmark
    from tests.test_result_schema import Unstable, _short

    sc = dataclasses.replace(_short("two_link", duration=3.0), controllers=("ct_oracle",))
    res = run_benchmark(sc, progress=False, controllers={"unstable": Unstable()})
    m = _per_seed(res, ["unstable"])["unstable"]
    seg = int(np.flatnonzero(np.isnan(m["saturation_fraction"][1]))[0])  # the segment it failed in
    assert np.isnan(m["saturation_fraction"][1, seg]) and m["sat_flag"][1, seg] > 0.01


def test_a_clean_trial_has_no_flag():
    assert trial_flags([_cell(0, 0.0, [0.0, 0.01], [np.nan, np.nan])]) == []


def test_a_failure_of_no_recorded_time_is_not_dated_to_zero():
    """A compiled plug-in that raised at 1.5 s was flagged "failed at t = 0.000 s" with t_s 0.0 in
    leaderboard.json (its failure time is not recorded: benchmark said so)."""
    cell = _cell(0, 0.0, [0.0, 0.0], [np.nan, np.nan], why=("ValueError in the compiled plug-in", ""))
    cell["failed_trial"] = np.array([True, False])
    (flag,) = trial_flags([cell])
    assert flag["seed"] == 0 and flag["t_s"] is None and flag["flag"] == "failed"
    assert flag["reasons"] == ["failed (time not recorded): ValueError in the compiled plug-in"]


def test_the_leaderboard_runs_its_units_with_blas_on_one_thread(monkeypatch):
    """The leaderboard's units run under one BLAS thread (threadpoolctl), and the count is restored."""
    import importlib

    from threadpoolctl import threadpool_info

    from adaptive_dd.arena import pool

    lb = importlib.import_module("adaptive_dd.arena.leaderboard")  # the module, not the function

    blas = [i for i in threadpool_info() if i["user_api"] == "blas"]
    if not blas:
        pytest.skip("no BLAS that threadpoolctl can control is loaded")
    before = [i["num_threads"] for i in blas]
    seen = []

    def run_units(run_unit, units, controllers, seeds, progress, workers, costs=None, design=None):
        seen.append([i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"])
        return []

    monkeypatch.setattr(pool, "run_units", run_units)
    lb.leaderboard([], ["ct_oracle"], seeds=1, arms=0)
    assert seen == [[1] * len(blas)]
    assert [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"] == before


def test_the_workers_take_the_largest_units_first():
    """Drawn arms with an excitation phase before scenarios without, more joints first, ties in
    order; the cost is each unit's joints squared, tripled by an excitation phase."""
    from types import SimpleNamespace

    from adaptive_dd.arena.leaderboard import unit_costs
    from adaptive_dd.arena.pool import largest_first
    from adaptive_dd.robots.random_arm import random_arm

    template = {"run": {"excite": 20.0}}
    units = [
        ("scenario", SimpleNamespace(n_joints=7, excite=0.0)),
        ("arm", (template, "t.toml", 0)),
        ("arm", (template, "t.toml", 3)),
        ("scenario", SimpleNamespace(n_joints=3, excite=0.0)),
        ("arm", ({"run": {}}, "t.toml", 3)),
    ]
    n0, n3 = random_arm(0).n_joints, random_arm(3).n_joints
    assert (n0, n3) == (3, 7)  # the drawn arms' joints this test is written for
    assert unit_costs(units) == [49.0, 27.0, 147.0, 9.0, 49.0]
    assert largest_first(unit_costs(units)) == [2, 0, 4, 1, 3]


def _fake_unit(u, controllers, seeds, progress, design=None):
    return ([u, design], 0.0, 0.0)


def _fake_design(u):
    return f"design of {u}"


def test_the_workers_design_the_other_units_while_the_first_runs():
    """With workers, the largest unit goes first, alone; every other one gets what ``design`` made of
    it in a task of its own (a drawn arm's excitation design, made while the first unit compiles
    the closed loop); with one worker, each unit designs its own."""
    from adaptive_dd.arena import pool

    units, costs = ["a", "b", "c"], [2.0, 3.0, 1.0]
    two = pool.run_units(_fake_unit, units, ("pd",), 1, False, 2, costs, _fake_design)
    assert [cells for cells, _, _ in two] == [["a", "design of a"], ["b", None], ["c", "design of c"]]
    one = pool.run_units(_fake_unit, units, ("pd",), 1, False, 1, costs, _fake_design)
    assert [cells for cells, _, _ in one] == [["a", None], ["b", None], ["c", None]]


def test_an_excitation_designed_beforehand_is_the_one_its_scenario_tracks():
    """``designed_excitation(name, reference)``: within the block, the scenario named so tracks that
    reference (no design of its own); after it, its own design again."""
    from types import SimpleNamespace

    from adaptive_dd.closed_loop import excitation_phase

    sc = SimpleNamespace(name="arm7", arm=None, source="arm7.toml", seed=0)
    ref = object()
    with excitation_phase.designed_excitation("arm7", ref):
        assert excitation_phase.excitation_reference(sc) is ref
    assert "arm7" not in excitation_phase._DESIGNED


def test_workers_must_be_a_positive_integer():
    from adaptive_dd.arena.leaderboard import leaderboard
    from adaptive_dd.errors import ParameterError

    for bad in (0, -1, 1.5, True):
        with pytest.raises(ParameterError, match="workers"):
            leaderboard([], ["pd"], workers=bad)


@pytest.mark.slow  # two worker processes load the closed loop's kernels (compiles them on a cold cache)
def test_two_workers_give_the_same_table_and_flags_as_one(tmp_path):
    from importlib import resources

    from adaptive_dd.arena.leaderboard import leaderboard
    from adaptive_dd.benchmark.scenario import load_scenario

    text = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload.toml").read_text("utf-8")
    text = text.replace("duration = 16.0", "duration = 1.6").replace("ramp = 1.0", "ramp = 0.2")
    head, _, _ = text.partition("[[payload]]")
    paths = []
    for k, mass in enumerate((1.0, 30.0)):  # 30 kg on the 3-joint arm: its laws saturate
        p = tmp_path / f"v3_{k}.toml"
        p.write_text(head + f"[[payload]]\nat = 0.8\nmass = {mass}\n", encoding="utf-8")
        paths.append(load_scenario(p))
    one = leaderboard(paths, ["pd_gravity"], seeds=2, workers=1)
    two = leaderboard(paths, ["pd_gravity"], seeds=2, workers=2)
    assert one.equals(two)
    assert one.attrs["flags"] == two.attrs["flags"]
    heavy = one[(one["scenario"] == paths[1].name) & (one["segment"] == 1)]
    assert heavy["saturated_seeds"].sum() + heavy["lost_seeds"].sum() + heavy["failures"].sum() > 0
    assert any(f["scenario"] == paths[1].name for f in one.attrs["flags"])


@pytest.mark.slow  # a recording loop of its own compiled for it: about 55 s of a fresh clone's default run
def test_the_loop_streams_each_segments_first_saturated_sample():
    """Per trial and segment, ``first_saturated`` is the first sample whose command saturated (as
    the recording has it), on the compiled and the Python path alike; NaN in a segment with none."""
    import tomllib
    from importlib import resources

    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.closed_loop.types import run_constants

    text = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload.toml").read_text("utf-8")
    data = tomllib.loads(text)
    data["run"] = {**data["run"], "duration": 1.2, "seeds": 2, "controllers": ["pd_gravity"]}
    data["reference"]["ramp"] = 0.2
    data["payload"] = [{"at": 0.4, "mass": 30.0}, {"at": 0.8, "mass": 0.0}]  # 30 kg: it saturates
    data.pop("controllers", None)
    sc = parse_scenario(data, "test.toml", name="v3_heavy")
    rc = run_constants(sc)
    runs = [run_closed_loop(sc, engine=e, keep_trajectories=2).runs["pd_gravity"] for e in ("auto", "python")]
    want = np.full((2, 3), np.nan)
    for i in range(2):
        hit = runs[0].saturated[i].any(axis=1)
        for s, (a, b) in enumerate(zip(rc.seg_start, rc.seg_end, strict=True)):
            if hit[a:b].any():
                want[i, s] = a + np.argmax(hit[a:b])
    np.testing.assert_array_equal(runs[0].acc.first_saturated, want)
    np.testing.assert_array_equal(runs[1].acc.first_saturated, want)
    assert np.isfinite(want[:, 1]).all() and (want[:, 1] > rc.seg_start[1]).any()  # not the segment's start


def _mapped_bytes_of_an_array(libc) -> int:
    """Bytes glibc holds in separately mapped blocks (``mallinfo2().hblkhd``) that a 64 MB array
    adds while it lives."""
    import ctypes

    class Info(ctypes.Structure):
        names = ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks")
        _fields_ = [(f, ctypes.c_size_t) for f in (*names, "fordblks", "keepcost")]

    libc.mallinfo2.restype = Info
    before = libc.mallinfo2().hblkhd
    a = np.ones(8 * 2**20)
    added = libc.mallinfo2().hblkhd - before
    del a
    return added


def test_the_units_reuse_freed_memory_and_the_defaults_come_back():
    """Within ``reused_memory`` a large array comes from the heap (what a freed one left is reused),
    where glibc's default maps each one afresh from the kernel (its zero pages faulted in); after
    the block the default is back. ``run_units`` runs each unit inside it, with its arguments."""
    from adaptive_dd.arena import pool

    libc = pool._libc()
    if libc is None or not hasattr(libc, "mallinfo2"):
        pytest.skip("not glibc >= 2.33: reused_memory does nothing here, or cannot be observed")
    size = 8 * 2**20 * 8
    assert _mapped_bytes_of_an_array(libc) >= size  # the default: mapped afresh
    with pool.reused_memory():
        assert _mapped_bytes_of_an_array(libc) == 0
    assert _mapped_bytes_of_an_array(libc) >= size
    seen = []

    def unit(u, controllers, seeds, progress):
        seen.append((u, controllers, seeds, progress, _mapped_bytes_of_an_array(libc)))
        return ([u], 0.0, 0.0)

    assert pool.run_units(unit, ["a", "b"], ("pd",), 2, False, 1) == [(["a"], 0.0, 0.0), (["b"], 0.0, 0.0)]
    assert seen == [("a", ("pd",), 2, False, 0), ("b", ("pd",), 2, False, 0)]


def test_nothing_is_lost_after_a_trial_failed():
    """A failed trial's arm is stopped while the reference runs on: its error past the failure is the
    failure's, not a loss of tracking (a plug-in failed at 0 s was flagged lost at 0.519, 4, 8 and 12 s,
    another kind of failure not at all)."""
    T = 0.01
    e = np.array([[0.0, 0.3, 0.3, 0.3], [0.0, 0.3, 0.3, 0.3]])
    t = lost_times([e, e], [0.0, 1.0], T, 2, until=np.array([np.inf, 0.02]))
    np.testing.assert_allclose(t[0], [0.01, 1.01])
    assert t[1, 0] == 0.01 and np.isnan(t[1, 1])  # lost before its failure at 0.02 s; nothing after
