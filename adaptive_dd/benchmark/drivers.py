"""The two paths of a two-link run, on the same set-up and the same compiled per-sample glue.

:func:`run_compiled` drives :func:`~adaptive_dd.benchmark.compiled.closed_loop_block` over a
run, block by block (a built-in controller's law and estimator compiled in); :func:`run_python`
runs any controller object (``reset / command / observe``) one Python ``command`` per sample for
the whole batch, between the batch wrappers of the same per-trial functions
(:func:`~adaptive_dd.benchmark.compiled.measure_batch`,
:func:`~adaptive_dd.benchmark.compiled.apply_batch`,
:func:`~adaptive_dd.benchmark.compiled.estimate_batch`): the measurement with its dropouts,
the divergence rule, actuator, plant step, failure freeze, streamed sums and recordings are
written once (:mod:`adaptive_dd.benchmark.compiled`), so the two paths agree to rounding.
"""

from __future__ import annotations

import warnings

import numpy as np
from numba.core.errors import NumbaPerformanceWarning

from adaptive_dd.benchmark.compiled import (
    LAW_ADAPTIVE,
    LAW_SLOTINE,
    CompiledSpec,
    OnlineKernelConfig,
    TwoLinkPlant,
    TwoLinkTrialState,
    apply_batch,
    closed_loop_block,
    estimate_batch,
    measure_batch,
    segment_of,
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
from adaptive_dd.controllers.base import declared
from adaptive_dd.errors import SignalError
from adaptive_dd.identification.online import OnlineConfig, online_init
from adaptive_dd.plant.integrator import friction_vector
from adaptive_dd.plant.sampling import first_sample
from adaptive_dd.plant.simulator import MAX_SPEED

__all__ = ["run_compiled", "run_python"]


def _setup(name, ctrl, scenario, idx, reference, keep: int, estimates: bool, engine: str):
    """``(run, rc, io, pl, ts, rec)``: an empty run and the records both paths pass to the glue."""
    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    seg_start, seg_end, seg_settled = segment_bounds(scenario.segments(), T, SETTLE)
    run = new_run(name, ctrl, S, len(seg_start), N, keep, estimates, engine)
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
    rec = Recording(
        run.q, run.qd, run.tau, run.saturated, run.sigma_hat if estimates else np.zeros((0, N, 7)),
        run.sigma_end if estimates else np.zeros((S, len(seg_start), 7)),
    )  # fmt: skip
    return run, rc, io, pl, ts, rec


class _Draws:
    """Sensor noise and dropouts of the trials, block by block (common random numbers)."""

    def __init__(self, scenario, idx):
        self.rngs = trial_rngs(scenario.seed, idx)
        self.drop_rngs = dropout_rngs(scenario, idx)
        self.p = scenario.dropout
        self.none = np.zeros((len(idx), 0), dtype=np.bool_)

    def block(self, n: int):
        """``noise (S, n, 4)`` standard normal, ``drop (S, n)`` (or ``(S, 0)``: no dropouts)."""
        noise = np.ascontiguousarray(np.stack([g.standard_normal((n, 4)) for g in self.rngs]))
        drop = self.none if self.drop_rngs is None else dropout_block(self.drop_rngs, self.p, n)
        return noise, drop


def run_compiled(name, ctrl, spec: CompiledSpec, scenario, idx, reference, keep: int, bar) -> ControllerRun:
    """One built-in controller's trials on the compiled path; the same result as :func:`run_python`.

    ``spec`` its :func:`~adaptive_dd.benchmark.compiled.compiled_spec`; ``idx`` the seed indices;
    ``reference`` ``(q_d, qd_d, qdd_d)``, each ``(n_samples, 2)``; ``keep`` trials recorded;
    ``bar`` a progress bar (samples) or None."""
    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    adaptive = spec.law == LAW_ADAPTIVE
    estimates = adaptive or spec.law == LAW_SLOTINE
    run, rc, io, pl, ts, rec = _setup(name, ctrl, scenario, idx, reference, keep, estimates, "compiled")
    cfg = spec.online if adaptive else OnlineConfig(sample_period=T, tau_f=max(0.01, T))  # unused
    es = online_init(cfg, S, spec.sigma)
    ec = OnlineKernelConfig(*cfg.packed)
    alarms = Alarms(np.zeros((S, MAX_ALARMS)), np.zeros(S, dtype=np.int64))
    draws = _Draws(scenario, idx)
    for k0 in range(0, N, CHUNK):
        k1 = min(N, k0 + CHUNK)
        noise, drop = draws.block(k1 - k0)
        with warnings.catch_warnings():  # trial_block asks for numba's parallel pipeline on purpose
            warnings.filterwarnings(  # (COPY_PROPAGATE_ONLY); its compilation warns that nothing ran parallel
                "ignore", message=r"\s*The keyword argument 'parallel=True' was specified",
                category=NumbaPerformanceWarning,
            )  # fmt: skip
            closed_loop_block(k0, k1, noise, drop, rc, io, pl, spec.gains, ts, es, ec, run.acc, rec, alarms)
        if bar is not None:
            bar.update(k1 - k0)
    if adaptive:
        run.skipped = es.n_skipped.copy()
    if adaptive and cfg.detector is not None:
        run.alarm_times = [list(alarms.times[i, : min(n, MAX_ALARMS)]) for i, n in enumerate(alarms.count)]
    return run


def run_python(name, ctrl, scenario, idx, reference, keep: int, bar) -> ControllerRun:
    """One controller object's trials on the Python path: a vectorised batch, one ``command`` and
    one ``observe`` per sample; a controller that raises fails its own trials (``run.error``)."""
    S, N, T = len(idx), scenario.n_samples, scenario.sample_period
    error = ""
    try:
        ctrl.reset(S, T)
        estimates = bool(declared(ctrl, "adaptive"))
    except Exception as exc:  # contain any controller failure to its own trials
        error, estimates = f"{type(exc).__name__} in reset: {exc}", False
    run, rc, io, pl, ts, rec = _setup(name, ctrl, scenario, idx, reference, keep, estimates, "python")
    truth = bool(declared(ctrl, "needs_true_model"))
    draws = _Draws(scenario, idx)
    qm, qdm, qm_obs, qdm_obs, tau = (np.zeros((S, 2)) for _ in range(5))
    no_drop = np.zeros(0, dtype=np.bool_)
    for k in range(N):
        if k % CHUNK == 0:
            noise, drop = draws.block(min(CHUNK, N - k))
        measure_batch(io, ts, noise[:, k % CHUNK], drop[:, k % CHUNK] if drop.shape[1] else no_drop, qm, qdm,
                      qm_obs, qdm_obs)  # fmt: skip
        cmd = np.full((S, 2), np.nan)
        if not error:
            try:
                kw = {}
                if truth:
                    kw["sigma_true"] = np.broadcast_to(pl.sigma_seg[segment_of(pl, k)], (S, 7)).copy()
                out = np.array(ctrl.command(qm.copy(), qdm.copy(), rc.q_d[k], rc.qd_d[k], rc.qdd_d[k], **kw),
                               dtype=float)  # fmt: skip
                if out.shape != (S, 2):
                    raise SignalError(f"command returned shape {out.shape}, expected ({S}, 2)")
                cmd = np.ascontiguousarray(out)
            except Exception as exc:
                error = f"{type(exc).__name__} in command at t = {k * T:.3f} s: {exc}"
        s = apply_batch(rc, io, pl, ts, run.acc, rec, k, cmd, tau)
        if not error:
            try:
                ctrl.observe(qm_obs.copy(), qdm_obs.copy(), tau.copy())
                if estimates:
                    est = np.asarray(declared(ctrl, "sigma_hat"), dtype=float)
                    estimate_batch(rc, rec, k, s, np.ascontiguousarray(np.broadcast_to(est, (S, 7))))
            except Exception as exc:
                error = f"{type(exc).__name__} in observe at t = {k * T:.3f} s: {exc}"
        if bar is not None and k % 1000 == 999:
            bar.update(1000)
    if bar is not None:
        bar.update(N % 1000)
    run.error = error
    if error:
        run.failed[:] = True
    run.alarm_times = None if error else declared(ctrl, "alarm_times")
    run.skipped = None if error else declared(ctrl, "skipped_samples")
    return run
