"""The two forms of adaptive_ct's filtered regression (``[controllers.adaptive_ct.estimator]
regression``) on one scenario: ``"signals"`` (the regressor at the filtered signals, the paper's
M2 construction) against ``"momentum"`` (the momentum form, exact under filtering, its filters
restarted on an alarm). adaptive_ct's ratio to its floor per segment (mean, p90, max over seeds)
trials with a false alarm and swaps missed; the same seeds for both.

    python studies/regression_ablation.py [SCENARIO.toml] [--seeds 20] [--set tau_f=0.02 ...]

``--set KEY=VALUE`` (a TOML value) changes another estimator setting for every row.
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

from _ablation import UR5, ablation_row

from adaptive_dd.benchmark.scenario import read_toml


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(UR5))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--forms", nargs="+", default=["signals", "momentum"], choices=["signals", "momentum"])
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    a = ap.parse_args()
    extra = tomllib.loads("\n".join(a.set))
    base = read_toml(Path(a.scenario))
    print(
        f"{a.scenario}: adaptive_ct / ct_oracle, {a.seeds} seeds, estimator settings {extra or 'as shipped'}"
    )
    print("regression  per segment: mean / p90 / max          trials with a false alarm, swaps missed")
    for form in a.forms:
        print(
            f"{form:10s}  {ablation_row(base, a.scenario, a.seeds, {**extra, 'regression': form})}",
            flush=True,
        )


if __name__ == "__main__":
    main()
