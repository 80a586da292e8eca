"""Where adaptive_ct loses to ct_oracle after each payload swap: detection, the model's mass, the
error by window.

Usage::

    python benchmarks/swap_trace.py [SCENARIO] [--seeds 20] [--first 0] [--show 2]

Runs ``ct_oracle`` and ``adaptive_ct`` on ``SCENARIO`` (default
``benchmarks/scenarios/sice_general.toml``, the default scenario on the general kernels; give
``adaptive_dd/scenarios/payload_swap.toml`` for the closed forms) and prints, per swap, over the
seeds:

- the detection delay (median / max) [ms];
- the payload mass in the model control uses (the recorded ``sigma_hat``, read back through the
  arm's payload map or the paper's eq. 9), median over the seeds, 20 ms to 4.9 s after the swap;
- the squared tracking error in windows after the swap (0-0.1, 0.1-0.3, 0.3-1, 1-2, 2-5 s, cut
  at the segment's end) as a share of ``ct_oracle``'s over the whole segment, ``adaptive_ct`` /
  ``ct_oracle``, mean over the seeds: where the segment's ratio comes from;
- what the swap changed in the torque each trajectory asks, from the swap to ``adaptive_ct``'s
  alarm (30 ms without one), RMS per joint [N m], median over the seeds, on ``adaptive_ct``'s
  trajectory (the evidence its detector had) and on ``ct_oracle``'s; on the general kernels, the
  detector's margins for friction the model may get wrong near rest, per joint, beside it.

The ``--show`` worst seeds of each swap (by the segment's RMS ratio) are printed one by one, with
the model's base parameters minus the plant's (``sigma_hat - sigma_true``, in the order of
``arm.base.names`` or the paper's ``J1 J2 r b1 b2 d1 d2``) 1, 2 and 4.9 s after the swap.
Asserts nothing.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark import load_scenario, run_benchmark
from adaptive_dd.closed_loop.runner import make_controller_of
from adaptive_dd.plant.sampling import first_sample

ROOT = Path(__file__).resolve().parents[1]
DELAYS = (0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 4.9)
SIGMA_AT = (1.0, 2.0, 4.9)
WINDOWS = ((0.0, 0.1), (0.1, 0.3), (0.3, 1.0), (1.0, 2.0), (2.0, 5.0))


def _mass(sc, sigma_hat: np.ndarray) -> np.ndarray:
    """The payload mass [kg] of the models ``sigma_hat (N, p)``."""
    if sc.closed_forms is not None:
        return sc.closed_forms.payload_mass_from_sigma(sigma_hat)
    with np.errstate(invalid="ignore", divide="ignore"):
        return sc.arm.payload_from_sigma(sigma_hat).mass


def _payload_torque(sc, res, run, k: int, i0: int, i1: int) -> np.ndarray:
    """RMS per joint [N m] over samples ``i0 .. i1 - 1`` of what the swap changed in the torque
    trial k's trajectory asks, ``i0`` the swap's first sample (:func:`first_sample`): the regressor
    at the recorded ``q, qd`` (``qdd`` their central difference) times the plant's base parameters
    at ``i0`` minus those of the sample before."""
    arm = sc.closed_forms if sc.closed_forms is not None else sc.arm
    q, qd = np.asarray(run.q[k], float), np.asarray(run.qd[k], float)
    qdd = np.gradient(qd, sc.sample_period, axis=0)
    d_sigma = res.sigma_true[i0] - res.sigma_true[i0 - 1]
    tau = arm.regressor(q[i0:i1], qd[i0:i1], qdd[i0:i1]) @ d_sigma
    return np.sqrt(np.mean(tau**2, axis=0))


def _swap_rows(sc, res, k: int, ts: float, end: float) -> dict:
    """Trial k's figures for the swap at ``ts`` [s], its segment ending at ``end`` [s]."""
    T, ad, orc = sc.sample_period, res.runs["adaptive_ct"], res.runs["ct_oracle"]
    i0, i1 = first_sample(ts, T), min(first_sample(end, T), sc.n_samples)
    ea, eo = np.asarray(ad.e_norm[k], float), np.asarray(orc.e_norm[k], float)
    floor = np.sum(eo[i0:i1] ** 2)
    win = []
    for w0, w1 in WINDOWS:
        a, b = i0 + round(w0 / T), min(i0 + round(w1 / T), i1)
        win.append((np.sum(ea[a:b] ** 2) / floor, np.sum(eo[a:b] ** 2) / floor))
    m = _mass(sc, ad.sigma_hat[k])
    al = np.asarray(ad.alarm_times[k] if ad.alarm_times else [], float)
    hit = al[(al >= ts) & (al < ts + 0.3)]
    until = i0 + max(round((hit[0] - ts) / T) if hit.size else round(0.03 / T), 1)
    return {
        "ratio": float(np.sqrt(np.sum(ea[i0:i1] ** 2) / floor)),
        "delay": 1e3 * (hit[0] - ts) if hit.size else np.nan,
        "torque": [_payload_torque(sc, res, r, k, i0, until) for r in (ad, orc)],
        "mass": [float(m[min(i0 + round(d / T), sc.n_samples - 1)]) for d in DELAYS],
        "windows": win,
        "sigma_error": [
            ad.sigma_hat[k][j] - res.sigma_true[j]
            for j in (min(i0 + round(d / T), sc.n_samples - 1) for d in SIGMA_AT)
        ],
    }


