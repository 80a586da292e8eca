"""Shared by the estimator ablations: adaptive_ct's ratio to its floor per segment under one
setting of its N-joint estimator (``[controllers.adaptive_ct.estimator]``)."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario

UR5 = Path(__file__).resolve().parents[1] / "adaptive_dd" / "scenarios" / "ur5_tool_swap_exact.toml"


def ablation_row(
    base: dict,
    scenario: str,
    seeds: int,
    estimator: dict,
    plant: dict | None = None,
    controller: dict | None = None,
    torque: bool = False,
) -> str:
    """``mean/p90/max`` of adaptive_ct / ct_oracle per segment, the trials with a false alarm and
    the swaps missed, as one line, with the scenario's estimator settings updated by ``estimator`` (and its
    ``[plant]`` table by ``plant``, adaptive_ct's own settings by ``controller``); with ``torque``,
    also its RMS torque over ct_oracle's per segment and its saturated fraction."""
    d = copy.deepcopy(base)
    if plant:
        d.setdefault("plant", {}).update(plant)
    d["run"]["seeds"] = seeds
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    ac = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
    ac.update(controller or {})
    estimator = dict(estimator)
    if "detector" in estimator:  # the detector's table sits at the top of [controllers.adaptive_ct]
        ac["detector"] = estimator.pop("detector")
    ac.setdefault("estimator", {}).update(estimator)
    df = run_benchmark(parse_scenario(d, scenario, Path(scenario).stem), progress=False).to_frame()
    c = df[df.controller == "adaptive_ct"]
    cells = segment_cells(c)
    if torque:  # RMS torque over ct_oracle's, per segment (mean over seeds), and saturation
        o = df[df.controller == "ct_oracle"].set_index(["seed", "segment"]).rms_torque_Nm
        r = c.set_index(["seed", "segment"]).rms_torque_Nm / o
        sat = c.groupby("segment").saturation_fraction.mean()
        cells.append(
            "torque x "
            + "/".join(f"{v:.2f}" for v in r.groupby(level="segment").mean())
            + ", saturated % "
            + "/".join(f"{100 * v:.2f}" for v in sat)
        )
    fa = int((c.groupby("seed").false_alarms.sum() > 0).sum())
    missed = int(np.sum(c.detection_delay_s.isna() & (c.segment > 0))) if c.false_alarms.notna().any() else -1
    return f"{'  '.join(cells)}   {fa}   {missed}"


def segment_cells(c) -> list[str]:
    """``mean/p90/max`` of the ratio to the floor per segment of one controller's rows of ``to_frame()``."""
    cells = []
    for _, s in c.groupby("segment"):
        r = s.ratio_to_floor.to_numpy(dtype=float)
        cells.append(f"{np.nanmean(r):.3f}/{np.nanpercentile(r, 90):.3f}/{np.nanmax(r):.2f}")
    return cells


class Delegating:
    """A study's wrapper of a built-in controller ``self.inner``: what the benchmark reads after a
    run (the estimate, the alarms, the skipped samples) is the inner controller's."""

    @property
    def sigma_hat(self):
        return self.inner.sigma_hat

    @property
    def alarm_times(self):
        return self.inner.alarm_times

    @property
    def skipped_samples(self):
        return self.inner.skipped_samples
