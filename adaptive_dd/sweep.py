"""Parameter sweeps on Dask: tasks of (grid point, controller, block of seeds).

A task runs one controller on one grid point's scenario for a block of seed
indices and returns per-seed, per-segment metric rows (never trajectories), via
:func:`run_cell`, the one place that touches the benchmark runner. Tasks that are
identical (same scenario, controller, settings and seeds, e.g. the floor
controller at two values of another controller's setting) run once.

Each finished task's rows are written atomically to ``OUT/cells/<key>.parquet``
(``.csv`` without pyarrow), ``key`` a hash of the task, and reused by the next run:
an interrupted sweep resumes. A trial that diverges gives rows with ``failed`` set
from the segment where it failed on; a task that raises gives failed rows with the
message. Neither stops the sweep. A task whose every row failed is not kept in
``OUT/cells``: the next run tries it again (after a fix, say). The final table
``OUT/results.parquet|csv`` has one row per grid point x controller x seed x segment;
``OUT/heatmap*.png`` shows the per-seed-median ratio of the adaptive controller's RMS error to the floor's
(common random numbers: both ran on the same noise).
"""

from __future__ import annotations

import logging
import os
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from adaptive_dd.benchmark.scenario import Scenario
from adaptive_dd.sweep_keys import _cell_text, _code_id, _seeds_key
from adaptive_dd.sweep_ratios import FLOOR_FAR, SEEDS_FAILED, ratio_medians
from adaptive_dd.sweep_spec import Sweep, cell_scenario, mark_gains_apart

__all__ = [
    "FLOOR_FAR",
    "SEEDS_FAILED",
    "WORKER_ENV",
    "SweepResult",
    "Task",
    "execute_task",
    "failed_rows",
    "plan_tasks",
    "ratio_medians",
    "run_cell",
    "run_sweep",
]

WORKER_ENV = {
    "NUMBA_NUM_THREADS": "1",
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
}
"""One thread of numeric work per worker process (workers do not oversubscribe the cores)."""

ROW_COLUMNS = {
    "seed": "int64",
    "segment": "int64",
    "start": "float64",
    "end": "float64",
    "mass": "float64",
    "rms_error": "float64",
    "max_error": "float64",
    "saturation_fraction": "float64",
    "detector": "bool",
    "detection_delay": "float64",
    "failed": "bool",
    "error": "object",
}
"""The columns of a task's rows and their dtypes."""


def run_cell(
    scenario: Scenario,
    controller: str,
    seed_indices: Sequence[int],
    settings: Mapping[str, Any] | None = None,
) -> list[dict]:
    """Run one controller over some seeds of a scenario; per-seed, per-segment rows.

    The only use of the benchmark runner in the sweep (swap it here for another engine).

    Parameters
    ----------
    scenario : Scenario
    controller : str
        A built-in controller name (for the scenario's arm: two-link or any arm from a URDF); the
        scenario's ``[controllers.NAME]`` settings apply, ``settings`` over them.
    seed_indices : sequence of int
        Trial i uses the noise of ``(scenario.seed, seed_indices[i])``, as in a full run.
    settings : mapping, optional
        Settings of the controller, as in a ``[controllers.NAME]`` table.

    Returns
    -------
    list of dict
        One row per seed and segment with :data:`ROW_COLUMNS`: ``rms_error`` and
        ``max_error`` of ``|q_d - q|`` [rad] over the segment, ``saturation_fraction`` the
        fraction of its samples with a command beyond a torque limit; ``detector`` whether the
        controller has a change detector, ``detection_delay`` [s] the time from the swap that
        starts the segment to its first alarm within the benchmark's window
        (:func:`~adaptive_dd.benchmark.metrics.detection_delays`; NaN in the first segment,
        without a detector, for a missed swap or a failed trial); ``failed`` when the
        trial diverged (or its controller raised) before the segment's end, then the
        metrics are NaN and ``error`` says why.
    """
    from adaptive_dd.benchmark.metrics import detection_delays, per_seed_segment_metrics
    from adaptive_dd.benchmark.runner import run_benchmark

    scenario = cell_scenario(scenario, controller, settings)
    # a cell runs one controller: the sweep pairs it with its floor
    res = run_benchmark(scenario, progress=False, seed_indices=seed_indices, warn_missing_floors=False)
    (run,) = res.runs.values()
    per = per_seed_segment_metrics(res, run, settling=False)  # NaN: the benchmark's failure rule
    T = scenario.sample_period
    segments = scenario.segments()
    detector = run.alarm_times is not None
    delays = {
        j: detection_delays(run.alarm_times, a) for j, (a, _, _) in enumerate(segments) if j > 0 and detector
    }
    rows = []
    for i, seed in enumerate(seed_indices):
        at = int(run.failed_at[i]) if run.failed[i] else -1
        why = run.error or f"trial diverged at t = {at * T:.3f} s: {run.failed_why.get(i, '')}"
        for j, (start, end, mass) in enumerate(segments):
            bad = bool(np.isnan(per["rms_error"][i, j]))
            d = delays[j][i] if j in delays else None
            rows.append(
                {
                    "seed": int(seed),
                    "segment": j,
                    "start": start,
                    "end": end,
                    "mass": mass,
                    "rms_error": float(per["rms_error"][i, j]),
                    "max_error": float(per["max_error"][i, j]),
                    "saturation_fraction": float(per["saturation_fraction"][i, j]),
                    "detector": detector,
                    "detection_delay": np.nan if d is None or run.failed[i] or run.error else float(d),
                    "failed": bad,
                    "error": why if bad else "",
                }
            )
    return rows


