"""Why the N-joint detector alarms without a swap: adaptive_ct's estimator replayed, sample by
sample, on its own closed-loop records, each false alarm taken apart row by row.

Records adaptive_ct (the default law, or with ``--set``) on the Python path: per sample the
measured ``q, qd`` and the applied torque its estimator is stepped with. Replays the estimator
(:func:`adaptive_dd.identification.online.est_step`, the same compiled step as the closed loop:
the replay's alarms are the closed loop's, checked) and, at each alarm outside the benchmark's
window after a swap, prints per row: in use, the speed, its short and fast averages over the level
it is judged against, which level that is (``own``: learnt since the last alarm; ``ref``: the
level established before it, within the re-arm bound; ``past``: past the bound, what it learnt
since), that level and the row's level before the last alarm (RMS, before the floor), and the noise rise the
estimated payload implies for the row (the square root of ``(M diag(vn^2) M^T)_jj`` with the
estimate's payload over the same with the payload of the alarm before, ``M`` the model's inertia
at the measured ``q``, ``vn`` the sensor's velocity noise), recomputed here from the model and
as the detector has it (``EstState.ref_rise``; 1 outside the window in which ``ref`` serves).

    python studies/detector_fa_trace.py SCENARIO.toml [--seeds 10] [--first-seed 0]
        [--set KEY=VALUE ...] [--save FILE.npz | --load FILE.npz] [--detector KEY=VALUE ...]

``--detector`` (JSON values) replaces detector settings in the replay only (what a rule would have
done on the same records; the closed loop after a changed alarm would differ).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import json
from pathlib import Path

import numpy as np
from _ablation import Delegating

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import make_controllers
from adaptive_dd.identification import online
from adaptive_dd.identification import online_kernel as K
from adaptive_dd.plant.chain import mass_matrix_in, workspace


class Recorded(Delegating):
    """adaptive_ct, unchanged, recording what its estimator is stepped with."""

    def __init__(self, inner, n_samples):
        self.inner, self.N, self.name = inner, n_samples, "adaptive_ct"
        self.floor, self.has_detector = "ct_oracle", True

    def reset(self, n_trials, T):
        self.inner.reset(n_trials, T)
        self.k, self.r = 0, None

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None, pi_true=None):
        return self.inner.command(q, qd, q_d, qd_d, qdd_d, sigma_true, pi_true)

    def observe(self, q, qd, tau):
        self.inner.observe(q, qd, tau)
        S, n = np.shape(q)
        if self.r is None:
            self.r = {x: np.full((S, self.N, n), np.nan) for x in ("q", "qd", "tau")}
        if self.k < self.N:
            self.r["q"][:, self.k], self.r["qd"][:, self.k], self.r["tau"][:, self.k] = q, qd, tau
        self.k += 1


def scenario(path, seeds, sets):
    d = copy.deepcopy(read_toml(Path(path)))
    d["run"]["seeds"] = seeds
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    ac = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
    for kv in sets:
        key, v = kv.split("=", 1)
        ac[key] = json.loads(v)
    return parse_scenario(d, path, Path(path).stem)


def record(sc, first):
    inner = make_controllers(sc)["adaptive_ct"]
    rec = Recorded(inner, round(sc.duration / sc.sample_period) + 2)
    idx = tuple(range(first, first + sc.seeds))
    run_benchmark(sc, controllers={"adaptive_ct": rec}, progress=False, keep_trajectories=0, seed_indices=idx)
    return rec.r, [list(a) for a in inner.alarm_times], inner


def _noise(ch, pi, q, vn):
    """Per row, ``(M diag(vn^2) M^T)_jj`` of the model ``pi`` at ``q`` (armature included)."""
    n = q.shape[0]
    M = np.empty((n, n))
    mass_matrix_in(ch, np.ascontiguousarray(pi[: 10 * n]), np.ascontiguousarray(q), workspace(n), M)
    M[np.diag_indices(n)] += pi[12 * n : 13 * n]
    return (M * vn**2) @ M.T


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--set", nargs="*", default=[], help="adaptive_ct settings KEY=VALUE (JSON values)")
    ap.add_argument("--detector", nargs="*", default=[], help="replay only: detector KEY=VALUE (JSON)")
    ap.add_argument("--save")
    ap.add_argument("--load")
    a = ap.parse_args()
    sc = scenario(a.scenario, a.seeds, a.set)
    inner = make_controllers(sc)["adaptive_ct"]
    if a.load:
        f = np.load(a.load, allow_pickle=True)
        r = {x: f[x] for x in ("q", "qd", "tau")}
        loop_alarms = list(f["alarms"])
    else:
        r, loop_alarms, inner = record(sc, a.first_seed)
        if a.save:
            np.savez(a.save, **r, alarms=np.array(loop_alarms, dtype=object))
    T = sc.sample_period
    cfg = inner.online
    if a.detector:
        kv = (x.split("=", 1) for x in a.detector)
        det = dataclasses.replace(cfg.detector, **{k: json.loads(v) for k, v in kv})
        cfg = dataclasses.replace(cfg, detector=det)
    if getattr(cfg, "sample_period", T) != T:
        cfg = dataclasses.replace(cfg, sample_period=T)
    arm = inner.arm
    S, N, n = r["q"].shape
    c, s = online.est_init(cfg, arm, S)
    ints, fl = c.ints, c.floats
    a_l, floor2 = fl[K.F_ALPHA_LONG], fl[K.F_FLOOR2]
    vn = np.sqrt(np.asarray(arm.sensor.velocity_variance, dtype=float)) * np.ones(n)
    swaps = list(sc.swap_times)
    alarms = [[] for _ in range(S)]
    pay_at_alarm = np.zeros((S, 13 * n))
    pay_at_alarm[:] = online.est_model(c, s)
    nfa = 0
    print(
        f"{a.scenario}: seeds {a.first_seed}..{a.first_seed + S - 1}; "
        f"threshold {np.sqrt(fl[K.F_THRESHOLD2]):.1f}x, "
        f"slow {np.sqrt(fl[K.F_SLOW2]):.2f}, fast {np.sqrt(fl[K.F_FAST2]):.1f}x, resume {ints[K.I_RESUME]}, "
        f"min_learned {ints[K.I_MIN_LEARNED]}, holdoff {ints[K.I_HOLDOFF]} samples"
    )
    for k in range(N):
        q, qd, tau = r["q"][:, k], r["qd"][:, k], r["tau"][:, k]
        if not np.all(np.isfinite(q)):
            break
        pre = {x: getattr(s, x).copy() for x in ("ref", "cnt", "seen", "learned", "long", "hold")}
        pi_before = online.est_model(c, s)
        info = online.est_step(c, s, q, qd, tau)
        for i in np.flatnonzero(info.alarm):
            t = k * T
            alarms[i].append(t)
            false = bool(_false([t], swaps))
            pi_now = online.est_model(c, s)[i]
            if false:
                nfa += 1
                since = pre["cnt"][i, K.C_SINCE_ALARM]
                print(f"seed {a.first_seed + i}: FALSE alarm at {t:.3f} s, {since * T:.3f} s after the last")
                V1 = _noise(c.ch, pi_now, q[i], vn)
                V0 = _noise(c.ch, pay_at_alarm[i], q[i], vn)
                for j in range(n):
                    nl, seen = pre["learned"][i, j] + 1, pre["seen"][i, j] + 1
                    own_l = max(s.long[i, j] / (1 - (1 - a_l) ** max(nl, 1)), floor2)
                    if seen >= ints[K.I_MIN_LEARNED]:
                        kind, level = "own", own_l
                        if s.hold[i, j] > 0:
                            kind, level = "held", s.hold[i, j]
                    elif pre["ref"][i, j] > 0 and since + 1 < ints[K.I_RESUME] + ints[K.I_MIN_LEARNED]:
                        kind, level = "ref", max(pre["ref"][i, j] * s.ref_rise[i, j], floor2)
                    elif pre["ref"][i, j] > 0 and nl >= ints[K.I_GATE_AFTER]:
                        kind, level = "past", own_l
                    else:
                        kind, level = "-", np.nan
                    use = bool(np.isfinite(info.eps[i, j]))
                    sh, fa = np.sqrt(s.short[i, j] / level), np.sqrt(s.fast[i, j] / level)
                    print(
                        f"   row {j + 1}: {'in use' if use else 'out   '} |qd| {abs(qd[i, j]):5.2f}  "
                        f"short/level {sh:5.2f}  fast/level {fa:5.2f} (RMS)  judged on {kind:4s} "
                        f"{np.sqrt(level):.3f}  ref {np.sqrt(pre['ref'][i, j]):.3f}  learned {nl:3d}  "
                        f"noise rise {np.sqrt(V1[j, j] / V0[j, j]):.2f} "
                        f"(the detector's {np.sqrt(s.ref_rise[i, j]):.2f})"
                    )
            pay_at_alarm[i] = pi_before[i]
    print(f"trials with a false alarm (replay): {sum(1 for x in alarms if _false(x, swaps))} of {S}")
    loop_false = [(a.first_seed + i, _false(x, swaps)) for i, x in enumerate(loop_alarms)]
    loop_false = [x for x in loop_false if x[1]]
    print(f"the closed loop's false alarms (seed, times [s]): {loop_false} ({len(loop_false)} of {S} trials)")
    if not a.detector:
        same = all(np.allclose(x, y) for x, y in zip(alarms, loop_alarms, strict=True))
        print(f"replay's alarms equal the closed loop's: {same}")


def _false(times, swaps):
    """The alarm times [s] outside the benchmark's window after every swap."""
    return [round(float(t), 3) for t in times if not any(0 <= t - w < FALSE_ALARM_WINDOW for w in swaps)]


if __name__ == "__main__":
    main()
