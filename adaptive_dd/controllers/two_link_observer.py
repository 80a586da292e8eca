"""The two-link ``adaptive_ct``'s residual observer: the N-joint observer's own code, on the paper's sigma.

One definition for every arm (issue 27: the same controller name means the same thing on every
arm): :func:`observe_trial` is :func:`adaptive_dd.closed_loop.residual_observer._observe` itself (De Luca's
generalised-momentum observer in two stages, its output soft-thresholded at ``obs_kappa`` times
its own learnt RMS level and added to the command; ``docs/change_detection.md``, "The residual
observer"), compiled with the momentum of the paper's closed forms (:func:`momentum_two_link`) in
place of the chain's. The settings are the N-joint defaults (``0.4 / T``, 3x, a 1 s level, 0.5 s
of learning: :mod:`adaptive_dd.closed_loop.controllers`); the applied torques are summed by
:func:`~adaptive_dd.closed_loop.residual_observer.observe_applied`, as on an N-joint arm.

The state is :attr:`OnlineState.obs <adaptive_dd.identification.two_link_online.OnlineState>`
``(S, OBS_ROWS, 2)``: the law's model is the estimator's ``sigma_model``, so the residual is
what the *current* estimate leaves unexplained and fades as it learns the payload.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.closed_loop.glue import _bound
from adaptive_dd.closed_loop.residual_observer import _observe, observe_applied
from adaptive_dd.identification.two_link_momentum_test import momentum_two_link

__all__ = [
    "momentum_two_link",
    "observe_applied_batch",
    "observe_batch",
    "observe_trial",
    "observer_work",
]


observe_trial = njit(inline="always")(_bound(_observe.py_func, _momentum=momentum_two_link))
"""``observe_trial(0, cfg, sigma (7,), q, qd, obs (OBS_ROWS, 2), work, out (2,))``: one sample of
the N-joint residual observer (:func:`adaptive_dd.closed_loop.residual_observer._observe`, its code unchanged)
on the two-link model; ``cfg`` has the fields ``T, obs_a, obs_stages, obs_kappa, obs_alpha,
obs_warmup`` (:class:`~adaptive_dd.controllers.compiled_form.TwoLinkGains`), ``work``
:func:`observer_work`."""


@njit(cache=True)
def observer_work():  # pragma: no cover - compiled
    """Scratch of :func:`observe_trial`: the chain law's work tuple, of which the observer reads
    only ``[7]`` (the momenta and ``wv`` at the last and this measurement, ``(4, 2)``)."""
    e = np.empty(0)
    return (e, e, e, e, e, e, e, np.empty((4, 2)))


@njit(cache=True)
def _observe_loop(g, sg, q, qd, obs, out):  # pragma: no cover - compiled
    work = observer_work()
    for i in range(q.shape[0]):
        observe_trial(0, g, sg[i], q[i], qd[i], obs[i], work, out[i])


def observe_batch(g, sigma_model, q, qd, obs, tau):
    """``tau (S, 2)`` plus the observer's torque of every trial (the Python path's form of what the
    compiled loop does per trial); ``obs (S, OBS_ROWS, 2)`` updated in place. ``g`` a
    :class:`~adaptive_dd.controllers.compiled_form.TwoLinkGains`."""
    out = np.array(tau, dtype=float, order="C", copy=True)

    # writable C copies: one compiled type, whether the caller's arrays are read-only or not
    sg, q, qd = (np.array(x, dtype=float, order="C") for x in (sigma_model, q, qd))
    _observe_loop(g, sg, q, qd, obs, out)
    return out


@njit(cache=True)
def _applied_loop(obs, tau):  # pragma: no cover - compiled
    for i in range(tau.shape[0]):
        observe_applied(obs[i], tau[i])


def observe_applied_batch(obs, tau) -> None:
    """:func:`~adaptive_dd.closed_loop.residual_observer.observe_applied` for every trial: ``tau (S, 2)``
    applied over the last sample added to ``obs (S, OBS_ROWS, 2)``."""
    _applied_loop(obs, np.ascontiguousarray(tau, dtype=float))