@dataclass(frozen=True)
class Task:
    """One unit of work: a controller on a scenario for a block of seeds."""

    key: str
    scenario: Scenario
    controller: str
    settings: tuple[tuple[str, Any], ...]
    seeds: tuple[int, ...]
    code: str = ""  # the planning process's _code_id (part of ``key``); a worker on other code refuses


def plan_tasks(sweep: Sweep) -> tuple[dict[str, Task], list[tuple[int, str, str]]]:
    """The distinct tasks of a sweep, and ``(point index, controller, task key)`` per cell.

    Returns
    -------
    tasks : dict
        Task by key, in first-use order; identical tasks appear once.
    cells : list of (int, str, str)
        Every grid point x controller x seed block, with the key of its task.
    """
    tasks: dict[str, Task] = {}
    cells = []
    code = _code_id()
    for p in sweep.points:
        for c in sweep.controllers:
            settings = tuple(sorted(p.settings_for(c).items()))
            text = _cell_text(p.scenario, c, settings)  # once per cell: a block's key adds its seeds
            for block in sweep.seed_blocks():
                key = _seeds_key(text, block)
                tasks.setdefault(key, Task(key, p.scenario, c, settings, block, code))
                cells.append((p.index, c, key))
    return tasks, cells


def failed_rows(task: Task, message: str) -> list[dict]:
    """Rows of a task that did not run: every seed and segment failed with the message."""
    return [
        {
            "seed": s,
            "segment": j,
            "start": start,
            "end": end,
            "mass": mass,
            "rms_error": np.nan,
            "max_error": np.nan,
            "saturation_fraction": np.nan,
            "detector": False,  # not known: the controller did not run
            "detection_delay": np.nan,
            "failed": True,
            "error": message,
        }
        for s in task.seeds
        for j, (start, end, mass) in enumerate(task.scenario.segments())
    ]


_LOADED_CODE = _code_id()
"""The package's sources as this process imported them (a long-lived worker keeps its modules)."""


def execute_task(task: Task) -> list[dict]:
    """Run a task on a worker; an exception becomes failed rows with its message."""
    if task.code and task.code != _LOADED_CODE:  # its rows would be cached under the other code's key
        return failed_rows(
            task,
            f"worker runs other adaptive_dd code ({_LOADED_CODE}) than the sweep's ({task.code}): "
            "restart the Dask workers so that they import the same version",
        )
    try:
        return run_cell(task.scenario, task.controller, task.seeds, dict(task.settings))
    except Exception as exc:  # recorded in the table, never kills the sweep
        return failed_rows(task, f"{type(exc).__name__}: {exc}")


def _have_parquet() -> bool:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return False
    return True


def _typed(df: pd.DataFrame) -> pd.DataFrame:
    df = df.astype({k: v for k, v in ROW_COLUMNS.items() if k != "error"})
    df["error"] = df["error"].fillna("").astype(object)
    return df


def _umask() -> int:
    """The process's umask (read by setting it, then set back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _write_atomic(df: pd.DataFrame, path: Path) -> Path:
    """Write a table to ``path`` through a temporary file and ``os.replace``."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".tmp")
    os.close(fd)
    try:
        if path.suffix == ".parquet":
            df.to_parquet(tmp, index=False)
        else:  # pandas writes each float's shortest exact form (0.005, not 0.0050000000000000001)
            df.to_csv(tmp, index=False)
        os.chmod(tmp, 0o666 & ~_umask())  # a file made by open() would have these (mkstemp: 0600)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return path


