"""``benchmarks/scenarios/sice_general.toml`` is the default scenario on the general kernels:
the same arm (``general = true``), reference, payloads, noise and run, so that its
``adaptive_ct / ct_oracle`` ratios compare the general estimator with the closed forms' on the
paper's arm (``benchmarks/general_payload_prior.py``, ``benchmarks/swap_trace.py``). The arm
also states its rated payload (``payload_capacity``, 5 kg: the closed forms' Slotine-Li box) and
that its payloads are centred on the tip (``payload_offset = 0``, eq. 9's disk), which only the
general kernels read."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd import load_scenario

ROOT = Path(__file__).resolve().parents[1]
OWN = {"arm", "closed_forms", "controllers", "name", "seeds", "source", "origin", "defaulted"}  # may differ


def _same(a, b) -> bool:
    try:
        return bool(np.all(a == b))
    except (TypeError, ValueError):
        return False


def test_sice_general_is_the_default_scenario_on_the_general_kernels():
    default = load_scenario()
    general = load_scenario(ROOT / "benchmarks" / "scenarios" / "sice_general.toml")
    assert default.closed_forms is not None and general.closed_forms is None
    stated = {"general": True, "payload_capacity": 5.0, "payload_offset": 0.0}
    assert general.arm == dataclasses.replace(default.arm, **stated)
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


def test_the_payloads_are_centred_on_the_tip_as_the_scenario_states():
    """``payload_offset = 0``: the scenario's disks carry no centre of mass of their own, as the
    closed forms' eq. (9) takes them."""
    general = load_scenario(ROOT / "benchmarks" / "scenarios" / "sice_general.toml")
    assert general.arm.payload_offset == 0.0 and general.swap_com == ()


def test_the_general_estimator_tracks_the_papers_arm_as_the_closed_forms_do():
    """On the paper's arm the general estimator, told what the scenario states (the payloads' shape
    and that they are centred), is within the closed forms' figures after the 3 -> 1 kg swap (the
    closed forms: 1.02x the floor at 200 seeds; a point-mass prior 10 cm wide gave 1.87x)."""
    from adaptive_dd import run_benchmark

    sc = load_scenario(ROOT / "benchmarks" / "scenarios" / "sice_general.toml")
    sc = dataclasses.replace(sc, seeds=2)
    frame = run_benchmark(sc, progress=False).to_frame()
    ratio = frame[frame.controller == "adaptive_ct"].groupby("segment").ratio_to_floor.max()
    assert ratio[2] < 1.1, ratio  # 10-15 s, 1 kg
    assert ratio[1] < 1.45, ratio  # 5-10 s, 3 kg (closed forms 1.28 on average)


def test_the_general_sweep_is_the_shipped_sweep_on_the_general_kernels():
    """``benchmarks/sweeps/short_swap_general.toml`` is ``short_swap.toml`` with the paper's arm on
    the general kernels (as ``sice_general.toml`` states it), and its sweep the same grid."""
    import tomllib

    sweeps = ROOT / "benchmarks" / "sweeps"
    closed, general = (load_scenario(sweeps / f) for f in ("short_swap.toml", "short_swap_general.toml"))
    assert closed.closed_forms is not None and general.closed_forms is None
    sice = load_scenario(ROOT / "benchmarks" / "scenarios" / "sice_general.toml").arm
    assert general.arm == sice.with_(sensor=general.arm.sensor)  # the sweep's noise is its own
    differ = [
        f.name
        for f in dataclasses.fields(closed)
        if f.name not in OWN and not _same(getattr(closed, f.name), getattr(general, f.name))
    ]
    assert differ == []
    spec = {
        f: tomllib.loads((sweeps / f).read_text())
        for f in ("payload_mass_swap_time.toml", "payload_mass_swap_time_general.toml")
    }
    a, b = spec.values()
    assert (
        b["sweep"].pop("scenario") == "short_swap_general.toml"
        and a["sweep"].pop("scenario") == "short_swap.toml"
    )
    assert a == b
