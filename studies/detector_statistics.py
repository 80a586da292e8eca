"""Which statistic of the N-joint estimator's prior errors detects a payload swap soonest, at the
same margin over its own largest value without a swap.

The closed loop runs ``CONTROLLER`` (default ct_oracle: the trajectories the detection limit is
computed on) with the scenario's plant and payloads; its recorded true state gets the scenario's
sensor noise (seeded), and adaptive_ct's estimator (as the scenario derives it) runs over the
record (:func:`~adaptive_dd.identification.online.run_online`), which gives each row's weighted
prior error ``e_j`` and the detector's own alarms. Per row, ``z_j = e_j / sqrt(level_j)`` with
``level_j`` the running 1 s mean of ``e_j^2`` (the detector's level), and per statistic:

* ``E<w>``: the mean of ``z_j^2`` over ``w`` samples (an exponential window; ``E1``: the
  sample's own ``z_j^2``, the detector's one-sample test; ``E4``: its 4 ms average);
* ``S<w>``: the square of the *signed* mean of ``e_j`` over ``w`` samples, over its own running
  mean square (a matched filter for a step whose noise level it learns);

each either the largest over the rows (``max``) or summed over them (``sum``). The threshold is
1.2x (in RMS) the statistic's largest value outside the first second and the 0.4 s after each
swap over all seeds; the delay is the first sample after the swap above it.

    python studies/detector_statistics.py SCENARIO.toml [--seeds 8] [--controller ct_oracle]
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import make_controllers, run_closed_loop
from adaptive_dd.identification.online import run_online

MARGIN = 1.2
WINDOWS = (1, 2, 3, 5, 8)


def _ew(x: np.ndarray, a: float) -> np.ndarray:
    """Exponential mean with weight ``a`` along axis 0, held over NaN samples."""
    out = np.empty_like(x)
    s = np.zeros(x.shape[1:])
    for k in range(x.shape[0]):
        ok = np.isfinite(x[k])
        s = np.where(ok, s + a * (np.nan_to_num(x[k]) - s), s)
        out[k] = np.where(ok, s, np.nan)
    return out


def _level(x: np.ndarray, a: float = 1e-3) -> np.ndarray:
    """Bias-corrected running mean of ``x^2`` before each sample (the detector's level)."""
    out = np.full_like(x, np.nan)
    s = np.zeros(x.shape[1:])
    n = np.zeros(x.shape[1:])
    for k in range(x.shape[0]):
        with np.errstate(invalid="ignore", divide="ignore"):
            out[k] = np.where(n > 0, s / (1.0 - (1.0 - a) ** n), np.nan)
        ok = np.isfinite(x[k])
        s = np.where(ok, s + a * (np.nan_to_num(x[k]) ** 2 - s), s)
        n = n + ok
    return out


def statistics(eps: np.ndarray) -> dict[str, np.ndarray]:
    """``eps (N, n)`` one trial's prior errors -> statistic name -> (N,) values (module docstring)."""
    out = {}
    z2 = eps**2 / _level(eps)
    for w in WINDOWS:
        out[f"E{w}"] = _ew(z2, 1.0 / w)
        m = _ew(eps, 1.0 / w)
        out[f"S{w}"] = m**2 / _level(m)
    res = {}
    for name, v in out.items():
        with np.errstate(all="ignore"):
            res[name + "max"] = np.nanmax(np.where(np.isfinite(v), v, -np.inf), axis=1)
            res[name + "sum"] = np.nansum(v, axis=1)
    return res


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--controller", default="ct_oracle")
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["controllers"] = sorted({"ct_oracle", "adaptive_ct", a.controller})
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    res = run_closed_loop(sc, seed_indices=tuple(range(a.seeds)), keep_trajectories=a.seeds)
    run = res.runs[a.controller]
    cfg = make_controllers(sc)["adaptive_ct"].online
    rng = np.random.default_rng(0)
    q = run.q + rng.standard_normal(run.q.shape) * np.sqrt(sc.position_variance)
    qd = run.qd + rng.standard_normal(run.qd.shape) * np.sqrt(sc.velocity_variance)
    rec = run_online(sc.arm, cfg, q, qd, run.tau)
    T, N = sc.sample_period, q.shape[1]
    swaps = [round(s / T) for s in sc.swap_times]
    null = np.ones(N, bool)
    null[: round(1.0 / T)] = False
    for k in swaps:
        null[k : k + round(0.4 / T)] = False
    det = [[(np.flatnonzero(rec.alarm[i, k:])[:1] + 0).tolist() for k in swaps] for i in range(a.seeds)]
    own = np.array([[x[0] if x else 999 for x in row] for row in det])
    print(f"{a.scenario}, {a.seeds} seeds, {a.controller}'s trajectories, estimator mode {cfg.mode}")
    print(f"  the detector as configured: delay [ms] median {np.median(own, 0)} max {own.max(0)}")
    stats = [statistics(rec.eps[i]) for i in range(a.seeds)]
    print(f"  {'statistic':10s} {'null max (RMS)':>15s}   delay [ms] median / max per swap")
    for name in stats[0]:
        top = max(np.nanmax(s[name][null]) for s in stats)
        thr = MARGIN**2 * top
        dl = np.array([[_first(s[name][k : k + 100] > thr) for k in swaps] for s in stats])
        cells = "  ".join(f"{np.median(dl[:, g]):4.1f}/{dl[:, g].max():3d}" for g in range(len(swaps)))
        print(f"  {name:10s} {np.sqrt(top):15.2f}   {cells}")


def _first(hit: np.ndarray) -> int:
    k = np.flatnonzero(hit)
    return int(k[0]) if k.size else 999


if __name__ == "__main__":
    main()
