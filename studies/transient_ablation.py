"""adaptive_ct's transient after a payload change: the residual observer and its alternatives.

For each scenario, one run of ct_oracle and of adaptive_ct under each variant of its settings
(common random numbers: the same seeds, noise and drawn plants for every variant), and per
variant: adaptive_ct / ct_oracle per segment (mean / p90 / max over seeds), the trials with a
false alarm, the swaps missed, the median detection delay per swap [ms], and the mean RMS
ratio to ct_oracle over the first 50 ms after each swap (the transient itself).

    python studies/transient_ablation.py SCENARIO.toml [...] [--seeds 10] [--variants off on ...]

Variants (``[controllers.adaptive_ct]`` settings): ``off`` (``observer = false``: the law before
the observer), ``on`` (the default), ``bw50`` / ``bw200`` / ``bw400`` / ``bw800`` (``observer_bandwidth``),
``boost0.2`` (the observer with ``boost_duration = 0.2``), ``noboost`` (the observer, boost 0 s),
``off_boost0.2``; ``order1``, ``order1_bw200``: De Luca's first-order observer (one stage; the
default low-passes its output once more); ``kappa4``, ``kappa5``: the observer's threshold at 4 or
5 times its learnt level (3 by default); ``bb100`` / ``bb150`` / ``bb200``: the boost's
bandwidth [rad/s] (300 by default); ``trip``: the observer's residual starts the boost
(``observer_trip = true``; off by default since it tripped on friction the model lacks), ``notrip``:
it does not (the default), ``trip3`` ... ``trip10``: its trip at that many times a row's level
(derived by default: 5.4 for three joints at 1 kHz); ``trip_anyspeed``: a row may trip at any speed
of its joint beyond the trip alone (by default a joint at most the detector's creeping speed,
0.25 rad/s, needs twice its Coulomb friction more); ``nogate``: the
detector's level learns while its short average is raised (``learn_below = 0``), ``gate0.75``: up
to 0.75 of the threshold; ``notrip_nogate``: the law and detector of before issue 28's transient
round (their code path: no trip, no gate, no hold); ``gate``: the detector's level does not learn
while its short average exceeds half the threshold (``learn_below = 0.5``, established levels
only), without the hold; ``hold``: the hold (``hold_above = 0.5``, the default since issue 28's
gate round), ``hold50`` / ``hold200``: held for 50 / 200 ms instead of the derived rise time (94
ms at 1 kHz), ``nohold``: no hold (``hold_above = 0``, the detector of before that round);
``mtest``: the momentum test starts the boost (``observer_momentum_test =
true``; docs/change_detection.md, "The momentum test"), ``mreopen``: and it re-opens the estimator
as an alarm (``observer_momentum_test = "reopen"``); ``mreopen_slow0.25``: with every joint slower than
the detector's creeping speed (0.25 rad/s) near rest (by default the stated velocity noise's 1 %/min
quantile, about 5 sigma_v), ``mreopen_nocreep``: without the creeping joints' allowance.
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np
from _ablation import segment_cells

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import make_controllers

VARIANTS = {
    "off": {"observer": False},
    "on": {},
    "bw50": {"observer_bandwidth": 50.0},
    "bw200": {"observer_bandwidth": 200.0},
    "bw400": {"observer_bandwidth": 400.0},
    "boost0.2": {"boost_duration": 0.2},
    "noboost": {"boost_duration": 0.0},
    "off_boost0.2": {"observer": False, "boost_duration": 0.2},
    "order1": {"_stages": 1},
    "order1_bw200": {"_stages": 1, "observer_bandwidth": 200.0},
    "bw800": {"observer_bandwidth": 800.0},
    "kappa4": {"_kappa": 4.0},
    "kappa5": {"_kappa": 5.0},
    "bb100": {"boost_bandwidth": 100.0},
    "nogate": {"detector": {"learn_below": 0.0}},
    "gate0.75": {"detector": {"learn_below": 0.75}},
    "gate": {"detector": {"learn_below": 0.5, "hold_above": 0.0}},
    "hold": {"detector": {"hold_above": 0.5}},
    "hold50": {"detector": {"hold_above": 0.5, "hold_time": 0.05}},
    "hold200": {"detector": {"hold_above": 0.5, "hold_time": 0.2}},
    "nohold": {"detector": {"hold_above": 0.0}},
    "notrip": {"observer_trip": False},
    "notrip_nogate": {"observer_trip": False, "detector": {"learn_below": 0.0, "hold_above": 0.0}},
    "trip": {"observer_trip": True},
    "trip_anyspeed": {"observer_trip": True, "_trip_speed": 0.0},
    "trip3": {"_trip": 3.0},
    "trip4": {"_trip": 4.0},
    "trip5": {"_trip": 5.0},
    "trip6": {"_trip": 6.0},
    "trip6_nogate": {"_trip": 6.0, "detector": {"learn_below": 0.0}},
    "trip8": {"_trip": 8.0},
    "trip10": {"_trip": 10.0},
    "mtest": {"observer_momentum_test": True},
    "mreopen": {"observer_momentum_test": "reopen"},
    "mreopen_slow0.25": {"observer_momentum_test": "reopen", "_mslow": 0.25},
    "mreopen_nocreep": {"observer_momentum_test": "reopen", "_mcreep": 0.0},
    "bb150": {"boost_bandwidth": 150.0},
    "bb200": {"boost_bandwidth": 200.0},
}
TRANSIENT = 0.05
"""[s] after each swap: the window of the transient's own RMS ratio."""


