"""The paper's two-link arm as the closed loop's compile-time choices: its plant, laws and estimator.

The per-sample glue is the closed loop's, written once for every arm
(:mod:`adaptive_dd.closed_loop.glue`: measurement with drop-out hold, the divergence rule,
actuation, the runaway rule, the failure freeze, streamed sums, recordings, alarms). This module
adds the records of the two-link arm and the overloads that choose, by their type, what is
genuinely two-link:

* :class:`TwoLinkPlant`: the closed-form plant (:func:`adaptive_dd.plant.two_link_integrator.step_one`,
  stick-slip, smooth or LuGre friction on the paper's sigma);
* :class:`~adaptive_dd.controllers.compiled_form.TwoLinkGains`: the built-in two-link laws
  (:func:`~adaptive_dd.controllers.compiled_form.command_trial`, one dispatch on the law inside:
  the sample loop is compiled once for every law); their state is the estimator's
  :class:`~adaptive_dd.identification.two_link_online.OnlineState` (``adaptive_ct`` controls
  with its model, Slotine-Li adapts its ``theta``);
* :class:`OnlineKernelConfig`: the paper's estimator
  (:func:`~adaptive_dd.identification.two_link_online_kernel.online_step_trial`, sigma7 with the
  paper's splits), stepped when ``active``.

A controller spec says which law, with which gains and model (each built-in's
``compiled_spec`` method: :func:`~adaptive_dd.controllers.compiled_form.compiled_spec`);
plug-in controllers have none and run on the Python path.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba.extending import overload
from numpy.typing import NDArray

from adaptive_dd.closed_loop.glue import (
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
from adaptive_dd.closed_loop.laws import observe_applied
from adaptive_dd.controllers.compiled_form import (
    LAW_ADAPTIVE,
    LAW_SLOTINE,
    TwoLinkGains,
    boost_command,
    command_trial,
)
from adaptive_dd.identification.two_link_online import OnlineState
from adaptive_dd.identification.two_link_online_kernel import C_SINCE_ALARM, online_step_trial
from adaptive_dd.plant.two_link_integrator import step_one

__all__ = ["OnlineKernelConfig", "TwoLinkPlant"]

Array = NDArray[np.float64]


class OnlineKernelConfig(NamedTuple):
    """:attr:`TwoLinkOnlineConfig.packed
    <adaptive_dd.identification.two_link_online_config.TwoLinkOnlineConfig.packed>` by name: ``ci, cf``
    integer and float settings, ``A, B, C, D`` the derivative filters' state space,
    ``d`` payload direction, ``group`` parameter groups, ``split_rows (2,)``; ``active``: the
    estimator runs (``adaptive_ct``; the other laws carry an unused one, so that the sample loop
    is compiled once for every law)."""

    ci: NDArray[np.int64]
    cf: Array
    A: Array
    B: Array
    C: Array
    D: Array
    d: Array
    group: NDArray[np.int64]
    split_rows: NDArray[np.int64]
    active: bool


class TwoLinkPlant(NamedTuple):
    """The two-link plant of a run (:func:`adaptive_dd.plant.two_link_integrator.step_one`).

    ``sigma_seg (G, 7)`` true base parameters in each payload segment; ``substeps`` RK4
    substeps per sample; ``friction_code`` (:attr:`TwoLinkArm.friction_code
    <adaptive_dd.plant.two_link.TwoLinkArm.friction_code>`); ``fparams``
    :func:`~adaptive_dd.plant.two_link_integrator.friction_vector` of the arm (friction velocity,
    Stribeck ratio and velocity, LuGre sigma0 (2), sigma1 (2)); the plant's own per-trial state:
    ``slip (S, 2)`` stick-slip state, ``z (S, 2)`` LuGre bristle state.
    """

    sigma_seg: Array
    substeps: int
    friction_code: int
    fparams: Array
    slip: Array
    z: Array


def _is(typ, cls) -> bool:
    return getattr(typ, "instance_class", None) is cls


@overload(plant_work)
def _plant_work(pl, n):
    if _is(pl, TwoLinkPlant):
        return lambda pl, n: np.empty(0)


@overload(plant_joints, inline="always")
def _plant_joints(pl, q):
    if _is(pl, TwoLinkPlant):
        return lambda pl, q: 2


@overload(plant_advance, inline="always")
def _plant_advance(pl, i, s, q, qd, stuck, tau, T, pw):
    if _is(pl, TwoLinkPlant):

        def impl(pl, i, s, q, qd, stuck, tau, T, pw):  # pragma: no cover - compiled
            step_one(
                q,
                qd,
                stuck,
                pl.slip,
                pl.z,
                i,
                tau,
                pl.sigma_seg[s],
                T,
                pl.substeps,
                pl.friction_code,
                pl.fparams,
            )

        return impl


@overload(law_work_of)
def _law_work_of(law, n):
    if _is(law, TwoLinkGains):
        from adaptive_dd.controllers.two_link_observer import observer_work  # here: import cycle

        return lambda law, n: observer_work()


@overload(law_command, inline="always")
def _law_command(law, ls, pl, i, s, T, q, qd, q_d, qd_d, qdd_d, lw, out):
    if _is(law, TwoLinkGains) and _is(ls, OnlineState):
        from adaptive_dd.controllers.two_link_observer import observe_trial  # here: import cycle

        def impl(law, ls, pl, i, s, T, q, qd, q_d, qd_d, qdd_d, lw, out):  # pragma: no cover - compiled
            model = ls.theta[i] if law.law == LAW_SLOTINE else ls.sigma_model[i]
            since_alarm = ls.cnt[i, C_SINCE_ALARM]
            command_trial(law, T, pl.sigma_seg[s], model, since_alarm, q, qd, q_d, qd_d, qdd_d, out)
            if law.observer and law.law == LAW_ADAPTIVE:  # the residual observer (two_link_observer)
                observe_trial(0, law, model, q, qd, ls.obs[i], lw, out)
            boost_command(law, since_alarm, q, qd, q_d, qd_d, out)  # adaptive_ct's, within the limits

        return impl


@overload(law_delay, inline="always")
def _law_delay(law):
    if _is(law, TwoLinkGains):
        return lambda law: law.model_delay


@overload(law_estimate)
def _law_estimate(law, ls, i, lw, out):
    if _is(law, TwoLinkGains) and _is(ls, OnlineState):
        return lambda law, ls, i, lw, out: ls.theta[i]


@overload(estimator_work)
def _estimator_work(ec, es):
    if _is(ec, OnlineKernelConfig):
        return lambda ec, es: np.empty(2)


@overload(estimator_sample, inline="always")
def _estimator_sample(ec, es, ls, i, q, qd, tau, ew):
    if _is(ec, OnlineKernelConfig):

        def impl(ec, es, ls, i, q, qd, tau, ew):  # pragma: no cover - compiled
            if not ec.active:
                return 0
            alarm = online_step_trial(
                i, es.xf, es.u_last, es.cnt, es.tau_prev, es.theta, es.P, es.lam, es.short, es.long,
                es.sigma_model, q, qd, tau, ec.ci, ec.cf, ec.A, ec.B, ec.C, ec.D, ec.d, ec.group,
                ec.split_rows, ew,
            )  # fmt: skip
            observe_applied(es.obs[i], tau)  # the residual observer's applied torque
            return alarm

        return impl
