"""Prototype (Python path) of a momentum observer fed forward by adaptive_ct.

adaptive_ct's own compiled form, run one sample at a time, plus De Luca's generalised-momentum
observer on the residual torque of the model adaptive_ct is using at that sample:
``r = beta / (s + beta) (tau - d/dt p(q, qd; pi) - wv(q, qd; pi))`` (``p = M qd``,
``wv = g - C^T qd + friction``), discrete and consistent under a changing model (``p`` at the
previous and the current sample both with the current model). Gate: ``"none"`` (always fed),
``"shrink"`` (each row soft-thresholded at ``kappa`` times its learnt RMS level).

    python studies/observer_prototype.py SCENARIO.toml [--seeds 10] [--betas 50 200] [--gate none]
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np
from _ablation import Delegating, segment_cells
from momentum_prototype import _rho
from numba import njit

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import make_controllers


@njit(cache=True)
def _observe(ch, pi, qp, qdp, q, qd, taup, r, a, T, rho):
    _rho(ch, pi, qp, qdp, q, qd, taup, T, rho)
    for i in range(q.shape[0]):
        for j in range(q.shape[1]):
            r[i, j] = a * r[i, j] + (1.0 - a) * rho[i, j]


class ObservedCT(Delegating):
    """adaptive_ct plus the observer (a plug-in: Python path)."""

    def __init__(self, inner, beta: float, gate: str, kappa: float, name: str, hold: float = 1.0) -> None:
        self.inner, self.beta, self.gate, self.kappa, self.name = inner, beta, gate, kappa, name
        self.hold = hold
        self.floor = "ct_oracle"
        self.has_detector = True

    def reset(self, n_trials, T):
        self.inner.reset(n_trials, T)
        self.T, self.a = T, float(np.exp(-self.beta * T))
        self.r = None
        self.level = None
        self.nl = 0

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        out = self.inner.command(q, qd, q_d, qd_d, qdd_d)
        pi = self.inner._form.state.pi_model
        if self.r is None:
            self.r = np.zeros_like(q)
            self.level = np.zeros_like(q)
            self.taup = np.zeros_like(q)
        else:
            rho = np.empty_like(q)
            _observe(self.inner.ch, pi, self.qp, self.qdp, q, qd, self.taup, self.r, self.a, self.T, rho)
        self.qp, self.qdp = q.copy(), qd.copy()
        self.nl += 1
        since = self.inner._form.state.since_alarm
        recent = (since < round(self.hold / self.T))[:, None]
        if self.gate == "none":
            ff = self.r
        elif self.gate == "alarm":
            ff = np.where(recent, self.r, 0.0)
        else:
            a_l = min(1.0, self.T / 1.0)
            lvl = self.level / (1.0 - (1.0 - a_l) ** self.nl)
            r2 = self.r**2
            learn = (self.nl < 200) | (r2 <= 9.0 * lvl)
            self.level = np.where(learn, self.level + a_l * (r2 - self.level), self.level)
            lvl = self.level / (1.0 - (1.0 - a_l) ** self.nl)
            thr = self.kappa * np.sqrt(lvl)
            ff = np.sign(self.r) * np.maximum(np.abs(self.r) - thr, 0.0)
            if self.nl < 500:
                ff = 0.0 * ff
            if self.gate == "alarm+shrink":
                ff = np.where(recent, self.r, ff)
        return out + ff

    def observe(self, q, qd, tau):
        self.inner.observe(q, qd, tau)
        self.taup = np.array(tau, dtype=float)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--betas", type=float, nargs="+", default=[50.0, 200.0])
    ap.add_argument("--gate", default="none")
    ap.add_argument("--kappa", type=float, default=3.0)
    ap.add_argument("--hold", type=float, default=1.0)
    ap.add_argument("--kappas", type=float, nargs="+", default=None)
    ap.add_argument("--boost-duration", type=float, default=None)
    ap.add_argument("--gates", nargs="+", default=None)
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["seeds"] = a.seeds
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    ctrls = dict(make_controllers(sc))
    if a.boost_duration is not None:
        d.setdefault("controllers", {}).setdefault("adaptive_ct", {})["boost_duration"] = a.boost_duration
        sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    for gate in a.gates or [a.gate]:
        for beta in a.betas:
            for kappa in a.kappas or [a.kappa]:
                inner = make_controllers(sc)["adaptive_ct"]
                name = f"obs_{beta:g}_{gate}" + (f"{kappa:g}" if "shrink" in gate else "")
                if a.boost_duration is not None:
                    name += f"_boost{a.boost_duration:g}"
                ctrls[name] = ObservedCT(inner, beta, gate, kappa, name, a.hold)
    df = run_benchmark(sc, controllers=ctrls, progress=False).to_frame()
    print(
        f"{a.scenario}: {a.seeds} seeds; ratio to ct_oracle per segment: mean / p90 / max; false-alarm trials"
    )
    for name, c in df.groupby("controller", sort=False):
        if name == "ct_oracle":
            continue
        fa = int((c.groupby("seed").false_alarms.sum() > 0).sum())
        print(f"{name:24s} {'  '.join(segment_cells(c))}  fa {fa}", flush=True)


if __name__ == "__main__":
    main()
