"""The two-link adaptive_ct's residual observer around the first swap, sample by sample: its
residual ``r`` per joint, its threshold (``kappa`` times the learnt RMS level) and the estimate's
J1, every 4 ms from 10 ms before the swap to 60 ms after it; the residual's RMS over the 2 s
before the swap; the alarm times. The default scenario cut after its first swap, on the Python
path (the controller's state read after each command).

    python studies/two_link_observer_trace.py [SCENARIO.toml] [--seeds 2]
"""

from __future__ import annotations

import argparse
import copy
from importlib import resources
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.residual_observer import O_COUNT, O_LEVEL, O_R
from adaptive_dd.controllers.adaptive import AdaptiveCT


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument(
        "scenario", nargs="?", default=str(resources.files("adaptive_dd.scenarios") / "payload_swap.toml")
    )
    ap.add_argument("--seeds", type=int, default=2)
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    swap = float(d["payload"][0]["at"])
    d["run"] = {**d["run"], "controllers": ["adaptive_ct"], "duration": swap + 0.3}
    d["payload"] = d["payload"][:1]
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    log = []
    command = AdaptiveCT.command

    def traced(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        tau = command(self, q, qd, q_d, qd_d, qdd_d, sigma_true)
        st, g = self.estimator.state, self.observer_settings(self.T)
        bias = 1.0 - (1.0 - g.obs_alpha) ** st.obs[:, O_COUNT, 0]
        thr = g.obs_kappa * np.sqrt(st.obs[:, O_LEVEL] / np.maximum(bias, 1e-300)[:, None])
        log.append((st.obs[:, O_R].copy(), thr, st.sigma_model[:, 0].copy()))
        return tau

    AdaptiveCT.command = traced
    res = run_benchmark(sc, progress=False, engine="python", seed_indices=tuple(range(a.seeds)))
    T = sc.sample_period
    r = np.array([x[0] for x in log])
    k_swap = round(swap / T)
    print("alarms [s]:", res.runs["adaptive_ct"].alarm_times)
    for i in range(a.seeds):
        rms = np.sqrt(np.mean(r[k_swap - 2000 : k_swap, i] ** 2, axis=0))
        print(f"seed {i}: residual RMS over the 2 s before the swap {np.round(rms, 2)} N m")
        for k in range(k_swap - 10, k_swap + 61, 4):
            ri, thr, j1 = log[k][0][i], log[k][1][i], log[k][2][i]
            at = f"{1e3 * (k - k_swap) * T:+4.0f} ms"
            print(f"  {at}  r {np.round(ri, 2)}  threshold {np.round(thr, 2)}  J1 {j1:.3f}")


if __name__ == "__main__":
    main()