def _nm(x) -> str:
    return " ".join(f"{v:.3g}" for v in x)


def _friction_margin(sc) -> str | None:
    """The N-joint detector's margins for friction the model may get wrong near rest [N m per
    joint]: a creeping row's ``creep_margin fc``, a row out of use's ``(2 + creep_margin) fc``
    (``docs/change_detection.md``, "Creeping joints"); None on the closed forms (their own
    detector)."""
    if sc.closed_forms is not None:
        return None
    from adaptive_dd.identification.online_config import Detector

    n, cm = sc.arm.n_joints, Detector().creep_margin
    fc = np.asarray(sc.arm.pi, float)[11 * n : 12 * n]
    return f"creeping {_nm(cm * fc)}; out of use (reversing) {_nm((2 + cm) * fc)}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default=str(ROOT / "benchmarks/scenarios/sice_general.toml"))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--show", type=int, default=2, help="worst seeds printed one by one per swap")
    a = ap.parse_args()
    sc = load_scenario(a.scenario)
    seeds = list(range(a.first, a.first + a.seeds))
    t0, c0 = time.perf_counter(), time.process_time()
    ctrls = dict(make_controller_of(sc, s) for s in ("ct_oracle", "adaptive_ct"))
    keep = len(seeds)
    res = run_benchmark(sc, progress=False, controllers=ctrls, seed_indices=seeds, keep_trajectories=keep)
    print(f"{a.scenario}, seeds {seeds[0]}-{seeds[-1]} ({'closed forms' if sc.closed_forms else 'general'})")
    print(f"mass at {', '.join(f'{d:g}' for d in DELAYS)} s after the swap; windows [s] {list(WINDOWS)}")
    margin = _friction_margin(sc)
    if margin:
        print(f"the detector's margin for friction near rest [N m per joint]: {margin}")
    ends = (*sc.swap_times[1:], sc.duration)
    for ts, end in zip(sc.swap_times, ends, strict=True):
        rows = [_swap_rows(sc, res, k, ts, end) for k in range(len(seeds))]
        ratio = np.array([r["ratio"] for r in rows])
        delay = np.array([r["delay"] for r in rows])
        mass = np.median([r["mass"] for r in rows], axis=0)
        win = np.mean([r["windows"] for r in rows], axis=0)
        found = delay[np.isfinite(delay)]
        when = (
            f"delay median {np.median(found):.0f} max {found.max():.0f} ms"
            + (
                f" ({found.size} trials with an alarm; none within 0.3 s in {delay.size - found.size} of "
                f"{delay.size})"
                if found.size < delay.size
                else ""
            )
            if found.size
            else "no alarm within 0.3 s in any trial"
        )
        print(f"swap at {ts:g} s: segment ratio mean {ratio.mean():.3f} max {ratio.max():.3f}; {when}")
        print(f"  model's mass (median) [kg]: {' '.join(f'{x:.2f}' for x in mass)}")
        print(f"  error share adaptive/oracle: {'  '.join(f'{x:.3f}/{y:.3f}' for x, y in win)}")
        for who, t in zip(
            ("adaptive_ct", "ct_oracle"), np.median([r["torque"] for r in rows], axis=0), strict=True
        ):
            print(f"  the swap's torque until the alarm, on {who}'s trajectory [N m RMS per joint]: {_nm(t)}")
        for k in np.argsort(-ratio)[: a.show]:
            r = rows[k]
            print(
                f"    seed {seeds[k]}: ratio {r['ratio']:.3f}, "
                + (f"delay {r['delay']:.0f} ms" if np.isfinite(r["delay"]) else "no alarm within 0.3 s")
                + ", mass "
                f"{' '.join(f'{x:.2f}' for x in r['mass'])}, windows "
                f"{'  '.join(f'{x:.3f}/{y:.3f}' for x, y in r['windows'])}"
            )
            for d, err in zip(SIGMA_AT, r["sigma_error"], strict=True):
                txt = np.array2string(err, precision=4, suppress_small=True)
                print(f"      model - plant at +{d:g} s: {txt}")
    print(f"({time.perf_counter() - t0:.0f} s wall, {time.process_time() - c0:.0f} s CPU)")


if __name__ == "__main__":
    main()