def _read(path: Path) -> pd.DataFrame:
    df = pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path, keep_default_na=False)
    if path.suffix == ".csv":
        for col in ("rms_error", "max_error", "saturation_fraction", "detection_delay"):
            df[col] = pd.to_numeric(df[col].replace("", np.nan))
    return _typed(df)


@dataclass
class SweepResult:
    """What a sweep produced.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per grid point x controller x seed x segment.
    table_path : Path
    heatmaps : list of Path
        The ratios' heat maps (``heatmap*.png``), then, for an adaptive controller with a change
        detector, its delays' (``delays*.png``). Empty when no grid point has a ratio (every row
        failed, or no seed where both the adaptive controller and the floor finished the heat map's
        segment).
    ratios : DataFrame or None
        Per grid point, the heat map's ratio and its marks (:func:`ratio_medians`), also written
        to ``OUT/ratios.csv``; None without a heat map.
    reused, ran : int
        Tasks read back from ``OUT/cells`` and tasks run now.
    failed_rows : int
        Rows with ``failed`` set.

    Examples
    --------
    Made by :func:`run_sweep` (``adaptive-dd sweep FILE --out DIR`` prints where it wrote it):

    >>> from adaptive_dd.sweep import SweepResult
    >>> sorted(SweepResult.__dataclass_fields__)
    ['failed_rows', 'heatmaps', 'ran', 'ratios', 'reused', 'table', 'table_path']
    """

    table: pd.DataFrame
    table_path: Path
    heatmaps: list
    reused: int
    ran: int
    failed_rows: int
    ratios: pd.DataFrame | None = None


