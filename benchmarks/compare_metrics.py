"""Compare two benchmark ``metrics.json`` files number by number (a refactoring's safety net).

Usage::

    python benchmarks/compare_metrics.py BEFORE.json AFTER.json [--rtol 1e-9]

Every number (ratios, RMS, alarms, delays, masses, ...) must agree to ``rtol`` relative
(``atol = rtol`` near zero); NaN/None must match; keys must match. The provenance block
(commit, command line, wall time, engines), wall-time fields and the scenario's file path are
left out; keys renamed since a file was written (:data:`RENAMED`) are read under their new names. Prints the
count of numbers compared and each difference; exits 1 on any difference.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

SKIP = {"provenance", "wall_time", "wall_time_s", "wall time"}
RENAMED = {"recovery_time": "settling_time"}
"""Keys renamed since (old: new): a file written before is read with the new names."""


def renamed(x):
    """``x`` (parsed JSON) with the keys of :data:`RENAMED` under their new names."""
    if isinstance(x, dict):
        return {RENAMED.get(k, k): renamed(v) for k, v in x.items()}
    if isinstance(x, list):
        return [renamed(v) for v in x]
    return x


def walk(a, b, path, out, stats):
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            out.append(f"{path}: keys differ: {sorted(set(a) ^ set(b))}")
        for k in sorted(set(a) & set(b)):
            if k in SKIP or "wall" in k or (k == "scenario" and isinstance(a[k], str)):
                continue  # the scenario's path differs between worktrees
            walk(a[k], b[k], f"{path}.{k}", out, stats)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{path}: lengths {len(a)} != {len(b)}")
        for i, (x, y) in enumerate(zip(a, b, strict=False)):
            walk(x, y, f"{path}[{i}]", out, stats)
    elif isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str) or a is None or b is None:
        stats["other"] += 1
        if a != b:
            out.append(f"{path}: {a!r} != {b!r}")
    elif isinstance(a, int | float) and isinstance(b, int | float):
        stats["numbers"] += 1
        if math.isnan(a) or math.isnan(b):
            if not (math.isnan(a) and math.isnan(b)):
                out.append(f"{path}: {a!r} != {b!r}")
        elif abs(a - b) > stats["rtol"] * max(abs(a), abs(b), 1.0):
            out.append(f"{path}: {a!r} != {b!r} (rel {abs(a - b) / max(abs(a), abs(b), 1e-300):.2e})")
    elif a != b:
        out.append(f"{path}: {a!r} != {b!r}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--rtol", type=float, default=1e-9)
    args = ap.parse_args()
    with open(args.before) as f:
        a = json.load(f)
    with open(args.after) as f:
        b = json.load(f)
    out: list[str] = []
    stats = {"numbers": 0, "other": 0, "rtol": args.rtol}
    walk(renamed(a), renamed(b), "", out, stats)
    print(f"compared {stats['numbers']} numbers and {stats['other']} other values at rtol {args.rtol:g}")
    for line in out[:50]:
        print("DIFF", line)
    print("agree" if not out else f"{len(out)} differences")
    return 1 if out else 0


if __name__ == "__main__":
    sys.exit(main())
