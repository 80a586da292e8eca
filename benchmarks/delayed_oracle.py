"""The floor that detection delay alone puts under adaptive control of an N-joint arm.

``DelayedOracle`` is computed torque with the textbook law of ``ct_oracle_textbook`` and the
TRUE model, except that it learns of each payload change only ``delay`` seconds after it: what
an estimator that knew the new payload exactly at its alarm would reach (adaptive_ct detects a
swap 5-10 ms after it on the UR5). Its ratio to ``ct_oracle_textbook`` per segment and seed,
beside adaptive_ct's ratio to ct_oracle, tells how much of adaptive_ct's excess the delay alone
explains. With ``delay = 0`` it is ``ct_oracle_textbook`` itself (ratio 1 to rounding: the
check that the plug-in is the same law). ``--boost`` adds adaptive_ct's feedback boost
(``M0(q) (dkp e + dkd e')`` raising the bandwidth to ``boost_bandwidth`` for ``boost_duration``)
from the moment the model switches, as adaptive_ct does from its alarm.

    python benchmarks/delayed_oracle.py [SCENARIO.toml] [--seeds 20] [--delays 0 0.005 0.01 0.02] [--boost]

The plug-in runs on the Python path (one compiled ``model_torque`` call per trial and sample).
"""

from __future__ import annotations

import argparse
import copy
from collections import deque
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.controllers import JointGains
from adaptive_dd.closed_loop.laws import model_torque
from adaptive_dd.closed_loop.runner import make_controllers
from adaptive_dd.plant.chain import mass_matrix

UR5 = Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml"


class DelayedOracle:
    """``ct_oracle_textbook``'s law with the true model of ``delay`` seconds ago (a plug-in).

    Parameters
    ----------
    arm : SerialArm
    gains : JointGains
    delay : float
        [s], >= 0.
    boost : (float, float) or None
        ``(boost_bandwidth [rad/s], boost_duration [s])`` after each switch of the model; None: none.
    """

    needs_true_model = True
    floor = "ct_oracle_textbook"

    def __init__(
        self, arm, gains: JointGains, delay: float, boost: tuple[float, float] | None = None
    ) -> None:
        if not delay >= 0:
            raise ValueError(f"delay must be >= 0 s, got {delay!r}")
        self.arm, self.gains, self.delay, self.boost = arm, gains, float(delay), boost
        self.name = f"delayed_oracle_{1e3 * delay:g}ms" + ("_boost" if boost else "")
        self._bpinv = np.linalg.pinv(arm.base.B)
        self._pi0, self._sigma0 = arm.pi, arm.base.B @ arm.pi

    def reset(self, n_trials: int, sample_period: float) -> None:
        self._past = deque(maxlen=round(self.delay / sample_period) + 1)
        self._boost_left = np.zeros(n_trials, dtype=np.int64)
        self._T = sample_period

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        self._past.append(np.array(sigma_true, dtype=float))
        sigma = self._past[0]  # the oldest kept: ``delay`` ago (the first sample's at the start)
        pi = self._pi0 + (sigma - self._sigma0) @ self._bpinv.T  # (m, 13 n), B pi == sigma
        e, ed = q_d - q, qd_d - qd
        a = qdd_d + self.gains.kd * ed + self.gains.kp * e
        out = np.empty_like(q)
        for i in range(q.shape[0]):
            model_torque(self.arm.chain, pi[i], q[i], qd[i], qd[i], qd_d, a[i], out[i])
        if self.boost is not None:
            if len(self._past) > 1:
                switched = np.any(self._past[0] != self._past[1], axis=-1)  # the model changes next sample
                self._boost_left[switched] = round(self.boost[1] / self._T) + 1
            w, z = self.gains.bandwidth, self.gains.damping
            wb = np.maximum(self.boost[0], w)
            dkp, dkd = wb**2 - w**2, 2.0 * z * (wb - w)
            n = q.shape[1]
            m0 = np.empty((n, n))
            for i in np.flatnonzero(self._boost_left > 0):
                mass_matrix(self.arm.chain, self._pi0[: 10 * n], q[i], m0)
                v = dkp * e[i] + dkd * ed[i]
                out[i] += m0 @ v + self._pi0[12 * n :] * v
            self._boost_left = np.maximum(self._boost_left - 1, 0)
        return out

    def observe(self, q, qd, tau) -> None:
        pass


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(UR5))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--delays", type=float, nargs="+", default=[0.0, 0.005, 0.01, 0.02])
    ap.add_argument("--boost", action="store_true", help="adaptive_ct's feedback boost after each switch")
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["seeds"] = a.seeds
    d["run"]["controllers"] = ["ct_oracle", "ct_oracle_textbook", "adaptive_ct"]
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    ctrls = make_controllers(sc)
    gains = JointGains.of(sc.bandwidth, sc.damping, sc.arm.n_joints)
    for delay in a.delays:
        boost = None
        if a.boost:
            ac = ctrls["adaptive_ct"]
            boost = (ac.boost_bandwidth, ac.boost_duration)
        c = DelayedOracle(sc.arm, gains, delay, boost)
        ctrls[c.name] = c
    df = run_benchmark(sc, controllers=ctrls).to_frame()
    print(f"{a.scenario}: {a.seeds} seeds; per segment, ratio to the floor per seed: mean / p90 / max")
    for name, c in df.groupby("controller", sort=False):
        if c.floor.iloc[0] in (None, "", "None") or c.ratio_to_floor.isna().all():
            continue
        cells = []
        for _, s in c.groupby("segment"):
            r = s.ratio_to_floor.to_numpy(dtype=float)
            cells.append(f"{np.nanmean(r):.3f}/{np.nanpercentile(r, 90):.3f}/{np.nanmax(r):.2f}")
        print(f"{name:24s} (floor {c.floor.iloc[0]:18s}) {'  '.join(cells)}", flush=True)


if __name__ == "__main__":
    main()
