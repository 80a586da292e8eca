"""Drives :func:`~adaptive_dd.benchmark.compiled.closed_loop_block` over a run, block by block."""

from __future__ import annotations

import numpy as np

from adaptive_dd.benchmark.compiled import LAW_ADAPTIVE, LAW_SLOTINE, CompiledSpec, closed_loop_block
from adaptive_dd.benchmark.streaming import segment_bounds
from adaptive_dd.benchmark.trials import (
    dropout_block,
    dropout_rngs,
    new_run,
    sensor_of,
    trial_rngs,
    true_sigma,
)
from adaptive_dd.benchmark.types import CHUNK, MAX_ALARMS, MAX_ERROR, SETTLE, ControllerRun
from adaptive_dd.identification.online import OnlineConfig, online_init
from adaptive_dd.plant.integrator import friction_vector
from adaptive_dd.plant.sampling import first_sample
from adaptive_dd.plant.simulator import MAX_SPEED

__all__ = ["run_compiled"]


def run_compiled(name, ctrl, spec: CompiledSpec, scenario, idx, ref, keep: int, bar) -> ControllerRun:
    """One controller's trials on the compiled path; the same result as the Python path."""
    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    rngs = trial_rngs(scenario.seed, idx)
    adaptive = spec.law == LAW_ADAPTIVE
    estimates = adaptive or spec.law == LAW_SLOTINE
    seg_start, seg_end, seg_settled = segment_bounds(scenario.segments(), T, SETTLE)
    run = new_run(name, ctrl, S, len(seg_start), N, keep, estimates, "compiled")
    K = run.q.shape[0]
    arm = scenario.arm
    act, sens = arm.actuator, sensor_of(scenario)
    plant_f = np.concatenate(
        (
            [T, MAX_SPEED, MAX_ERROR],
            act._lim,
            act._lsb,
            sens.resolution,
            sens.noise_std,
            friction_vector(arm.friction_params),
        )
    )
    plant_i = np.array(
        [scenario.substeps, act.saturate, act.quantize, sens.quantize, arm.friction_code], dtype=np.int64
    )
    sigma_true, _ = true_sigma(scenario, np.arange(N) * T)
    swap_k = np.array([first_sample(at, T) for at in scenario.swap_times], dtype=np.int64)
    sig_seg = np.ascontiguousarray(sigma_true[np.concatenate(([0], np.minimum(swap_k, N - 1)))])
    q = np.broadcast_to(ref[0, 0:2], (S, 2)).copy()
    qd = np.broadcast_to(ref[0, 2:4], (S, 2)).copy()
    stuck, slip, zb = qd == 0.0, np.ones((S, 2)), np.zeros((S, 2))
    cfg = spec.online if adaptive else OnlineConfig(sample_period=T, tau_f=max(0.01, T))  # unused
    state = online_init(cfg, S, spec.sigma)
    alarm_t = np.zeros((S, MAX_ALARMS))
    n_alarms = np.zeros(S, dtype=np.int64)
    sig_rec = run.sigma_hat if estimates else np.zeros((0, N, 7))
    sigma_end = run.sigma_end if estimates else np.zeros((S, len(seg_start), 7))
    drop_rngs = dropout_rngs(scenario, idx)
    no_drop = np.zeros((S, 0), dtype=np.bool_)
    hq, hqd = q.copy(), qd.copy()
    run.dropped = np.zeros(S, dtype=np.int64)
    for k0 in range(0, N, CHUNK):
        k1 = min(N, k0 + CHUNK)
        noise = np.ascontiguousarray(np.stack([g.standard_normal((k1 - k0, 4)) for g in rngs]))
        drop = no_drop if drop_rngs is None else dropout_block(drop_rngs, scenario.dropout, k1 - k0)
        closed_loop_block(
            k0, k1, noise, ref, sig_seg, swap_k, plant_f, plant_i, spec.law, spec.gains, spec.sigma,
            spec.extra, q, qd, stuck, slip, zb, run.failed, run.failed_at, *state, *cfg.packed,
            seg_start, seg_settled, run.acc, run.e_norm, sigma_end, seg_end, alarm_t, n_alarms,
            K, run.q, run.qd, run.tau, run.saturated, sig_rec, drop, hq, hqd, run.dropped,
        )  # fmt: skip
        if bar is not None:
            bar.update(k1 - k0)
    if adaptive:
        run.skipped = state.n_skipped.copy()
    if adaptive and cfg.detector is not None:
        run.alarm_times = [list(alarm_t[i, : min(n, MAX_ALARMS)]) for i, n in enumerate(n_alarms)]
    return run
