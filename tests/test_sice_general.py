"""``benchmarks/scenarios/sice_general.toml`` is the default scenario on the general kernels:
the same arm (``general = true``), reference, payloads, noise and run, so that its
``adaptive_ct / ct_oracle`` ratios compare the general estimator with the closed forms' on the
paper's arm (``benchmarks/general_payload_prior.py``, ``benchmarks/swap_trace.py``). The arm
also states its rated payload (``payload_capacity``, 5 kg: the closed forms' Slotine-Li box),
which only the general kernels read."""

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
    assert general.arm == dataclasses.replace(default.arm, general=True, payload_capacity=5.0)
    assert set(general.controllers) <= set(default.controllers)
    differ = [
        f.name
        for f in dataclasses.fields(default)
        if f.name not in OWN and not _same(getattr(default, f.name), getattr(general, f.name))
    ]
    assert differ == []


def test_the_rated_payload_is_what_the_closed_forms_box_assumes():
    """The general scenario's ``payload_capacity`` is the closed forms' Slotine-Li box (5 kg): one
    rated payload for the arm on either runtime, read by the general estimator only."""
    from adaptive_dd.controllers.slotine_li import MAX_MASS

    general = load_scenario(ROOT / "benchmarks" / "scenarios" / "sice_general.toml")
    assert general.arm.payload_capacity == MAX_MASS
