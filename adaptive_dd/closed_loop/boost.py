"""``adaptive_ct``'s boost bandwidth per joint, from the torque the task leaves and the sensors' noise.

After an alarm the N-joint ``adaptive_ct`` adds ``M0(q) (dkp e + dkd e')`` to its command
(``dkp = wb^2 - w^2``, ``dkd = 2 zeta (wb - w)``; :mod:`adaptive_dd.closed_loop.laws`). The
measured ``e`` and ``e'`` carry the sensors' noise, so the added torque carries

    std_j(t) = sqrt( sum_l M0_jl(q(t))^2 (dkp_l^2 var_q,l + dkd_l^2 var_qd,l) )

of it on joint ``j``, which grows as ``wb^2``: at 300 rad/s and the benchmark's default noise it
is a few N m on a drawn arm's shoulder, as large as the torque its limit leaves beside the
reference's, and the command saturated on a few per cent of each loaded segment after its alarm.
The bandwidth of each joint is therefore the largest, up to ``boost_bandwidth``, for which that
noise stays :data:`NOISE_SIGMAS` standard deviations inside the room the torque limit leaves
beside the reference's own torque (inverse dynamics with each segment's payload) at every
instant of the reference: ``NOISE_SIGMAS std_j(t) <= limit_j - |tau_ref,j(t)|``. A joint
with no room keeps the law's own bandwidth (no boost). Without a task (a controller built with
no scenario) the boost is ``boost_bandwidth`` on every joint.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "NOISE_SIGMAS",
    "boost_bandwidths",
    "detection_horizon",
    "observer_bandwidth_for",
    "observer_noise_gain",
    "observer_task",
    "task_room",
]

Array = NDArray[np.float64]

NOISE_SIGMAS = 3.0
"""Standard deviations of the boost's noise torque kept inside the room (the residual observer's
threshold is the same three)."""

ROOM_STEP = 0.01
"""[s] between the reference's instants at which the room is taken."""


def task_room(scenario) -> tuple[Array, Array]:
    """``(q (K, n), room (K, n))``: the reference's positions every :data:`ROOM_STEP` and the
    torque each joint's limit leaves beside the reference's inverse dynamics there, the largest
    over the scenario's payload segments (``limit - max |tau|``, negative where none is left)."""
    arm = scenario.arm
    step = max(1, round(ROOM_STEP / scenario.sample_period))
    t = np.arange(0, scenario.n_samples, step) * scenario.sample_period
    q, qd, qdd = scenario.reference.sample(t)
    Y = arm.regressor(q, qd, qdd)  # (K, n, p)
    tau = np.abs(np.einsum("knp,sp->skn", Y, scenario.segment_sigmas())).max(axis=0)
    limit = np.asarray(arm.actuator.torque_limit, dtype=float)
    return np.asarray(q, dtype=float), limit[None, :] - tau


def boost_bandwidths(
    cap: float,
    bandwidth: Array,
    damping: float,
    inertia: Array,
    room: Array,
    position_variance: Array,
    velocity_variance: Array,
) -> Array:
    """Per joint, the boost's bandwidth [rad/s] (module docstring): at most ``cap``, at least the
    law's ``bandwidth (n,)``; ``inertia (K, n, n)`` the nominal ``M0`` at the task's instants and
    ``room (K, n)`` the torque left there [N m]; the sensors' variances ``(n,)``.

    Columns that feed a row whose noise is beyond its room are lowered together, 2 % of their
    added bandwidth a step, until every row is inside; a column feeding a row with no room at all
    (the reference alone needs the limit) gets no boost.
    """
    w = np.broadcast_to(np.asarray(bandwidth, dtype=float), room.shape[1:]).copy()
    wb = np.maximum(np.full_like(w, float(cap)), w)
    vq, vv = np.asarray(position_variance, dtype=float), np.asarray(velocity_variance, dtype=float)
    M2 = np.asarray(inertia, dtype=float) ** 2
    room = np.asarray(room, dtype=float)
    for _ in range(1000):
        dkp, dkd = wb**2 - w**2, 2.0 * damping * (wb - w)
        part = M2 * (dkp**2 * vq + dkd**2 * vv)[None, None, :]  # (K, n rows, n columns)
        over = NOISE_SIGMAS * np.sqrt(part.sum(axis=2)) > room  # (K, n): rows beyond their room
        if not over.any():
            break
        # the columns that carry at least a tenth of an offending row's noise variance
        share = part / np.maximum(part.sum(axis=2, keepdims=True), 1e-300)
        feeds = (share >= 0.1) & over[:, :, None]
        lower = feeds.any(axis=(0, 1)) & (wb > w)
        if not lower.any():
            break
        none_left = (feeds & (room <= 0.0)[:, :, None]).any(axis=(0, 1))
        wb = np.where(lower, w + 0.98 * (wb - w), wb)
        wb = np.where(none_left | (wb - w < 1e-3 * w), w, wb)
    return wb


