"""Where a benchmark result came from: the resolved scenario as JSON-ready data, version, commit,
command line, seeds and wall time (the ``provenance`` block of ``metrics.json``)."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np

__all__ = ["provenance", "scenario_dict"]


def scenario_dict(sc) -> dict:
    """The resolved scenario as JSON-ready data (every field, defaults filled in)."""
    out = {}
    for f in dataclasses.fields(sc):
        if f.name == "origin":  # where the file was: the machine's, not the scenario's (source says it)
            continue
        v = getattr(sc, f.name)
        if f.name == "defaulted":
            v = sorted(v)
        elif f.name == "controller_options":
            v = {n: sc.options(n) for n, _ in v}
        elif hasattr(v, "to_dict"):  # the arm, the closed forms' record: their own description
            v = v.to_dict()
        elif dataclasses.is_dataclass(v):
            v = dataclasses.asdict(v)
        out[f.name] = _jsonable(v)
    return out


def _jsonable(v):
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, frozenset | set):
        return sorted(v)
    if isinstance(v, Path):
        return str(v)
    return v


def provenance(res) -> dict:
    """What a figure in a paper needs to be traced back: version, commit, command, seeds, time."""
    return {
        **code_provenance(),
        "runtime": "closed_forms" if res.scenario.closed_forms is not None else "general",
        "seed": res.scenario.seed,
        "seed_indices": list(res.seed_indices),
        "wall_time_s": res.wall_time,
        "engines": {n: r.engine for n, r in res.runs.items()},
        "scenario": scenario_dict(res.scenario),
    }


def code_provenance() -> dict:
    """The code a result came from: package, version, git commit (``+dirty`` with local edits),
    the command line and Python's version."""
    from adaptive_dd import __version__

    commit = None
    try:
        here = Path(__file__).resolve().parent
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=5, check=False
        )
        commit = out.stdout.strip() or None
        if commit:
            dirty = subprocess.run(
                ["git", "status", "--porcelain", "--untracked-files=no"],
                cwd=here,
                capture_output=True,
                text=True,
                timeout=5,
                check=False,
            )
            commit += "+dirty" if dirty.stdout.strip() else ""
    except (OSError, subprocess.SubprocessError):
        commit = None
    return {
        "package": "adaptive_dd",
        "version": __version__,
        "git_commit": commit,
        "command_line": list(sys.argv),
        "python": sys.version.split()[0],
    }
