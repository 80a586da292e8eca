"""``adaptive-dd sweep SWEEP.toml``: a grid over scenario fields x controllers x seeds, on Dask.

Any arm the sweep's scenario names. Exits 1 when every row failed (no heat map drawn), and
says why the failed rows failed.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from adaptive_dd.cli._common import NO_PROGRESS_HELP, SEEDS, add_command, number, refuse, show_progress

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """The options of ``sweep``."""
    w = add_command(sub, "sweep", help="grid over scenario fields x controllers x seeds, on Dask")
    w.add_argument("sweep", help="sweep TOML (see docs/sweeps.md)")
    w.add_argument("--out", default="results/sweep", help="folder for cells, table and heatmaps")
    w.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (default: local cluster)")
    w.add_argument(
        "--workers",
        type=number(int, 1, 1024),
        help="local cluster worker processes (default: all cores; refused with --scheduler)",
    )
    w.add_argument("--block", type=SEEDS, metavar="SEEDS", help="seeds per task (overrides sweep.block)")
    w.add_argument("--no-progress", action="store_true", help=NO_PROGRESS_HELP)
    w.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the sweep (cells already computed are reused); report failures and the heat map's table."""
    import dataclasses

    from adaptive_dd.sweep import run_sweep
    from adaptive_dd.sweep_spec import gains_apart, load_sweep

    if args.scheduler:
        refuse(
            args,
            ("--workers",),
            "sizes the local cluster; with --scheduler the running scheduler's own workers run the tasks",
        )
    sweep = load_sweep(args.sweep)
    for i, why in gains_apart(sweep).items():  # (its cells marked in ratios.csv and the heat map)
        print(f"warning: grid point {dict(sweep.points[i].values)}: {why}", file=sys.stderr)
    if args.block is not None:
        sweep = dataclasses.replace(sweep, block=min(args.block, sweep.seeds))
    res = run_sweep(
        sweep, args.out, scheduler=args.scheduler, workers=args.workers, progress=show_progress(args)
    )
    print(
        f"{len(res.table)} rows ({res.failed_rows} failed), {res.ran} tasks run, {res.reused} reused; "
        f"wrote {res.table_path}"
        + (f", {res.table_path.parent / 'ratios.csv'}" if res.ratios is not None else "")
        + "".join(f", {p}" for p in res.heatmaps)
    )
    if res.failed_rows:
        _print_failures(res)
    if res.failed_rows == len(res.table):
        print("every row failed: no heat map drawn; fix the cause above and rerun", file=sys.stderr)
        return 1
    _print_heatmap(res, sweep)
    return 0


def _print_failures(res) -> None:
    """How many rows failed, in how many tasks, and the five commonest reasons (on stderr)."""
    failed = res.table.loc[res.table["failed"], "error"]
    n_tasks = res.table.loc[res.table["failed"], "task"].nunique()
    print(
        f"{'error' if res.failed_rows == len(res.table) else 'warning'}: {res.failed_rows} of "
        f"{len(res.table)} rows failed (in {n_tasks} task(s)); why:",
        file=sys.stderr,
    )
    for msg, count in failed.value_counts().head(5).items():
        print(f"  {count} rows: {msg}", file=sys.stderr)


def _print_heatmap(res, sweep) -> None:
    """The heat map's ratios as a table, or why there is no heat map."""
    hm = sweep.heatmap
    if hm and not res.heatmaps:
        print(
            f"no heat map: no grid point has a seed where both {hm['adaptive']} and {hm['floor']} finished "
            f"segment {hm['segment']}",
            file=sys.stderr,
        )
    elif hm:
        r = res.ratios
        marks = r.assign(cell=r["ratio"].round(3).astype(str) + np.where(r["marked"] != "", " *", ""))
        title = f"median over seeds of rms {hm['adaptive']} / rms {hm['floor']}, segment {hm['segment']}"
        _print_tables(marks, sweep, title, "; * marked")
        _print_marks(r, hm)
        from adaptive_dd.benchmark.metrics import floor_caveat

        caveat = floor_caveat(sweep.base)
        if caveat:
            print(f"note: {caveat}")
        _print_delays(r, sweep)


