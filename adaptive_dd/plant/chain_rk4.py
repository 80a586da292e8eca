"""One sample of a serial chain's plant under each friction family: modes, then RK4.

The arithmetic behind :func:`adaptive_dd.plant.integrator.plant_step` (its records and its
public step are there): the accelerations with the stuck joints held (:func:`_solve`, a
Cholesky of the free joints' block of ``M + diag(armature)``, the rigid-body terms from
:func:`adaptive_dd.plant.chain_dynamics.bias_and_mass`), the modes of the resting joints
(:func:`_resolve`), one RK4 step with the modes fixed (:func:`_rk4`) and the sample under
each family of friction laws (:func:`_stick_slip`, :func:`_smooth`).

Stick-slip (law 0)
------------------
A joint at rest (velocity exactly 0) with ``fc_i > 0`` either sticks or slides from
rest. At the start of every substep the modes of the resting joints are decided by
an active set:

1. all resting joints start stuck (velocity and acceleration held at 0);
2. the accelerations of the free joints are solved from
   ``(M + diag(armature))_FF qdd_F = tau_F - bias_F - fv_F qd_F - fc_F sgn_F``
   (``bias = rnea(q, qd, 0)``, moving joints with ``sgn = sgn(qd)``, released joints
   with their slide direction), and each stuck joint's holding torque
   ``h_i = tau_i - bias_i - ((M + diag(armature)) qdd)_i`` follows;
3. if some stuck joint needs ``|h_i| > fc_i``, the one with the largest excess
   ``|h_i| - fc_i`` is released, sliding in the direction ``sgn(h_i)``, and step 2 is
   repeated (at most n times); otherwise the modes are consistent;
4. re-stick pass (when two or more joints were released): in the order of release,
   each released joint is stuck again if the modes then stay consistent (every stuck
   joint holds, every released joint accelerates in its slide direction): joints stay
   at rest unless they must move.

Within a substep the modes are fixed. When a moving joint's velocity reaches zero
inside a substep (detected as a sign change of its velocity in any RK4 stage), the
substep is split at the first crossing (located from the initial acceleration, as
in the two-link integrator), the crossing joints are set to rest, the modes are
decided anew and the rest of the substep is integrated; a second crossing within
that remainder also rests there, decided at the next substep.

Coulomb friction can admit several consistent mode sets. Step 4 matters there: when
a moving joint stops while a coupled joint is held, releasing the held joint (largest
excess) and then both can be consistent, but so is the held joint staying stuck
while the other reverses (its acceleration continuous); the re-stick pass finds the
latter. The two-link integrator's enumeration (stick first, joint 1's modes outer)
picks the same modes on the SICE arm over the Table 2 torques (tests); with n = 2 the
rules can still differ where both resting joints could slide, each alone consistent.

Smooth laws (1 tanh, 2 Stribeck)
--------------------------------
``fc_i tanh(qd_i / v)`` or ``fc_i (1 + (k - 1) exp(-(qd_i / v_s)^2)) tanh(qd_i / v)``
(:mod:`adaptive_dd.plant.two_link`), integrated by plain RK4; each substep ``h`` is split
into ``ceil(h rho / 2)`` equal steps, ``rho = trace((M + diag(armature))^-1 K) >= `` the
spectral radius of ``M^-1 K``, ``K`` the largest friction slopes
``fv_i + fc_i (k / v + (k - 1) 0.8578 / v_s)`` at the substep's start, as the two-link
integrator does.

LuGre (law 3)
-------------
Every joint with Coulomb friction carries a bristle deflection ``z_i`` (Canudas de Wit, Olsson,
Astrom, Lischinsky, IEEE TAC 40(3), 1995), the friction ``sigma0 z + sigma1 dz/dt + fv v`` with
``dz/dt = v - sigma0 |v| z / g(v)``, ``g(v) = fc (1 + (k - 1) exp(-(v / v_s)^2))``. The
bristles make the ODE stiff, so :func:`_lugre` takes the two-link integrator's linearly implicit
micro-steps (:mod:`adaptive_dd.plant.two_link_integrator`, "LuGre plant friction") with the
whole inertia: ``(M + h diag(K)) v+ = M v + h (tau - bias - F0)`` (``M`` with the armature,
``bias = rnea(q, v, 0)``), then ``z+ = (z + h v+) / (1 + h a)`` and ``q+ = q + h v+``. On the
paper's geometry it is the two-link step's arithmetic (tests hold them together).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.chain_dynamics import _cholesky_solve, bias_and_mass, workspace
from adaptive_dd.plant.two_link_integrator import LUGRE_DT_MAX

__all__: list[str] = []  # compiled internals of adaptive_dd.plant.integrator

# ----------------------------------------------------------------------------- accelerations


@njit(cache=True)
def _scratch(n):  # pragma: no cover - compiled
    """Per-call scratch: chain workspace, M (stages), a factor, float rows, free-joint indices,
    flags, M at the substep's start (``rows[18]`` holds its bias), reused by its first stage."""
    return (
        workspace(n),
        np.empty((n, n)),
        np.empty((n, n)),
        np.empty((21, n)),
        np.empty((2, n), dtype=np.int64),
        np.zeros((3, n), dtype=np.bool_),
        np.empty((n, n)),
    )


