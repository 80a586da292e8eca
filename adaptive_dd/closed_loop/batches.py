"""The Python path's steps of the closed loop over every trial at once, each one compiled loop
over the trials of :mod:`adaptive_dd.closed_loop.glue`'s per-sample pieces: the measurement
(step 1), the applied sample (step 3), the estimator (step 4) and the estimate's record. The
Python path (:mod:`adaptive_dd.closed_loop.python_path`: plug-ins, the stepping API, the
Gymnasium environments) calls them between the Python calls of a plain plug-in's law."""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from adaptive_dd.closed_loop.chain_choices import (
    ChainEstimator,
    _chain_estimator_sample,
    _chain_estimator_work,
    _chain_plant_work,
)
from adaptive_dd.closed_loop.glue import (
    _bound,
    _chain_apply_sample,
    _named,
    accumulate_sample,
    apply_sample,
    estimator_sample,
    estimator_work,
    measure_sample,
    plant_work,
    record_estimate,
    segment_of,
)
from adaptive_dd.closed_loop.tool_frame import accumulate_tool
from adaptive_dd.closed_loop.types import Plant
from adaptive_dd.identification.online_kernel import EstCfg

__all__ = ["apply_batch", "estimator_batch", "measure_batch", "sigma_batch"]


@njit(cache=True)
def _measure_loop(io, ts, noise, lost, qm, qdm, qm_obs, qdm_obs):  # pragma: no cover - compiled
    for i in range(qm.shape[0]):
        measure_sample(
            ts.q, ts.qd, ts.held_q, ts.held_qd, ts.n_dropped, io.res, io.std, io.quantize_encoder, i,
            noise[i], lost[i], qm[i], qdm[i], qm_obs[i], qdm_obs[i],
        )  # fmt: skip


def measure_batch(io, ts, noise, lost) -> tuple:
    """Step 1 for every trial: ``noise (S, 2 n)``, ``lost (S,)`` -> ``qm, qdm, qm_obs, qdm_obs (S, n)``."""
    S, n = ts.q.shape
    qm, qdm, qm_obs, qdm_obs = (np.empty((S, n)) for _ in range(4))
    _measure_loop(io, ts, np.ascontiguousarray(noise), np.ascontiguousarray(lost), qm, qdm, qm_obs, qdm_obs)
    return qm, qdm, qm_obs, qdm_obs


@njit(cache=True)
def _apply_loop(rc, io, pl, ts, acc, rec, k, cmd, tau):  # pragma: no cover - compiled
    s = segment_of(rc, k)
    n = cmd.shape[1]
    pw, e, prev = plant_work(pl, n), np.empty(n), np.empty(n)  # one per call: trials one after another
    tw, tr = np.zeros((max(rc.ee_index.shape[0], 1), 12)), np.zeros(9)
    for i in range(cmd.shape[0]):
        mask = apply_sample(
            rc.T, rc.max_error, rc.max_speed, rc.q_d, io.lim, io.lsb, io.saturate,
            io.quantize_dac, pl, pw, ts.q, ts.qd, ts.stuck, ts.failed, ts.failed_at, ts.failed_cmd, rec.q,
            rec.qd, rec.tau, rec.saturated, i, k, cmd[i], tau[i], e, prev, s,
        )  # fmt: skip
        accumulate_sample(
            acc.sum_e2, acc.sum_e2_joint, acc.max_e, acc.sum_tau2, acc.n_saturated, acc.first_saturated,
            acc.sum_e2_settled, acc.e_norm, rc.seg_settled, i, s, k, e, tau[i], mask,
        )  # fmt: skip
        accumulate_tool(
            rc.ee_index, rc.ee_links, rc.ee_ref, acc.ee_sum_p2, acc.ee_max_p, acc.ee_sum_th2, i, s, k, prev,
            tw, tr,
        )  # fmt: skip
    return s


_chain_apply_loop = njit(cache=True)(
    _named(
        _bound(_apply_loop.py_func, apply_sample=_chain_apply_sample, plant_work=_chain_plant_work),
        "_chain_apply_loop",
    )
)
""":func:`_apply_loop` of an N-joint arm (:class:`~adaptive_dd.closed_loop.types.Plant`), its choices
called by name as in :data:`_chain_trial_samples`: through the overloads, numba compiled the plant
step's choice in full to type it and threw it away (about 4.6 CPU s on the UR5)."""


