"""When adaptive_ct's momentum test starts the boost (``observer_momentum_test = true``): per swap
the median delay from the swap to the first start [ms] (against the estimator's alarm), and the
starts outside every swap's first second (false starts: the trials with one, and when).

The law run on the Python path (its compiled kernels, one sample at a time), so that the
observer's state can be read after each sample: a start is ``obs[O_TRIP, 0] == 0``.

    python studies/momentum_trips.py SCENARIO.toml [...] [--seeds 10] [--set KEY=VALUE ...]
"""

from __future__ import annotations

import argparse
import copy
import json
from pathlib import Path

import numpy as np
from _ablation import Delegating

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.residual_observer import O_TRIP
from adaptive_dd.closed_loop.runner import make_controllers


class Starts(Delegating):
    """adaptive_ct (its command unchanged) recording the samples at which the boost was started
    by the momentum test."""

    def __init__(self, inner):
        self.inner, self.name, self.floor, self.has_detector = inner, "adaptive_ct", "ct_oracle", True

    def reset(self, n_trials, T):
        self.inner.reset(n_trials, T)
        self.T, self.k, self.starts = T, 0, [[] for _ in range(n_trials)]

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        out = self.inner.command(q, qd, q_d, qd_d, qdd_d)
        for i in np.flatnonzero(self.inner._form.state.obs[:, O_TRIP, 0] == 0.0):
            self.starts[i].append((self.k + 1) * self.T)
        self.k += 1
        return out

    def observe(self, q, qd, tau):
        self.inner.observe(q, qd, tau)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenarios", nargs="+")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--set", nargs="*", default=[], help="adaptive_ct settings KEY=VALUE (TOML/JSON values)")
    a = ap.parse_args()
    for path in a.scenarios:
        d = copy.deepcopy(read_toml(Path(path)))
        d["run"]["seeds"] = a.seeds
        d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
        ac = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
        ac["observer_momentum_test"] = True
        for kv in a.set:
            k, v = kv.split("=", 1)
            ac[k] = json.loads(v)
        sc = parse_scenario(d, path, Path(path).stem)
        rec = Starts(make_controllers(sc)["adaptive_ct"])
        run_benchmark(sc, controllers={"adaptive_ct": rec}, progress=False, keep_trajectories=0)
        swaps = list(sc.swap_times)
        delay = np.full((a.seeds, len(swaps)), np.nan)
        alarm = np.full((a.seeds, len(swaps)), np.nan)
        false = []
        for s in range(a.seeds):
            st = np.array(rec.starts[s])
            for i, sw in enumerate(swaps):
                hit = st[(st >= sw) & (st < sw + FALSE_ALARM_WINDOW)]
                delay[s, i] = hit[0] - sw if hit.size else np.nan
                al = [x - sw for x in rec.alarm_times[s] if 0 <= x - sw < FALSE_ALARM_WINDOW]
                alarm[s, i] = min(al) if al else np.nan
            inside = np.zeros(st.shape, bool)
            for sw in swaps:
                inside |= (st >= sw) & (st < sw + 1.0)
            if (~inside).any():
                false.append((s, np.round(st[~inside][:4], 3).tolist()))
        print(
            f"{path}: {a.seeds} seeds; the momentum test's first start after each swap, median (max) [ms]; "
            "the estimator's alarm (median); trials with a start outside the swaps' first second"
        )
        cells = [f"{1e3 * np.nanmedian(delay[:, i]):.0f} ({1e3 * np.nanmax(delay[:, i]):.0f})"
                 if np.isfinite(delay[:, i]).any() else "-" for i in range(len(swaps))]  # fmt: skip
        print(
            f"  starts {' / '.join(cells)}; none after {int(np.isnan(delay).sum())} swaps; "
            f"alarm {' / '.join(f'{1e3 * np.nanmedian(alarm[:, i]):.0f}' for i in range(len(swaps)))}; "
            f"false starts in {len(false)} of {a.seeds} trials {false}",
            flush=True,
        )


if __name__ == "__main__":
    main()