def _client(scheduler: str | None, workers: int | None):
    """A Dask client: to ``scheduler``, or to a new local cluster of single-threaded workers."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            return Client(scheduler), None
        except (OSError, TimeoutError, ValueError) as exc:  # name the option, not only the address
            from adaptive_dd.errors import ParameterError

            raise ParameterError(
                f"--scheduler {scheduler}: cannot connect to the Dask scheduler ({exc}); start one "
                "(dask scheduler) and its workers, or leave --scheduler out to run on this machine"
            ) from None
    import dask

    from adaptive_dd.arena.pool import environment

    n = workers or os.cpu_count() or 1
    # in the environment each worker process starts with, not only Dask's ``env`` (applied after the
    # worker has imported numba: its config then read 2 threads while the environment said 1, and a
    # kernel compiled in the worker reloaded it, so that numba refused to run: "Cannot set
    # NUMBA_NUM_THREADS to a different value once the threads have been launched"). The nannies take
    # their pre-spawn environment when made (from the process's environment, over Dask's config) and
    # set it before every start of their worker, a restart's too.
    pre = {**dask.config.get("distributed.nanny.pre-spawn-environ"), **WORKER_ENV}
    with environment(WORKER_ENV), dask.config.set({"distributed.nanny.pre-spawn-environ": pre}):
        cluster = LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, env=dict(WORKER_ENV), dashboard_address=":0",
            preload=["adaptive_dd.sweep_worker"],
        )  # fmt: skip
    return Client(cluster), cluster


def _quiet_logs() -> None:
    """Run on each worker of the local cluster as it is closed: its Dask logs silenced."""
    logging.getLogger("distributed").setLevel(logging.CRITICAL)


def _run_tasks(todo: list[Task], cells_dir: Path, ext: str, client, progress: bool) -> dict[str, list]:
    """Submit tasks, write each one's rows as it completes; rows of lost tasks and of tasks whose
    every row failed (not cached)."""
    from distributed import as_completed
    from tqdm.auto import tqdm

    futures = {client.submit(execute_task, t, key=f"sweep-{t.key}", pure=False): t for t in todo}
    lost: dict[str, list] = {}
    bar = tqdm(as_completed(futures), total=len(futures), desc="sweep", unit="task", disable=not progress)
    for fut in bar:
        task = futures[fut]
        try:
            rows = fut.result()
        except Exception as exc:  # a worker died or the task could not be sent
            lost[task.key] = failed_rows(task, f"task lost: {type(exc).__name__}: {exc}")
            continue
        if rows and all(r["failed"] for r in rows):  # not cached: the next run tries it again
            lost[task.key] = rows
            continue
        _write_atomic(_typed(pd.DataFrame(rows, columns=list(ROW_COLUMNS))), cells_dir / f"{task.key}.{ext}")
    return lost


def run_sweep(
    sweep: Sweep,
    out: str | Path,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    client=None,
    progress: bool = True,
) -> SweepResult:
    """Run a sweep on Dask, resuming from ``OUT/cells``; write the table and heatmaps.

    Parameters
    ----------
    sweep : Sweep
        From :func:`~adaptive_dd.sweep_spec.load_sweep`.
    out : path
        Output folder.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); default: a
        ``LocalCluster`` of ``workers`` single-threaded processes (default: all cores).
    client : distributed.Client, optional
        Use this client instead (tests).
    progress : bool
        Show a progress bar over completed tasks.

    Returns
    -------
    SweepResult
        The tidy table's path, the per-cell rows, the heatmaps written and the failed cells.

    Examples
    --------
    Two payload masses on the paper's arm, one seed, on an in-process Dask cluster:

    >>> import tempfile
    >>> import distributed
    >>> from adaptive_dd.benchmark.scenario import default_scenario_path
    >>> from adaptive_dd.sweep import run_sweep
    >>> from adaptive_dd.sweep_spec import parse_sweep
    >>> sweep = parse_sweep({"sweep": {"scenario": str(default_scenario_path()), "seeds": 1,
    ...                                "controllers": ["ct_oracle", "ct_nominal"]},
    ...                      "grid": {"payload_mass": [1.0, 3.0]}})
    >>> with distributed.Client(processes=False, n_workers=1, dashboard_address=None) as client:
    ...     res = run_sweep(sweep, tempfile.mkdtemp(), client=client, progress=False)
    sweep <memory>: 2 grid points x 2 controllers x 1 block(s) of seeds (1 seeds, 1 per block) = 4
    cells in 4 distinct tasks; 0 reused from ..., 4 to run
    running 4 task(s) on the given client, 1 worker(s)
    >>> len(res.table), res.ran  # grid points x controllers x seeds x 4 segments; tasks run
    (16, 4)
    """
    from adaptive_dd.outputs import check_output_dir

    out = Path(out)
    cells_dir = check_output_dir(out / "cells")  # an unwritable folder is reported before the run
    ext = "parquet" if _have_parquet() else "csv"
    tasks, cells = plan_tasks(sweep)
    todo = [t for k, t in tasks.items() if not (cells_dir / f"{k}.{ext}").is_file()]
    reused = len(tasks) - len(todo)
    print(
        f"sweep {sweep.source}: {len(sweep.points)} grid points x {len(sweep.controllers)} controllers x "
        f"{len(sweep.seed_blocks())} block(s) of seeds ({sweep.seeds} seeds, {sweep.block} per block) = "
        f"{len(cells)} cells in {len(tasks)} distinct tasks; "
        f"{reused} reused from {cells_dir}, {len(todo)} to run"
    )
    lost = _run_on_dask(todo, cells_dir, ext, scheduler, workers, client, progress) if todo else {}
    table = _assemble(sweep, cells, cells_dir, ext, lost)
    path = _write_atomic(table, out / f"results.{ext}")
    ratios, maps = _heatmaps(sweep, table, out)
    return SweepResult(table, path, maps, reused, len(todo), int(table["failed"].sum()), ratios)


WORKER_WAIT = 60.0
"""[s] How long a sweep waits for a scheduler with no worker to get one before it stops."""


def _run_on_dask(todo, cells_dir: Path, ext: str, scheduler, workers, client, progress: bool) -> dict:
    """Run the ``todo`` tasks on ``client`` (or a cluster made here and closed after); the lost
    tasks' errors (:func:`_run_tasks`)."""
    made = client is None
    cluster = None
    if made:
        client, cluster = _client(scheduler, workers)
    where = (
        f"the Dask scheduler {scheduler}"
        if scheduler
        else "a local Dask cluster"
        if made
        else "the given client"
    )
    try:
        n = len(client.scheduler_info().get("workers", {}))
        if n == 0:  # the tasks would wait forever at 0 %
            print(f"{where} has no worker yet; waiting up to {WORKER_WAIT:g} s for one", flush=True)
            try:
                client.wait_for_workers(1, timeout=WORKER_WAIT)
            except (TimeoutError, OSError) as exc:
                from adaptive_dd.errors import ParameterError

                address = scheduler or "<the scheduler's address>"
                raise ParameterError(
                    f"{where} has no worker after {WORKER_WAIT:g} s ({type(exc).__name__}); start one "
                    f"(`dask worker {address}`) or run without --scheduler (a local cluster)"
                ) from None
            n = len(client.scheduler_info().get("workers", {}))
        print(f"running {len(todo)} task(s) on {where}, {n} worker(s); {_estimate(todo, n)}", flush=True)
        return _run_tasks(todo, cells_dir, ext, client, progress)
    finally:
        # the scheduler's warnings about the workers it loses as they stop (on Ctrl-C: a hundred task
        # ids per worker) are the shutdown's, not the sweep's
        quiet = logging.getLogger("distributed")
        level = quiet.level
        quiet.setLevel(logging.CRITICAL)
        if cluster is not None:  # and the workers' (a heartbeat to a scheduler that closed first):
            try:  # their warnings while the tasks ran (memory, restarts) were printed
                client.run(_quiet_logs)
            except Exception:  # a worker already gone has nothing to say
                pass
        try:
            if made:
                client.close()
            if cluster is not None:
                cluster.close()
        finally:
            quiet.setLevel(level)


