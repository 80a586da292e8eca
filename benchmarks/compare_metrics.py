"""Compare two ``metrics.json`` of ``adaptive-dd benchmark`` number by number.

    python benchmarks/compare_metrics.py BEFORE/metrics.json AFTER/metrics.json

Prints the worst relative difference over every float (wall times and provenance left out)
and any other value that differs; exits 1 if the structures differ. Used to check that a speed
change leaves the results unchanged (e.g. the UR5 scenario at 20 seeds, main against a branch).
"""

from __future__ import annotations

import json
import math
import sys

SKIP = ("wall_time", "provenance")


def compare(a, b, path: str = "") -> tuple[int, float, str, list[str]]:
    """(floats compared, worst relative difference, where, other differences)."""
    count, worst, where, other = 0, 0.0, "", []
    if any(s in path for s in SKIP):
        return count, worst, where, other
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            raise ValueError(f"{path}: keys differ: {sorted(set(a) ^ set(b))}")
        parts = [compare(a[k], b[k], f"{path}/{k}") for k in a]
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            raise ValueError(f"{path}: lengths {len(a)} and {len(b)}")
        parts = [compare(x, y, f"{path}[{i}]") for i, (x, y) in enumerate(zip(a, b, strict=True))]
    elif isinstance(a, float) and isinstance(b, float):
        if math.isnan(a) or math.isnan(b):
            return 1, (0.0 if math.isnan(a) and math.isnan(b) else math.inf), path, other
        r = abs(a - b) / max(abs(a), abs(b), 1e-300)
        return 1, r, path, other
    else:
        return 0, 0.0, "", ([] if a == b else [f"{path}: {a!r} != {b!r}"])
    for c, w, p, o in parts:
        count += c
        other += o
        if w > worst:
            worst, where = w, p
    return count, worst, where, other


def main() -> int:
    with open(sys.argv[1], encoding="utf-8") as fa, open(sys.argv[2], encoding="utf-8") as fb:
        a, b = json.load(fa), json.load(fb)
    try:
        count, worst, where, other = compare(a, b)
    except ValueError as exc:
        print(f"structures differ: {exc}")
        return 1
    for line in other:
        print(f"differs: {line}")
    at = f" at {where}" if where else ""
    print(f"{count} floats compared; worst relative difference {worst:.3g}{at}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
