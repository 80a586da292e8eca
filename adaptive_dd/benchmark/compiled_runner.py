"""Drives :func:`~adaptive_dd.benchmark.compiled.closed_loop_block` over a run, block by block."""

from __future__ import annotations

import numpy as np

from adaptive_dd.benchmark.compiled import (
    LAW_ADAPTIVE,
    LAW_SLOTINE,
    CompiledSpec,
    OnlineKernelConfig,
    TwoLinkPlant,
    TwoLinkTrialState,
    closed_loop_block,
)
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
from adaptive_dd.closed_loop.glue import Alarms
from adaptive_dd.closed_loop.types import Io, Recording, RunConstants
from adaptive_dd.identification.online import OnlineConfig, online_init
from adaptive_dd.plant.integrator import friction_vector
from adaptive_dd.plant.sampling import first_sample
from adaptive_dd.plant.simulator import MAX_SPEED

__all__ = ["run_compiled"]


def run_compiled(name, ctrl, spec: CompiledSpec, scenario, idx, reference, keep: int, bar) -> ControllerRun:
    """One controller's trials on the compiled path; the same result as the Python path.

    ``reference``: ``(q_d, qd_d, qdd_d)``, each ``(n_samples, 2)``."""
    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    rngs = trial_rngs(scenario.seed, idx)
    adaptive = spec.law == LAW_ADAPTIVE
    estimates = adaptive or spec.law == LAW_SLOTINE
    seg_start, seg_end, seg_settled = segment_bounds(scenario.segments(), T, SETTLE)
    run = new_run(name, ctrl, S, len(seg_start), N, keep, estimates, "compiled")
    c = np.ascontiguousarray
    q_d, qd_d, qdd_d = (c(x, dtype=float) for x in reference)
    rc = RunConstants(
        float(T), float(MAX_ERROR), float(MAX_SPEED), q_d, qd_d, qdd_d, seg_start, seg_end, seg_settled
    )
    arm = scenario.arm
    act, sens = arm.actuator, sensor_of(scenario)
    io = Io(
        c(act._lim, dtype=float), c(act._lsb, dtype=float), bool(act.saturate), bool(act.quantize),
        c(sens.resolution, dtype=float), c(sens.noise_std, dtype=float), bool(sens.quantize),
    )  # fmt: skip
    sigma_true, _ = true_sigma(scenario, np.arange(N) * T)
    swap_k = np.array([first_sample(at, T) for at in scenario.swap_times], dtype=np.int64)
    sig_seg = c(sigma_true[np.concatenate(([0], np.minimum(swap_k, N - 1)))])
    pl = TwoLinkPlant(
        sig_seg, swap_k, int(scenario.substeps), int(arm.friction_code), friction_vector(arm.friction_params)
    )
    q = np.broadcast_to(q_d[0], (S, 2)).copy()
    qd = np.broadcast_to(qd_d[0], (S, 2)).copy()
    run.dropped = np.zeros(S, dtype=np.int64)
    ts = TwoLinkTrialState(
        q, qd, qd == 0.0, np.ones((S, 2)), np.zeros((S, 2)), run.failed, run.failed_at, q.copy(), qd.copy(),
        run.dropped,
    )  # fmt: skip
    cfg = spec.online if adaptive else OnlineConfig(sample_period=T, tau_f=max(0.01, T))  # unused
    es = online_init(cfg, S, spec.sigma)
    ec = OnlineKernelConfig(*cfg.packed)
    alarms = Alarms(np.zeros((S, MAX_ALARMS)), np.zeros(S, dtype=np.int64))
    rec = Recording(
        run.q, run.qd, run.tau, run.saturated, run.sigma_hat if estimates else np.zeros((0, N, 7)),
        run.sigma_end if estimates else np.zeros((S, len(seg_start), 7)),
    )  # fmt: skip
    drop_rngs = dropout_rngs(scenario, idx)
    no_drop = np.zeros((S, 0), dtype=np.bool_)
    for k0 in range(0, N, CHUNK):
        k1 = min(N, k0 + CHUNK)
        noise = np.ascontiguousarray(np.stack([g.standard_normal((k1 - k0, 4)) for g in rngs]))
        drop = no_drop if drop_rngs is None else dropout_block(drop_rngs, scenario.dropout, k1 - k0)
        closed_loop_block(k0, k1, noise, drop, rc, io, pl, spec.gains, ts, es, ec, run.acc, rec, alarms)
        if bar is not None:
            bar.update(k1 - k0)
    if adaptive:
        run.skipped = es.n_skipped.copy()
    if adaptive and cfg.detector is not None:
        run.alarm_times = [list(alarms.times[i, : min(n, MAX_ALARMS)]) for i, n in enumerate(alarms.count)]
    return run