@njit(cache=True, fastmath={"contract", "reassoc"}, inline="always")
def _dynamics(ch, pi, arm, q, v, w, bias, m):  # pragma: no cover - compiled
    """``bias = rnea(q, v, 0)`` (n,) and ``m = M(q) + diag(armature)`` (n, n); w: chain workspace."""
    bias_and_mass(ch, pi, q, v, w, bias, m)
    for i in range(q.shape[0]):
        m[i, i] += arm[i]


@njit(cache=True, fastmath={"contract", "reassoc"}, inline="always")
def _solve(
    fv, fc, law, fp, v, tau, stuck, sdir, rows, ib, m, lf, ints, ia, ih
):  # pragma: no cover - compiled
    """Accelerations ``acc = rows[ia]`` (n,) with the stuck joints held; ``hold = rows[ih]`` (n,)
    torque to hold each stuck joint.

    Uses the terms ``bias = rows[ib], m`` of :func:`_dynamics`; ``rows, lf, ints`` the scratch's
    float rows, factor and integer rows (:func:`_scratch`), read by index, no view taken (each view
    is a reference-count update). Friction: law 0 ``fc sgn(v)`` (``sdir`` at v == 0), else the
    smooth law. Returns False if ``M + diag(armature)`` restricted to the free joints is not
    positive definite (the accelerations and holding torques then NaN).
    """
    n = v.shape[0]
    vc, ratio, vs = fp[0], fp[1], fp[2]
    nf = 0
    for i in range(n):
        if stuck[i]:
            continue
        if law == 0:
            sg = np.sign(v[i]) if v[i] != 0.0 else sdir[i]
            coul = fc[i] * sg
        else:
            g = fc[i]
            if law == 2:
                g = fc[i] * (1.0 + (ratio - 1.0) * np.exp(-((v[i] / vs) ** 2)))
            coul = g * np.tanh(v[i] / vc)
        ints[0, nf] = i
        rows[1, nf] = tau[i] - rows[ib, i] - fv[i] * v[i] - coul
        nf += 1
    # Cholesky of the free block (reciprocal diagonal kept: no division in the loops),
    # then the two triangular solves
    for jj in range(nf):
        j = ints[0, jj]
        d = m[j, j]
        for kk in range(jj):
            d -= lf[jj, kk] * lf[jj, kk]
        if not d > 0.0:  # the step's state becomes NaN, caught by the callers' rules (no stale scratch)
            for i in range(n):
                rows[ia, i] = np.nan
                rows[ih, i] = np.nan
            return False
        d = np.sqrt(d)
        lf[jj, jj] = d
        r = 1.0 / d
        rows[19, jj] = r
        for ii in range(jj + 1, nf):
            x = m[ints[0, ii], j]
            for kk in range(jj):
                x -= lf[ii, kk] * lf[jj, kk]
            lf[ii, jj] = x * r
    for ii in range(nf):
        x = rows[1, ii]
        for kk in range(ii):
            x -= lf[ii, kk] * rows[1, kk]
        rows[1, ii] = x * rows[19, ii]
    for ii in range(nf - 1, -1, -1):
        x = rows[1, ii]
        for kk in range(ii + 1, nf):
            x -= lf[kk, ii] * rows[1, kk]
        rows[1, ii] = x * rows[19, ii]
    for i in range(n):
        rows[ia, i] = 0.0
    for ii in range(nf):
        rows[ia, ints[0, ii]] = rows[1, ii]
    if nf == n:
        return True
    for i in range(n):
        if stuck[i]:
            x = tau[i] - rows[ib, i]
            for j in range(n):
                x -= m[i, j] * rows[ia, j]
            rows[ih, i] = x
        else:
            rows[ih, i] = 0.0
    return True


