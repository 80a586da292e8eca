"""Rewrite the leaderboard's generated blocks and figure from its table; ``--run`` runs it first.

Without options: reads ``docs/leaderboard/leaderboard.csv`` and rewrites the generated blocks of
``docs/leaderboard.md`` and ``docs/results.md`` (between their ``<!-- leaderboard:NAME ... -->``
markers) and ``docs/leaderboard_ratios.png`` (:mod:`adaptive_dd.arena.page`). With ``--run``:
first runs ``adaptive-dd leaderboard ARGS --out docs/leaderboard`` (the table, its JSON and heat
map), ARGS by default the docs' run below, printing its wall and CPU time
(``benchmarks/leaderboard_time.py``).

Usage::

    python tools/leaderboard_page.py                 # re-render from the committed table
    python tools/leaderboard_page.py --run           # run the docs' leaderboard, then render
    python tools/leaderboard_page.py --run --arms 10 --seeds 3   # another run's arguments
    python tools/leaderboard_page.py --print results/leaderboard/leaderboard.csv  # print, write nothing
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUN_ARGS = "--arms 50 --seeds 10 --template benchmarks/scenarios/population_drawn.toml --workers 2".split()
"""The docs' run, the whole leaderboard: the shipped scenarios and fifty drawn arms, ten seeds each,
on two cores (about an hour of CPU)."""


def render(root: Path = ROOT) -> list[Path]:
    """Rewrite the blocks and the figure under ``root``; the files written."""
    from adaptive_dd.arena.page import (
        BLOCKS,
        CSV,
        FIGURE,
        plot_ratios,
        read_table,
        render_blocks,
        replace_blocks,
    )

    df = read_table(root / CSV)
    blocks = render_blocks(df)
    written = []
    for page, names in BLOCKS.items():
        path = root / page
        text = path.read_text(encoding="utf-8")
        new = replace_blocks(text, blocks, names, page)
        if new != text:
            path.write_text(new, encoding="utf-8")
            written.append(path)
    plot_ratios(df).savefig(root / FIGURE, dpi=110, metadata={"Software": None})
    from adaptive_dd.arena.latex import write_latex

    tex = write_latex(df, (root / CSV).with_suffix(".tex"))
    return [*written, root / FIGURE, tex]


def main(argv: list[str] | None = None) -> int:
    """Parse the options, run the leaderboard if asked, render."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--run", action="store_true", help="run the leaderboard into docs/leaderboard first")
    p.add_argument("--print", dest="table", metavar="CSV", help="print the blocks another table renders")
    args, rest = p.parse_known_args(argv)
    if rest and not args.run:
        p.error(f"{' '.join(rest)}: leaderboard arguments need --run")
    if args.table and args.run:
        p.error("--print: prints a table's blocks; --run writes the docs' table: give one")
    if args.run:
        sys.path.insert(0, str(ROOT / "benchmarks"))
        from leaderboard_time import main as timed

        code = timed([*(rest or RUN_ARGS), "--out", str(ROOT / "docs" / "leaderboard")])
        if code:
            return code
    from adaptive_dd.arena.page import read_table, render_blocks
    from adaptive_dd.errors import ParameterError

    try:
        if args.table:
            for name, text in render_blocks(read_table(args.table)).items():
                print(f"== {name}\n{text}\n")
            return 0
        written = render()
    except ParameterError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for path in written:
        print(f"wrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
