"""Sweeps: grid expansion and validation, seed blocks, resume, failures, the table, a real cluster."""

from __future__ import annotations

import dataclasses
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import adaptive_dd.sweep as sweep_mod
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.errors import ParameterError
from adaptive_dd.sweep import plan_tasks, ratio_medians, run_cell, run_sweep
from adaptive_dd.sweep_spec import SweepError, load_sweep, parse_sweep

distributed = pytest.importorskip("distributed")

BASE = """
[run]
duration = 0.3
controllers = ["ct_oracle", "adaptive_ct"]
[[payload]]
at = 0.1
mass = 3.0
[[payload]]
at = 0.2
mass = 0.0
"""

SWEEP = """
[sweep]
scenario = "base.toml"
seeds = 2
block = 1
controllers = ["ct_oracle", "adaptive_ct"]
[grid]
payload_mass = [1.0, 6.0]
swap_time = [0.08, 0.12]
"""


def _write(tmp_path: Path, sweep: str = SWEEP, base: str = BASE) -> Path:
    (tmp_path / "base.toml").write_text(base)
    path = tmp_path / "sweep.toml"
    path.write_text(sweep)
    return path


@pytest.fixture(scope="module")
def client():
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as c,
    ):
        yield c


# ---- the sweep file ---------------------------------------------------------------------


def test_grid_expansion_applies_each_axis(tmp_path):
    text = SWEEP.replace("0.12]", "0.12]\nbandwidth = [30.0, 50.0]\nnoise_scale = [4.0]")
    text += "[grid.controller.adaptive_ct]\nboost_bandwidth = [150.0, 300.0]\n"
    sw = load_sweep(_write(tmp_path, text))
    base = load_scenario(tmp_path / "base.toml")
    assert len(sw.points) == 2 * 2 * 2 * 1 * 2
    assert [a for a, _ in sw.axes] == [
        "payload_mass",
        "swap_time",
        "bandwidth",
        "noise_scale",
        "adaptive_ct.boost_bandwidth",
    ]
    p = sw.points[-1]  # last axis fastest: the last value of every axis
    assert dict(p.values) == {
        "payload_mass": 6.0,
        "swap_time": 0.12,
        "bandwidth": 50.0,
        "noise_scale": 4.0,
        "adaptive_ct.boost_bandwidth": 300.0,
    }
    sc = p.scenario
    assert sc.swap_masses == (6.0, 0.0) and sc.swap_times == (0.12, 0.2)  # only payload 0 changes
    assert sc.bandwidth == 50.0
    np.testing.assert_allclose(sc.position_variance, 4 * np.asarray(base.position_variance))
    np.testing.assert_allclose(sc.velocity_variance, 4 * np.asarray(base.velocity_variance))
    assert p.settings_for("adaptive_ct") == {"boost_bandwidth": 300.0} and p.settings_for("ct_oracle") == {}
    assert sw.points[0].settings_for("adaptive_ct") == {"boost_bandwidth": 150.0}
    assert sw.points[1].settings_for("adaptive_ct") == {"boost_bandwidth": 300.0}
    assert sw.seed_blocks() == [(0,), (1,)]


def test_swap_index_selects_the_payload(tmp_path):
    text = SWEEP.replace("block = 1", "block = 1\nswap = 1").replace("[0.08, 0.12]", "[0.15, 0.25]")
    sw = load_sweep(_write(tmp_path, text))
    assert sw.points[-1].scenario.swap_times == (0.1, 0.25)
    assert sw.points[-1].scenario.swap_masses == (3.0, 6.0)


def test_identical_tasks_run_once(tmp_path):
    # ct_oracle takes no settings: its task is the same at both boost bandwidths
    text = SWEEP.replace("[1.0, 6.0]", "[1.0]").replace("[0.08, 0.12]", "[0.08]")
    text += "[grid.controller.adaptive_ct]\nboost_bandwidth = [150.0, 300.0]\n"
    tasks, cells = plan_tasks(load_sweep(_write(tmp_path, text)))
    assert len(cells) == 2 * 2 * 2  # points x controllers x blocks
    assert len(tasks) == 2 + 2 * 2  # ct_oracle once per block, adaptive_ct per boost bandwidth and block


def test_a_task_key_holds_the_code_so_other_code_runs_its_cells_again(tmp_path, monkeypatch):
    """Cells written by other code (a changed default) were reused by the same sweep command: the task
    key holds a hash of the package's sources (``_code_id``), so another one gives other keys."""
    import adaptive_dd.sweep_keys as keys_mod

    sw = load_sweep(_write(tmp_path))
    before = set(plan_tasks(sw)[0])
    assert set(plan_tasks(sw)[0]) == before  # the same code: the same keys (resume)
    monkeypatch.setattr(keys_mod, "_code_id", lambda: "other code")
    assert not set(plan_tasks(sw)[0]) & before


@pytest.mark.parametrize(
    ("edit", "needle"),
    [
        (("[grid]", "[grid]\nspeed = [1.0]"), "unknown key 'grid.speed'"),
        (
            ("[grid]", "[grid]\npayload_mas = [1.0]"),
            "'grid.payload_mas' (did you mean 'grid.payload_mass'?)",
        ),
        (("block = 1", "block = 0"), "key 'sweep.block' must be an integer >= 1"),
        (("seeds = 2", "seeds = 2.5"), "key 'sweep.seeds' must be an integer"),
        (("[0.08, 0.12]", "[0.08, 0.25]"), "key 'grid.swap_time' = 0.25 s"),
        (("[1.0, 6.0]", "[1.0, -2.0]"), "key 'grid.payload_mass': mass must be >= 0"),
        (("[1.0, 6.0]", "[1.0, 1.0]"), "key 'grid.payload_mass' lists a value twice"),
        (("[1.0, 6.0]", '["heavy"]'), "key 'grid.payload_mass': values must be numbers"),
        (('"ct_oracle", "adaptive_ct"]', '"ct_oracle", "mpc"]'), "unknown controller 'mpc'"),
        (('"ct_oracle", "adaptive_ct"]', '"ct_oracle", "my_laws:PD"]'), "'my_laws:PD' is a plug-in; a sweep"),
        (('"base.toml"', '"nope.toml"'), "key 'sweep.scenario': no such scenario file"),
        (("block = 1", "block = 1\nswap = 2"), "key 'sweep.swap' = 2"),
        (("block = 1", "block = 1\nduration = 0.15"), "= 0.15 s ends before the scenario's swap at 0.2 s"),
        (("[grid]", "[heatmap]\nx = 'mass'\n[grid]"), "key 'heatmap.x' = 'mass' must name a grid axis"),
        (("[grid]", "[heatmap]\nfloor = 'pd'\n[grid]"), "key 'heatmap.floor' = 'pd' is not in"),
        (("[grid]", "[heatmap]\nsegment = 3\n[grid]"), "key 'heatmap.segment' = 3"),
        (("[grid]", "[grid.controller.pd]\nkp = [1]\n[grid]"), "key 'grid.controller.pd'"),
        (("[sweep]", "[sweeps]"), "unknown table [sweeps]"),
    ],
)
def test_validation_names_file_key_and_reason(tmp_path, edit, needle):
    path = _write(tmp_path, SWEEP.replace(*edit))
    with pytest.raises(SweepError) as info:
        load_sweep(path)
    assert str(path) in str(info.value)
    assert needle in str(info.value)


