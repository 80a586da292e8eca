"""Time each gallery example as the documentation's build runs it: wall and CPU seconds.

Each ``examples/gallery/plot_*.py`` runs in a fresh Python process (as sphinx-gallery runs it in
the build, figures drawn but not shown), one after the other; the script prints, per example, the
wall time, the CPU time of the process and its threads (user + system), and the load average
before it started, then the totals. CPU seconds depend little on what else runs on the machine;
wall seconds do. Run it with the numba cache warm (a first run compiles the kernels; the build's
own timing, ``docs/sg_execution_times.rst``, is the wall time of the same scripts). From the
repository's root::

    python docs/figures/gallery_times.py
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
GALLERY = ROOT / "examples" / "gallery"


def run(script: Path) -> tuple[float, float]:
    """Wall and CPU seconds of one example in a fresh process (the CPU of its threads included)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    env = os.environ | {"PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    subprocess.run([sys.executable, str(script)], cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> None:
    total_wall = total_cpu = 0.0
    print(f"{'example':32s} {'wall [s]':>9s} {'CPU [s]':>9s} {'load before':>12s}")
    for script in sorted(GALLERY.glob("plot_*.py")):
        load = os.getloadavg()[0]
        wall, cpu = run(script)
        total_wall, total_cpu = total_wall + wall, total_cpu + cpu
        print(f"{script.stem:32s} {wall:9.1f} {cpu:9.1f} {load:12.1f}")
    print(f"{'total':32s} {total_wall:9.1f} {total_cpu:9.1f}   ({os.cpu_count()} cores)")


if __name__ == "__main__":
    main()
