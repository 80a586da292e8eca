"""adaptive_ct / ct_oracle per segment (mean, p90, max over the seeds) and the trials with a false
alarm, for a scenario with adaptive_ct's estimator given extra settings (JSON); the scenario's
other controllers left out. The figures of ``docs/any_arm.md`` ("The Gen3's wrist") with and
without the whitened rows:

    python studies/estimator_option.py adaptive_dd/scenarios/ur5_tool_swap.toml 20 '{"whiten": true}'
    python studies/estimator_option.py adaptive_dd/scenarios/ur5_tool_swap.toml 20
"""

from __future__ import annotations

import copy
import json
import sys
from pathlib import Path

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml


def main() -> None:
    path, seeds = sys.argv[1], int(sys.argv[2])
    extra = json.loads(sys.argv[3]) if len(sys.argv) > 3 else {}
    d = copy.deepcopy(read_toml(Path(path)))
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    d["run"]["seeds"] = seeds
    if extra:
        table = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
        table.setdefault("estimator", {}).update(extra)
    sc = parse_scenario(d, str(Path(path).resolve()), Path(path).stem)
    res = run_benchmark(sc, progress=False, keep_trajectories=0)
    s = res.summary()
    s = s[s.controller == "adaptive_ct"]
    m = res.metrics()["controllers"]["adaptive_ct"]

    def col(c: str) -> str:
        return " / ".join(f"{x:.3f}" for x in s[c])

    print(
        f"{Path(path).stem} {seeds} seeds {extra}: mean {col('ratio_mean')} | p90 {col('ratio_p90')} | "
        f"max {col('ratio_max')} | false-alarm trials {m['trials_with_false_alarms']} of {seeds}; "
        f"missed {m.get('missed_swaps')}"
    )


if __name__ == "__main__":
    main()
