"""The excitation design's objective and limits with their exact first derivatives.

:func:`~adaptive_dd.identification.excitation.design_excitation` maximises ``log det`` of the
information of the base parameters along a Fourier trajectory subject to limits at every grid
point (:mod:`adaptive_dd.identification.excitation`). SLSQP needs the gradient of the objective
and the Jacobian of the limits; :class:`DesignProblem` gives both by the chain rule instead of
finite differences over the ``n (2 K + 1)`` coefficients.

Chain rule
----------
Joint ``j``'s position, velocity and acceleration at grid time ``t_i`` are linear in its own
coefficients ``c_j = (q0_j, a_j1..a_jK, b_j1..b_jK)``: ``q_j(t_i) = S^q_i . c_j`` (and ``S^qd``,
``S^qdd``). So the derivative of anything evaluated at the grid points with respect to ``c_j`` is
that of ``q_j``, ``qd_j`` and ``qdd_j`` at each point times those rows. The base regressor's
derivatives in ``q_j``, ``qd_j`` and ``qdd_j`` come from ``5 n`` evaluations of the compiled
regressor over the whole grid (one batch): central differences of step :data:`STEP_Q` in ``q_j``
(error ``O(STEP_Q^2)``, about 1e-10 relative), central differences of step 1 in ``qd_j`` (exact: the
rigid-body regressor is quadratic in the velocities) and a forward difference of step 1 in
``qdd_j`` (exact: it is linear in the accelerations); the friction and armature columns are
differentiated in closed form. Finite differences over the coefficients took ``n (2 K + 1) + 1``
evaluations for the objective and as many for the limits, with an error about 1e-8.

Objective
---------
``f = -log det(D^-1 F D^-1 + 1e-9 I) / p`` with ``F = sum_i Y_i^T Y_i`` (rows weighted by the
torque limits): ``df = -(2 / p) sum_i <Y_i H, dY_i>`` with ``H = D^-1 (D^-1 F D^-1 + 1e-9 I)^-1 D^-1``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.identification.model import Model, base_regressor
from adaptive_dd.plant.chain import regressor_batch

__all__ = ["STEP_Q", "DesignProblem", "limit_slack"]

Array = NDArray[np.float64]

STEP_Q = 1e-5
"""[rad] The central differences' step in each joint position (truncation about ``STEP_Q^2``
relative, rounding about ``1e-16 / STEP_Q``)."""

SINGULAR_COST = 1e3
"""The objective where the scaled information is not positive definite (its gradient there 0)."""


def limit_slack(q: Array, qd: Array, qdd: Array, tau: Array, lim) -> Array:
    """Slack of every limit at every grid point (>= 0 when met), normalised by the limit: the
    positions above the lower and below the upper limit, then ``|qd|``, ``|qdd|``, ``|tau|``, each
    ``(m, n)`` raveled (``lim``: :class:`~adaptive_dd.identification.excitation.ExcitationLimits`)."""
    span = lim.upper - lim.lower
    return np.concatenate(
        [
            ((q - lim.lower) / span).ravel(),
            ((lim.upper - q) / span).ravel(),
            (1 - np.abs(qd) / lim.velocity).ravel(),
            (1 - np.abs(qdd) / lim.acceleration).ravel(),
            (1 - np.abs(tau) / lim.torque).ravel(),
        ]
    )


class DesignProblem:
    """The design's objective, limits and their derivatives on a grid ``t (m,)`` for ``n`` joints and
    ``K`` harmonics of base frequency ``f0`` (coefficients packed ``[q0, a.ravel(), b.ravel()]``).

    ``d (p,)``: the fixed scaling of the information (:meth:`set_scaling`). The last point's
    regressor (and derivatives, once asked) are kept, so that SLSQP's calls of the objective, the
    limits and their derivatives at one point share them.
    """

    def __init__(self, model: Model, lim, n: int, K: int, f0: float, t: Array) -> None:
        self.model, self.lim, self.n, self.K = model, lim, n, K
        w = 2 * np.pi * f0 * np.arange(1, K + 1)
        s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
        one, zero = np.ones((len(t), 1)), np.zeros((len(t), 1))
        self.Sq = np.hstack([one, s, c])  # (m, 1 + 2K): d q_j(t_i) / d c_j
        self.Sqd = np.hstack([zero, c * w, -s * w])
        self.Sqdd = np.hstack([zero, -s * w**2, -c * w**2])
        k = np.arange(K)
        self.index = np.array(  # (n, 1 + 2K): where c_j's entries sit in the packed vector
            [np.concatenate([[j], n + j * K + k, n + n * K + j * K + k]) for j in range(n)]
        )
        self.size = n * (2 * K + 1)
        self.d = np.ones(model.p)
        self._x: Array | None = None
        self._at: dict = {}

    # the states and the regressor at a point ------------------------------------------------
    def states(self, x: Array) -> tuple[Array, Array, Array]:
        """``q, qd, qdd (m, n)`` at the grid points for the coefficients ``x``."""
        coef = np.asarray(x, float)[self.index]  # (n, 1 + 2K)
        return self.Sq @ coef.T, self.Sqd @ coef.T, self.Sqdd @ coef.T

    def _point(self, x: Array) -> dict:
        x = np.asarray(x, float)
        if self._x is None or not np.array_equal(x, self._x):
            self._x = x.copy()
            q, qd, qdd = self.states(x)
            self._at = {"q": q, "qd": qd, "qdd": qdd, "Y": base_regressor(self.model, q, qd, qdd)}
        return self._at

    def _derivatives(self, x: Array) -> dict:
        """The point's base regressor's derivatives ``(n, m, n, p)`` in each joint's position,
        velocity and acceleration (module docstring), unweighted."""
        at = self._point(x)
        if "dq" in at:
            return at
        model, n = self.model, self.n
        q, qd, qdd = at["q"], at["qd"], at["qdd"]
        eye = np.eye(n)[:, None, :]  # (n, 1, n): a step in joint j at every grid point
        ones = np.ones((n, 1, 1))
        Q = np.concatenate([q + STEP_Q * eye, q - STEP_Q * eye, q * ones, q * ones, q * ones])
        Qd = np.concatenate([qd * ones, qd * ones, qd + eye, qd - eye, qd * ones])
        Qdd = np.concatenate([qdd * ones, qdd * ones, qdd * ones, qdd * ones, qdd + eye])
        ind = model.independent
        rigid = ind < 10 * n  # the links' columns, then friction and armature (ind is sorted)
        R = regressor_batch(model.chain, Q, Qd, Qdd)[..., ind[rigid]]  # (5n, m, n, r)
        d = np.zeros((3, n, *R.shape[1:-1], model.p))
        r = int(rigid.sum())
        d[0, ..., :r] = (R[:n] - R[n : 2 * n]) / (2 * STEP_Q)
        d[1, ..., :r] = (R[2 * n : 3 * n] - R[3 * n : 4 * n]) / 2.0
        d[2, ..., :r] = R[4 * n :] - at["Y"][..., :r]
        sech2 = 1.0 / np.cosh(qd / model.friction_velocity) ** 2  # (m, n)
        for col, k in zip(range(r, model.p), ind[~rigid] - 10 * n, strict=True):
            kind, j = divmod(int(k), n)  # viscous fv_j qd_j, Coulomb fc_j tanh(qd_j / v_f), armature
            if kind == 0:
                d[1, j, :, j, col] = 1.0
            elif kind == 1:
                d[1, j, :, j, col] = sech2[:, j] / model.friction_velocity
            else:
                d[2, j, :, j, col] = 1.0
        at["dq"], at["dqd"], at["dqdd"] = d[0], d[1], d[2]
        return at

    def _pointwise(self, dq: Array, dqd: Array, dqdd: Array) -> Array:
        """``(m, r, N)``: derivatives ``(n, m, r)`` of ``r`` values at each grid point in each joint's
        ``q_j, qd_j, qdd_j`` there, carried to the packed coefficients."""
        m, r = dq.shape[1], dq.shape[2]
        out = np.zeros((m, r, self.size))
        for j in range(self.n):
            out[:, :, self.index[j]] = (
                dq[j][:, :, None] * self.Sq[:, None, :]
                + dqd[j][:, :, None] * self.Sqd[:, None, :]
                + dqdd[j][:, :, None] * self.Sqdd[:, None, :]
            )
        return out

    # the objective ---------------------------------------------------------------------
    def information(self, x: Array) -> Array:
        """``F (p, p)``: the information of the base parameters (rows weighted by the torque limits)."""
        Y = self._point(x)["Y"] / self.lim.torque[None, :, None]
        A = Y.reshape(-1, self.model.p)
        return A.T @ A

    def set_scaling(self, x: Array) -> None:
        """``D``: the square roots of the information's diagonal at ``x`` (floored at 1e-6)."""
        self.d = np.sqrt(np.maximum(np.diag(self.information(x)), 1e-12))

    def _scaled(self, x: Array) -> Array:
        p = self.model.p
        return self.information(x) / np.outer(self.d, self.d) + 1e-9 * np.eye(p)

    def cost(self, x: Array) -> float:
        """``-log det(D^-1 F D^-1 + 1e-9 I) / p`` (:data:`SINGULAR_COST` where not positive definite)."""
        sign, val = np.linalg.slogdet(self._scaled(x))
        return float(-val / self.model.p) if sign > 0 else SINGULAR_COST

    def cost_gradient(self, x: Array) -> Array:
        """``(N,)``: the gradient of :meth:`cost` (0 where it is :data:`SINGULAR_COST`)."""
        Fn = self._scaled(x)
        sign, _ = np.linalg.slogdet(Fn)
        if sign <= 0:
            return np.zeros(self.size)
        at = self._derivatives(x)
        w = 1.0 / self.lim.torque[None, :, None]
        H = np.linalg.inv(Fn) / np.outer(self.d, self.d)
        P = (at["Y"] * w) @ H * w  # (m, n, p): Y_i H, weighted twice (once for dY_i's rows)
        g = [np.einsum("irc,jirc->ji", P, at[k]) for k in ("dq", "dqd", "dqdd")]  # (n, m) each
        grad = np.zeros(self.size)
        for j in range(self.n):
            grad[self.index[j]] = g[0][j] @ self.Sq + g[1][j] @ self.Sqd + g[2][j] @ self.Sqdd
        return -2.0 / self.model.p * grad

    # the limits ------------------------------------------------------------------------
    def constraints(self, x: Array) -> Array:
        """Slack of every limit at every grid point (>= 0 when met), normalised by the limit: the
        positions above the lower and below the upper limit, then ``|qd|``, ``|qdd|``, ``|tau|``
        (the URDF's model), each ``(m, n)`` raveled."""
        at = self._point(x)
        return limit_slack(at["q"], at["qd"], at["qdd"], at["Y"] @ self.model.sigma_ref, self.lim)

    def constraints_jacobian(self, x: Array) -> Array:
        """``(5 m n, N)``: the Jacobian of :meth:`constraints` (``d|y| = sign(y) dy``)."""
        at, lim, n = self._derivatives(x), self.lim, self.n
        m = self.Sq.shape[0]
        span = lim.upper - lim.lower
        J = np.zeros((5, m, n, self.size))
        for j in range(n):
            cols = self.index[j]
            J[0, :, j, cols] = (self.Sq / span[j]).T
            J[2, :, j, cols] = (-np.sign(at["qd"][:, j])[:, None] / lim.velocity[j] * self.Sqd).T
            J[3, :, j, cols] = (-np.sign(at["qdd"][:, j])[:, None] / lim.acceleration[j] * self.Sqdd).T
        J[1] = -J[0]
        sig = self.model.sigma_ref
        dtau = self._pointwise(at["dq"] @ sig, at["dqd"] @ sig, at["dqdd"] @ sig)  # (m, n, N)
        tau = at["Y"] @ sig
        J[4] = -(np.sign(tau) / lim.torque)[:, :, None] * dtau
        return J.reshape(5 * m * n, self.size)
