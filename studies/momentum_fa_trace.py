"""Why the momentum test crosses without a swap: its shipped arithmetic replayed on adaptive_ct's
own closed-loop records, each false crossing taken apart.

Records adaptive_ct (the default law, its command unchanged: the test does not act before its first
crossing, so the first false crossing is the one ``"reopen"`` would raise) on the Python path: per
sample the observer's residual ``rho`` of the model the law uses, the same with each trial's true
plant (``rho_true``: what the plant's own model error leaves out of it), ``M(q)``, the model's and
the plant's Coulomb friction, the measured and the reference velocity. Then replays the shipped
:func:`adaptive_dd.closed_loop.residual_observer._momentum_test` sample by sample (its compiled form, the
law's own settings) and, at each crossing outside the swaps' first second, prints the window
that crossed, each row's share of the statistic, each joint's measured / reference speed, and
the window's mean of ``rho - rho_true`` per row (the model's error) against the model's Coulomb
friction.

    python studies/momentum_fa_trace.py SCENARIO.toml [--seeds 10] [--set KEY=VALUE ...]
        [--plant KEY=VALUE ...] [--save FILE.npz | --load FILE.npz] [--show 3]
"""

from __future__ import annotations

import argparse
import copy
import json
from pathlib import Path

import numpy as np
from _ablation import Delegating
from momentum_prototype import _mass, _rho

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop import laws
from adaptive_dd.closed_loop import residual_observer as ro
from adaptive_dd.closed_loop.runner import make_controllers


class Recorded(Delegating):
    """adaptive_ct, its command unchanged, recording what the momentum test reads."""

    needs_true_model = True
    takes_pi_true = True

    def __init__(self, inner, K):
        self.inner, self.K, self.name = inner, K, "adaptive_ct"
        self.floor, self.has_detector = "ct_oracle", True

    def reset(self, n_trials, T):
        self.inner.reset(n_trials, T)
        self.T, self.k, self.qp, self.r = T, 0, None, None

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None, pi_true=None):
        out = self.inner.command(q, qd, q_d, qd_d, qdd_d)
        S, n = q.shape
        if self.r is None:
            K = self.K
            self.r = {
                "rho": np.zeros((S, K, n)), "rho_true": np.zeros((S, K, n)), "qd": np.zeros((S, K, n)),
                "qd_d": np.zeros((K, n)), "mass": np.zeros((S, K, n, n)), "fc": np.zeros((S, K, n)),
                "fc_true": np.zeros((S, K, n)),
            }  # fmt: skip
        pi = self.inner._form.state.pi_model
        k, r = self.k, self.r
        if self.qp is not None and k < self.K:
            ch = self.inner.ch
            _rho(ch, pi, self.qp, self.qdp, q, qd, self.taup, self.T, r["rho"][:, k])
            pt = np.ascontiguousarray(pi_true, dtype=float)
            _rho(ch, self.ptp, self.qp, self.qdp, q, qd, self.taup, self.T, r["rho_true"][:, k])
            r["qd"][:, k], r["qd_d"][k] = qd, qd_d
            _mass(ch, pi, q, r["mass"][:, k])
            r["fc"][:, k] = pi[:, 11 * n : 12 * n]
            r["fc_true"][:, k] = pt[:, 11 * n : 12 * n]
        self.qp, self.qdp = q.copy(), qd.copy()
        self.ptp = np.ascontiguousarray(pi_true, dtype=float).copy()
        self.k += 1
        return out

    def observe(self, q, qd, tau):
        self.inner.observe(q, qd, tau)
        self.taup = np.array(tau, dtype=float)


def record(path: str, seeds: int, sets: list[str], plant: list[str]):
    d = copy.deepcopy(read_toml(Path(path)))
    for kv in plant:
        key, v = kv.split("=", 1)
        d.setdefault("plant", {})[key] = json.loads(v)
    d["run"]["seeds"] = seeds
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    ac = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
    for kv in sets:
        key, v = kv.split("=", 1)
        ac[key] = json.loads(v)
    sc = parse_scenario(d, path, Path(path).stem)
    inner = make_controllers(sc)["adaptive_ct"]
    rec = Recorded(inner, round(sc.duration / sc.sample_period) + 2)
    run_benchmark(sc, controllers={"adaptive_ct": rec}, progress=False, keep_trajectories=0)
    ac["observer_momentum_test"] = True
    sc2 = parse_scenario(d, path, Path(path).stem)
    cfg = make_controllers(sc2)["adaptive_ct"].law_config(sc.sample_period)
    return sc, rec, inner, cfg


def replay(cfg, rho, mass, fc, qd, on_cross, last=True):
    """The shipped test over one trial's record; ``on_cross(k, obs, mt)`` at each crossing (the
    state after the update)."""
    K, n = rho.shape
    obs = np.zeros((ro.OBS_ROWS, n))
    mt = np.zeros((n + 4, n))
    for k in range(K):
        if not np.isfinite(mass[k, 0, 0]) or mass[k, 0, 0] == 0.0:
            continue
        mt[:n] = np.linalg.inv(mass[k])
        mt[n], mt[n + 1] = rho[k], np.abs(fc[k])
        obs[ro.O_QD] = qd[k - 1] if k and last else qd[k]  # the last measurement (the allowance reads both)
        pre = obs.copy()
        ro._momentum_test(cfg, obs, mt, np.ascontiguousarray(qd[k]), 1.0)
        if obs[ro.O_MC, 1] > 0.0:
            on_cross(k, pre, obs, mt.copy())


