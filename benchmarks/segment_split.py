"""Where a drawn arm's loaded segments lose to their floor: adaptive_ct's excess squared error split
at the alarm and at the payload's convergence.

Runs ``benchmarks/scenarios/population.toml`` on ``random:ARM`` for each ARM given (as ``benchmark
--arms`` does; ``ct_oracle`` and ``adaptive_ct``) and prints, per seed and per segment after a
swap, the segment's ratio (adaptive_ct / ct_oracle RMS), the alarm's delay, the time after which
the control model's payload mass stays within 5 % of the truth, and the excess squared error
``sum(e_a^2 - e_o^2)`` over the segment as a share of the floor's ``sum(e_o^2)``, split into
before the first alarm in the segment, from it to that convergence, and after (the three add to
``ratio^2 - 1``), and over the segment's first 60 ms alone (the swap's transient).
``--detail`` adds the first ``--span`` ms (300) in ``--window`` ms windows (10) and the model's
payload mass and first moments at the end of each window. Asserts nothing.

Run: ``PYTHONPATH=. python benchmarks/segment_split.py ARM [ARM ...] [--seeds 3] [--observer-bandwidth B]``
(``B``: adaptive_ct's ``observer_bandwidth``, one chain at B rad/s), or ``--scenario FILE`` for a
scenario file's own arm and schedule instead of drawn arms (``segment_split.py --scenario
adaptive_dd/scenarios/vertical3_payload_exact.toml --seeds 50``).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario, read_toml
from adaptive_dd.benchmark.scenario_settings import with_settings

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"
EARLY = 0.06
"""[s] the excess is also given over the segment's first this long (the swap's transient)."""


def _segment(t, ea, eo, pay_hat, pay_true, alarms, t0, t1):
    m = (t >= t0) & (t < t1)
    floor = np.sum(eo[m] ** 2)
    ratio = np.sqrt(np.sum(ea[m] ** 2) / floor)
    inside = [x for x in alarms if t0 <= x < t1]
    ta = inside[0] if inside else t1
    mt, mh, tt = pay_true[m, 0], pay_hat[m, 0], t[m]
    ok = np.abs(mh - mt) <= 0.05 * max(float(np.max(mt)), 1e-9) + 1e-12
    bad = np.flatnonzero(~ok)
    if not len(bad):
        tc = tt[0]
    else:
        tc = tt[bad[-1] + 1] if bad[-1] + 1 < len(tt) else t1
    tc = max(tc, ta)
    ex = ea**2 - eo**2
    parts = [ex[m & (t < ta)].sum(), ex[m & (t >= ta) & (t < tc)].sum(), ex[m & (t >= tc)].sum()]
    early = ex[m & (t < t0 + EARLY)].sum() / floor
    return ratio, ta - t0, tc - t0, [p / floor for p in parts], inside[1:], early


def _presence_weight_off() -> None:
    """A measurement only: adaptive_ct's control model takes the raw payload, not scaled by
    :func:`~adaptive_dd.identification.online_control_model.presence_weight` (its carried-payload
    variance set to 0, which the compiled model reads as "no weighting")."""
    from adaptive_dd.identification import online

    est_init = online.est_init

    def without(cfg, arm, n_trials):
        c, st = est_init(cfg, arm, n_trials)
        return c._replace(present2=0.0), st

    online.est_init = without


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("arms", type=int, nargs="*", help="the arms' seeds (random:ARM)")
    ap.add_argument("--scenario", default=None, help="a scenario file: its arm and schedule instead")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--observer-bandwidth", type=float, default=None)
    ap.add_argument("--detail", action="store_true")
    ap.add_argument("--window", type=float, default=10.0, help="--detail's window [ms]")
    ap.add_argument("--span", type=float, default=300.0, help="--detail's span after each swap [ms]")
    ap.add_argument(
        "--no-presence-weight", action="store_true", help="adaptive_ct's model without the presence weight"
    )
    args = ap.parse_args()
    if args.no_presence_weight:
        _presence_weight_off()
    if not args.arms and args.scenario is None:
        ap.error("give arms' seeds or --scenario FILE")
    for arm in [args.scenario] if args.scenario is not None else args.arms:
        if args.scenario is not None:
            sc = load_scenario(args.scenario)
            if sc.closed_forms is not None:  # its sigma_hat is the paper's 7, not the arm's base parameters
                ap.error(
                    f"{args.scenario}: the paper's arm on its closed forms; this split reads the N-joint "
                    "estimate: set [arm] general = true (e.g. benchmarks/scenarios/sice_general.toml)"
                )
        else:
            sc = population_scenario(read_toml(TEMPLATE), str(TEMPLATE), arm)
            arm = f"random:{arm}"
        sc = dataclasses.replace(sc, seeds=args.seeds, controllers=("ct_oracle", "adaptive_ct"))
        if args.observer_bandwidth is not None:
            sc = with_settings(sc, "adaptive_ct", {"observer_bandwidth": args.observer_bandwidth})
        print(arm)
        res = run_benchmark(sc, progress=False, keep_trajectories=args.seeds)
        t = res.t
        a, o = res.runs["adaptive_ct"], res.runs["ct_oracle"]
        sh = np.asarray(a.sigma_hat)
        masses = [round(float(x), 3) for x in sc.swap_masses]
        print(f"{arm} ({sc.arm.n_joints} joints): swaps at {sc.swap_times} s of {masses} kg")
        q_d = sc.reference.sample(t)[0]
        pooled = {k: [] for k in range(len(sc.swap_times))}
        for s in range(args.seeds):
            ea, eo = a.e_norm[s].astype(float), o.e_norm[s].astype(float)
            alarms = [float(x) for x in (a.alarm_times or [[]] * args.seeds)[s]]
            pay_hat = sc.arm.payload_from_sigma(sh[s]).params
            pay_true = sc.arm.payload_from_sigma(np.broadcast_to(res.sigma_true, sh[s].shape)).params
            print(f"  seed {s}: alarms {[round(x, 3) for x in alarms]} s")
            for k, t0 in enumerate(sc.swap_times):
                t1 = sc.swap_times[k + 1] if k + 1 < len(sc.swap_times) else sc.duration
                ratio, da, dc, p, extra, early = _segment(t, ea, eo, pay_hat, pay_true, alarms, t0, t1)
                w0 = (t >= t0) & (t < t0 + EARLY)
                sat_a, sat_o = (np.asarray(r.saturated[s][w0]).sum(axis=0) for r in (a, o))
                m_seg = (t >= t0) & (t < t1)
                per_joint = np.sum(
                    (q_d[w0] - a.q[s][w0]) ** 2 - (q_d[w0] - o.q[s][w0]) ** 2, axis=0
                ) / np.sum(eo[m_seg] ** 2)
                pooled[k].append((ratio, *p, early, bool(sat_a.any()), *per_joint))
                print(
                    f"    segment {k + 2} ({t0:g}-{t1:g} s): ratio {ratio:.3f}, alarm +{1e3 * da:.0f} ms, "
                    f"mass within 5 % from +{1e3 * dc:.0f} ms; excess / floor: before the alarm "
                    f"{p[0]:+.3f}, alarm to convergence {p[1]:+.3f}, after {p[2]:+.3f}; in the first "
                    f"{1e3 * EARLY:.0f} ms {early:+.3f} (per joint {np.round(per_joint, 3).tolist()}), "
                    f"saturated samples per joint there {sat_a.tolist()} "
                    f"(ct_oracle {sat_o.tolist()})"
                    + (f"; more alarms {[round(x, 3) for x in extra]}" if extra else "")
                )
                if args.detail:
                    dw = 1e-3 * args.window
                    for lo in np.arange(0.0, 1e-3 * args.span - 1e-9, dw):
                        w = (t >= t0 + lo) & (t < t0 + lo + dw)
                        kk = int(np.searchsorted(t, t0 + lo + dw)) - 1
                        ra, ro = (1e3 * np.sqrt(np.mean(x[w] ** 2)) for x in (ea, eo))
                        ej = 1e3 * (q_d[kk] - a.q[s, kk])
                        print(
                            f"      +{1e3 * lo:3.0f}-{1e3 * (lo + dw):3.0f} ms: {ra:.3f} / {ro:.3f} mrad"
                            f" (per joint at the end {np.round(ej, 3)}), saturated samples per joint "
                            f"{np.asarray(a.saturated[s][w]).sum(axis=0).tolist()},"
                            f" model mass {pay_hat[kk, 0]:.3f} kg,"
                            f" first moments {np.round(pay_hat[kk, 1:4], 4)}"
                            f" (true {np.round(pay_true[kk, 1:4], 4)}) kg m"
                        )
        for k, rows in pooled.items():
            r = np.asarray(rows, dtype=float)
            print(
                f"  segment {k + 2}, {len(rows)} seeds: ratio mean {r[:, 0].mean():.3f} (p90 "
                f"{np.quantile(r[:, 0], 0.9):.3f}, max {r[:, 0].max():.3f}); excess / floor, means: before "
                f"the alarm {r[:, 1].mean():+.3f}, alarm to convergence {r[:, 2].mean():+.3f}, after "
                f"{r[:, 3].mean():+.3f}; in the first {1e3 * EARLY:.0f} ms {r[:, 4].mean():+.3f}; "
                f"(per joint {np.round(r[:, 6:].mean(axis=0), 3).tolist()}); "
                f"adaptive_ct saturated there in {int(r[:, 5].sum())} of {len(rows)} trials"
            )


if __name__ == "__main__":
    main()