@njit(cache=True, _nrt=False)
def _consistent(rest, stuck, acc, hold, sdir, fc):  # pragma: no cover - compiled
    """Stuck resting joints hold (|h_i| <= fc_i) and released ones accelerate in their slide direction."""
    for i in range(rest.shape[0]):
        if rest[i] and ((stuck[i] and abs(hold[i]) > fc[i]) or (not stuck[i] and acc[i] * sdir[i] <= 0.0)):
            return False
    return True


@njit(cache=True, _nrt=False)
def _resolve(ch, pi, fv, fc, arm, fp, q, v, tau, rest, stuck, sdir, sc):  # pragma: no cover - compiled
    """Active-set modes of the resting joints (module docstring); False if M is not positive definite."""
    n = q.shape[0]
    acc, hold, order = sc[3][2], sc[3][3], sc[4][1]
    for i in range(n):
        stuck[i] = rest[i]
    n_rel = 0
    bias0, m0 = sc[3][18], sc[6]
    _dynamics(ch, pi, arm, q, v, sc[0], bias0, m0)
    for _ in range(n + 1):
        if not _solve(fv, fc, 0, fp, v, tau, stuck, sdir, sc[3], 18, m0, sc[2], sc[4], 2, 3):
            return False
        worst, excess = -1, 0.0
        for i in range(n):
            if stuck[i] and abs(hold[i]) - fc[i] > excess:
                worst, excess = i, abs(hold[i]) - fc[i]
        if worst < 0:
            break
        stuck[worst] = False
        sdir[worst] = 1.0 if hold[worst] > 0.0 else -1.0
        order[n_rel] = worst
        n_rel += 1
    if n_rel < 2:
        return True
    # re-stick pass: in the order of release, a released joint is stuck again if the
    # modes stay consistent (joints stay at rest unless they must move)
    for k in range(n_rel):
        r = order[k]
        stuck[r] = True
        if not _solve(fv, fc, 0, fp, v, tau, stuck, sdir, sc[3], 18, m0, sc[2], sc[4], 2, 3):
            return False
        if not _consistent(rest, stuck, acc, hold, sdir, fc):
            stuck[r] = False
    return True


# ----------------------------------------------------------------------------- integration


@njit(cache=True, fastmath={"contract", "reassoc"}, _nrt=False)
def _rk4(
    ch, pi, fv, fc, arm, law, fp, q, v, tau, dt, stuck, sdir, sc, reuse, qn, vn, cross
):  # pragma: no cover
    """One classical RK4 step of length dt with the modes fixed, into (qn, vn).

    The first stage takes the start slots of :func:`_dynamics`, computed here unless
    ``reuse`` (they already hold the terms at (q, v)). ``cross[i]``: moving joint i's
    velocity changed sign (or reached 0) in some stage, so the step met the Coulomb
    discontinuity (stick-slip law only). Returns False if a mass matrix was not
    positive definite.
    """
    n = q.shape[0]
    # the stages' rows read by index (rows 4-7 the accelerations, 9-11 the stages' velocities,
    # 14 the holding torques): each view of a row would be a reference-count update
    w, lf, rows, ints, m0, m = sc[0], sc[2], sc[3], sc[4], sc[6], sc[1]
    qs, vcur, bias0, bias = rows[8], rows[20], rows[18], rows[0]
    ok = True
    # one call site for the four stages (the dynamics are inlined: one copy of the code)
    for st in range(4):
        if st == 0:
            for i in range(n):
                qs[i] = q[i]
                vcur[i] = v[i]
        else:
            c = 1.0 if st == 3 else 0.5
            for i in range(n):
                vprev = v[i] if st == 1 else rows[7 + st, i]  # previous stage's velocity
                vcur[i] = v[i] + c * dt * rows[3 + st, i]
                qs[i] = q[i] + c * dt * vprev
                rows[8 + st, i] = vcur[i]
        bb = bias0 if st == 0 else bias
        mm = m0 if st == 0 else m
        if st > 0 or not reuse:
            _dynamics(ch, pi, arm, qs, vcur, w, bb, mm)
        ib = 18 if st == 0 else 0
        ok &= _solve(fv, fc, law, fp, vcur, tau, stuck, sdir, rows, ib, mm, lf, ints, 4 + st, 14)
    for i in range(n):
        wv, xv, yv = rows[9, i], rows[10, i], rows[11, i]
        qn[i] = q[i] + (dt / 6.0) * (v[i] + 2.0 * wv + 2.0 * xv + yv)
        acc = rows[4, i] + 2.0 * rows[5, i] + 2.0 * rows[6, i] + rows[7, i]
        vn[i] = 0.0 if stuck[i] else v[i] + (dt / 6.0) * acc
        cross[i] = False
        if law == 0 and not stuck[i]:
            s = np.sign(v[i]) if v[i] != 0.0 else sdir[i]
            cross[i] = min(wv * s, xv * s, yv * s, vn[i] * s) <= 0.0
    return ok


