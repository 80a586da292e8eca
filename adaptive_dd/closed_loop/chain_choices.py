"""The N-joint arm's choices in the closed loop: its plant, its built-in laws and its estimator.

The implementations of :mod:`adaptive_dd.closed_loop.choices` for an N-joint arm
(:class:`~adaptive_dd.closed_loop.types.Plant`, :class:`ChainLaw`, no estimator,
:class:`ChainEstimator` or :class:`~adaptive_dd.identification.online_kernel.EstCfg`): the
``_chain_*`` functions, which the N-joint loop of :mod:`adaptive_dd.closed_loop.glue` calls by
name, and the overloads that give them to the Python path's loops, which choose by type; the
estimator's sample (:func:`online_sample`) and the records' builders (:func:`chain_law`,
:func:`chain_estimator`). All public names are importable from :mod:`adaptive_dd.closed_loop.glue`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import overload
from numpy.typing import NDArray

from adaptive_dd.closed_loop.choices import (
    _is,
    estimator_sample,
    estimator_work,
    law_command,
    law_delay,
    law_estimate,
    law_work_of,
    plant_advance,
    plant_joints,
    plant_work,
)
from adaptive_dd.closed_loop.laws import (
    OBS_ROWS,
    LawConfig,
    LawState,
    law_trial_in,
    law_work,
    observe_applied,
)
from adaptive_dd.closed_loop.plant import plant_scratch, plant_step
from adaptive_dd.closed_loop.types import Plant
from adaptive_dd.identification.online_kernel import (
    EstCfg,
    est_step_model,
    est_work,
)

__all__ = [
    "ChainEstimator",
    "ChainLaw",
    "chain_estimator",
    "chain_law",
    "compile_estimator",
    "online_sample",
]

Array = NDArray[np.float64]


class ChainLaw(NamedTuple):
    """An N-joint built-in law as the loop takes it: ``cfg`` its
    :class:`~adaptive_dd.closed_loop.laws.LawConfig`, ``pi_true (S, G, 13 n)`` each trial's
    true model per segment (what the oracles are given), ``B (p, 13 n)`` standard -> base
    parameters (the recorded estimate is ``B pi_model``), ``cols, count`` B's nonzero columns
    per row (:func:`chain_law`)."""

    cfg: LawConfig
    pi_true: Array
    B: Array
    cols: NDArray[np.int64]
    count: NDArray[np.int64]


class ChainEstimator(NamedTuple):
    """The N-joint compiled loop's estimator: ``cfg`` an
    :class:`~adaptive_dd.identification.online_kernel.EstCfg`, ``active`` whether it runs
    (``adaptive_ct``). The other laws carry an inactive one of the same arm, so that the sample
    loop, whose type is that of its arguments, is compiled once for every law (as the two-link
    arm's ``OnlineKernelConfig.active``; :func:`chain_estimator`)."""

    cfg: EstCfg
    active: bool


# The N-joint arm's choices, as functions inlined where they are called (the loop of an N-joint
# arm calls them by name, :data:`_chain_trial_samples`); the overloads below give them to the
# Python path's loops, which choose by type.
@njit(cache=True, inline="always")
def _chain_plant_work(pl, n):  # pragma: no cover - compiled
    return plant_scratch(n)


@njit(cache=True, inline="always")
def _chain_plant_joints(pl, q):  # pragma: no cover - compiled
    return q.shape[1]


@njit(cache=True, inline="always")
def _chain_plant_advance(pl, i, s, q, qd, stuck, tau, T, pw):  # pragma: no cover - compiled
    return plant_step(pl, i, s, q[i], qd[i], tau, T, stuck[i], pw)


@njit(cache=True, inline="always")
def _chain_law_work(law, n):  # pragma: no cover - compiled
    return law_work(n)


@njit(cache=True, inline="always")
def _chain_law_command(law, ls, pl, i, s, T, q, qd, q_d, qd_d, qdd_d, lw, out):  # pragma: no cover
    law_trial_in(
        pl.chain, law.cfg, law.pi_true[i, s], ls.pi_model[i], ls.theta[i], ls.since_alarm[i],
        ls.obs[i], q, qd, q_d, qd_d, qdd_d, lw, out,
    )  # fmt: skip


@njit(cache=True, inline="always")
def _chain_law_delay(law):  # pragma: no cover - compiled
    return law.cfg.model_delay


@njit(cache=True, inline="always")
def _chain_law_estimate(law, ls, i, lw, out):  # pragma: no cover - compiled
    _sigma_of(law.B, law.cols, law.count, ls.pi_model[i], out)
    return out


@njit(cache=True, inline="always")
def _chain_estimator_work(ec, es):  # pragma: no cover - compiled
    return est_work(ec.cfg.w.shape[0], es.theta.shape[1])


@njit(cache=True, inline="always")
def _chain_estimator_sample(ec, es, ls, i, q, qd, tau, ew):  # pragma: no cover - compiled
    if not ec.active:
        ls.since_alarm[i] += 1
        observe_applied(ls.obs[i], tau)  # the residual observer of a law without an estimator
        return 0
    return online_sample(ec.cfg, es, ls, i, q, qd, tau, ew)


@overload(plant_work)
def _plant_work(pl, n):
    if _is(pl, Plant):
        return _chain_plant_work.py_func


@overload(plant_joints, inline="always")
def _plant_joints(pl, q):
    if _is(pl, Plant):
        return _chain_plant_joints.py_func


@overload(plant_advance, inline="always")
def _plant_advance(pl, i, s, q, qd, stuck, tau, T, pw):
    if _is(pl, Plant):
        return _chain_plant_advance.py_func


@overload(law_work_of)
def _law_work_of(law, n):
    if _is(law, ChainLaw):
        return _chain_law_work.py_func


@overload(law_command, inline="always")
def _law_command(law, ls, pl, i, s, T, q, qd, q_d, qd_d, qdd_d, lw, out):
    if _is(law, ChainLaw):
        return _chain_law_command.py_func


@overload(law_delay, inline="always")
def _law_delay(law):
    if _is(law, ChainLaw):
        return _chain_law_delay.py_func


@overload(law_estimate)
def _law_estimate(law, ls, i, lw, out):
    if _is(law, ChainLaw):
        return _chain_law_estimate.py_func


@overload(estimator_work)
def _estimator_work(ec, es):
    if isinstance(ec, types.Array):
        return lambda ec, es: np.empty(0)
    if _is(ec, EstCfg):
        return lambda ec, es: est_work(ec.w.shape[0], es.theta.shape[1])
    if _is(ec, ChainEstimator):
        return _chain_estimator_work.py_func


@overload(estimator_sample, inline="always")
def _estimator_sample(ec, es, ls, i, q, qd, tau, ew):
    if isinstance(ec, types.Array):

        def none(ec, es, ls, i, q, qd, tau, ew):  # pragma: no cover - compiled
            ls.since_alarm[i] += 1
            observe_applied(ls.obs[i], tau)  # as the compiled loop's inactive estimator
            return 0

        return none
    if _is(ec, EstCfg):
        return lambda ec, es, ls, i, q, qd, tau, ew: online_sample(ec, es, ls, i, q, qd, tau, ew)
    if _is(ec, ChainEstimator):
        return _chain_estimator_sample.py_func


@njit(cache=True, inline="always")
def online_sample(ec, es, ls, i, q, qd, tau, ew):  # pragma: no cover - compiled
    """One sample of trial i of the N-joint online estimator ``ec, es``
    (:func:`~adaptive_dd.identification.online_kernel.est_step_trial_in`): 1 on an alarm, else
    0; the law's model (``ls.pi_model[i]``) and its count of samples since the last alarm
    updated. Inlined where it is called (both paths); the step and the model are one compiled
    function, :func:`~adaptive_dd.identification.online_kernel.est_step_model`, the same that the
    estimator run alone calls (one compilation of the step for both), which a cold-cache benchmark
    compiles first while a second process compiles the plant and the law (:func:`compile_estimator`)."""
    alarm = est_step_model(ec, es, i, q, qd, tau, ew, ls.pi_model[i])
    if alarm == 1:
        ls.since_alarm[i] = 0
    else:
        ls.since_alarm[i] += 1
    observe_applied(ls.obs[i], tau)
    return alarm


def compile_estimator(arm) -> None:
    """Compile the estimator's step (:func:`~adaptive_dd.identification.online_kernel.est_step_model`)
    for the records of ``arm`` (the argument types the closed loop calls it with), without running it."""
    from numba import typeof

    ec, es = chain_estimator(np.zeros(1), np.zeros(1), arm, 1e-3)
    n = arm.n_joints
    ls = LawState(
        np.zeros((1, 13 * n)), np.zeros((1, 10)), np.zeros(1, dtype=np.int64), np.zeros((1, OBS_ROWS, n))
    )
    v, ew = np.zeros(n), est_work(n, es.theta.shape[1])
    args = (ec.cfg, es, 0, v, v, v, ew, ls.pi_model[0])
    est_step_model.compile(tuple(typeof(a) for a in args))


def chain_estimator(ec, es, arm, sample_period: float) -> tuple[ChainEstimator, object]:
    """``(ChainEstimator, state)`` the compiled loop takes for a law's estimator ``ec, es``: itself,
    active, when it is an :class:`~adaptive_dd.identification.online_kernel.EstCfg`; else (no
    estimator) an inactive one of ``arm`` with the state of one trial (never stepped)."""
    if isinstance(ec, EstCfg):
        return ChainEstimator(ec, True), es
    from adaptive_dd.identification import online

    cfg, state = online.est_init(online.OnlineConfig(sample_period=sample_period), arm, 1)
    return ChainEstimator(cfg, False), state


@njit(cache=True)
def _nonzero_columns(B):  # pragma: no cover - compiled
    """Per row of ``B (p, m)``: its nonzero columns in order, ``cols (p, m)`` and their count ``(p,)``."""
    p, m = B.shape
    cols = np.empty((p, m), dtype=np.int64)
    count = np.zeros(p, dtype=np.int64)
    for r in range(p):
        for c in range(m):
            if B[r, c] != 0.0:
                cols[r, count[r]] = c
                count[r] += 1
    return cols, count


def chain_law(cfg: LawConfig, pi_true: Array, B: Array) -> ChainLaw:
    """:class:`ChainLaw` of an N-joint law ``cfg``, the trials' true models and the arm's ``B``."""
    B = np.ascontiguousarray(B, dtype=float)
    cols, count = _nonzero_columns(B)
    return ChainLaw(cfg, np.ascontiguousarray(pi_true, dtype=float), B, cols, count)


@njit(cache=True)
def _sigma_of(B, cols, count, pi, out):  # pragma: no cover - compiled
    """``out = B pi`` over B's nonzero entries (the same sums in the same order as the dense
    product: a skipped term ``0 * pi_c`` adds exactly zero for a finite ``pi``); a non-finite
    ``pi`` falls back to the dense product so that NaN spreads as it would."""
    finite = True
    for c in range(pi.shape[0]):
        if not np.isfinite(pi[c]):
            finite = False
    for r in range(B.shape[0]):
        acc = 0.0
        if finite:
            for t in range(count[r]):
                c = cols[r, t]
                acc += B[r, c] * pi[c]
        else:
            for c in range(B.shape[1]):
                acc += B[r, c] * pi[c]
        out[r] = acc