def apply_batch(rc, io, pl, ts, acc, rec, k: int, cmd) -> tuple[NDArray[np.float64], int]:
    """Step 3 for every trial; ``cmd (S, n)`` (copied); returns the applied torque ``(S, n)`` and
    the segment of sample k."""
    cmd = np.array(cmd, dtype=float, order="C")
    tau = np.empty_like(cmd)
    loop = _chain_apply_loop if isinstance(pl, Plant) else _apply_loop
    s = loop(rc, io, pl, ts, acc, rec, k, cmd, tau)
    return tau, int(s)


@njit(cache=True)
def _sigma_loop(rc, rec, k, s, sigma):  # pragma: no cover - compiled
    for i in range(sigma.shape[0]):
        record_estimate(rc.seg_end, rec.sigma_end, rec.sigma, i, k, s, sigma[i])


def sigma_batch(rc, rec, k: int, s: int, sigma) -> None:
    """Record every trial's estimate ``sigma (S, p)`` (see :func:`record_estimate`)."""
    _sigma_loop(rc, rec, k, s, np.array(sigma, dtype=float, order="C"))  # writable: one compiled type


@njit(cache=True)
def _estimator_loop(ec, es, ls, qm_obs, qdm_obs, tau, alarm):  # pragma: no cover - compiled
    ew = estimator_work(ec, es)  # one per call: trials run one after the other here
    for i in range(tau.shape[0]):
        alarm[i] = estimator_sample(ec, es, ls, i, qm_obs[i], qdm_obs[i], tau[i], ew)


_chain_estimator_loop = njit(cache=True)(
    _named(
        _bound(
            _estimator_loop.py_func,
            estimator_work=_chain_estimator_work,
            estimator_sample=_chain_estimator_sample,
        ),
        "_chain_estimator_loop",
    )
)
""":func:`_estimator_loop` of an N-joint arm's estimator (a :class:`ChainEstimator`), its choices
called by name: through the overloads, numba compiled the estimator's choice in full to type it
(linking the estimator's step) and threw it away (about 6.6 CPU s on the UR5)."""


def estimator_batch(ec, es, ls, qm_obs, qdm_obs, tau) -> NDArray[np.int64]:
    """:func:`estimator_sample` for every trial ``(S, n)``; returns the alarms ``(S,)`` (1: alarm)."""
    alarm = np.zeros(tau.shape[0], dtype=np.int64)
    c = np.ascontiguousarray
    loop = _estimator_loop
    if isinstance(ec, EstCfg):
        ec, loop = ChainEstimator(ec, True), _chain_estimator_loop
    elif isinstance(ec, ChainEstimator):
        loop = _chain_estimator_loop
    loop(ec, es, ls, c(qm_obs), c(qdm_obs), c(tau), alarm)
    return alarm


def shaped_inputs(n: int, S: int, q, qd, q_d, qd_d, qdd_d) -> tuple:
    """The Python form's inputs as the compiled law takes them: ``q, qd (S, n)`` (or the first
    trials' rows) and the reference
    ``(n,)`` (one row of a batch, ``(1, n)``, as the two-link classes take it, too); else a
    :class:`~adaptive_dd.errors.SignalError` naming the shapes (numba's typing error said nothing)."""
    from adaptive_dd.errors import SignalError

    q, qd = (np.ascontiguousarray(x, dtype=float) for x in (q, qd))
    refs = [np.asarray(x, dtype=float) for x in (q_d, qd_d, qdd_d)]
    refs = [np.ascontiguousarray(r[0] if r.shape == (1, n) else r) for r in refs]
    rows_ok = q.ndim == 2 and 1 <= q.shape[0] <= S and q.shape[1] == n and qd.shape == q.shape
    if not rows_ok or any(r.shape != (n,) for r in refs):
        raise SignalError(
            f"command: q and qd must be (n_trials, n) = ({S}, {n}) (the first trials: fewer rows) and "
            f"q_d, qd_d, qdd_d the reference ({n},) (or (1, {n})), got {q.shape}, {qd.shape}, "
            + ", ".join(str(r.shape) for r in refs)
        )
    return q, qd, *refs
