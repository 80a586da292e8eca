"""The estimator's row weights from a first pass over the task (``identification/row_weights.py``,
the default in payload mode) against the torque limits' (``derived_row_weights``, mode "arm"'s
default): adaptive_ct / ct_oracle per segment, false alarms and missed swaps, both given as the
estimator's ``row_weights`` in one run (common random numbers: the same seeds), so that either mode
compares them.

The first pass runs over the scenario's reference (``--first-pass reference``, the library's rule)
or over an exciting motion about the middle of the position limits (``--first-pass limits``).
Prints per arm the weights and both runs' segment means, then pooled mean / p90 / max per segment,
trials with a false alarm (an alarm more than 0.5 s after every swap) and missed swaps (none within
0.5 s). Asserts nothing.

Run: ``PYTHONPATH=. python benchmarks/residual_row_weights.py ARM [ARM ...]`` (drawn arms of
``benchmarks/scenarios/population.toml``, or ``--template FILE``), ``--first-arm K --arms N``, or
``--scenario FILE``; ``--seeds 3``.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario, read_toml
from adaptive_dd.benchmark.scenario_settings import with_settings
from adaptive_dd.identification.online import OnlineConfig, derived_row_weights
from adaptive_dd.identification.row_weights import first_pass_row_weights
from adaptive_dd.plant.prescribed import exciting_motion

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"
EXCITE = 6.0


def first_pass_weights(arm, sample_period: float, reference=None, seed: int = 0) -> np.ndarray:
    """The library's first-pass weights over ``reference`` (``EXCITE`` s of it), or over an exciting
    motion about the middle of the position limits when ``reference`` is None."""
    t = np.arange(round(EXCITE / sample_period)) * sample_period
    if reference is not None:
        motion = reference.sample(t)
    else:
        lim = np.asarray(arm.position_limits, dtype=float)
        ok = np.isfinite(lim).all(axis=1)
        offset = np.where(ok, np.where(ok[:, None], lim, 0.0).mean(axis=1), 0.0)
        motion = exciting_motion(arm, t, np.random.default_rng(seed), offset=list(offset), speed=0.5)
    return first_pass_row_weights(arm, OnlineConfig(sample_period=sample_period), motion, seed=seed)


def _ratios(sc, res):
    t, a, o = res.t, res.runs["adaptive_ct"], res.runs["ct_oracle"]
    edges = [0.0, *sc.swap_times, sc.duration]
    rows, false, missed = [], 0, 0
    for s in range(sc.seeds):
        ea, eo = a.e_norm[s].astype(float), o.e_norm[s].astype(float)
        m = [(t >= t0) & (t < t1) for t0, t1 in itertools.pairwise(edges)]
        rows.append([np.sqrt(np.sum(ea[k] ** 2) / np.sum(eo[k] ** 2)) for k in m])
        al = [float(x) for x in (a.alarm_times or [[]] * sc.seeds)[s]]
        false += any(not any(0.0 <= x - w < 0.5 for w in sc.swap_times) for x in al)
        missed += sum(1 for w in sc.swap_times if not any(0.0 <= x - w < 0.5 for x in al))
    return rows, false, missed


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("arm", type=int, nargs="*", help="the drawn arms' seeds (random:ARM)")
    ap.add_argument("--first-arm", type=int, default=0)
    ap.add_argument("--arms", type=int, default=None)
    ap.add_argument("--scenario", type=Path, action="append", default=[], help="a scenario file")
    ap.add_argument("--template", type=Path, default=TEMPLATE, help="the drawn arms' template scenario")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument(
        "--first-pass",
        choices=("reference", "limits"),
        default="reference",
        help="the first pass's motion: the scenario's reference (default) or an exciting "
        "motion about the middle of the position limits",
    )
    args = ap.parse_args()
    cases = [(f"random:{k}", k) for k in args.arm]
    if args.arms is not None:
        cases += [(f"random:{k}", k) for k in range(args.first_arm, args.first_arm + args.arms)]
    cases += [(str(p), p) for p in args.scenario]
    if not cases:
        ap.error("give arms' seeds, --arms N or --scenario FILE")
    pooled = {"torque limits": ([], 0, 0), "first pass": ([], 0, 0)}
    for name, what in cases:
        if isinstance(what, int):
            sc = population_scenario(read_toml(args.template), str(args.template), what)
        else:
            sc = load_scenario(what)
        sc = dataclasses.replace(sc, seeds=args.seeds, controllers=("ct_oracle", "adaptive_ct"))
        ref = sc.reference if args.first_pass == "reference" else None
        w = first_pass_weights(sc.arm, sc.sample_period, ref)
        line = [
            f"{name}: first-pass weights {np.round(w, 4).tolist()} (torque limits' "
            f"{np.round(derived_row_weights(sc.arm), 4).tolist()})"
        ]
        w0 = tuple(float(x) for x in derived_row_weights(sc.arm))
        variants = {
            "torque limits": with_settings(sc, "adaptive_ct", {"estimator": {"row_weights": w0}}),
            "first pass": with_settings(
                sc, "adaptive_ct", {"estimator": {"row_weights": tuple(float(x) for x in w)}}
            ),
        }
        for label, v in variants.items():
            rows, false, missed = _ratios(v, run_benchmark(v, progress=False, keep_trajectories=args.seeds))
            r, f, m = pooled[label]
            pooled[label] = (r + rows, f + false, m + missed)
            line.append(
                f"  {label}: segment means {np.round(np.mean(rows, axis=0), 3).tolist()}, "
                f"false-alarm trials {false}, missed {missed}"
            )
        print("\n".join(line), flush=True)
    for label, (r, f, m) in pooled.items():
        if len({len(x) for x in r}) > 1:  # scenarios with different segments: no pooled line
            break
        r = np.asarray(r)
        print(
            f"{label}, {len(r)} trials: mean {np.round(r.mean(axis=0), 3).tolist()}, "
            f"p90 {np.round(np.quantile(r, 0.9, axis=0), 3).tolist()}, "
            f"max {np.round(r.max(axis=0), 3).tolist()}; "
            f"false-alarm trials {f}, missed swaps {m}"
        )


if __name__ == "__main__":
    main()