def variant_controller(base: dict, path: str, settings: dict):
    """adaptive_ct of the scenario ``base`` with ``settings`` added to its table."""
    d = copy.deepcopy(base)
    settings = dict(settings)
    law = {k[1:]: settings.pop(k) for k in list(settings) if k.startswith("_")}
    d.setdefault("controllers", {}).setdefault("adaptive_ct", {}).update(settings)
    d["run"]["controllers"] = ["adaptive_ct"]
    ctrl = make_controllers(parse_scenario(d, path, Path(path).stem))["adaptive_ct"]
    if law:  # not settings: the law's configuration with the observer's order or threshold replaced
        law_config = ctrl.law_config
        fields = {f"obs_{k}": v for k, v in law.items()}
        ctrl.law_config = lambda T: law_config(T)._replace(**fields)
    return ctrl


def transient_cells(res, names, sc) -> dict:
    """Per variant: the mean over seeds of the RMS ratio to ct_oracle in the first 50 ms after each swap."""
    T = sc.sample_period
    eo = res.runs["ct_oracle"].e_norm.astype(float) ** 2
    out = {}
    for nm in names:
        ea = res.runs[nm].e_norm.astype(float) ** 2
        cells = []
        for swap in sc.swap_times:
            i, j = round(swap / T), round((swap + TRANSIENT) / T)
            cells.append(np.mean(np.sqrt(ea[:, i:j].mean(1) / eo[:, i:j].mean(1))))
        out[nm] = "/".join(f"{c:.2f}" for c in cells)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenarios", nargs="+")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--variants", nargs="+", default=["off", "on"], choices=sorted(VARIANTS))
    a = ap.parse_args()
    for path in a.scenarios:
        base = read_toml(Path(path))
        d = copy.deepcopy(base)
        d["run"]["seeds"] = a.seeds
        d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
        sc = parse_scenario(d, path, Path(path).stem)
        ctrls = {"ct_oracle": make_controllers(sc)["ct_oracle"]}
        for v in a.variants:
            ctrls[v] = variant_controller(d, path, VARIANTS[v])
        res = run_benchmark(sc, controllers=ctrls, progress=False, keep_trajectories=0)
        df = res.to_frame()
        trans = transient_cells(res, a.variants, sc)
        print(
            f"{path}: {a.seeds} seeds; adaptive_ct / ct_oracle per segment (mean/p90/max); false-alarm "
            "trials; missed; median delay [ms]; first 50 ms after each swap (mean ratio)"
        )
        for v in a.variants:
            c = df[df.controller == v]
            fa = int((c.groupby("seed").false_alarms.sum() > 0).sum())
            missed = int(np.sum(c.detection_delay_s.isna() & (c.segment > 0)))
            delays = []
            for swap in sc.swap_times:
                at = res.runs[v].alarm_times or []
                dl = [
                    min((x - swap for x in t if 0 <= x - swap < FALSE_ALARM_WINDOW), default=np.nan)
                    for t in at
                ]
                delays.append(f"{1e3 * np.nanmedian(dl):.0f}" if np.isfinite(dl).any() else "-")
            cells = "  ".join(segment_cells(c))
            print(
                f"  {v:13s} {cells}   fa {fa}  missed {missed}  delay {'/'.join(delays)}  50 ms {trans[v]}",
                flush=True,
            )


if __name__ == "__main__":
    main()