def _print_tables(r, sweep, title: str, tail: str, label: str = "ratio") -> None:
    """The grid's ``cell`` column (text) as tables, rows ``y`` and columns ``x`` of the heat map,
    one per combination of the other axes (the heat maps' order), under ``title``; with one axis
    varied, one row named ``label``."""
    hm = sweep.heatmap
    # the other grid axes: one table per combination of their values, in the heat maps' order
    other = [a for a, _ in sweep.axes if a not in (hm["x"], hm["y"])]
    groups = list(r.groupby(other, sort=False)) if other else [((), r)]
    rows = hm["y"] or "_row"  # one varied axis: one row
    if hm["y"] is None:
        groups = [(k, part.assign(_row=label)) for k, part in groups]
    print(
        f"{title} ({f'rows {rows}, ' if hm['y'] else ''}columns {hm['x']}"
        + (f"; one table per {', '.join(other)}" if len(groups) > 1 else "")
        + f"{tail}):"
    )
    for i, (key, part) in enumerate(groups):
        if len(groups) > 1:
            values = key if isinstance(key, tuple) else (key,)
            # str: a float's shortest exact form (0.005, not 0.0050000000000000001)
            where = ", ".join(f"{a} = {v}" for a, v in zip(other, values, strict=True))
            print(f"{where} (heatmap_{i}.png):")
        table = part.pivot_table(index=rows, columns=hm["x"], values="cell", aggfunc="first", dropna=False)
        if hm["y"] is None:
            table.index.name = None
        print(table.fillna("").to_string())  # every column, whatever the terminal


def _print_delays(r, sweep) -> None:
    """The adaptive controller's median detection delay per cell [ms], with its missed swaps, when
    it has a change detector (:func:`~adaptive_dd.sweep.ratio_medians`)."""
    hm = sweep.heatmap
    if "missed" not in r or r["missed"].isna().all():
        return
    ms = (1e3 * r["delay_median"]).round(0)
    text = [
        ("-" if np.isnan(d) else f"{d:.0f}") + (f" ({m})" if m else "")
        for d, m in zip(ms, r["missed"].fillna(0), strict=True)
    ]
    _print_tables(
        r.assign(cell=text), sweep,
        f"median delay from the swap to {hm['adaptive']}'s first alarm [ms], segment {hm['segment']}",
        "; (k): k seeds with no alarm", "delay",
    )  # fmt: skip


def _print_marks(r, hm) -> None:
    """How many cells are marked and why, and the median ratio of the marked and the other cells."""
    m = r["marked"] != ""
    print(
        f"{int(m.sum())} of {len(r)} cells marked ({hm['floor']} saturated or far from its own error "
        f"before the swap, at other gains, or seeds failed: the ratio is not against a floor over "
        f"every seed; the why per cell in ratios.csv)"
    )
    from adaptive_dd.benchmark.metrics import SATURATION_LIMIT
    from adaptive_dd.benchmark.preflight import GAINS_APART
    from adaptive_dd.sweep import FLOOR_FAR, SEEDS_FAILED

    for what, needle in ((f"at other gains than {hm['floor']}", GAINS_APART), ("seeds failed", SEEDS_FAILED)):
        k = int(r["marked"].str.contains(needle, regex=False).sum())
        if k:
            print(f"  {k} cells: {what} (ratios.csv's marked column says how)")

    sat = r.loc[m & (r["floor_saturation"] > SATURATION_LIMIT), "floor_saturation"] * 100
    if len(sat):
        print(
            f"  {len(sat)} cells: {hm['floor']} saturated in {sat.min():.3g} .. {sat.max():.3g} % of the "
            f"segment's samples (limit {100 * SATURATION_LIMIT:g} %)"
        )
    far = (r["floor_rms"] / r["floor_nominal_rms"])[m]
    far = far[far > FLOOR_FAR] if hm["segment"] != 0 else far[:0]
    if len(far):
        print(
            f"  {len(far)} cells: {hm['floor']} at {far.min():.3g} .. {far.max():.3g} x its own RMS error "
            f"before the swap (limit {FLOOR_FAR:g} x)"
        )
    for name, sel in (("marked", m), ("not marked", ~m)):
        x = r.loc[sel, "ratio"].dropna()
        if len(x):
            print(
                f"  {name}: median ratio per cell {x.min():.3g} .. {x.max():.3g} (median of the cells "
                f"{x.median():.3g}, {len(x)} cells)"
            )