@njit(cache=True, _nrt=False)
def _decide(ch, pi, fv, fc, arm, fp, q, v, tau, stuck, sdir, sc):  # pragma: no cover - compiled
    """Modes at the current state: resting joints with Coulomb friction go through :func:`_resolve`.

    Returns (ok, whether the start slots now hold the dynamics at (q, v)).
    """
    rest = sc[5][0]
    any_rest = False
    for i in range(q.shape[0]):
        rest[i] = v[i] == 0.0 and fc[i] > 0.0
        stuck[i] = False
        any_rest |= rest[i]
    if not any_rest:
        return True, False
    return _resolve(ch, pi, fv, fc, arm, fp, q, v, tau, rest, stuck, sdir, sc), True


@njit(cache=True, _nrt=False)
def _stick_slip(ch, pi, fv, fc, arm, fp, q, qd, tau, T, substeps, stuck, sc):  # pragma: no cover
    """One sample under the stick-slip law (module docstring), q and qd in place."""
    n = q.shape[0]
    h = T / substeps
    rows, flags = sc[3], sc[5]
    qn, vn, frac, sdir = rows[12], rows[13], rows[15], rows[16]
    cross, z = flags[1], flags[2]
    # "reuse" as a typed value, not the literal True: numba compiles a callee once per literal
    # value (_rk4, the integrator's largest kernel, was compiled twice here). The law stays the
    # literal 0: _rk4 compiled for it alone runs the stick-slip plant 8 % faster than one taking
    # the law at run time (UR5, CPU time per sample); the smooth laws' _rk4 is the other copy
    law0, held = 0, np.bool_(True)
    for i in range(n):
        sdir[i] = 1.0
    ok = True
    for _ in range(substeps):
        good, have = _decide(ch, pi, fv, fc, arm, fp, q, qd, tau, stuck, sdir, sc)
        ok &= good
        ok &= _rk4(ch, pi, fv, fc, arm, law0, fp, q, qd, tau, h, stuck, sdir, sc, have, qn, vn, cross)
        f = 1.0
        any_cross = False
        for i in range(n):
            cross[i] = cross[i] and fc[i] > 0.0
            if cross[i]:
                any_cross = True
                if qd[i] * rows[4, i] < 0.0:
                    frac[i] = min(1.0, abs(qd[i]) / (h * abs(rows[4, i])))
                else:
                    frac[i] = 0.0
            else:
                frac[i] = 1.0
            f = min(f, frac[i])
        if any_cross:
            # a velocity reaches zero: step to the first crossing (located from the initial
            # acceleration), decide the modes there, finish the substep
            if f > 0.0:
                # same start state and modes: the start slots still hold its dynamics
                ok &= _rk4(ch, pi, fv, fc, arm, law0, fp, q, qd, tau, f * h, stuck, sdir, sc, held, qn, vn, z)
                for i in range(n):
                    q[i], qd[i] = qn[i], vn[i]
            for i in range(n):
                if cross[i] and frac[i] <= f:
                    qd[i] = 0.0
            good, have = _decide(ch, pi, fv, fc, arm, fp, q, qd, tau, stuck, sdir, sc)
            ok &= good
            ok &= _rk4(
                ch, pi, fv, fc, arm, law0, fp, q, qd, tau, (1.0 - f) * h, stuck, sdir, sc, have, qn, vn, z
            )
            # another crossing within the same substep: rest there (decided next substep)
            for i in range(n):
                if z[i] and fc[i] > 0.0 and f < 1.0:
                    vn[i] = 0.0
        for i in range(n):
            q[i], qd[i] = qn[i], vn[i]
    for i in range(n):
        stuck[i] = stuck[i] and qd[i] == 0.0
    return ok


