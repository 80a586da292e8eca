"""Experiment (issue 45, removed after): coverage with the per-direction small-sample correction, the same fits.

Run from the repository root: python benchmarks/log_bounds_direction.py FIRST SEEDS OUT.npz MODES (global,hmatrix,...)
"""

import sys, time, functools
import numpy as np

sys.path.insert(0, "benchmarks")
import log_bounds_coverage as B
import adaptive_dd.identification.log_fit as LF
from adaptive_dd.identification.model import arm_model
from adaptive_dd.identification.records import synthetic_log
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import robot_urdf

MODES = sys.argv[4].split(",") if len(sys.argv) > 4 else ["global", "none", "diag", "matrix"]
_orig = LF.filtered_regression
_cache = {}


def cached(model, q, *a, **k):
    key = (id(model), q.shape, float(q[0, 0]), float(q[-1, -1]), float(q.sum()))
    if key not in _cache:
        _cache.clear()
        _cache[key] = _orig(model, q, *a, **k)
    return _cache[key]


LF.filtered_regression = cached
B.OFFSET["on"] = True
first, seeds, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
arm = Arm.from_urdf(robot_urdf("vertical3"))
model = arm_model(arm)
ur5 = Arm.from_urdf(robot_urdf("ur5"))
m5 = arm_model(ur5)
from adaptive_dd.identification.payload_pair import payload_from_pair
from adaptive_dd.plant.payload import payload_parameters

res = {}


def add(key, v):
    res.setdefault(key, []).append(v)


t0 = time.perf_counter()
c0 = time.process_time()
for s in range(first, first + seeds):
    rng = np.random.default_rng([45, s])
    one = synthetic_log(arm, 24.0, B.T, rng)
    two = [synthetic_log(arm, 12.0, B.T, rng) for _ in range(2)]
    for case, logs, holes, truth in (
        ("gaps", [one], B.HOLES, one.sigma_true),
        ("records", two, (), two[0].sigma_true),
    ):
        for mode in MODES:
            LF.CORRECTION["mode"] = mode
            f = B.fit(model, logs, holes)
            add(f"{case}_{mode}_z", (f.sigma - truth) / f.std)
            add(f"{case}_{mode}_est", f.sigma)
            add(f"{case}_{mode}_std", f.std)
            add(f"{case}_{mode}_q", f.quantile)
    rng = np.random.default_rng([45, s, 1])
    com = np.array([0.03, -0.02, 0.05])
    pp = payload_parameters(2.0, com, np.diag([4e-3, 5e-3, 3e-3]))
    L = [synthetic_log(ur5, 12.0, B.T, rng, payload=pp) for _ in range(2)]
    U = [synthetic_log(ur5, 12.0, B.T, rng) for _ in range(2)]
    for mode in MODES:
        LF.CORRECTION["mode"] = mode
        fl = B.fit(m5, L)
        fu = B.fit(m5, U)
        pr = payload_from_pair(ur5, fl.sigma, fl.cov, fu.sigma, fu.cov, weighting="diagonal")
        est = np.array([pr.mass, *pr.com])
        std = np.array([pr.mass_std, *pr.com_std])
        add(f"pair_{mode}_z", (est - np.array([2.0, *com])) / std)
        add(f"pair_{mode}_est", est)
        add(f"pair_{mode}_std", std)
        add(f"pair_{mode}_q", 1.96)
    np.savez(out, **{k: np.array(v) for k, v in res.items()})
    print(s, f"{time.perf_counter() - t0:.0f} s wall {time.process_time() - c0:.0f} s cpu", flush=True)
