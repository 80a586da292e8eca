"""Slotine-Li adaptive control of the payload (Slotine and Li 1987) as a compiled plug-in.

``s = e' + lam e``, ``qd_r = qd_d + lam e``, ``qdd_r = qdd_d + lam e'`` (``e = q_d - q``) and

    tau = Y(q, qd, qd_r, qdd_r) pi0 + Y_p(q, qd, qd_r, qdd_r) theta + k M0(q) s,
    theta += T Gamma Y_p^T s, then projected on the a-priori box,

``pi0`` the model the scenario gives the controllers, ``Y_p`` the payload link's regressor times
the payload map (the torque's derivative with respect to the payload's ten parameters about the
payload frame), ``theta`` the adapted payload, ``M0`` the model's inertia with the armature,
``lam`` and ``k`` the two roots of ``x^2 - 2 zeta omega x + omega^2``. The box: mass in
``[0, max_mass]``, first moments within ``max_mass com_radius``, inertias within
``2 max_mass com_radius^2``, the centre of mass within ``com_radius`` of the payload frame.

The same law as the built-in ``slotine_li``, written against the public protocol only: the loop
hands ``command`` the model's inertia (``needs`` ``mass_matrix``) and the arm's kernels
(``regressor``), which :func:`~adaptive_dd.controllers.kernels.reference_torque` and
:func:`~adaptive_dd.controllers.kernels.payload_regressor` evaluate at the law's reference
(``docs/own_controller.md``). ``adaptive-dd benchmark examples/plugins/slotine_li.toml`` runs
both side by side.
"""

import numpy as np
from numba import njit

from adaptive_dd.controllers.kernels import payload_regressor, reference_torque

GAMMA = (2.0, 0.2, 0.2, 0.2, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02)  # m, m c, I about the payload frame


class SlotineLiPlugin:
    """Slotine-Li adapting the payload's ten parameters, compiled into the closed loop."""

    name = "slotine_li_plugin"
    floor = "slotine_li_oracle"  # the same law with the true model, no adaptation
    needs = ("mass_matrix", "regressor")
    state_size = 10  # per trial: the adapted payload theta

    def __init__(self, arm, gains, gamma=GAMMA, max_mass=20.0, com_radius=0.3):
        w, z = gains.bandwidth, max(gains.damping, 1.0)
        root = w * np.sqrt(z * z - 1.0)
        n = arm.n_joints
        self.lam, self.k = np.full(n, w * z - root), np.full(n, w * z + root)  # [1/s]
        self.gamma = np.asarray(gamma, dtype=float)
        if self.gamma.shape != (10,) or not np.all(self.gamma > 0):
            raise ValueError(f"gamma: 10 positive gains (the payload's m, m c, I), got {gamma!r}")
        m, r = float(max_mass), float(com_radius)
        i_max = 2.0 * m * r * r
        self.hi = np.array([m, m * r, m * r, m * r, i_max, i_max / 2, i_max, i_max / 2, i_max / 2, i_max])
        self.lo = np.array([0.0, -m * r, -m * r, -m * r, 0.0, -i_max / 2, 0.0, -i_max / 2, -i_max / 2, 0.0])
        self.com_radius = r
        self.sigma0 = np.asarray(arm.sigma, dtype=float)  # (p,) base parameters without payload
        self.basis = np.ascontiguousarray(arm.payload_basis)  # (p, 10): how theta moves them

    def parameters(self, sample_period):
        return (self.lam, self.k, self.gamma, self.lo, self.hi, self.com_radius, float(sample_period),
                self.sigma0, self.basis)  # fmt: skip

    @staticmethod
    @njit
    def reset(p, x):
        x[:] = 0.0  # no payload

    @staticmethod
    @njit
    def command(p, x, q, qd, q_d, qd_d, qdd_d, terms, tau):
        lam, k, gamma, lo, hi, radius, T = p[0], p[1], p[2], p[3], p[4], p[5], p[6]
        m0, kin = terms[1], terms[3]
        n = q.shape[0]
        qd_r, qdd_r, s = np.empty(n), np.empty(n), np.empty(n)
        for j in range(n):
            e, ed = q_d[j] - q[j], qd_d[j] - qd[j]
            qd_r[j] = qd_d[j] + lam[j] * e
            qdd_r[j] = qdd_d[j] + lam[j] * ed
            s[j] = ed + lam[j] * e
        yp = np.empty((n, 10))
        payload_regressor(kin, q, qd, qd_r, qdd_r, yp)
        reference_torque(kin, q, qd, qd_r, qdd_r, tau)  # the model without payload
        for r in range(n):
            acc = 0.0
            for c in range(10):
                acc += yp[r, c] * x[c]  # the adapted payload's torque
            for c in range(n):
                acc += m0[r, c] * k[c] * s[c]  # the feedback k M0(q) s
            tau[r] += acc
        for c in range(10):  # the gradient step, then the box
            g = 0.0
            for r in range(n):
                g += yp[r, c] * s[r]
            step = T * gamma[c] * g
            x[c] += step if np.isfinite(step) else 0.0
            x[c] = min(max(x[c], lo[c]), hi[c])
        x[0] = max(x[0], 0.0)
        mc = np.sqrt(x[1] ** 2 + x[2] ** 2 + x[3] ** 2)
        if mc > radius * x[0]:  # the centre of mass back inside its ball
            f = radius * x[0] / mc
            x[1], x[2], x[3] = f * x[1], f * x[2], f * x[3]

    @staticmethod
    @njit
    def observe(p, x, q, qd, tau):
        return 0  # no change detector

    @staticmethod
    @njit
    def estimate(p, x, out):
        """The estimate's base parameters: the model's plus the adapted payload's."""
        sigma0, basis = p[7], p[8]
        for r in range(out.shape[0]):
            acc = sigma0[r]
            for c in range(10):
                acc += basis[r, c] * x[c]
            out[r] = acc