def explain(cfg, k, pre, obs, mt, r, s, T, n):
    """The window that crossed, each row's share, speeds, the model's error per row."""
    c = obs[ro.O_MC, 0]
    pos = int(c - 1) % ro.M_RING
    bias = 1.0 - (1.0 - cfg.obs_alpha) ** c
    best, bw, bu = 0.0, 0, None
    for w, mw in enumerate(ro.M_WINDOWS):
        back = (pos + ro.M_RING - mw) % ro.M_RING
        sm = obs[ro.O_ME + pos] - obs[ro.O_ME + back]
        u = mt[:n] @ sm
        al = obs[ro.O_MA + pos] - obs[ro.O_MA + back]
        v = pre[ro.O_MV + w]
        tot = np.sum(u * u * bias / v)
        if tot > best:
            best, bw, bu, bal = tot, mw, u * u * bias / v, al
    lo = max(0, k - bw + 1)
    err = (r["rho"][s, lo : k + 1] - r["rho_true"][s, lo : k + 1]).mean(0)
    noise = r["rho_true"][s, lo : k + 1].mean(0)
    spd = np.abs(r["qd"][s, lo : k + 1]).min(0)
    flips = (np.diff(np.sign(r["qd"][s, max(0, lo - 1) : k + 1]), axis=0) != 0).sum(0)
    return (
        f"  t {(k + 1) * T:.3f} window {bw:2d}  stat {np.sqrt(best):5.2f} (thr {cfg.obs_mtest:.2f})  "
        f"share {np.round(bu / best, 2)}  |qd| min {np.round(spd, 3)}  qd_d {np.round(r['qd_d'][k], 3)}  "
        f"sign flips {flips}  allowance {np.round(bal, 4)}\n"
        f"      window mean of rho - rho_true [N m] {np.round(err, 3)}  of rho_true {np.round(noise, 3)}  "
        f"model fc {np.round(mt[n + 1], 3)}  plant fc {np.round(r['fc_true'][s, k], 3)}"
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--set", nargs="*", default=[], help="adaptive_ct settings KEY=VALUE (JSON values)")
    ap.add_argument("--plant", nargs="*", default=[], help="[plant] KEY=VALUE (JSON values)")
    ap.add_argument("--cfg", nargs="*", default=[], help="with --load: law settings replaced")
    ap.add_argument("--end-only", action="store_true", help="the allowance reads a sample's end alone")
    ap.add_argument("--save")
    ap.add_argument("--load")
    ap.add_argument("--show", type=int, default=3, help="crossings printed per trial")
    a = ap.parse_args()
    if a.load:
        f = dict(np.load(a.load, allow_pickle=True))
        cfg = laws.LawConfig(**f.pop("cfg").item())
        cfg = cfg._replace(**{k: float(v) for k, v in (kv.split("=", 1) for kv in a.cfg)})
        r, T, swaps = f, float(f["T"]), list(f["swaps"])
    else:
        sc, rec, _, cfg = record(a.scenario, a.seeds, a.set, a.plant)
        r, T, swaps = rec.r, sc.sample_period, list(sc.swap_times)
        if a.save:
            np.savez(a.save, **r, T=T, swaps=np.array(swaps), cfg=np.array(cfg._asdict(), dtype=object))
    S, K, n = r["rho"].shape
    print(
        f"{a.scenario}: {S} seeds; threshold {cfg.obs_mtest:.2f}, near rest below {cfg.obs_mslow:.3f} "
        f"rad/s, creeping below {cfg.obs_mcreep:.3f} rad/s ({cfg.obs_mcreep_margin} fc)"
    )
    nfa = 0
    first = np.full((S, len(swaps)), np.nan)
    for s in range(S):
        lines = []

        def on_cross(k, pre, obs, mt, s=s, lines=lines):
            t = (k + 1) * T
            for i, sw in enumerate(swaps):
                if sw - 0.002 <= t < sw + 1.0 and np.isnan(first[s, i]):
                    first[s, i] = t - sw
            if any(sw - 0.002 <= t < sw + 1.0 for sw in swaps):
                return
            if len(lines) < a.show:
                lines.append(explain(cfg, k, pre, obs, mt, r, s, T, n))
            else:
                lines.append(None)

        replay(cfg, r["rho"][s, : K - 2], r["mass"][s], r["fc"][s], r["qd"][s], on_cross, not a.end_only)
        if lines:
            nfa += 1
            print(f"seed {s}: {len(lines)} false crossings")
            print("\n".join(x for x in lines if x))
    d = 1e3 * first
    print(
        f"trials with a false crossing: {nfa} of {S}; first crossing after each swap, median (max) [ms]: "
        + " / ".join(
            f"{np.nanmedian(c):.0f} ({np.nanmax(c):.0f})" if np.isfinite(c).any() else "-" for c in d.T
        )
        + f"; swaps without one within 1 s: {int(np.isnan(d).sum())}"
    )


if __name__ == "__main__":
    main()
