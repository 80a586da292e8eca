"""A shared record for the residual observer's tests: adaptive_ct's law alone (no estimator, no
alarm from any detector) driven sample by sample on sinusoids of the vertical arm, the applied
torque the true arm's inverse dynamics (``tests/test_residual_observer.py``,
``tests/test_momentum_test.py``)."""

from __future__ import annotations

import numpy as np

from adaptive_dd.closed_loop.laws import LawState, law_trial, model_torque, observe_applied
from adaptive_dd.closed_loop.residual_observer import O_TRIP


def law_on_sines(cfg, arm, seed, N, T, sigma_v, w, k_swap, pi_after, step=None) -> np.ndarray:
    """The law of ``cfg`` over ``N`` samples of ``q = q0 + 0.4 sin(w t)`` (``w (3,)`` [rad/s]), the
    measured velocity with white noise ``sigma_v`` (generator ``seed``); the law's model is
    ``arm.pi``, the arm's from sample ``k_swap`` on ``pi_after``, and from there the observer is
    told ``step (n,)`` [N m] less than the arm gets. Per sample: the observer's samples since it
    started the boost (0: started at that sample)."""
    n = arm.n_joints
    rng = np.random.default_rng(seed)
    t = np.arange(N + 1) * T
    w = np.asarray(w, dtype=float)
    q = np.array([0.3, -0.6, 0.4]) + 0.4 * np.sin(np.outer(t, w))
    qd = 0.4 * w * np.cos(np.outer(t, w))
    qdd = -0.4 * w**2 * np.sin(np.outer(t, w))
    st = LawState.start(cfg, 1)
    obs, pi_model, theta = st.obs[0], arm.pi.copy(), np.zeros(10)
    z, out, tau = np.zeros(n), np.empty(n), np.empty((2, n))
    since = np.empty(N, dtype=np.int64)
    for k in range(N):
        qd_m = qd[k] + sigma_v * rng.standard_normal(n)
        law_trial(arm.chain, cfg, pi_model, pi_model, theta, 1 << 40, obs, q[k], qd_m, q[k], qd[k], z, out)
        since[k] = min(obs[O_TRIP, 0], 1 << 40)
        for i in (0, 1):  # the torque over the sample: the mean of its ends' inverse dynamics
            pi = pi_after if k + i >= k_swap else arm.pi
            model_torque(arm.chain, pi, q[k + i], qd[k + i], qd[k + i], qd[k + i], qdd[k + i], tau[i])
        told = tau.mean(0)
        if step is not None and k >= k_swap:
            told = told - step  # the arm gets step more than the observer is told
        observe_applied(obs, told)
    return since