def _estimate(todo: list[Task], n_workers: int) -> str:
    """A rough wall time of the tasks on ``n_workers``: the benchmark's estimate of each distinct
    kind of task, its set-up and a cold cache's compilation once per worker (a guide, not a
    promise)."""
    import dataclasses

    from adaptive_dd.benchmark.scenario_base import _duration

    seen: dict[tuple, tuple[float, float, float]] = {}
    run = setup = compiling = 0.0
    for t in todo:
        sc = t.scenario
        kind = (sc.n_samples, len(t.seeds), sc.n_joints, sc.closed_forms is None)
        key = (t.controller, repr(t.settings), *kind)  # repr: a vector setting is a list
        if key not in seen:
            cell = dataclasses.replace(cell_scenario(sc, t.controller, dict(t.settings)), seeds=len(t.seeds))
            e = cell.estimate()
            seen[key] = (e.seconds - e.compile_seconds - e.setup_seconds, e.setup_seconds, e.compile_seconds)
        run += seen[key][0]
        setup, compiling = max(setup, seen[key][1]), max(compiling, seen[key][2])
    cold = (
        f", of which about {_duration(compiling)} compiling the kernels (a cold cache; each worker "
        "loads them once compiled, the progress bar waits meanwhile)"
        if compiling
        else ""
    )
    total = run / max(n_workers, 1) + setup + compiling
    return f"estimate: about {_duration(total)}{cold} (a guide, not a promise)"


def _heatmaps(sweep: Sweep, table: pd.DataFrame, out: Path) -> tuple[pd.DataFrame | None, list]:
    """The per-cell ratios and marks (written to ``OUT/ratios.csv``) and the heat maps of
    ``[sweep] heatmap`` (none when every row failed or no ratio is finite: never an empty heat
    map)."""
    if not sweep.heatmap or table["failed"].all():
        return None, []
    from adaptive_dd.sweep_plot import plot_delay_heatmaps, plot_ratio_heatmaps

    ratios = mark_gains_apart(ratio_medians(table, sweep.heatmap, [a for a, _ in sweep.axes]), sweep)
    _write_atomic(ratios, out / "ratios.csv")
    if not np.isfinite(ratios["ratio"]).any():
        return ratios, []
    axes = [a for a, _ in sweep.axes]
    return ratios, plot_ratio_heatmaps(ratios, sweep.heatmap, axes, out) + plot_delay_heatmaps(
        ratios, sweep.heatmap, axes, out
    )


def _cell_value(value):
    """A grid axis's value as the tables hold it: a list (a vector setting, e.g. ``slotine_li``'s
    seven gains) as its text ``"[0.05, 0.05, ...]"``, one value a table cell and a heat map's
    tick can carry; a number as it is."""
    if isinstance(value, list | tuple):
        return "[" + ", ".join(str(x) for x in value) + "]"  # each number to its last digit
    return value


def _assemble(sweep: Sweep, cells, cells_dir: Path, ext: str, lost: dict) -> pd.DataFrame:
    """The tidy table: grid coordinates + controller + task rows, in grid order."""
    cache: dict[str, pd.DataFrame] = {}
    parts = []
    for index, controller, key in cells:
        if key not in cache:
            cache[key] = _typed(pd.DataFrame(lost[key])) if key in lost else _read(cells_dir / f"{key}.{ext}")
        df = cache[key].copy()
        df.insert(0, "controller", controller)
        for pos, (axis, value) in enumerate(sweep.points[index].values):
            df.insert(pos, axis, [_cell_value(value)] * len(df))
        df.insert(0, "point", index)
        df["task"] = key
        parts.append(df)
    return pd.concat(parts, ignore_index=True)