def test_a_plug_in_in_the_scenarios_list_is_named_there_not_in_the_sweeps(tmp_path):
    """With no sweep.controllers the sweep reads the scenario's run.controllers; a plug-in there was
    blamed on 'sweep.controllers', a key the file does not have."""
    sweep = SWEEP.replace('controllers = ["ct_oracle", "adaptive_ct"]\n', "")
    base = BASE.replace(
        'controllers = ["ct_oracle", "adaptive_ct"]', 'controllers = ["ct_oracle", "my_laws:PD"]'
    )
    with pytest.raises(SweepError) as info:
        load_sweep(_write(tmp_path, sweep, base))
    msg = str(info.value)
    assert (
        "base.toml's run.controllers (the sweep gives no sweep.controllers): 'my_laws:PD' is a plug-in" in msg
    )
    assert "set sweep.controllers to some of those" in msg and "key 'sweep.controllers'" not in msg


def test_sweep_error_is_a_value_error():
    with pytest.raises(ValueError, match="unknown table"):
        parse_sweep({"grids": {}}, "x.toml")


def test_default_heatmap_axes_and_one_row_with_one_axis(tmp_path):
    assert load_sweep(_write(tmp_path)).heatmap == {
        "x": "payload_mass",
        "y": "swap_time",
        "adaptive": "adaptive_ct",
        "floor": "ct_oracle",
        "segment": 1,
    }
    one_axis = SWEEP.replace("swap_time = [0.08, 0.12]\n", "")
    # one varied axis: a map of one row (the sweep wrote no ratios.csv, no table and no figure at all)
    assert load_sweep(_write(tmp_path, one_axis)).heatmap == {
        "x": "payload_mass",
        "y": None,
        "adaptive": "adaptive_ct",
        "floor": "ct_oracle",
        "segment": 1,
    }
    with pytest.raises(SweepError, match=r"key 'heatmap.y' = 'swap_time' must name a grid axis"):
        load_sweep(_write(tmp_path, one_axis + '\n[heatmap]\nx = "payload_mass"\ny = "swap_time"\n'))


# ---- seeds, cells and the table ---------------------------------------------------------------


def test_seed_block_equals_the_same_seeds_in_a_full_run(tmp_path):
    sc = dataclasses.replace(load_scenario(_write(tmp_path).parent / "base.toml"), seeds=3)
    full = run_benchmark(sc, progress=False)
    part = run_benchmark(sc, progress=False, seed_indices=[2, 1])
    for name in sc.controllers:
        np.testing.assert_array_equal(part.runs[name].q, full.runs[name].q[[2, 1]])
        np.testing.assert_array_equal(part.runs[name].tau, full.runs[name].tau[[2, 1]])
    rows = run_cell(sc, "adaptive_ct", [1])
    both = run_cell(sc, "adaptive_ct", [0, 1])
    assert rows == [r for r in both if r["seed"] == 1]
    assert rows != [dict(r, seed=1) for r in both if r["seed"] == 0]  # the seeds differ


