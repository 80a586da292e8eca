"""``adaptive_ct``'s boost bandwidth per joint, from the torque limits and the sensors' noise.

After an alarm the N-joint ``adaptive_ct`` adds ``M0(q) (dkp e + dkd e')`` to its command
(``dkp = wb^2 - w^2``, ``dkd = 2 zeta (wb - w)``; :mod:`adaptive_dd.closed_loop.laws`). At each
sample the added bandwidth ``wb - w`` of every joint is scaled by the largest common factor in
``[0, 1]`` whose command stays within the torque limits (``laws._boost_within_limits``, as the
two-link law's ``boost_within_trial``): the boost takes the room the limits leave at that
instant, whatever the payload, and never pushes the command beyond a limit.

What is fixed before the run is each joint's cap ``wb``. The measured ``e`` and ``e'`` carry the
sensors' noise, so the added torque carries

    std_j(t) = sqrt( sum_l M0_jl(q(t))^2 (dkp_l^2 var_q,l + dkd_l^2 var_qd,l) )

of it on joint ``j``, which grows as ``wb^2``. The cap of each joint is the largest, up to
``boost_bandwidth``, for which that noise stays :data:`NOISE_SIGMAS` standard deviations inside
the torque limit at every posture of the reference: ``NOISE_SIGMAS std_j(t) <= limit_j``. Neither
the scenario's payloads nor the rated payload enter: no other law is told them, and the
per-sample scaling takes care of the torque the task itself needs. Without a task (a controller
built with no scenario) the cap is ``boost_bandwidth`` on every joint.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["NOISE_SIGMAS", "boost_bandwidths", "task_room"]

Array = NDArray[np.float64]

NOISE_SIGMAS = 3.0
"""Standard deviations of the boost's noise torque kept inside the room (the residual observer's
threshold is the same three)."""

ROOM_STEP = 0.01
"""[s] between the reference's instants at which the room is taken."""


def task_room(scenario, arm=None) -> tuple[Array, Array]:
    """``(q (K, n), room (K, n))``: the reference's positions every :data:`ROOM_STEP` and the room
    the boost's noise may take there, each joint's torque limit on the model ``arm`` (default
    ``scenario.arm``; inf where the actuator does not saturate)."""
    from adaptive_dd.closed_loop.laws import actuator_limits

    arm = scenario.arm if arm is None else arm
    step = max(1, round(ROOM_STEP / scenario.sample_period))
    t = np.arange(0, scenario.n_samples, step) * scenario.sample_period
    q = np.asarray(scenario.reference.sample(t)[0], dtype=float)
    return q, np.broadcast_to(actuator_limits(arm), q.shape).copy()


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
    ``room (K, n)`` the torque the noise may take there [N m]; the sensors' variances ``(n,)``.

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
