"""Cold-cache compilation of the N-joint estimator and closed loop, in CPU seconds.

Usage (from the repository's root)::

    python benchmarks/cold_compile.py

Runs, each in a fresh process with ``NUMBA_CACHE_DIR`` a fresh temporary folder (a cold cache,
removed afterwards): (1) the estimator alone, ``run_online`` on a 50-sample UR5 record in payload
mode then in mode "arm"; (2) one 0.3-s ``adaptive_ct`` trial of the UR5 tool-swap scenario (no
swap) through ``run_benchmark`` (``chain_loop_block``, the estimator inlined). Prints each one's
CPU seconds (``time.process_time``) and a result to compare across trees. Asserts nothing: a
measurement; read it beside the load printed.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile

_ESTIMATOR = """
import time
t0 = time.process_time()
import numpy as np
from adaptive_dd.identification.arm_prior import ArmUncertainty
from adaptive_dd.identification.online import OnlineConfig, run_online
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import ROBOTS, robot_urdf
arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
t1 = time.process_time()
rng = np.random.default_rng(0)
q, qd, tau = rng.normal(size=(50, 6)) * 0.1, rng.normal(size=(50, 6)), rng.normal(size=(50, 6))
run_online(arm, OnlineConfig(), q, qd, tau)
rec = run_online(arm, OnlineConfig(arm_uncertainty=ArmUncertainty()), q, qd, tau)
t2 = time.process_time()
print(f"estimator: import {t1 - t0:.1f} CPU s, run_online payload + arm {t2 - t1:.1f} CPU s; "
      f"sum of the arm-mode estimate {np.nansum(rec.theta[0, -1]):.6g}")
"""

_LOOP = """
import time, tomllib
from importlib import resources
t0 = time.process_time()
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario
path = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml"))
data = tomllib.loads(open(path, encoding="utf-8").read())
data["run"] = {**data["run"], "duration": 0.3, "seeds": 1, "controllers": ["adaptive_ct"]}
data["payload"], data["reference"]["ramp"] = [], 0.2
sc = parse_scenario(data, "x.toml", name="ur5_tool_swap")
t1 = time.process_time()
df = run_benchmark(sc, progress=False).to_frame()
t2 = time.process_time()
print(f"closed loop: import {t1 - t0:.1f} CPU s, one 0.3-s UR5 adaptive_ct trial {t2 - t1:.1f} CPU s; "
      f"rms error {df.rms_error_rad.iloc[0]:.10g} rad")
"""


def main() -> None:
    for code in (_ESTIMATOR, _LOOP):
        cache = tempfile.mkdtemp(prefix="adaptive_dd_cold_")
        try:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            subprocess.run([sys.executable, "-c", code], env=env, check=True)
        finally:
            shutil.rmtree(cache, ignore_errors=True)
    print(f"load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
