"""The first tutorial shows the report the first benchmark prints, line for line.

``docs/getting_started.md`` quotes what ``adaptive-dd benchmark --seeds 10`` prints. The slow test
runs that command and compares its report with the quote: only the wall time (which depends on
the machine) and the scenario's path (which depends on where the code is) are masked. The masks
are tested first on planted reports, so the comparison cannot pass by masking everything.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "getting_started.md"
COMMAND = ["benchmark", "--seeds", "10", "--no-progress"]
MASKS = (
    (re.compile(r"^Scenario \S*payload_swap\.toml:", re.M), "Scenario payload_swap.toml:"),
    (re.compile(r"^(  wall time: )[0-9.]+ s", re.M), r"\1... s"),
)


def masked(report: str) -> str:
    """``report`` with its machine-dependent parts replaced by fixed text.

    Parameters
    ----------
    report : str
        The report as printed, or as quoted in the tutorial.

    Returns
    -------
    str
        The report with the scenario's path and the wall time masked, trailing spaces removed.
    """
    for pattern, repl in MASKS:
        report = pattern.sub(repl, report)
    return "\n".join(line.rstrip() for line in report.strip().splitlines())


def quoted_report() -> str:
    """The report the tutorial quotes: the first ``text`` block after "prints this report"."""
    text = PAGE.read_text(encoding="utf-8")
    after = text[text.index("prints this report") :]
    block = re.search(r"```text\n(.*?)```", after, re.S)
    assert block, "docs/getting_started.md: no ```text block after 'prints this report'"
    return block.group(1)


def test_the_masks_hide_the_path_and_wall_time_only():
    a = "Scenario /home/u/adaptive_dd/scenarios/payload_swap.toml: 10 seeds\n  wall time: 41.3 s\nx 1.008"
    b = "Scenario adaptive_dd/scenarios/payload_swap.toml: 10 seeds\n  wall time: ... s\nx 1.008"
    assert masked(a) == masked(b)
    assert masked(a) != masked(b.replace("1.008", "1.009"))  # a figure differs: seen
    assert masked(a) != masked(b.replace("10 seeds", "20 seeds"))


def test_the_tutorial_quotes_a_whole_report():
    report = quoted_report()
    assert report.startswith("Scenario ") and "Targets (measured, not asserted):" in report
    assert report.rstrip().endswith("results/benchmark/per_seed.csv")


@pytest.mark.slow
def test_the_first_benchmark_prints_the_report_the_tutorial_shows(tmp_path):
    """About a minute on 2 cores with the kernels cached (more on a cold cache: they compile)."""
    env = os.environ | {"PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    out = subprocess.run(
        [sys.executable, "-m", "adaptive_dd.cli", *COMMAND],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    printed, quoted = masked(out.stdout).splitlines(), masked(quoted_report()).splitlines()
    differ = [(i, q, p) for i, (q, p) in enumerate(zip(quoted, printed, strict=False)) if q != p]
    assert not differ and len(printed) == len(quoted), (
        "docs/getting_started.md's report differs from what `adaptive-dd benchmark --seeds 10` prints "
        f"(line, quoted, printed): {differ[:5]}; lines {len(quoted)} quoted, {len(printed)} printed"
    )
    for name in ("tracking_error.png", "estimates.png"):
        assert (tmp_path / "results" / "benchmark" / name).is_file()
