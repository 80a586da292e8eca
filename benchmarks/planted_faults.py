"""Plant faults in the headline statistics, one at a time, and check that the tests catch each.

Copies the package, the tests and the scenarios they read (``benchmarks/``, ``examples/``) to a
temporary folder (stops, exit 2, if the tests fail there before any fault), applies one fault to
the copy of ``adaptive_dd/benchmark/metrics.py`` (the three of the issue, the review's six, and two more:
missed swaps and detection delays), runs ``tests/test_statistics.py`` there and prints how many
tests failed. A fault that no test catches is printed as ``NOT caught``. The working tree is
never touched.

Run: ``python benchmarks/planted_faults.py`` (about 5 s per fault).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
METRICS = "adaptive_dd/benchmark/metrics.py"

FAULTS = {
    "false-alarm window 1e9 s": (
        "FALSE_ALARM_WINDOW = 0.3  #",
        "FALSE_ALARM_WINDOW = 1e9  #",
    ),
    "trials with a false alarm forced to 0": (
        '"trials_with_false_alarms"] = int(sum(1 for n, g in zip(false, ok, strict=True) if g and n))',
        '"trials_with_false_alarms"] = 0',
    ),
    "p90 computed as the 10th percentile": (
        '"p90": float(np.percentile(r, 90)),',
        '"p90": float(np.percentile(r, 10)),',
    ),
    "worst seed as a position, not a seed index": (
        '"worst_seed": int(seeds[idx[np.argmax(r)]]),',
        '"worst_seed": int(idx[np.argmax(r)]),',
    ),
    "median computed as the mean": (
        '"median": float(np.median(r)),',
        '"median": float(np.mean(r)),',
    ),
    "95 % interval drawn from an unseeded generator (not reproducible)": (
        "ci = mean_interval(r)",
        "ci = mean_interval(r, np.random.default_rng())",
    ),
    "missed swaps not counted": (
        "missed += lost",
        "pass",
    ),
    "detection delay averaged over all seeds (a miss as 0)": (
        'seg["detection_delay"] = float(np.mean(hit)) if hit else None',
        'seg["detection_delay"] = float(np.sum(hit) / max(len(ok), 1)) if hit else None',
    ),
}


def run_one(tmp: Path, old: str, new: str) -> str:
    """Apply one fault to the copy, run the statistics tests, restore; pytest's last line."""
    path = tmp / METRICS
    text = path.read_text()
    if old not in text:
        return "fault not applicable (the code changed): update FAULTS"
    path.write_text(text.replace(old, new, 1))
    try:
        p = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/test_statistics.py"],
            cwd=tmp,
            capture_output=True,
            text=True,
            check=False,
        )
    finally:
        path.write_text(text)
    return (p.stdout.strip().splitlines() or ["?"])[-1]


def main() -> int:
    missed = 0
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        shutil.copytree(
            ROOT / "adaptive_dd", tmp / "adaptive_dd", ignore=shutil.ignore_patterns("__pycache__")
        )
        for folder in ("tests", "benchmarks", "examples"):  # the tests read scenarios of the other two
            shutil.copytree(ROOT / folder, tmp / folder, ignore=shutil.ignore_patterns("__pycache__"))
        clean = run_one(tmp, "", "")
        print(f"clean copy: {clean}")
        if " failed" in clean or " passed" not in clean:
            print("the tests fail on the clean copy: no fault's verdict would mean anything")
            return 2
        for name, (old, new) in FAULTS.items():
            line = run_one(tmp, old, new)
            caught = " failed" in line
            missed += not caught
            print(f"{name:55s} {line}  ({'caught' if caught else 'NOT caught'})")
    print(f"{len(FAULTS) - missed} of {len(FAULTS)} planted faults caught by tests/test_statistics.py")
    return 1 if missed else 0


if __name__ == "__main__":
    raise SystemExit(main())
