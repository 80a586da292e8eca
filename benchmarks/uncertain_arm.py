"""adaptive_ct on an arm that is not its URDF: one plant per seed drawn around the scenario's arm
(:func:`adaptive_dd.identification.arm_prior.draw_parameters`: masses 10 %, com 1 cm, inertias
20 %, friction 50 %, armature 30 %, times ``--level``), every controller built from the URDF but
``ct_oracle``, whose model is the plant (the compiled path takes the oracle's model from the
plant). Prints adaptive_ct / ct_oracle and ct_nominal / ct_oracle per segment (mean, p90, max,
worst seed), trials with a false alarm and swaps missed.

    python benchmarks/uncertain_arm.py [SCENARIO.toml] [--seeds 20] [--level 1] [--duration S]
        [--set 'KEY = VALUE' ...] [--exact-estimator]

``--set`` (TOML) changes adaptive_ct's estimator settings (``[controllers.adaptive_ct.estimator]``);
``--exact-estimator`` drops the scenario's own estimator table first (the derived settings).
"""

from __future__ import annotations

import argparse
import copy
import tomllib
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.metrics import detection_delays, false_alarm_counts, ratio_statistics
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import _run_compiled
from adaptive_dd.closed_loop.types import Plant, io_of, plant_of, run_constants
from adaptive_dd.controllers import gains_for, make_controller
from adaptive_dd.identification.arm_prior import ArmUncertainty, draw_parameters

UR5 = Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml"

WINDOW = 0.25
"""[s] Windows of the first segment's RMS ratio (the time to come within 1.2x of the floor)."""
PLANT_STREAM = 7_777
"""Second key of the plant draws' generator ``(scenario.seed, PLANT_STREAM, seed)``."""


def drawn_plant(scenario, levels: ArmUncertainty, seed: int) -> tuple[Plant, np.ndarray]:
    """The scenario's plant with the arm's parameters drawn for ``seed`` (and those parameters)."""
    arm = scenario.arm
    n = arm.n_joints
    pi = draw_parameters(arm, levels, np.random.default_rng([scenario.seed, PLANT_STREAM, seed]))
    pl = plant_of(scenario)
    rows = pl.pi_seg - arm.pi_links + pi[: 10 * n]  # each segment's payload kept
    plant = pl._replace(
        pi_seg=np.ascontiguousarray(rows),
        fv=pi[10 * n : 11 * n].copy(),
        fc=pi[11 * n : 12 * n].copy(),
        armature=pi[12 * n :].copy(),
    )
    return plant, pi


def run_seed(scenario, ctrls: dict, plant: Plant, seed: int) -> dict:
    """Per controller: its run of one seed on ``plant``."""
    rc, io = run_constants(scenario), io_of(scenario)
    return {
        name: _run_compiled(name, c, scenario, (seed,), rc, io, plant, 0, None) for name, c in ctrls.items()
    }


def time_to_floor(e: np.ndarray, e_floor: np.ndarray, end: int, T: float, level: float = 1.2) -> float:
    """[s] End of the last window (:data:`WINDOW`) of ``[0, end)`` whose RMS error exceeds ``level``
    times the floor's (0: none does)."""
    w = max(1, round(WINDOW / T))
    last = 0
    for k in range(0, end - w + 1, w):
        a, b = e[k : k + w].astype(float), e_floor[k : k + w].astype(float)
        if np.sqrt(np.mean(a * a)) > level * np.sqrt(np.mean(b * b)):
            last = k + w
    return last * T


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(UR5))
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--level", type=float, default=1.0, help="uncertainty levels times this (0: exact arm)")
    ap.add_argument("--duration", type=float, default=None)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--exact-estimator", action="store_true", help="drop the scenario's estimator table")
    ap.add_argument("--per-seed", action="store_true")
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    if a.duration:
        d["run"]["duration"] = a.duration
        d["payload"] = [p for p in d.get("payload", []) if p["at"] < a.duration]
    ac = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
    if a.exact_estimator:
        ac.pop("estimator", None)
    ac.setdefault("estimator", {}).update(tomllib.loads("\n".join(a.set)))
    d["run"]["controllers"] = ["ct_oracle", "ct_nominal", "adaptive_ct"]
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    ctrls = {
        nm: make_controller(nm, gains_for(sc.arm, sc.bandwidth, sc.damping), sc.options(nm), arm=sc.arm)
        for nm in sc.controllers
    }
    levels = ArmUncertainty().scaled(a.level)
    seeds = list(range(a.first_seed, a.first_seed + a.seeds))
    n_seg = len(sc.swap_times) + 1
    lengths = np.array(sc.segment_samples(), dtype=float)
    rms = {nm: np.full((len(seeds), n_seg), np.nan) for nm in ctrls}
    false, missed, delays, settle = [], [], [[] for _ in sc.swap_times], []
    print(f"{a.scenario}: level {a.level} ({levels}), seeds {seeds[0]}..{seeds[-1]}, settings {a.set}")
    for r, seed in enumerate(seeds):
        plant, _ = drawn_plant(sc, levels, seed)
        runs = run_seed(sc, ctrls, plant, seed)
        for nm, run in runs.items():
            rms[nm][r] = np.sqrt(run.acc.sum_e2[0] / lengths)
            if run.failed[0]:
                rms[nm][r] = np.nan
        end0 = int(lengths[0])
        settle.append(
            time_to_floor(runs["adaptive_ct"].e_norm[0], runs["ct_oracle"].e_norm[0], end0, sc.sample_period)
        )
        at = runs["adaptive_ct"].alarm_times or [[]]
        false.append(false_alarm_counts(at, sc.swap_times)[0])
        m = 0
        for i, s in enumerate(sc.swap_times):
            dd = detection_delays(at, s)[0]
            m += dd is None
            if dd is not None:
                delays[i].append(dd)
        missed.append(m)
        if a.per_seed:
            ratio = rms["adaptive_ct"][r] / rms["ct_oracle"][r]
            print(
                f"  seed {seed}: " + " / ".join(f"{x:.3f}" for x in ratio) + f"  alarms {at[0]}", flush=True
            )
    for nm in ("adaptive_ct", "ct_nominal"):
        ratio = rms[nm] / rms["ct_oracle"]
        cells = []
        for i in range(n_seg):
            st = ratio_statistics(ratio[:, i], seeds)
            cells.append(
                f"{st['mean']:.3f}/{st['p90']:.3f}/{st['max']:.2f}@{st['worst_seed']}" if st else "nan"
            )
        print(f"{nm:12s} mean/p90/max@worst per segment: " + "  ".join(cells))
    print(
        "floor (ct_oracle RMS, mrad, mean per segment): "
        + " / ".join(f"{1e3 * x:.3f}" for x in np.nanmean(rms["ct_oracle"], 0))
    )
    st = np.array(settle)
    print(
        "first segment: time to come within 1.2x of the floor (0.25 s windows) "
        f"median {np.median(st):.2f} s, "
        f"p90 {np.percentile(st, 90):.2f} s, max {st.max():.2f} s"
    )
    print(
        f"trials with a false alarm: {sum(1 for x in false if x)} / {len(seeds)}; "
        f" swaps missed: {sum(missed)};"
        f"  median delay ms: " + " / ".join(f"{1e3 * np.median(x):.0f}" if x else "-" for x in delays)
    )


if __name__ == "__main__":
    main()
