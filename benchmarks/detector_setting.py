"""Judge an N-joint detector setting before it becomes the default: the shipped N-joint scenarios
and a population of drawn arms, with ``adaptive_ct``'s :class:`Detector` settings given.

    python benchmarks/detector_setting.py --detector fast_threshold=6.5
    python benchmarks/detector_setting.py                      # the defaults, for the other side
    python benchmarks/detector_setting.py --detector fast_threshold=6.5 \\
        --scenarios adaptive_dd/scenarios/panda_payload.toml --seeds 200 --arms 0

Runs ``ct_oracle`` and ``adaptive_ct`` (its detector settings replaced by ``--detector KEY=VALUE``,
the same on every arm, through
:func:`~adaptive_dd.benchmark.scenario_settings.with_settings`) on each scenario, ``--seeds``
trials, and prints per scenario the per-seed ratio ``adaptive_ct / ct_oracle`` per segment (mean,
p90, max), the trials with a false alarm and the missed swaps; then the template
``benchmarks/scenarios/population.toml`` over ``--arms`` drawn arms from ``--first-arm``,
``--arm-seeds`` trials each, pooled as ``adaptive-dd benchmark --arms`` pools them (0 arms: none).
Run it once with the setting and once without, on a quiet machine or not (nothing here is timed),
and compare. The two-link closed forms' detector has its own script,
``benchmarks/detector_acceptance.py``. Asserts nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

from adaptive_dd.benchmark.metrics import compute_metrics, missed_swap_counts
from adaptive_dd.benchmark.population import format_population, run_population
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario, read_toml
from adaptive_dd.benchmark.scenario_settings import with_settings
from adaptive_dd.identification.online_config import Detector

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = (
    "adaptive_dd/scenarios/ur5_tool_swap.toml",
    "adaptive_dd/scenarios/ur5_tool_swap_exact.toml",
    "adaptive_dd/scenarios/panda_payload.toml",
    "adaptive_dd/scenarios/iiwa14_payload.toml",
    "adaptive_dd/scenarios/vertical3_payload.toml",
    "adaptive_dd/scenarios/vertical3_payload_exact.toml",
    "benchmarks/scenarios/gen3_drawn.toml",
    "benchmarks/scenarios/sice_general.toml",
)
TEMPLATE = ROOT / "benchmarks" / "scenarios" / "population.toml"


def detector_settings(pairs: list[str]) -> dict:
    """``["fast_threshold=6.5", ...]`` -> ``{"fast_threshold": 6.5}``, typed as the defaults;
    an unknown key or a bad value fails here, by name."""
    fields = {f.name for f in dataclasses.fields(Detector)}
    out: dict = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or key not in fields:
            raise SystemExit(f"--detector: expected KEY=VALUE with KEY one of {sorted(fields)}, got {pair!r}")
        default = getattr(Detector(), key)
        try:
            if isinstance(default, bool):
                if value.lower() not in ("true", "false"):
                    raise ValueError("expected true or false")
                out[key] = value.lower() == "true"
            elif default is None or isinstance(default, float):
                out[key] = float(value)
            else:
                out[key] = type(default)(value)
        except ValueError as exc:
            raise SystemExit(f"--detector {pair}: {key} takes a {type(default).__name__}: {exc}") from None
    Detector(**out)
    return out


def scenario_lines(path: Path, seeds: int, detector: dict) -> list[str]:
    sc = dataclasses.replace(load_scenario(path).with_controllers(["ct_oracle", "adaptive_ct"]), seeds=seeds)
    if detector:
        sc = with_settings(sc, "adaptive_ct", {"detector": detector})
    res = run_benchmark(sc, progress=False)
    a = compute_metrics(res)["controllers"]["adaptive_ct"]
    run = res.runs["adaptive_ct"]
    missed = int(missed_swap_counts(run.alarm_times, sc.swap_times, run.failed).sum())
    lines = [
        f"{path}: false-alarm trials {a['trials_with_false_alarms']} of {seeds}, missed swaps {missed}, "
        f"failed {a['failed_trials']}"
    ]
    for seg in a["segments"]:
        st = seg["ratio_to_floor"]
        lines.append(
            f"    {seg['start']:4.1f}-{seg['end']:4.1f} s {seg['mass']:3g} kg: mean {st['mean']:.3f} "
            f"p90 {st['p90']:.3f} max {st['max']:.2f} (seed {st['worst_seed']})"
        )
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--detector", nargs="*", default=[], metavar="KEY=VALUE", help="Detector settings")
    ap.add_argument("--scenarios", nargs="*", default=list(SCENARIOS), help="scenario files")
    ap.add_argument("--seeds", type=int, default=50, help="trials per scenario")
    ap.add_argument("--arms", type=int, default=50, help="drawn arms (0: no population)")
    ap.add_argument("--first-arm", type=int, default=0)
    ap.add_argument("--arm-seeds", type=int, default=10, help="trials per drawn arm")
    args = ap.parse_args()
    detector = detector_settings(args.detector)
    print(f"adaptive_ct detector settings: {detector or 'the defaults'}", flush=True)
    t0 = time.perf_counter()
    for name in args.scenarios:
        path = Path(name) if Path(name).is_file() else ROOT / name
        print("\n".join(scenario_lines(path, args.seeds, detector)), flush=True)
    if args.arms > 0:
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1, user_api="blas"):  # as `benchmark --arms` runs them
            pop = run_population(
                read_toml(TEMPLATE),
                str(TEMPLATE),
                range(args.first_arm, args.first_arm + args.arms),
                seeds=args.arm_seeds,
                controllers=lambda sc: ("ct_oracle", "adaptive_ct"),
                settings={"adaptive_ct": {"detector": detector}} if detector else None,
            )
        keep = ("pooled", "segment ", "trials with a false alarm", "missed swaps", "worst arms")
        print("\n".join(ln for ln in format_population(pop).splitlines() if ln.strip().startswith(keep)))
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
