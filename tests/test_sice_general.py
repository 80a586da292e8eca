"""``benchmarks/scenarios/sice_general.toml`` is the default scenario on the general kernels:
the same arm (``general = true``), reference, payloads, noise and run, so that its
``adaptive_ct / ct_oracle`` ratios compare the general estimator with the closed forms' on the
paper's arm (``benchmarks/general_payload_prior.py``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd import load_scenario

ROOT = Path(__file__).resolve().parents[1]
OWN = {"arm", "closed_forms", "controllers", "name", "seeds", "source"}  # what it may differ in


def _same(a, b) -> bool:
    try:
        return bool(np.all(a == b))
    except (TypeError, ValueError):
        return False


def test_sice_general_is_the_default_scenario_on_the_general_kernels():
    default = load_scenario()
    general = load_scenario(ROOT / "benchmarks" / "scenarios" / "sice_general.toml")
    assert default.closed_forms is not None and general.closed_forms is None
    assert general.arm == dataclasses.replace(default.arm, general=True)
    assert set(general.controllers) <= set(default.controllers)
    differ = [
        f.name
        for f in dataclasses.fields(default)
        if f.name not in OWN and not _same(getattr(default, f.name), getattr(general, f.name))
    ]
    assert differ == []
