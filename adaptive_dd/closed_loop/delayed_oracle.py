"""``DelayedOracle``: the floor that detection delay alone puts under adaptive control of an
N-joint arm (a plug-in controller, measured by ``studies/delayed_oracle.py`` of commit d41702f).

It is computed torque with the textbook law of ``ct_oracle_textbook`` and the TRUE model,
except that it learns of each payload change only ``delay`` seconds after it: what an estimator
that knew the new payload exactly at its alarm would reach. With ``delay = 0`` it is
``ct_oracle_textbook`` itself (to rounding: the test that the plug-in is the same law). ``boost``
adds adaptive_ct's feedback boost (``M0(q) (dkp e + dkd e')`` raising the bandwidth to
``boost_bandwidth`` for ``boost_duration``) from the moment the model switches. It runs on the
Python path (one compiled ``model_torque`` call per trial and sample).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from adaptive_dd.closed_loop.controllers import JointGains
from adaptive_dd.closed_loop.laws import model_torque
from adaptive_dd.plant.chain import mass_matrix

__all__ = ["DelayedOracle"]


class DelayedOracle:
    """``ct_oracle_textbook``'s law with the true model of ``delay`` seconds ago (a plug-in).

    Parameters
    ----------
    arm : Arm
    gains : JointGains
    delay : float
        [s], >= 0.
    boost : (float, float) or None
        ``(boost_bandwidth [rad/s], boost_duration [s])`` after each switch of the model; None: none.
    """

    needs_true_model = True
    floor = "ct_oracle_textbook"

    def __init__(
        self, arm, gains: JointGains, delay: float, boost: tuple[float, float] | None = None
    ) -> None:
        if not delay >= 0:
            raise ValueError(f"delay must be >= 0 s, got {delay!r}")
        self.arm, self.gains, self.delay, self.boost = arm, gains, float(delay), boost
        self.name = f"delayed_oracle_{1e3 * delay:g}ms" + ("_boost" if boost else "")
        self._bpinv = np.linalg.pinv(arm.base.B)
        self._pi0, self._sigma0 = arm.pi, arm.base.B @ arm.pi

    def reset(self, n_trials: int, sample_period: float) -> None:
        self._past = deque(maxlen=round(self.delay / sample_period) + 1)
        self._boost_left = np.zeros(n_trials, dtype=np.int64)
        self._T = sample_period

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        self._past.append(np.array(sigma_true, dtype=float))
        sigma = self._past[0]  # the oldest kept: ``delay`` ago (the first sample's at the start)
        pi = self._pi0 + (sigma - self._sigma0) @ self._bpinv.T  # (m, 13 n), B pi == sigma
        e, ed = q_d - q, qd_d - qd
        a = qdd_d + self.gains.kd * ed + self.gains.kp * e
        out = np.empty_like(q)
        for i in range(q.shape[0]):
            model_torque(self.arm.chain, pi[i], q[i], qd[i], qd[i], qd_d, a[i], out[i])
        if self.boost is not None:
            if len(self._past) > 1:
                switched = np.any(self._past[0] != self._past[1], axis=-1)  # the model changes next sample
                self._boost_left[switched] = round(self.boost[1] / self._T) + 1
            w, z = self.gains.bandwidth, self.gains.damping
            wb = np.maximum(self.boost[0], w)
            dkp, dkd = wb**2 - w**2, 2.0 * z * (wb - w)
            n = q.shape[1]
            m0 = np.empty((n, n))
            for i in np.flatnonzero(self._boost_left > 0):
                mass_matrix(self.arm.chain, self._pi0[: 10 * n], q[i], m0)
                v = dkp * e[i] + dkd * ed[i]
                out[i] += m0 @ v + self._pi0[12 * n :] * v
            self._boost_left = np.maximum(self._boost_left - 1, 0)
        return out

    def observe(self, q, qd, tau) -> None:
        pass