def test_cells_in_threads_say_nothing_of_the_floor_they_leave_out(tmp_path):
    """A cell runs one controller without its floor and says nothing of it, from any thread: the
    run is told by a keyword (a warnings filter is process-wide state, not a thread's); a run
    left to warn still warns."""
    import warnings
    from concurrent.futures import ThreadPoolExecutor

    sc = load_scenario(_write(tmp_path).parent / "base.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any warning of the cells' runs fails the test
        with ThreadPoolExecutor(2) as pool:
            cells = list(pool.map(lambda s: run_cell(sc, "adaptive_ct", [s]), [0, 1]))
    assert all(r["seed"] == s for s, rows in enumerate(cells) for r in rows)
    with pytest.warns(UserWarning, match="adaptive_ct's floor ct_oracle did not run"):
        run_benchmark(dataclasses.replace(sc, controllers=("adaptive_ct",), seeds=1), progress=False)


def test_run_cell_rows_match_the_trajectory(tmp_path):
    sc = load_scenario(_write(tmp_path).parent / "base.toml")
    rows = run_cell(sc, "ct_oracle", [0])
    res = run_benchmark(dataclasses.replace(sc, seeds=1), progress=False, controllers=None)
    en = np.sqrt(((res.q_d - res.runs["ct_oracle"].q[0]) ** 2).sum(axis=-1))
    assert [(r["start"], r["end"], r["mass"]) for r in rows] == sc.segments()
    for r in rows:
        seg = en[round(r["start"] / sc.sample_period) : round(r["end"] / sc.sample_period)]
        assert r["rms_error"] == pytest.approx(np.sqrt(np.mean(seg**2)), rel=1e-12)
        assert r["max_error"] == pytest.approx(seg.max(), rel=1e-12)
        assert not r["failed"] and r["error"] == ""


def test_run_cell_detection_delays_are_the_benchmarks_per_seed_rows(tmp_path):
    """Each segment's delay from its swap to the first alarm, as the benchmark's per-seed table has
    it (``to_frame``: its own path from the alarm times); none in the first segment or without a
    detector."""
    from adaptive_dd.benchmark.results import to_frame

    base = BASE.replace("duration = 0.3", "duration = 2.0").replace("at = 0.1", "at = 1.0")
    base = base.replace("at = 0.2", "at = 1.5")  # late enough for the detector's warm-up
    sc = dataclasses.replace(load_scenario(_write(tmp_path, base=base).parent / "base.toml"), seeds=2)
    frame = to_frame(run_benchmark(sc, progress=False)).set_index(["controller", "seed", "segment"])
    for name in ("adaptive_ct", "ct_oracle"):
        rows = run_cell(sc, name, [0, 1])
        assert {r["detector"] for r in rows} == {name == "adaptive_ct"}
        for r in rows:
            want = frame.loc[(name, r["seed"], r["segment"]), "detection_delay_s"]
            if np.isnan(want):
                assert np.isnan(r["detection_delay"]), (name, r)
            else:
                assert r["detection_delay"] == pytest.approx(want, abs=1e-12), (name, r)
    delays = [r["detection_delay"] for r in run_cell(sc, "adaptive_ct", [0, 1]) if r["segment"] > 0]
    assert np.isfinite(delays).all() and 0.0 <= min(delays) and max(delays) < 0.1  # the swaps are found


def test_ratio_medians_give_the_adaptive_laws_median_delay_and_its_missed_swaps():
    """Over the seeds that finished the segment: the median of the delays of those with an alarm,
    and the count of those without; NA for a law with no detector."""
    rows = []
    for seed, (d, failed) in enumerate([(0.010, False), (0.030, False), (np.nan, False), (0.001, True)]):
        for c in ("adaptive_ct", "ct_oracle"):
            own = c == "adaptive_ct"
            rows.append({
                "point": 0, "m": 1.0, "controller": c, "seed": seed, "segment": 1, "rms_error": 1.0,
                "detector": own, "detection_delay": d if own else np.nan, "failed": failed and own,
            })  # fmt: skip
    t = pd.DataFrame(rows)
    r = ratio_medians(t, {"adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}, ["m"])
    assert r["delay_median"].item() == pytest.approx(0.020)  # seeds 0 and 1; seed 3 failed
    assert r["missed"].item() == 1  # seed 2
    r = ratio_medians(t, {"adaptive": "ct_oracle", "floor": "adaptive_ct", "segment": 1}, ["m"])
    assert np.isnan(r["delay_median"].item()) and pd.isna(r["missed"].item())
    old = t.drop(columns=["detector", "detection_delay"])  # a table of before the columns
    r = ratio_medians(old, {"adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}, ["m"])
    assert np.isnan(r["delay_median"].item()) and pd.isna(r["missed"].item())


def test_diverging_trial_fails_from_its_segment_on(tmp_path):
    wild = """
[run]
duration = 0.3
controllers = ["ct_oracle"]
[reference]
ramp = 0.1
joint1 = { amplitude = [10.0], frequency = [1.5] }
joint2 = { amplitude = [0.1], frequency = [1.0] }
[[payload]]
at = 0.03
mass = 1.0
"""
    sc = load_scenario(_write(tmp_path, base=wild).parent / "base.toml")
    rows = run_cell(sc, "ct_oracle", [0])
    assert [r["failed"] for r in rows] == [False, True]
    assert np.isfinite(rows[0]["rms_error"]) and np.isnan(rows[1]["rms_error"])
    assert rows[1]["error"].startswith("trial diverged at t = ")


def test_sweep_table_columns_and_order(tmp_path, client):
    sw = load_sweep(_write(tmp_path))
    res = run_sweep(sw, tmp_path / "out", client=client, progress=False)
    t = res.table
    assert list(t.columns) == [
        "point",
        "payload_mass",
        "swap_time",
        "controller",
        "seed",
        "segment",
        "start",
        "end",
        "mass",
        "rms_error",
        "max_error",
        "saturation_fraction",
        "detector",
        "detection_delay",
        "failed",
        "error",
        "task",
    ]
    assert len(t) == 4 * 2 * 2 * 3  # points x controllers x seeds x segments
    assert t.groupby(["point", "controller", "seed"]).size().eq(3).all()
    row = t[(t.point == 3) & (t.controller == "adaptive_ct") & (t.seed == 1) & (t.segment == 1)]
    assert row[["payload_mass", "swap_time", "start", "mass"]].values.tolist() == [[6.0, 0.12, 0.12, 6.0]]
    expected = run_cell(sw.points[3].scenario, "adaptive_ct", [1])[1]["rms_error"]
    assert row["rms_error"].item() == expected
    assert res.failed_rows == 0 and res.ran == 16 and res.reused == 0
    on_disk = pd.read_parquet(res.table_path) if res.table_path.suffix == ".parquet" else None
    if on_disk is not None:
        pd.testing.assert_frame_equal(on_disk, t, check_dtype=False)
    # the ratios' heat map, then adaptive_ct's delays' (no alarm in these 0.3 s trials: "none")
    assert [p.name for p in res.heatmaps] == ["heatmap.png", "delays.png"]
    assert all(p.stat().st_size > 0 for p in res.heatmaps)


def test_resume_reads_cells_and_gives_the_same_table(tmp_path, client):
    sw = load_sweep(_write(tmp_path))
    out = tmp_path / "out"
    first = run_sweep(sw, out, client=client, progress=False)
    cells = sorted((out / "cells").iterdir())
    assert len(cells) == 16 and not any(p.name.endswith(".tmp") for p in cells)
    cells[0].unlink()  # as if interrupted before this task finished
    again = run_sweep(sw, out, client=client, progress=False)
    assert (again.reused, again.ran) == (15, 1)
    pd.testing.assert_frame_equal(again.table, first.table)
    # a reused cell is read, not recomputed: doctor one and see it in the table
    doctored = pd.read_parquet(cells[1]) if cells[1].suffix == ".parquet" else pd.read_csv(cells[1])
    doctored["rms_error"] = 123.0
    doctored.to_parquet(cells[1]) if cells[1].suffix == ".parquet" else doctored.to_csv(cells[1])
    third = run_sweep(sw, out, client=client, progress=False)
    assert third.ran == 0
    assert (third.table.loc[third.table.task == cells[1].stem, "rms_error"] == 123.0).all()


def test_csv_cells_without_pyarrow(tmp_path, client, monkeypatch):

    sw = load_sweep(_write(tmp_path))
    monkeypatch.setattr(sweep_mod, "_have_parquet", lambda: False)
    first = run_sweep(sw, tmp_path / "out", client=client, progress=False)
    assert first.table_path.name == "results.csv"
    assert {p.suffix for p in (tmp_path / "out" / "cells").iterdir()} == {".csv"}
    again = run_sweep(sw, tmp_path / "out", client=client, progress=False)
    assert again.reused == 16
    pd.testing.assert_frame_equal(again.table, first.table)  # the CSV gives every float back exactly
    assert (again.table["error"] == "").all()
    umask = os.umask(0o022)
    os.umask(umask)
    for f in (first.table_path, *(tmp_path / "out" / "cells").iterdir()):  # as open() makes them
        assert f.stat().st_mode & 0o777 == 0o666 & ~umask, f


def _planted_failure(monkeypatch, controllers=("adaptive_ct",)):
    """Tasks of ``controllers`` raise when they run (a worker's failure; every setting is checked
    when the sweep file is read, so no bad setting reaches a task)."""

    def planted(scenario, controller, seeds, settings):
        if controller in controllers:
            raise ParameterError(f"planted bogus failure of {controller}")
        return run_cell(scenario, controller, seeds, settings)  # the module's own

    monkeypatch.setattr(sweep_mod, "run_cell", planted)


def test_failing_task_is_recorded_and_the_sweep_completes(tmp_path, client, monkeypatch):
    _planted_failure(monkeypatch)
    text = SWEEP + "[grid.controller.adaptive_ct]\nboost_bandwidth = [150.0, 300.0]\n"
    sw = load_sweep(_write(tmp_path, text))
    res = run_sweep(sw, tmp_path / "out", client=client, progress=False)
    t = res.table
    bad = t[t.controller == "adaptive_ct"]
    assert bad["failed"].all() and bad["rms_error"].isna().all()
    assert bad["error"].str.contains("ParameterError").all() and bad["error"].str.contains("bogus").all()
    good = t[t.controller == "ct_oracle"]
    assert not good["failed"].any() and np.isfinite(good["rms_error"]).all()
    assert res.failed_rows == len(bad)
    assert ratio_medians(t, sw.heatmap, [a for a, _ in sw.axes])["n_seeds"].eq(0).all()
    assert sw.heatmap and res.heatmaps == []  # no ratio anywhere: no empty heat map drawn


def test_ratio_is_per_seed_then_median():
    rows = []
    for seed, (a, f) in enumerate([(2.0, 1.0), (9.0, 3.0), (1.0, 4.0)]):
        for c, v in (("adaptive_ct", a), ("ct_oracle", f)):
            rows.append({"point": 0, "m": 1.0, "controller": c, "seed": seed, "segment": 1, "rms_error": v})
    t = pd.DataFrame(rows)
    hm = {"adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}
    r = ratio_medians(t, hm, ["m"])
    assert r["ratio"].item() == 2.0  # median of 2, 3, 0.25 (a ratio of medians would be 2/3)
    assert r["n_seeds"].item() == 3


# ---- a cluster started separately ---------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _dask_cli() -> list[str]:
    exe = Path(sys.executable).parent / "dask"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "dask"]


@pytest.mark.slow
def test_separate_scheduler_and_worker_give_the_same_numbers(tmp_path, client):
    sw = load_sweep(_write(tmp_path))
    local = run_sweep(sw, tmp_path / "local", client=client, progress=False)
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    root = str(Path(__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=root, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
    opts = {"env": env, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "cwd": tmp_path}
    procs = [
        subprocess.Popen([*_dask_cli(), "scheduler", "--host", "127.0.0.1", "--port", str(port)], **opts)
    ]
    try:
        time.sleep(1.0)
        procs.append(
            subprocess.Popen([*_dask_cli(), "worker", address, "--nworkers", "1", "--nthreads", "1"], **opts)
        )
        with distributed.Client(address, timeout=60) as c:
            c.wait_for_workers(1, timeout=120)
        remote = run_sweep(sw, tmp_path / "remote", scheduler=address, progress=False)
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
    assert remote.ran == 16
    pd.testing.assert_frame_equal(remote.table, local.table)


# ---- the command line ---------------------------------------------------------------------


def test_cli_reports_a_bad_sweep_file(tmp_path, capsys):
    from adaptive_dd.cli import main

    path = _write(tmp_path, SWEEP.replace("block = 1", "block = -1"))
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "adaptive-dd sweep: error:" in err and "key 'sweep.block'" in err and str(path) in err
    with pytest.raises(SystemExit) as e:
        main(["sweep", str(_write(tmp_path)), "--block", "0"])
    assert e.value.code == 2 and "--block: 0 is outside" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_runs_on_a_local_cluster_and_resumes(tmp_path, capsys):
    from adaptive_dd.cli import main

    path = _write(tmp_path)
    out = tmp_path / "out"
    args = ["sweep", str(path), "--out", str(out), "--workers", "1", "--no-progress"]
    assert main([*args, "--block", "2"]) == 0
    first = capsys.readouterr().out
    assert "8 tasks run, 0 reused" in first and "heatmap.png" in first and "swap_time" in first
    assert main(args) == 0
    assert "16 tasks run, 0 reused" in capsys.readouterr().out  # blocks of 1 seed are new tasks
    assert main(args) == 0
    assert "0 tasks run, 16 reused" in capsys.readouterr().out


def test_one_heatmap_per_combination_of_the_other_axes(tmp_path):
    from adaptive_dd.sweep_plot import plot_ratio_heatmaps

    grid = [(m, t, bw) for bw in (30.0, 50.0) for m in (1.0, 5.0) for t in (0.1, 0.2)]
    ratios = pd.DataFrame(
        [
            {"point": i, "m": m, "t": t, "bw": bw, "ratio": 1.0 + i, "n_seeds": 2}
            for i, (m, t, bw) in enumerate(grid)
        ]
    )
    hm = {"x": "m", "y": "t", "adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}
    paths = plot_ratio_heatmaps(ratios, hm, ["m", "t", "bw"], tmp_path)
    assert [p.name for p in paths] == ["heatmap_0.png", "heatmap_1.png"]
    assert all(p.stat().st_size > 0 for p in paths)
    assert [p.name for p in plot_ratio_heatmaps(ratios[ratios.bw == 30.0], hm, ["m", "t"], tmp_path)] == [
        "heatmap.png"
    ]


def test_a_sweep_of_one_axis_draws_one_row(tmp_path):
    from adaptive_dd.sweep_plot import _figure, plot_ratio_heatmaps

    ratios = pd.DataFrame({"m": [1.0, 3.0], "ratio": [1.1, 1.3], "n_seeds": [2, 2], "marked": ["", "x"]})
    hm = {"x": "m", "y": None, "adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}
    assert [p.name for p in plot_ratio_heatmaps(ratios, hm, ["m"], tmp_path)] == ["heatmap.png"]
    ax = _figure(ratios, hm, "t").axes[0]
    assert ax.images[0].get_array().shape == (1, 2) and list(ax.get_yticks()) == []
    assert [c.get_gid() for c in ax.patches] == ["marked"]


def _thread_env() -> dict:
    keys = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")
    return {k: os.environ.get(k) for k in keys}


@pytest.mark.slow
def test_local_cluster_workers_are_single_threaded():
    from adaptive_dd.sweep import WORKER_ENV, _client

    client, cluster = _client(None, 1)
    try:
        info = client.scheduler_info()["workers"]
        assert [w["nthreads"] for w in info.values()] == [1]
        assert list(client.run(_thread_env).values()) == [WORKER_ENV]
    finally:
        client.close()
        cluster.close()


_NUMBA_IN_MAIN = """
import numba  # the main module imports numba, as the adaptive-dd command does: a spawned worker
from adaptive_dd.sweep import _client  # re-imports it before Dask sets the worker's environment


def threads():
    import numba

    return numba.config.NUMBA_NUM_THREADS


if __name__ == "__main__":
    client, cluster = _client(None, 1)
    print(list(client.run(threads).values()))
    client.restart()  # a worker the nanny starts again (after a crash or a memory kill)
    print(list(client.run(threads).values()))
    client.close()
    cluster.close()
"""


@pytest.mark.slow
def test_workers_numba_reads_one_thread_when_the_main_module_imported_numba(tmp_path):
    # numba reads its thread count when imported; a worker that read 2 while its environment said 1
    # refused to run a kernel it compiled ("Cannot set NUMBA_NUM_THREADS to a different value once
    # the threads have been launched"): every adaptive_ct row of the general sweep failed
    script = tmp_path / "main.py"
    script.write_text(_NUMBA_IN_MAIN)
    env = {**os.environ, "NUMBA_NUM_THREADS": "2"}  # the user's shell, on a 2-core machine
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-2:] == ["[1]", "[1]"]


# ---- any arm; failures said ---------------------------------------------------------------

URDF_BASE = """
[arm]
robot = "vertical3"
[run]
duration = 0.3
controllers = ["ct_oracle", "adaptive_ct"]
[reference]
ramp = 0.2
joint1 = { offset = 0.3, amplitude = [0.4, 0.1], frequency = [0.3, 0.9], phase = [0.0, 0.4] }
joint2 = { offset = -0.6, amplitude = [0.5, 0.15], frequency = [0.4, 1.1], phase = [0.5, 0.0] }
joint3 = { offset = 0.4, amplitude = [0.6, 0.2], frequency = [0.5, 1.3], phase = [0.0, 0.8] }
[[payload]]
at = 0.1
mass = 1.0
"""


def test_a_cell_runs_on_a_urdf_arm_with_the_scenario_settings(tmp_path):
    """Issue 27: every row of a sweep on a URDF arm failed with 'sigma must have shape (..., 7)'."""
    base = URDF_BASE + "[controllers.adaptive_ct]\nboost_duration = 0.3\n"
    text = SWEEP.replace("payload_mass = [1.0, 6.0]", "payload_mass = [2.0]")
    sw = load_sweep(_write(tmp_path, text, base))
    sc = sw.points[0].scenario
    assert sc.n_joints == 3
    rows = run_cell(sc, "ct_oracle", [0])
    assert len(rows) == 2 and not any(r["failed"] for r in rows)
    assert all(np.isfinite(r["rms_error"]) and r["error"] == "" for r in rows)
    # the same numbers as the benchmark's trial of that seed
    one = dataclasses.replace(sc, controllers=("ct_oracle",), controller_options=())
    res = run_benchmark(one, progress=False, seed_indices=[0])
    np.testing.assert_allclose(
        [r["rms_error"] for r in rows], res.to_frame()["rms_error_rad"].to_numpy(), rtol=1e-12
    )
    # the scenario's [controllers.adaptive_ct] table applies, the grid's settings over it
    from adaptive_dd.sweep_spec import cell_scenario

    cell = cell_scenario(sc, "adaptive_ct", {"boost_bandwidth": 150.0})
    assert cell.controllers == ("adaptive_ct",)
    assert cell.options("adaptive_ct") == {"boost_duration": 0.3, "boost_bandwidth": 150.0}


def test_a_two_link_only_controller_is_refused_on_a_urdf_arm(tmp_path):
    text = SWEEP.replace('controllers = ["ct_oracle", "adaptive_ct"]', 'controllers = ["adaptive_ct_paper"]')
    with pytest.raises(SweepError, match="controller 'adaptive_ct_paper' is not for this 3-joint arm"):
        load_sweep(_write(tmp_path, text.replace("[grid]", "[grid]"), URDF_BASE))


def test_cli_a_sweep_whose_rows_all_fail_exits_1_without_a_heat_map(tmp_path, capsys, monkeypatch):
    """Issue 27: '72 rows (72 failed)' and exit code 0 with an empty heat map."""
    from adaptive_dd.cli import main

    def local(scheduler, workers):
        cluster = distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0"
        )
        return distributed.Client(cluster), cluster

    monkeypatch.setattr(sweep_mod, "_client", local)
    text = SWEEP.replace("payload_mass = [1.0, 6.0]", "payload_mass = [1.0]").replace("0.08, 0.12", "0.12")
    text = text.replace("seeds = 2", "seeds = 1")
    _planted_failure(monkeypatch, ("adaptive_ct", "ct_oracle"))
    out = tmp_path / "out"
    assert main(["sweep", str(_write(tmp_path, text)), "--out", str(out), "--no-progress"]) == 1
    cap = capsys.readouterr()
    assert "error: 6 of 6 rows failed (in 2 task(s))" in cap.err and "bogus" in cap.err
    assert "no heat map drawn" in cap.err and not list(out.glob("heatmap*"))
    assert not list((out / "cells").iterdir())  # failed tasks are not cached: a rerun tries again
    # partly failed: exit 0, and how many failed and why
    _planted_failure(monkeypatch, ("adaptive_ct",))
    assert main(["sweep", str(_write(tmp_path, text)), "--out", str(out), "--no-progress"]) == 0
    cap = capsys.readouterr()
    assert "warning: 3 of 6 rows failed (in 1 task(s)); why:" in cap.err and "bogus" in cap.err


def _marks_table(floor_sat: float, floor_seg1: float) -> pd.DataFrame:
    """Two grid points, 3 seeds: point 0 a plain cell; point 1 whose floor has ``floor_sat``
    saturation and ``floor_seg1`` RMS error [rad] after the swap (1e-4 before it)."""
    rows = []
    for p in (0, 1):
        for seed in range(3):
            for seg, (a, f, sat) in enumerate([(1e-4, 1e-4, 0.0), (2e-4, 1e-4, 0.0)]):
                if p == 1 and seg == 1:
                    f, sat = floor_seg1, floor_sat
                for c, v, s in (("adaptive_ct", a, 0.0), ("ct_oracle", f, sat)):
                    rows.append(
                        {"point": p, "m": [1.0, 10.0][p], "w": 0.0, "controller": c, "seed": seed,
                         "segment": seg, "rms_error": v, "saturation_fraction": s}
                    )  # fmt: skip
    return pd.DataFrame(rows)


def test_the_cli_prints_each_cells_median_delay_and_missed_swaps(tmp_path, capsys):
    """Below the ratios, the adaptive law's median delay to its first alarm per cell [ms] with the
    seeds that raised none, in the heat map's rows and columns; nothing for a law with no detector."""
    import types

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.cli.sweep import _print_heatmap
    from adaptive_dd.sweep import _heatmaps

    t = _marks_table(0.0, 1e-4).assign(failed=False, detector=False, detection_delay=np.nan)
    mine = (t.controller == "adaptive_ct") & (t.segment == 1)
    t.loc[mine, "detector"] = True
    # point 0 (m = 1): 12, 20, 31 ms; point 1 (m = 10): 7 ms and two seeds without an alarm
    t.loc[mine, "detection_delay"] = [0.012, 0.031, 0.020, 0.007, np.nan, np.nan]
    hm = {"x": "m", "y": "w", "adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}
    sw = types.SimpleNamespace(
        heatmap=hm, axes=[("m", [1.0, 10.0]), ("w", [0.0])], base=load_scenario(), points=()
    )
    ratios, maps = _heatmaps(sw, t, tmp_path)
    _print_heatmap(types.SimpleNamespace(ratios=ratios, heatmaps=maps), sw)
    out = capsys.readouterr().out
    assert "median delay from the swap to adaptive_ct's first alarm [ms], segment 1" in out
    row = out.split("first alarm [ms]")[1].splitlines()[3]  # title, columns, index name, w = 0.0
    assert row.split() == ["0.0", "20", "7", "(2)"], out
    on_disk = pd.read_csv(tmp_path / "ratios.csv")
    assert on_disk["missed"].tolist() == [0, 2] and on_disk["delay_median"].tolist() == [0.020, 0.007]
    assert [p.name for p in maps] == ["heatmap.png", "delays.png"]
    from adaptive_dd.sweep_plot import _delay_figure

    texts = [t.get_text() for t in _delay_figure(ratios, hm, "t").axes[0].texts]
    assert texts == ["20", "7\n(2 missed)"]  # each cell's median [ms] and its seeds without an alarm
    hm_floor = dict(hm, adaptive="ct_oracle", floor="adaptive_ct")  # no detector: no delay table
    sw = types.SimpleNamespace(heatmap=hm_floor, axes=sw.axes, base=sw.base, points=())
    ratios, maps = _heatmaps(sw, t, tmp_path)
    _print_heatmap(types.SimpleNamespace(ratios=ratios, heatmaps=maps), sw)
    assert "first alarm" not in capsys.readouterr().out
    assert [p.name for p in maps] == ["heatmap.png"]  # nor a delays' heat map


@pytest.mark.parametrize(
    ("floor_sat", "floor_seg1", "why"),
    [(0.3, 1e-4, "saturated in 30 %"), (0.0, 4.2e-2, "420 x its 0.1 mrad"), (0.005, 4.9e-4, "")],
)
def test_a_cell_whose_floor_is_no_floor_is_marked(floor_sat, floor_seg1, why, tmp_path):
    """A cell whose floor saturates beyond the benchmark's limit (1 %), or sits far from its own
    error before the swap (more than FLOOR_FAR = 5 times), is marked with the reason; below both
    limits (0.5 %, 4.9 x) it is not; the heat map hatches exactly the marked cells."""
    from adaptive_dd.sweep_plot import _figure

    hm = {"x": "m", "y": "w", "adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}
    r = ratio_medians(_marks_table(floor_sat, floor_seg1), hm, ["m", "w"])
    assert r.loc[0, "marked"] == ""
    assert r.loc[0, "floor_rms"] == pytest.approx(1e-4) and r.loc[0, "floor_nominal_rms"] == pytest.approx(
        1e-4
    )
    if why:
        assert why in r.loc[1, "marked"] and "ct_oracle" in r.loc[1, "marked"]
    else:
        assert r.loc[1, "marked"] == ""
    fig = _figure(r, hm, "t")
    hatched = [p for p in fig.axes[0].patches if p.get_gid() == "marked"]
    assert len(hatched) == (1 if why else 0)
    if why:
        assert hatched[0].get_xy() == (0.5, -0.5)  # the 10 kg column's cell


def test_the_ratios_csv_and_the_cli_count_the_marked_cells(tmp_path, capsys):
    """``OUT/ratios.csv`` holds every cell with its mark; the command says how many are marked,
    why, and the median ratio of the marked and the other cells."""
    import types

    from adaptive_dd.cli.sweep import _print_heatmap
    from adaptive_dd.sweep import _heatmaps

    t = _marks_table(0.3, 4.2e-2).assign(failed=False)
    hm = {"x": "m", "y": "w", "adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}
    from adaptive_dd.benchmark.scenario import load_scenario

    sw = types.SimpleNamespace(
        heatmap=hm, axes=[("m", [1.0, 10.0]), ("w", [0.0])], base=load_scenario(), points=()
    )
    ratios, maps = _heatmaps(sw, t, tmp_path)
    on_disk = pd.read_csv(tmp_path / "ratios.csv", keep_default_na=False)
    assert list(on_disk["marked"] != "") == [False, True] and len(maps) == 1
    _print_heatmap(types.SimpleNamespace(ratios=ratios, heatmaps=maps), sw)
    out = capsys.readouterr().out
    assert "1 of 2 cells marked" in out
    assert "marked: median ratio per cell 0.0" in out and "not marked: median ratio per cell 2 .. 2" in out


def test_the_docs_sweep_file_parses_and_a_bad_grid_setting_names_the_sweep_file(tmp_path):
    """The sweep file shown in docs/sweeps.md is a valid sweep (on the shipped short scenario),
    and a grid of controller settings is checked when the file is read, naming the grid key and
    the point: an unknown setting, a value out of range, a bandwidth the sample period cannot carry."""
    import re
    from pathlib import Path

    from adaptive_dd.sweep_spec import SweepError, load_sweep

    root = Path(__file__).resolve().parents[1]
    text = (root / "docs" / "sweeps.md").read_text()
    block = re.search(r"#+ The sweep file\n\n```toml\n(.*?)```", text, re.S).group(1)
    short = (root / "benchmarks" / "sweeps" / "short_swap.toml").as_posix()
    doc = tmp_path / "doc.toml"
    doc.write_text(block.replace('"short_swap.toml"', f'"{short}"'))
    sw = load_sweep(doc)
    assert len(sw.points) == 5 * 5 * 2 * 2 * 2
    assert sw.points[1].settings_for("adaptive_ct") == {"boost_bandwidth": 300.0}
    head = f'[sweep]\nscenario = "{short}"\nseeds = 1\ncontrollers = ["ct_oracle", "adaptive_ct"]\n'
    bad = {
        "[grid.controller.adaptive_ct]\ntau_f = [0.006]\n": r"key 'grid.controller.adaptive_ct' \(at "
        r"adaptive_ct.tau_f = 0.006\): controllers.adaptive_ct: unknown setting",
        "[grid.controller.adaptive_ct]\nboost_duration = [0.5, 50.0]\n": r"boost_duration = 50.0\): "
        r"controllers.adaptive_ct.boost_duration: must be in \[0, 5\]",
        "[grid]\nbandwidth = [40.0, 400.0]\n": r"key 'grid.bandwidth' \(at bandwidth = 400.0\)",
        # the axis at fault alone, not every axis of the point
        "[grid]\npayload_mass = [1.0, 80.0]\nswap_time = [2.0]\n": r"key 'grid.payload_mass' \(at "
        r"payload_mass = 80.0, swap_time = 2.0\): payload\[0\].mass",
    }
    for grid, match in bad.items():
        f = tmp_path / "bad.toml"
        f.write_text(head + grid)
        with pytest.raises(SweepError, match=match):
            load_sweep(f)


@pytest.mark.parametrize("friction", ["stick-slip", "lugre"])
def test_the_cli_table_per_other_axis_names_its_heat_map_and_a_plant_friction_caveat(
    tmp_path, capsys, friction
):
    from types import SimpleNamespace

    from adaptive_dd.cli.sweep import _print_heatmap

    base = BASE + f'[plant]\nfriction = "{friction}"\n'
    sweep = SWEEP + "[grid.controller.adaptive_ct]\nboost_bandwidth = [150.0, 300.0]\n"
    sw = load_sweep(_write(tmp_path, sweep, base))
    rows = [
        {"point": i, "payload_mass": m, "swap_time": t, "adaptive_ct.boost_bandwidth": b, "ratio": r}
        for i, (m, t, b, r) in enumerate(
            (m, t, b, 1.0 + 0.1 * k)
            for k, (b, m, t) in enumerate(
                (b, m, t) for b in (150.0, 300.0) for m in (1.0, 6.0) for t in (0.08, 0.12)
            )
        )
    ]
    ratios = pd.DataFrame(rows).assign(
        n_seeds=2, floor_rms=1e-4, floor_nominal_rms=1e-4, floor_saturation=0.0
    )
    ratios["marked"] = ""
    _print_heatmap(SimpleNamespace(ratios=ratios, heatmaps=["h0", "h1"]), sw)
    out = capsys.readouterr().out
    assert "one table per adaptive_ct.boost_bandwidth" in out
    # the tables in the heat maps' order (plot_ratio_heatmaps: grid order), each naming its file
    assert out.index("adaptive_ct.boost_bandwidth = 150.0 (heatmap_0.png):") < out.index(
        "adaptive_ct.boost_bandwidth = 300.0 (heatmap_1.png):"
    )
    assert out.split("(heatmap_1.png):")[1].split("\n")[4].split()[-1] == "1.7"  # 6 kg at 0.12 s, 300 rad/s
    assert ("note: the plant's friction law (lugre)" in out) == (friction == "lugre")


def test_an_unreachable_scheduler_is_named_by_the_option():
    import dask

    from adaptive_dd.errors import ParameterError
    from adaptive_dd.sweep import _client

    with dask.config.set({"distributed.comm.timeouts.connect": "0.5s"}):
        with pytest.raises(ParameterError, match=r"--scheduler tcp://127.0.0.1:1: cannot connect"):
            _client("tcp://127.0.0.1:1", None)
    with pytest.raises(ParameterError, match=r"--scheduler foo://x: cannot connect"):
        _client("foo://x", None)  # an address distributed cannot parse (a ValueError inside it)


def test_a_cell_is_marked_on_the_floors_mean_saturation_as_the_report():
    """One seed in three saturated 30 %: the benchmark's rule (the segment's mean over seeds, 10 %)
    marks the floor; a median over seeds (0) let it pass."""
    df = _marks_table(0.0, 1e-4)
    pick = (df["point"] == 1) & (df["controller"] == "ct_oracle") & (df["segment"] == 1) & (df["seed"] == 0)
    df.loc[pick, "saturation_fraction"] = 0.3
    hm = {"x": "m", "y": "w", "adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}
    r = ratio_medians(df, hm, ["m", "w"])
    assert r.loc[1, "floor_saturation"] == pytest.approx(0.1) and "saturated in 10 %" in r.loc[1, "marked"]


def test_a_scheduler_with_no_worker_stops_with_a_message(tmp_path, monkeypatch, capsys):
    """A scheduler with no worker left the sweep at 0 % for ever, with no word."""
    from adaptive_dd import sweep as sweep_module
    from adaptive_dd.errors import ParameterError

    monkeypatch.setattr(sweep_module, "WORKER_WAIT", 0.5)
    with (
        distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=":0") as cluster,
        distributed.Client(cluster) as c,
    ):
        with pytest.raises(ParameterError, match=r"has no worker after 0.5 s .*start one \(`dask worker"):
            sweep_module._run_on_dask(["task"], tmp_path, "csv", cluster.scheduler_address, None, c, False)
    assert "has no worker yet; waiting up to 0.5 s" in capsys.readouterr().out


def test_a_vector_setting_is_a_grid_axis(tmp_path, client):
    """``slotine_li``'s seven gains as a grid axis stopped the sweep (exit 3, "unhashable type:
    'list'") at its check, then at its heat map; each value runs, and the tables and the heat map
    carry it as text."""
    gains = [[0.05, 0.05, 0.05, 0.5, 0.1, 0.5, 0.1], [0.1, 0.1, 0.1, 1.0, 0.2, 1.0, 0.2]]
    sweep = (
        '[sweep]\nscenario = "base.toml"\nseeds = 1\ncontrollers = ["slotine_li_oracle", "slotine_li"]\n'
        f"[grid]\npayload_mass = [1.0]\n[grid.controller.slotine_li]\ngamma = {gains}\n"
        '[heatmap]\nadaptive = "slotine_li"\nfloor = "slotine_li_oracle"\n'
    )
    base = BASE.replace('["ct_oracle", "adaptive_ct"]', '["slotine_li_oracle", "slotine_li"]')
    res = run_sweep(
        load_sweep(_write(tmp_path, sweep, base)), tmp_path / "out", client=client, progress=False
    )
    axis = res.table.loc[res.table.controller == "slotine_li", "slotine_li.gamma"]
    assert sorted(set(axis)) == [
        "[0.05, 0.05, 0.05, 0.5, 0.1, 0.5, 0.1]",
        "[0.1, 0.1, 0.1, 1.0, 0.2, 1.0, 0.2]",
    ]
    assert res.failed_rows == 0 and res.heatmaps and res.heatmaps[0].stat().st_size > 0


def test_the_duration_is_checked_against_the_grids_swap_time(tmp_path):
    """``sweep.duration`` was checked against the base scenario's swap (2.0 s) although the grid
    moved it (to 1.0 s): the file was refused. The grid point's swap is what must lie before it."""
    base = BASE.replace(
        "at = 0.1\nmass = 3.0\n[[payload]]\nat = 0.2\nmass = 0.0\n", "at = 0.25\nmass = 3.0\n"
    )
    sweep = SWEEP.replace("swap_time = [0.08, 0.12]", "swap_time = [0.05, 0.1]").replace(
        "block = 1", "block = 1\nduration = 0.2"
    )
    sw = load_sweep(_write(tmp_path, sweep, base))
    assert {p.scenario.duration for p in sw.points} == {0.2}
    assert sorted({p.scenario.swap_times for p in sw.points}) == [(0.05,), (0.1,)]
    # a swap the grid does not move, beyond the duration: no grid point named
    two = base.replace(
        "at = 0.25\nmass = 3.0\n", "at = 0.05\nmass = 3.0\n[[payload]]\nat = 0.25\nmass = 0.0\n"
    )
    with pytest.raises(SweepError) as info:
        load_sweep(
            _write(tmp_path, sweep.replace("swap_time = [0.05, 0.1]", "swap_time = [0.02, 0.03]"), two)
        )
    assert str(info.value).endswith("ends before the scenario's swap at 0.25 s")
    bad = sweep.replace("swap_time = [0.05, 0.1]", "swap_time = [0.05, 0.2]")
    with pytest.raises(SweepError, match=r"swap_time' = 0.2 s .*strictly between 0.0 s and 0.2 s"):
        load_sweep(_write(tmp_path, bad, base))


def test_the_local_clusters_workers_ignore_ctrl_c():
    """Ctrl-C reached the workers too, each printing a traceback before the sweep's own line; the
    local cluster preloads a hook that makes a worker ignore SIGINT (the parent closes them)."""
    import signal

    from adaptive_dd.sweep_worker import dask_setup

    before = signal.getsignal(signal.SIGINT)
    try:
        dask_setup(None)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, before)
    import inspect

    from adaptive_dd import sweep

    assert 'preload=["adaptive_dd.sweep_worker"]' in inspect.getsource(sweep._client)


def test_a_cell_whose_law_and_floor_run_at_two_bandwidths_is_marked_and_said(tmp_path, capsys):
    """``[grid.controller.pd_gravity] bandwidth = [20, 40]`` against a floor at 40: the sweep
    ranked 8.0 and 2.3 as ratios to the floor and marked no cell; the cell at 20 rad/s is marked
    (a ratio of two gains), the one at 40 is not, and the command says which before it runs. A
    grid axis of the scenario's own bandwidth moves both: no mark."""
    import pandas as pd

    from adaptive_dd.cli import main
    from adaptive_dd.sweep_spec import gains_apart, mark_gains_apart

    text = SWEEP.replace(
        'controllers = ["ct_oracle", "adaptive_ct"]', 'controllers = ["ct_oracle", "ct_nominal"]'
    )
    text += "[grid.controller.ct_nominal]\nbandwidth = [20.0, 40.0]\n"
    text += '[heatmap]\nx = "payload_mass"\ny = "swap_time"\nadaptive = "ct_nominal"\nfloor = "ct_oracle"\n'
    base = BASE.replace('"adaptive_ct"]', '"ct_nominal"]') + "[control]\nbandwidth = 40.0\n"
    sw = load_sweep(_write(tmp_path, text, base))
    apart = gains_apart(sw)
    at_20 = [p.index for p in sw.points if dict(p.values)["ct_nominal.bandwidth"] == 20.0]
    assert sorted(apart) == at_20 and len(at_20) == len(sw.points) // 2
    assert apart[at_20[0]].startswith("ct_nominal.bandwidth = 20.0 but its floor ct_oracle's is 40.0")
    ratios = pd.DataFrame(
        {"point": [p.index for p in sw.points], "marked": ["", "saturated"] * (len(sw.points) // 2)}
    )
    marked = mark_gains_apart(ratios.copy(), sw).set_index("point")["marked"]
    for p in sw.points:
        own = ratios.set_index("point")["marked"][p.index]
        assert marked[p.index] == (
            "; ".join(filter(None, (own, apart[p.index]))) if p.index in apart else own
        )
    both = text.replace("[grid.controller.ct_nominal]\nbandwidth = [20.0, 40.0]\n", "").replace(
        "[grid]\n", "[grid]\nbandwidth = [20.0, 40.0]\n"
    )
    assert gains_apart(load_sweep(_write(tmp_path, both, base))) == {}
    sweep_file = _write(tmp_path, text, base)
    assert (
        main(["sweep", str(sweep_file), "--out", str(tmp_path / "out"), "--no-progress", "--workers", "1"])
        == 0
    )
    err = capsys.readouterr().err
    assert err.count("warning: grid point") == len(at_20) and "ct_nominal.bandwidth = 20.0" in err
    table = pd.read_csv(tmp_path / "out" / "ratios.csv")
    assert table["marked"].fillna("").str.contains("two gains").sum() == len(at_20)


# ---- a large study's walk-through -------------------------------------------------------------


def test_a_cell_where_some_seeds_failed_is_marked_not_a_ratio_of_the_survivors():
    """A cell where the law failed on half its seeds printed the survivors' median unmarked."""
    rows = []
    for seed, (a, f) in enumerate([(1.2, 1.0), (np.nan, 1.0)]):  # seed 1: the law's trial failed
        for c, v in (("adaptive_ct", a), ("ct_oracle", f)):
            rows.append({"point": 0, "m": 1.0, "controller": c, "seed": seed, "segment": 1, "rms_error": v})
            rows.append({"point": 0, "m": 1.0, "controller": c, "seed": seed, "segment": 0, "rms_error": 1.0})
    r = ratio_medians(
        pd.DataFrame(rows), {"adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}, ["m"]
    )
    assert r["ratio"].item() == pytest.approx(1.2) and r["n_seeds"].item() == 1
    assert (
        r["marked"].item()
        == "1 of 2 seeds' trials failed (or their floor's did): the median is over the others"
    )


def test_a_worker_on_other_code_refuses_its_task():
    """Long-lived Dask workers that imported other code ran the task and its rows were cached under
    the new code's key."""
    task = sweep_mod.Task("k", load_scenario(), "ct_oracle", (), (0,), code="other")
    rows = sweep_mod.execute_task(task)
    assert rows and all(r["failed"] for r in rows)
    assert (
        "worker runs other adaptive_dd code" in rows[0]["error"]
        and "restart the Dask workers" in rows[0]["error"]
    )


def test_a_value_given_twice_as_int_and_float_and_the_seeds_bound_are_named(tmp_path):
    with pytest.raises(SweepError, match=r"lists a value twice: \[1, 1.0\]"):
        load_sweep(_write(tmp_path, SWEEP.replace("[1.0, 6.0]", "[1, 1.0]")))
    with pytest.raises(SweepError, match=r"key 'sweep.seeds' = 100000000 .*must be in \[1, 10000\]"):
        load_sweep(_write(tmp_path, SWEEP.replace("seeds = 2", "seeds = 100000000")))
    with pytest.raises(SweepError, match=r"unknown key 'sweep.seedz' \(did you mean 'seed' or 'seeds'"):
        load_sweep(_write(tmp_path, SWEEP.replace("seeds = 2", "seedz = 2")))


def test_the_sweep_prints_an_estimate_and_every_column(tmp_path, capsys):
    import re

    from adaptive_dd.cli import main

    text = SWEEP.replace("[1.0, 6.0]", "[" + ", ".join(f"{0.25 * k:.2f}" for k in range(1, 15)) + "]")
    text = text.replace("swap_time = [0.08, 0.12]", "swap_time = [0.08]").replace("seeds = 2", "seeds = 1")
    assert main(["sweep", str(_write(tmp_path, text)), "--out", str(tmp_path / "out"), "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"running \d+ task\(s\) on .*worker\(s\); estimate: about [\d.]+ (s|min)", out), out
    header = next(line for line in out.splitlines() if line.startswith("payload_mass"))
    assert "..." not in header and header.split()[1:] == [f"{0.25 * k:.2f}" for k in range(1, 15)]


def test_another_controllers_setting_keeps_the_floors_cells(tmp_path):
    """A setting of adaptive_ct's added to the base scenario ran ct_oracle's cells again."""
    sw = load_sweep(_write(tmp_path))
    before = {(c, k) for _, c, k in plan_tasks(sw)[1]}
    sw2 = load_sweep(_write(tmp_path, base=BASE + "\n[controllers.adaptive_ct]\nboost_duration = 0.1\n"))
    after = {(c, k) for _, c, k in plan_tasks(sw2)[1]}
    assert {k for c, k in before if c == "ct_oracle"} == {k for c, k in after if c == "ct_oracle"}
    assert not {k for c, k in before if c == "adaptive_ct"} & {k for c, k in after if c == "adaptive_ct"}
