"""The plant step the closed loop calls: one trial, one sample, zero-order hold, in place.

It is :func:`adaptive_dd.plant.serial_integrator.serial_plant_step` (RK4 substeps,
stick-slip / tanh / Stribeck friction) when that module is present. Until it is, an
interim integrator stands in: RK4 over the forward dynamics
(:func:`~adaptive_dd.plant.chain.bias_and_mass`, the armature added, a Cholesky solve) with
the smooth friction ``fv qd + fc tanh(qd / v_f)`` whatever the arm's friction law
(:data:`INTERIM` is True then, and the runner says so in every result's ``engine``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.chain import bias_and_mass, workspace

__all__ = ["INTERIM", "plant_step"]

try:  # pragma: no cover - depends on which branches are merged
    from adaptive_dd.plant.serial_integrator import PlantParams, serial_plant_step

    INTERIM = False
except ImportError:  # pragma: no cover
    PlantParams = serial_plant_step = None
    INTERIM = True


@njit(cache=True)
def _accel(ch, pl, pi, q, qd, tau, w, m, out):  # pragma: no cover - compiled
    """``out = (M + diag(Ia))^-1 (tau - friction - bias)`` by Cholesky; False if not positive definite."""
    n = q.shape[0]
    vf = pl.fparams[0]
    bias_and_mass(ch, pi, q, qd, w, out, m)
    for j in range(n):
        out[j] = tau[j] - pl.fv[j] * qd[j] - pl.fc[j] * np.tanh(qd[j] / vf) - out[j]
        m[j, j] += pl.armature[j]
    for j in range(n):
        d = m[j, j]
        for k in range(j):
            d -= m[j, k] * m[j, k]
        if not d > 0.0:
            out[:] = np.nan
            return False
        d = np.sqrt(d)
        m[j, j] = d
        for i in range(j + 1, n):
            x = m[i, j]
            for k in range(j):
                x -= m[i, k] * m[j, k]
            m[i, j] = x / d
    for i in range(n):
        x = out[i]
        for k in range(i):
            x -= m[i, k] * out[k]
        out[i] = x / m[i, i]
    for i in range(n - 1, -1, -1):
        x = out[i]
        for k in range(i + 1, n):
            x -= m[k, i] * out[k]
        out[i] = x / m[i, i]
    return True


@njit(cache=True)
def _interim_step(ch, pl, seg, q, qd, tau, T):  # pragma: no cover - compiled
    """RK4 with ``pl.substeps`` substeps over one sample; False if the dynamics failed."""
    n = q.shape[0]
    pi = pl.pi_seg[seg]
    h = T / pl.substeps
    w = workspace(n)
    m = np.empty((n, n))
    k1q, k2q, k3q, k4q = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    k1v, k2v, k3v, k4v = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    qt, vt = np.empty(n), np.empty(n)
    ok = True
    for _ in range(pl.substeps):
        k1q[:] = qd
        ok &= _accel(ch, pl, pi, q, qd, tau, w, m, k1v)
        for j in range(n):
            qt[j] = q[j] + 0.5 * h * k1q[j]
            vt[j] = qd[j] + 0.5 * h * k1v[j]
        k2q[:] = vt
        ok &= _accel(ch, pl, pi, qt, vt, tau, w, m, k2v)
        for j in range(n):
            qt[j] = q[j] + 0.5 * h * k2q[j]
            vt[j] = qd[j] + 0.5 * h * k2v[j]
        k3q[:] = vt
        ok &= _accel(ch, pl, pi, qt, vt, tau, w, m, k3v)
        for j in range(n):
            qt[j] = q[j] + h * k3q[j]
            vt[j] = qd[j] + h * k3v[j]
        k4q[:] = vt
        ok &= _accel(ch, pl, pi, qt, vt, tau, w, m, k4v)
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
