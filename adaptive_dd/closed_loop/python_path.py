"""The Python path of the closed loop, written once for both arms.

A controller object with ``reset / command / observe`` (a plug-in, or a built-in run with
``engine="python"``) runs as one vectorised batch: one ``command`` and one ``observe`` per
sample for all the trials, between the batch wrappers of the closed loop's compiled per-trial
glue (:class:`PythonGlue`, :mod:`adaptive_dd.closed_loop.glue`): the measurement with its
dropouts, then the divergence rule, actuator, plant step, failure freeze, streamed sums and
recordings, then the estimate's record. The two-link arm
(:func:`adaptive_dd.benchmark.drivers.run_python`) and the N-joint arm
(:func:`adaptive_dd.closed_loop.runner.run_closed_loop`) differ only in their records.

A controller that raises (at reset, command or observe), or returns a command of the wrong
shape, fails its own trials with the message in ``run.error``; the run goes on (the plant
then gets a NaN command, which the divergence rule turns into a failed trial at rest).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.benchmark.types import ControllerRun
from adaptive_dd.closed_loop.noise import NoiseBlocks, RunNoise
from adaptive_dd.closed_loop.types import RunConstants
from adaptive_dd.controllers.base import declared
from adaptive_dd.errors import SignalError

__all__ = ["PythonGlue", "run_python_batch"]

Array = NDArray[np.float64]


class PythonGlue(NamedTuple):
    """One arm's per-sample glue around a Python controller, bound to one run's records.

    Attributes
    ----------
    measure : callable
        ``measure(noise (S, 2 n), lost (S,)) -> qm, qdm, qm_obs, qdm_obs`` each ``(S, n)``, new
        arrays: the law's measurement (the last good one where lost) and the estimator's (NaN
        where lost).
    sigma_true : callable
        ``sigma_true(k) -> (p,) or (S, p)`` the true base parameters over sample k (for oracles;
        per trial when each trial has its own plant).
    apply : callable
        ``apply(k, cmd (S, n)) -> tau (S, n), s``: the command applied over sample k (``cmd`` is
        not changed), the torque that was applied, the sample's payload segment.
    record_estimate : callable
        ``record_estimate(k, s, sigma (S, p))``: the estimate after sample k (segment s).
    pi_true : callable or None
        ``pi_true(k) -> (S, 13 n)`` each trial's true standard parameters over sample k (N-joint
        arm), given to a controller with ``takes_pi_true`` (the built-in oracles' Python form).
    """

    measure: Callable
    sigma_true: Callable
    apply: Callable
    record_estimate: Callable
    pi_true: Callable | None = None


def run_python_batch(
    ctrl, rc: RunConstants, draws: NoiseBlocks | RunNoise, records: Callable, bar=None
) -> ControllerRun:
    """One controller object's trials on the Python path.

    Parameters
    ----------
    ctrl : object
        ``reset(n_trials, T)``, ``command(q, qd, q_d, qd_d, qdd_d[, sigma_true]) -> (S, n)``,
        ``observe(q, qd, tau)``; the optional attributes of
        :data:`~adaptive_dd.controllers.base.DECLARED` (read through
        :func:`~adaptive_dd.controllers.base.declared`).
    rc : RunConstants
        Sample period and the reference ``q_d, qd_d, qdd_d (N, n)``.
    draws : NoiseBlocks or RunNoise
        The trials' sensor noise and dropouts (S trials).
    records : callable
        ``records(estimates) -> (run, glue)`` after ``reset``: the empty
        :class:`~adaptive_dd.benchmark.types.ControllerRun` (with the estimate's arrays if
        ``estimates``) and the :class:`PythonGlue` bound to its arrays.
    bar : tqdm-like or None
        Progress (samples).

    Returns
    -------
    ControllerRun
        ``run``, filled in; ``error``, ``alarm_times`` and ``skipped`` from the controller.
    """
    S, N, T = draws.n_trials, rc.q_d.shape[0], rc.T
    error = ""
    lag = None  # samples back that an oracle's true model is taken (None: not an oracle)
    try:
        ctrl.reset(S, T)
        lag = _truth_lag(ctrl, T) if declared(ctrl, "needs_true_model") else None
    except Exception as exc:  # contain any controller failure to its own trials
        error = f"{type(exc).__name__} in reset: {exc}"
    # the estimate's records always: a sigma_hat may appear after reset (then the samples before
    # it are NaN); dropped at the end if it never does
    run, glue = records(True)
    estimated = False
    no_drop = np.zeros(S, dtype=np.bool_)
    for k0, k1, noise, drop in draws.blocks(N):
        for k in range(k0, k1):
            lost = drop[:, k - k0] if drop.shape[1] else no_drop
            error, est = _sample(ctrl, glue, rc, run, k, noise[:, k - k0], lost, lag, error)
            estimated = estimated or est
            if bar is not None and k % 1000 == 999:
                bar.update(1000)
    if bar is not None:
        bar.update(N % 1000)
    if not estimated:
        run.sigma_end = run.sigma_hat = None
    run.error = error
    if error:
        run.failed[:] = True
    run.explain_failures(rc.max_error, rc.max_speed)
    run.alarm_times = None if error else declared(ctrl, "alarm_times")
    run.skipped = None if error else declared(ctrl, "skipped_samples")
    return run


def _sample(ctrl, glue, rc: RunConstants, run: ControllerRun, k: int, noise, lost, lag, error: str):
    """Sample k of every trial on the Python path (the steps of :mod:`adaptive_dd.closed_loop.glue`
    around the controller's ``command`` and ``observe``); ``(error, estimated)``: the controller's
    first failure (its trials then run on with no command) and whether it reported an estimate."""
    S, n, T = run.failed.shape[0], rc.q_d.shape[1], rc.T
    qm, qdm, qm_obs, qdm_obs = glue.measure(noise, lost)
    cmd = np.full((S, n), np.nan)
    if not error:
        try:
            cmd = _command(ctrl, glue, rc, k, qm, qdm, lag)
        except Exception as exc:  # contain any controller failure to its own trials
            error = f"{type(exc).__name__} in command at t = {k * T:.3f} s: {exc}"
    before = run.failed.copy()
    tau, s = glue.apply(k, cmd)
    _say_why(run, before, cmd, k * T, error)
    estimated = False
    if not error:
        try:
            ctrl.observe(qm_obs, qdm_obs, tau)
            est = declared(ctrl, "sigma_hat")
            if est is not None:
                estimated = True
                glue.record_estimate(k, s, _estimate(est, S, run.sigma_end.shape[2]))
        except Exception as exc:
            error = f"{type(exc).__name__} in observe at t = {k * T:.3f} s: {exc}"
    return error, estimated


def _say_why(run: ControllerRun, before, cmd: Array, t: float, error: str = "") -> None:
    """Name the reason of the trials that failed at time t: the controller's own ``error`` (its
    exception, after which it commands nothing), else the non-finite command it returned."""
    for i in np.flatnonzero(run.failed & ~before):
        bad = np.flatnonzero(~np.isfinite(cmd[i]))
        if error:
            run.failed_why[int(i)] = error
        elif bad.size:
            j = int(bad[0])
            why = f"non-finite torque command (joint {j + 1}: {cmd[i, j]}) at t = {t:.3f} s"
            run.failed_why[int(i)] = why


def _estimate(est, S: int, p: int) -> Array:
    """A controller's ``sigma_hat`` as ``(S, p)``; :class:`~adaptive_dd.errors.SignalError` if it
    has another shape (``(p,)`` stands for every trial)."""
    a = np.asarray(est, dtype=float)
    if a.shape not in ((p,), (S, p)):
        raise SignalError(f"sigma_hat has shape {a.shape}, expected ({S}, {p}) or ({p},)")
    return np.ascontiguousarray(np.broadcast_to(a, (S, p)))


def _truth_lag(ctrl, T: float) -> int:
    """Samples back that an oracle's truth is taken: ``ct_oracle_late``'s delay (the built-in on
    either arm, in whole samples as on the compiled path: a fraction of one is an error), else 0 (a
    plug-in's attribute of the same name is not read, on this path as on the compiled one)."""
    from adaptive_dd.closed_loop.controllers import CTOracleLate
    from adaptive_dd.controllers.base import delay_samples
    from adaptive_dd.controllers.feedback import ComputedTorque

    if isinstance(ctrl, (ComputedTorque, CTOracleLate)) and ctrl.model_delay > 0:
        return delay_samples(ctrl.model_delay, T, ctrl.name)
    return 0


def _command(ctrl, glue: PythonGlue, rc: RunConstants, k: int, qm: Array, qdm: Array, lag) -> Array:
    """The controller's command ``(S, n)`` at sample k (an oracle, ``lag`` not None, given the true
    model of ``lag`` samples back: :func:`_truth_lag`); :class:`~adaptive_dd.errors.SignalError`
    if it has another shape."""
    kw = {}
    if lag is not None:
        kt = max(k - lag, 0)
        sg = np.asarray(glue.sigma_true(kt))
        kw["sigma_true"] = np.broadcast_to(sg, (qm.shape[0], sg.shape[-1])).copy()
        if glue.pi_true is not None and getattr(ctrl, "takes_pi_true", False):
            kw["pi_true"] = glue.pi_true(kt)
    out = np.asarray(ctrl.command(qm, qdm, rc.q_d[k], rc.qd_d[k], rc.qdd_d[k], **kw), dtype=float)
    if out.shape != qm.shape:
        raise SignalError(f"command returned shape {out.shape}, expected ({qm.shape[0]}, {qm.shape[1]})")
    return out
