"""The gradient laws' adaptation gains, derived from the arm and the task instead of one constant.

``slotine_li`` (and ``composite``, ``icl``, which add to its gradient) adapts the payload's ten
parameters ``theta`` by ``theta' = Gamma (Y_j P)^T s``. Near the reference, with the sliding
variable's feedback ``kd M0(q) s`` faster than the adaptation, the sliding variable follows the
torque the estimate leaves unexplained, ``s ~ (kd M0)^-1 Y_p theta~`` (``Y_p = Y_j P``, the payload's
regressor along the reference), and the estimate's error decays as

    theta~' = - Gamma R theta~,    R = mean_t  Y_p(t)^T (kd M0(q(t)))^-1 Y_p(t)

(Slotine and Li, *Applied Nonlinear Control*, 1991, sec. 9.2; the averaging argument of Anderson
et al., *Stability of Adaptive Systems*, 1986). One constant ``Gamma`` therefore adapts a light
arm's payload hundreds of times faster than a heavy one's, or not at all. :func:`payload_gains`
takes ``Gamma = c diag(R)^-1`` (each parameter adapted at the same rate on its own: the diagonal
preconditioning of the gradient) with ``c`` such that the fastest mode of ``Gamma R`` decays at
:data:`RATE_OF_BANDWIDTH` times the law's smaller gain root ``lambda`` (slower than the sliding
variable's ``kd``, so the averaging holds). ``R`` is taken along the scenario's reference on the
controller's model, unloaded: what the arm and the task state, never the schedule's payloads.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "DEFAULT_PAYLOAD_GAMMA",
    "RATE_OF_BANDWIDTH",
    "given_gains",
    "payload_gains",
    "payload_sensitivity",
]

Array = NDArray[np.float64]

DEFAULT_PAYLOAD_GAMMA = (2.0, 0.2, 0.2, 0.2, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02)
"""Adaptation gains of the payload's ten parameters (m, m c, I about the frame) of a law built
without a task (no scenario: :func:`payload_gains` needs its reference)."""

RATE_OF_BANDWIDTH = 0.5
"""The fastest adaptation mode's rate over the law's ``lambda`` (the smaller root of the feedback)."""

STEP = 0.01
"""[s] between the reference's instants at which ``R`` is averaged."""


def payload_sensitivity(arm, scenario, kd: Array) -> Array:
    """``R (10, 10)`` of the module docstring: the payload regressor's weight through the sliding
    variable's feedback ``kd (n,)`` [1/s], averaged along ``scenario``'s reference on ``arm``."""
    T = float(scenario.sample_period)
    step = max(1, round(STEP / T))
    t = np.arange(0, scenario.n_samples, step) * T
    q, qd, qdd = (np.asarray(x, dtype=float) for x in scenario.reference.sample(t))
    j = int(arm.payload_joint)
    Yp = arm.standard_regressor(q, qd, qdd)[..., 10 * j : 10 * j + 10] @ arm.payload_map  # (K, n, 10)
    M0 = arm.mass_matrix(q)  # (K, n, n), armature included
    root = 1.0 / np.sqrt(np.broadcast_to(np.asarray(kd, dtype=float), (arm.n_joints,)))
    X = np.linalg.solve(M0, root[None, :, None] * Yp)  # (kd M0)^-1 Y_p, symmetrised by sqrt(kd)
    R = np.einsum("kia,kib->ab", root[None, :, None] * Yp, X) / len(t)
    return 0.5 * (R + R.T)


def payload_gains(arm, scenario, kd: Array, lam: Array) -> Array:
    """``Gamma (10,)``, the diagonal adaptation gains of the payload's ``m, m c, I`` (module
    docstring): ``c / R_ii`` with the fastest mode of ``Gamma R`` at :data:`RATE_OF_BANDWIDTH`
    ``min(lam)``. A parameter the reference does not move (``R_ii`` below 1e-9 of the largest) keeps
    the gain of the weakest one that it does."""
    R = payload_sensitivity(arm, scenario, kd)
    d = np.diag(R).copy()
    seen = d > 1e-9 * d.max()
    d[~seen] = d[seen].min()
    s = 1.0 / np.sqrt(d)
    fastest = float(np.linalg.eigvalsh(s[:, None] * R * s[None, :]).max())
    rate = RATE_OF_BANDWIDTH * float(np.min(lam))
    return rate / fastest / d


def given_gains(where: str, gamma) -> Array:
    """``gamma`` as 10 positive adaptation gains, else a :class:`ParameterError` naming ``where``."""
    from adaptive_dd.errors import ParameterError, is_finite_number

    g = gamma.tolist() if isinstance(gamma, np.ndarray) else gamma
    numbers = isinstance(g, list | tuple) and all(is_finite_number(x) for x in g)
    if not numbers or len(g) != 10 or not all(x > 0 for x in g):
        raise ParameterError(
            f"{where}.gamma: 10 positive adaptation gains (the payload's m, m c, I), got {gamma!r}"
        )
    return np.array(g, dtype=float)
