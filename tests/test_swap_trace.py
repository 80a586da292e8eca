"""``benchmarks/swap_trace.py``'s line "the swap's torque until the alarm": what the swap changed
in the torque a recorded trajectory asks (the closed forms' regressor or the general arm's, as the
run took), against the general arm's inverse dynamics with the payload as a disk at the tip."""

from __future__ import annotations

import dataclasses
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd import load_scenario, run_benchmark
from adaptive_dd.plant.sampling import first_sample

ROOT = Path(__file__).resolve().parents[1]


def _script():
    spec = importlib.util.spec_from_file_location("swap_trace", ROOT / "benchmarks" / "swap_trace.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("base", ["short_swap.toml", "short_swap_general.toml"])
def test_the_swaps_torque_is_the_payloads_inverse_dynamics(base):
    """3 kg at 2 s on the paper's arm, on the closed forms and on the general kernels."""
    mod = _script()
    sc = load_scenario(ROOT / "benchmarks" / "sweeps" / base)
    sc = dataclasses.replace(sc.with_controllers(["ct_oracle", "adaptive_ct"]), seeds=1)
    assert (sc.closed_forms is not None) == (base == "short_swap.toml") and sc.swap_times == (2.0,)
    res = run_benchmark(sc, progress=False, keep_trajectories=1)
    i0 = first_sample(2.0, sc.sample_period)
    run = res.runs["adaptive_ct"]
    got = mod._payload_torque(sc, res, run, 0, i0, i0 + 40)
    q, qd = run.q[0][i0 : i0 + 40], run.qd[0][i0 : i0 + 40]
    qdd = np.gradient(np.asarray(run.qd[0], float), sc.sample_period, axis=0)[i0 : i0 + 40]
    arm = sc.arm  # the general arm's inverse dynamics, whichever kernels ran
    loaded = arm.sigma_with_payload(3.0, radius=sc.payload_radius)
    tau = arm.inverse_dynamics(q, qd, qdd, sigma=loaded) - arm.inverse_dynamics(q, qd, qdd)
    want = np.sqrt(np.mean(tau**2, axis=0))
    assert np.all(want > 0.05)  # the swap asks for torque on both joints here
    np.testing.assert_allclose(got, want, rtol=1e-6)
