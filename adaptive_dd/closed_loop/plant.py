"""The plant step the closed loop calls: one trial, one sample, zero-order hold, in place.

It is :func:`adaptive_dd.plant.serial_integrator.serial_plant_step` (RK4 substeps,
stick-slip / tanh / Stribeck friction) when that module is present. Until it is, an
interim integrator stands in: RK4 over :func:`~adaptive_dd.plant.chain.forward_dynamics`
with the smooth friction ``fv qd + fc tanh(qd / v_f)`` whatever the arm's friction law
(:data:`INTERIM` is True then, and the runner says so in every result's ``engine``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.chain import forward_dynamics

__all__ = ["INTERIM", "plant_step"]

try:  # pragma: no cover - depends on which branches are merged
    from adaptive_dd.plant.serial_integrator import PlantParams, serial_plant_step

    INTERIM = False
except ImportError:  # pragma: no cover
    PlantParams = serial_plant_step = None
    INTERIM = True


@njit(cache=True)
def _accel(ch, pl, pi, q, qd, tau, tf, out):  # pragma: no cover - compiled
    n = q.shape[0]
    vf = pl.fparams[0]
    for j in range(n):
        tf[j] = tau[j] - pl.fv[j] * qd[j] - pl.fc[j] * np.tanh(qd[j] / vf)
    return forward_dynamics(ch, pi, pl.armature, q, qd, tf, out)


@njit(cache=True)
def _interim_step(ch, pl, seg, q, qd, tau, T):  # pragma: no cover - compiled
    """RK4 with ``pl.substeps`` substeps over one sample; False if the dynamics failed."""
    n = q.shape[0]
    pi = pl.pi_seg[seg]
    h = T / pl.substeps
    tf = np.empty(n)
    k1q, k2q, k3q, k4q = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    k1v, k2v, k3v, k4v = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    qt, vt = np.empty(n), np.empty(n)
    ok = True
    for _ in range(pl.substeps):
        k1q[:] = qd
        ok &= _accel(ch, pl, pi, q, qd, tau, tf, k1v)
        for j in range(n):
            qt[j] = q[j] + 0.5 * h * k1q[j]
            vt[j] = qd[j] + 0.5 * h * k1v[j]
        k2q[:] = vt
        ok &= _accel(ch, pl, pi, qt, vt, tau, tf, k2v)
        for j in range(n):
            qt[j] = q[j] + 0.5 * h * k2q[j]
            vt[j] = qd[j] + 0.5 * h * k2v[j]
        k3q[:] = vt
        ok &= _accel(ch, pl, pi, qt, vt, tau, tf, k3v)
        for j in range(n):
            qt[j] = q[j] + h * k3q[j]
            vt[j] = qd[j] + h * k3v[j]
        k4q[:] = vt
        ok &= _accel(ch, pl, pi, qt, vt, tau, tf, k4v)
        for j in range(n):
            q[j] += h / 6.0 * (k1q[j] + 2.0 * k2q[j] + 2.0 * k3q[j] + k4q[j])
            qd[j] += h / 6.0 * (k1v[j] + 2.0 * k2v[j] + 2.0 * k3v[j] + k4v[j])
    return ok


if INTERIM:

    @njit(cache=True)
    def plant_step(ch, pl, seg, q, qd, tau, T, stuck):  # pragma: no cover - compiled
        """Advance one trial's ``q, qd (n,)`` over one sample under ``tau (n,)`` in segment ``seg``."""
        _interim_step(ch, pl, seg, q, qd, tau, T)

else:  # pragma: no cover

    @njit(cache=True)
    def plant_step(ch, pl, seg, q, qd, tau, T, stuck):  # pragma: no cover - compiled
        """Advance one trial's ``q, qd (n,)`` over one sample under ``tau (n,)`` in segment ``seg``."""
        pp = PlantParams(pl.pi_seg[seg], pl.fv, pl.fc, pl.armature, pl.friction_law, pl.fparams)
        serial_plant_step(ch, pp, q, qd, tau, T, pl.substeps, stuck)