@njit(cache=True, _nrt=False)
def _smooth(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):  # pragma: no cover
    """One sample under a smooth law: RK4, each substep split so that h rho <= 2 (module docstring)."""
    n = q.shape[0]
    h = T / substeps
    vc, ratio, vs = fp[0], fp[1], fp[2]
    extra = 0.0 if law != 2 else (ratio - 1.0) * 0.8578 / vs
    kpeak = (ratio if law == 2 else 1.0) / vc + extra
    rows, lf, flags = sc[3], sc[2], sc[5]
    qn, vn, sdir, col = rows[12], rows[13], rows[16], rows[17]
    for i in range(n):
        stuck[i] = False
    ok = True
    for _ in range(substeps):
        # factor M + diag(armature) (all joints free) and rho = sum_i K_i (M^-1)_ii
        _dynamics(ch, pi, arm, q, qd, sc[0], rows[18], sc[6])
        ok &= _solve(fv, fc, law, fp, qd, tau, stuck, sdir, rows, 18, sc[6], lf, sc[4], 4, 14)
        rho = 0.0
        for i in range(n):
            # column i of L^-1 by forward substitution; (M^-1)_ii is its squared norm
            nrm = 0.0
            for r in range(n):
                x = 1.0 if r == i else 0.0
                for k in range(i, r):
                    x -= lf[r, k] * col[k]
                col[r] = x / lf[r, r] if r >= i else 0.0
                nrm += col[r] * col[r]
            rho += (fv[i] + fc[i] * kpeak) * nrm
        m = max(1, int(np.ceil(h * rho / 2.0)))
        dt = h / m
        for k in range(m):
            # the first step starts where the start slots were filled
            ok &= _rk4(
                ch, pi, fv, fc, arm, law, fp, q, qd, tau, dt, stuck, sdir, sc, k == 0, qn, vn, flags[1]
            )
            for i in range(n):
                q[i], qd[i] = qn[i], vn[i]
    return ok


@njit(cache=True, fastmath={"contract", "reassoc"}, _nrt=False)
def _lugre(ch, pi, fv, fc, arm, fp, q, qd, tau, T, substeps, z, stuck, sc):  # pragma: no cover
    """One sample under the LuGre law (module docstring): linearly implicit micro-steps of at most
    ``LUGRE_DT_MAX`` in ``(v, z)``, the bristle state ``z (n,)`` updated in place. ``fp`` is
    ``[friction_velocity, stribeck_ratio, stribeck_velocity, sigma0 (n), sigma1 (n)]``."""
    n = q.shape[0]
    steps = max(substeps, int(np.ceil(T / LUGRE_DT_MAX - 1e-9)))
    h = T / steps
    ratio, vs = fp[1], fp[2]
    m, rows = sc[1], sc[3]
    bias, rhs, den = rows[0], rows[1], rows[12]
    for i in range(n):
        stuck[i] = False
    for _ in range(steps):
        _dynamics(ch, pi, arm, q, qd, sc[0], bias, m)
        for i in range(n):
            s0, s1 = fp[3 + i], fp[3 + n + i]
            d, k, f0 = 1.0, fv[i], 0.0
            if fc[i] > 0.0:
                g = fc[i] * (1.0 + (ratio - 1.0) * np.exp(-((qd[i] / vs) ** 2)))
                a = s0 * abs(qd[i]) / g
                d = 1.0 + h * a
                k += (s0 * h + s1) / d
                f0 = z[i] * (s0 - s1 * a) / d
            den[i] = d
            x = h * (tau[i] - bias[i] - f0)
            for j in range(n):
                x += m[i, j] * qd[j]
            rhs[i] = x
            m[i, i] += h * k  # row i's right-hand side is formed: only row i reads m[i, i]
        if not _cholesky_solve(m, rhs):  # (M + h diag(K)) v+ = rhs, m its factor after
            return False
        for i in range(n):
            qd[i] = rhs[i]
            z[i] = (z[i] + h * qd[i]) / den[i] if fc[i] > 0.0 else 0.0
            q[i] += h * qd[i]
    ok = True
    for i in range(n):
        ok &= np.isfinite(q[i]) and np.isfinite(qd[i]) and np.isfinite(z[i])
    return ok
