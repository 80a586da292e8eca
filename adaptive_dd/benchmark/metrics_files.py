"""The benchmark's metrics written to files: ``metrics.json`` (every figure) and ``metrics.csv``
(one row per controller and segment), each written atomically."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from adaptive_dd.outputs import atomic_write

__all__ = ["write_csv", "write_json"]


def write_json(metrics: dict, path: str | Path) -> Path:
    """The metrics as JSON, written atomically (temporary file renamed into place)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(metrics, indent=1)
    with atomic_write(path, encoding="utf-8") as fh:
        fh.write(text)
    return path


def write_csv(metrics: dict, path: str | Path) -> Path:
    """One row per controller and segment, written atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    keys = [
        "start",
        "end",
        "mass",
        "rms_error",
        "rms_error_settled",
        "max_error",
        "settling_time",
        "detection_delay",
        "rms_torque",
        "saturation_fraction",
        "mass_estimate",
    ]
    with atomic_write(path, newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        n_joints = max(
            len(s["rms_error_joint"]) for c in metrics["controllers"].values() for s in c["segments"]
        )
        joints = [f"rms_error_joint{j}" for j in range(1, n_joints + 1)]
        w.writerow(["controller", *keys, *joints, "failed_trials"])
        for name, c in metrics["controllers"].items():
            for s in c["segments"]:
                w.writerow([name, *(s[k] for k in keys), *s["rms_error_joint"], c["failed_trials"]])
    return path