def observer_noise_gain(beta: float, sample_period: float) -> float:
    """``sum_k h_k^2 / T^2`` of the residual observer's path from the measured velocity to ``r``:
    the momentum's difference over a sample ``(1 - z^-1) / T`` through its two stages
    ``((1 - a) / (1 - a z^-1))^2``, ``a = exp(-beta T)``. Times ``sum_l M_jl^2 var_qd,l`` it is
    the variance of joint j's ``r`` from the velocity noise (the level the observer learns)."""
    T = float(sample_period)
    a = float(np.exp(-beta * T))
    k = np.arange(int(np.ceil(60.0 / max(beta * T, 1e-9))) + 2)
    s = (1.0 - a) ** 2 * (k + 1) * a**k  # the two stages' impulse response
    h = s - np.concatenate([[0.0], s[:-1]])  # times (1 - z^-1)
    return float(np.sum(h**2) / T**2)


def observer_bandwidth_for(
    cap: float,
    bandwidth: Array,
    damping: float,
    inertia: Array,
    load: Array,
    velocity_variance: Array,
    horizon: int,
    sample_period: float,
) -> float:
    """The residual observer's bandwidth [rad/s] (module :func:`observer_bandwidth_for` docstring
    in ``docs/change_detection.md``): the one of ``OBSERVER_GRID`` bandwidths from the law's own
    bandwidth up to ``cap`` that minimises the tracking error a step of the rated payload's torque
    leaves over the ``horizon`` samples before the detector can see it.

    At each of the task's instants (``inertia (K, n, n)``, ``load (K, n)`` the rated payload's
    gravity torque there) the step ``d`` is passed by the observer as ``soft(d s(t), 3 sigma)``
    (``s`` its two stages' step response, ``sigma`` the velocity noise's RMS in ``r``,
    :func:`observer_noise_gain`: the threshold the observer learns); what it does not pass drives
    the law's error dynamics ``e'' + 2 zeta w e' + w^2 e = M^-1 u``. A higher bandwidth passes the
    step sooner but holds back more of it behind its threshold, which grows as ``bandwidth^1.5``.
    """
    T = float(sample_period)
    w = np.broadcast_to(np.asarray(bandwidth, dtype=float), load.shape[1:])
    M = np.asarray(inertia, dtype=float)
    Minv = np.linalg.inv(M)
    noise = np.sqrt(np.einsum("kjl,l->kj", M**2, np.asarray(velocity_variance, dtype=float)))
    # swaps of every size up to the rated payload, equally likely: its torque times SIZES
    d = np.asarray(load, dtype=float)[None] * ((np.arange(SIZES) + 0.5) / SIZES)[:, None, None]
    M, Minv, noise = (np.broadcast_to(x[None], d.shape[:1] + x.shape) for x in (M, Minv, noise))
    H = max(int(horizon), 1)
    grid = np.geomspace(max(float(np.max(w)), 1.0), float(cap), OBSERVER_GRID)
    cost = np.empty(grid.shape)
    for g, beta in enumerate(grid):
        a = np.exp(-beta * T)
        k = np.arange(1, H + 1)
        s = 1.0 - a**k - k * (1.0 - a) * a**k  # the two stages' step response (k samples)
        thr = 3.0 * noise * np.sqrt(observer_noise_gain(beta, T))  # (K, n)
        passed = np.sign(d)[None] * np.maximum(np.abs(d)[None] * s[:, None, None, None] - thr[None], 0.0)
        u = d[None] - passed  # (H, K, n) the torque left to the feedback
        acc = np.einsum("mkjl,hmkl->hmkj", Minv, u)
        e = np.zeros(d.shape)
        ed = np.zeros(d.shape)
        total = 0.0
        for h in range(H):  # the error dynamics, semi-implicit Euler at the sample period
            ed += T * (acc[h] - 2.0 * damping * w * ed - w**2 * e)
            e += T * ed
            total += float(np.sum(e**2))
        cost[g] = total
    return float(grid[int(np.argmin(cost))])


SIZES = 8
"""Swap sizes (shares of the rated payload, evenly spaced) over which the error is summed."""
OBSERVER_GRID = 24
"""Bandwidths tried by :func:`observer_bandwidth_for`, spaced evenly in log between the law's
bandwidth and the cap."""


def observer_task(scenario, step: float = 0.05) -> tuple[Array, Array] | None:
    """``(inertia (K, n, n), load (K, n))`` for :func:`observer_bandwidth_for`: the arm's inertia
    carrying its rated payload (the observer's noise is highest then) and that payload's gravity
    torque (at the flange's frame) at the reference's instants every ``step`` s; None when the arm
    states no payload capacity."""
    arm = scenario.arm
    cap = getattr(arm, "payload_capacity", None)
    if cap is None or not cap > 0:
        return None
    t = np.arange(0.0, scenario.duration, step)
    q, _, _ = scenario.reference.sample(t)
    q = np.asarray(q, dtype=float)
    inertia = arm.mass_matrix(q, arm.sigma_with_payload(cap))
    dsig = arm.sigma_with_payload(cap) - arm.sigma_with_payload(0.0)
    zero = np.zeros_like(q)
    return inertia, arm.regressor(q, zero, zero) @ dsig


def detection_horizon(online, sample_period: float) -> int:
    """Samples a row out of use through a swap may take to come back (the data selection's
    memory; the filters' taint without a selection): how long the detector may not see a swap,
    the horizon of :func:`observer_bandwidth_for`."""
    memory = online.selection[1] if online.selection is not None else online.taint
    return int(np.ceil(memory * online.tau_f / sample_period - 1e-9))
