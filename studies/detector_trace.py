"""Sample-by-sample trace of the change detector of ``adaptive_ct`` on one scenario, plant and seed.

``python studies/detector_trace.py SCENARIO --plant stick-slip --seed 7 --window 1.80 1.90``
runs ``adaptive_ct`` alone on that seed through the Python path (the same compiled step as the
benchmark) and prints, for every sample in the window: the measured joint speeds, which
equations feed the tests (``act``: faster than the detector's speed for its memory; ``rest``:
not at rest within the selection memory), the prior errors, the weights, and the best GLR
candidate (score, onset age, mass estimate ``A / B``, explained fraction ``A^2 / (B E)``) with
the threshold in force, the payload mass the estimate carries, and the alarms. With
``--alarms`` it first lists the alarm times of the first ``--seeds`` seeds and which of them
are false alarms.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.controllers.adaptive import adaptive_ct
from adaptive_dd.identification import two_link_online_kernel as K

PLANTS = {
    "own": None,
    "stick-slip": {"friction": "stick-slip"},
    "tanh-0.02": {"friction": "tanh", "friction_velocity": 0.02},
    "tanh-0.1": {"friction": "tanh", "friction_velocity": 0.1},
    "stribeck": {"friction": "stribeck"},
    "lugre": {"friction": "lugre"},
}


class TracedAdaptiveCT(type(adaptive_ct())):
    """``adaptive_ct`` that records, after every sample, what its detector saw."""

    def reset(self, n_trials, sample_period):
        super().reset(n_trials, sample_period)
        self.rows = []

    def observe(self, q, qd, tau):
        info = self.estimator.update(q, qd, tau)
        st = self.estimator.state
        self.rows.append(
            (
                qd[0].copy(),
                info.eps[0].copy(),
                st.short[0].copy(),
                st.cnt[0].copy(),
                info.alarm[0],
                st.theta[0].copy(),
            )
        )


def glr_best(sh: np.ndarray, hetero: float) -> tuple[float, float, float, float, float]:
    """Best GLR candidate of one trial's statistics: (score, age [samples], A, B, E)."""
    best = (0.0, 0.0, 0.0, 0.0, 0.0)
    for c in range(K.GLR_CANDIDATES):
        c0 = K.S_GLR + c * K.GLR_STRIDE
        a0, a1, b0, b1 = sh[c0 + K.G_A : c0 + K.G_A + 4]
        a, b = a0 + a1, b0 + b1
        if not b > 0:
            continue
        glr = a * a / b
        het = (a0 * a0 / b0 if b0 > 0 else 0.0) + (a1 * a1 / b1 if b1 > 0 else 0.0) - glr
        score = glr - het / hetero
        if score > best[0]:
            best = (score, sh[c0 + K.G_AGE], a, b, sh[c0 + K.G_E])
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("--plant", default="own", choices=list(PLANTS))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--window", type=float, nargs=2, default=None)
    ap.add_argument("--alarms", action="store_true", help="list alarm times of the first --seeds seeds")
    ap.add_argument("--seeds", type=int, default=50)
    args = ap.parse_args()
    sc = load_scenario(args.scenario)
    spec = PLANTS[args.plant]
    arm = sc.arm if spec is None else dataclasses.replace(sc.arm, **spec)
    sc = dataclasses.replace(sc, arm=arm, controllers=("adaptive_ct",))
    if args.alarms:
        res = run_benchmark(sc, progress=False, keep_trajectories=0, seed_indices=range(args.seeds))
        for s, tr in enumerate(res.runs["adaptive_ct"].alarm_times):
            false = [x for x in tr if not any(0 <= x - w < FALSE_ALARM_WINDOW for w in sc.swap_times)]
            if false:
                print(f"seed {s}: alarms {[round(x, 3) for x in tr]}  false {[round(x, 3) for x in false]}")
    if args.window is None:
        return
    ctrl = TracedAdaptiveCT()
    res = run_benchmark(
        sc, progress=False, controllers={"adaptive_ct": ctrl}, engine="python", seed_indices=[args.seed]
    )
    print(f"seed {args.seed}: alarms {[round(x, 3) for x in res.runs['adaptive_ct'].alarm_times[0]]}")
    cfg = ctrl.estimator.cfg
    ci, cf = cfg.packed[0], cfg.packed[1]
    T = cfg.sample_period
    print(
        "   t      qd1     qd2  act rest     eps1       eps2      w1       w2     GLR   age   dm_hat  expl"
        "   thr  m_hat alarm"
    )
    d = np.asarray(cfg.payload_direction)
    for k, (qd, eps, sh, cnt, alarm, th) in enumerate(ctrl.rows):
        t = k * T
        if not args.window[0] <= t <= args.window[1]:
            continue
        act = [cnt[K.C_SINCE_SLOW_DET1 + j] > ci[K.I_SPEED_MEMORY] for j in range(2)]
        rest = [cnt[K.C_SINCE_SLOW1 + j] > ci[K.I_SEL_MEMORY] for j in range(2)]
        w = [1.0 / sh[K.S_LREF + j] if sh[K.S_LREF + j] > 0 else 0.0 for j in range(2)]
        score, age, a, b, e = glr_best(sh, cf[K.F_HETERO])
        thr = cf[K.F_GLR_THRESHOLD] * (1.0 if all(rest) else np.sqrt(cf[K.F_SLOW_FACTOR]))
        dm = a / b if b > 0 else 0.0
        expl = a * a / (b * e) if b > 0 and e > 0 else 0.0
        m_hat = th[:3] @ d[:3] / (d @ d) - sh[K.S_M0]
        print(
            f"{t:7.3f} {qd[0]:7.3f} {qd[1]:7.3f}  {int(act[0])}{int(act[1])}   {int(rest[0])}{int(rest[1])}  "
            f"{eps[0]:9.2e} {eps[1]:9.2e} {w[0]:8.2e} {w[1]:8.2e} {score:7.1f} {age:5.0f} {dm:7.3f} "
            f"{expl:5.2f} {thr:5.0f} {m_hat:6.2f}  {'ALARM' if alarm else ''}"
        )


if __name__ == "__main__":
    main()
