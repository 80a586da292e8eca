"""The compiled sampled-data plant for any serial chain: one sample under a held torque.

The N-joint generalisation of :mod:`adaptive_dd.plant.two_link_integrator` (two links): the
torque is held over one sample ``T`` (zero-order hold) and the state is advanced by
``substeps`` classical RK4 steps; the rigid-body terms come from
:func:`adaptive_dd.plant.chain.bias_and_mass`. Joint friction is viscous ``fv_i qd_i``
plus a Coulomb term of level ``fc_i`` under one of three laws
(:data:`adaptive_dd.plant.two_link_integrator.FRICTION_CODES`).

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
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange
from numba.extending import overload
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.chain import Chain, bias_and_mass, workspace
from adaptive_dd.plant.two_link_integrator import FRICTION_CODES

__all__ = [
    "PlantParams",
    "SmoothLaw",
    "StickSlipLaw",
    "friction_law",
    "plant_batch",
    "plant_params",
    "plant_run",
    "plant_step",
]


class PlantParams(NamedTuple):
    """The physical plant of one serial arm, as the compiled step takes it.

    Attributes
    ----------
    pi : ndarray, shape (10 n,)
        Standard link parameters (payload already folded in by the caller),
        :func:`adaptive_dd.plant.chain.standard_parameters`.
    fv : ndarray, shape (n,)
        Viscous friction [N m s] (N s/m for prismatic joints).
    fc : ndarray, shape (n,)
        Coulomb friction level [N m] (N).
    armature : ndarray, shape (n,)
        Rotor inertia added to M's diagonal [kg m^2] (kg).
    law : int or StickSlipLaw or SmoothLaw
        0 stick-slip, 1 tanh, 2 stribeck (:data:`adaptive_dd.plant.two_link_integrator.FRICTION_CODES`);
        as a code, the step compiles the integrators of both families and chooses at run time; as a
        :func:`friction_law` record, only its family's.
    fparams : ndarray, shape (3,)
        ``friction_velocity, stribeck_ratio, stribeck_velocity`` of the smooth laws.
    """

    pi: NDArray[np.float64]
    fv: NDArray[np.float64]
    fc: NDArray[np.float64]
    armature: NDArray[np.float64]
    law: int | StickSlipLaw | SmoothLaw
    fparams: NDArray[np.float64]


class StickSlipLaw(NamedTuple):
    """The stick-slip law (``code`` 0) as a type of its own (:func:`friction_law`)."""

    code: int


class SmoothLaw(NamedTuple):
    """A smooth law (``code`` 1 tanh, 2 Stribeck) as a type of its own (:func:`friction_law`)."""

    code: int


def friction_law(code: int) -> StickSlipLaw | SmoothLaw:
    """Friction law ``code`` with its family (stick-slip or smooth) a compile-time choice.

    numba compiles a kernel per argument type: a plant step given this record instead of the
    integer code compiles only its family's integrator (a closed loop on a stick-slip arm does not
    compile the smooth laws' RK4 and step splitting, about a fifth of its compilation).
    """
    code = int(code)
    if code not in (0, 1, 2):
        raise ParameterError(f"friction law code of a serial arm must be 0, 1 or 2, got {code!r}")
    return StickSlipLaw(code) if code == 0 else SmoothLaw(code)


def plant_params(
    ch: Chain,
    pi: NDArray,
    fv: NDArray,
    fc: NDArray,
    armature: NDArray | None = None,
    law: str | int = "stick-slip",
    friction_velocity: float = 0.02,
    stribeck_ratio: float = 1.5,
    stribeck_velocity: float = 0.1,
) -> PlantParams:
    """Checked :class:`PlantParams` of chain ``ch`` (shapes, finite, friction >= 0, law known).

    ``law`` is a name or code of :data:`adaptive_dd.plant.two_link_integrator.FRICTION_CODES`;
    ``armature`` defaults to zeros.

    Raises
    ------
    ParameterError
        Naming the field and the offending value.
    """
    n = ch.jtype.shape[0]
    code = FRICTION_CODES.get(law, law) if isinstance(law, str) else law
    if code not in FRICTION_CODES.values():
        raise ParameterError(f"friction law must be one of {FRICTION_CODES}, got {law!r}")
    arrays = {"pi": (pi, 10 * n), "fv": (fv, n), "fc": (fc, n), "armature": (armature, n)}
    out = {}
    for name, (value, size) in arrays.items():
        a = np.zeros(size) if value is None else np.array(value, dtype=np.float64).reshape(-1)
        if a.shape != (size,) or not np.all(np.isfinite(a)):
            raise ParameterError(f"plant {name} must be {size} finite numbers, got {value!r}")
        if name != "pi" and np.any(a < 0.0):
            raise ParameterError(f"plant {name} must be >= 0, got {a}")
        out[name] = a
    fparams = np.array([friction_velocity, stribeck_ratio, stribeck_velocity], dtype=np.float64)
    if not (np.all(np.isfinite(fparams)) and fparams[0] > 0 and fparams[2] > 0 and fparams[1] >= 1):
        raise ParameterError(
            "friction_velocity and stribeck_velocity must be > 0 and stribeck_ratio >= 1, got "
            f"{friction_velocity!r}, {stribeck_velocity!r}, {stribeck_ratio!r}"
        )
    return PlantParams(out["pi"], out["fv"], out["fc"], out["armature"], int(code), fparams)


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
def _solve(fv, fc, law, fp, v, tau, stuck, sdir, bias, m, sc, acc, hold):  # pragma: no cover - compiled
    """Accelerations ``acc`` (n,) with the stuck joints held; ``hold`` (n,) torque to hold each stuck joint.

    Uses the terms ``bias, m`` of :func:`_dynamics`. Friction: law 0 ``fc sgn(v)``
    (``sdir`` at v == 0), else the smooth law. Returns False if ``M + diag(armature)``
    restricted to the free joints is not positive definite.
    """
    lf, rhs, idx = sc[2], sc[3][1], sc[4][0]
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
        idx[nf] = i
        rhs[nf] = tau[i] - bias[i] - fv[i] * v[i] - coul
        nf += 1
    # Cholesky of the free block (reciprocal diagonal kept: no division in the loops),
    # then the two triangular solves
    inv = sc[3][19]
    for jj in range(nf):
        j = idx[jj]
        d = m[j, j]
        for kk in range(jj):
            d -= lf[jj, kk] * lf[jj, kk]
        if not d > 0.0:
            return False
        d = np.sqrt(d)
        lf[jj, jj] = d
        r = 1.0 / d
        inv[jj] = r
        for ii in range(jj + 1, nf):
            x = m[idx[ii], j]
            for kk in range(jj):
                x -= lf[ii, kk] * lf[jj, kk]
            lf[ii, jj] = x * r
    for ii in range(nf):
        x = rhs[ii]
        for kk in range(ii):
            x -= lf[ii, kk] * rhs[kk]
        rhs[ii] = x * inv[ii]
    for ii in range(nf - 1, -1, -1):
        x = rhs[ii]
        for kk in range(ii + 1, nf):
            x -= lf[kk, ii] * rhs[kk]
        rhs[ii] = x * inv[ii]
    for i in range(n):
        acc[i] = 0.0
    for ii in range(nf):
        acc[idx[ii]] = rhs[ii]
    if nf == n:
        return True
    for i in range(n):
        if stuck[i]:
            x = tau[i] - bias[i]
            for j in range(n):
                x -= m[i, j] * acc[j]
            hold[i] = x
        else:
            hold[i] = 0.0
    return True


@njit(cache=True)
def _consistent(rest, stuck, acc, hold, sdir, fc):  # pragma: no cover - compiled
    """Stuck resting joints hold (|h_i| <= fc_i) and released ones accelerate in their slide direction."""
    for i in range(rest.shape[0]):
        if rest[i] and ((stuck[i] and abs(hold[i]) > fc[i]) or (not stuck[i] and acc[i] * sdir[i] <= 0.0)):
            return False
    return True


@njit(cache=True)
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
        if not _solve(fv, fc, 0, fp, v, tau, stuck, sdir, bias0, m0, sc, acc, hold):
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
        if not _solve(fv, fc, 0, fp, v, tau, stuck, sdir, bias0, m0, sc, acc, hold):
            return False
        if not _consistent(rest, stuck, acc, hold, sdir, fc):
            stuck[r] = False
    return True


# ----------------------------------------------------------------------------- integration


@njit(cache=True, fastmath={"contract", "reassoc"})
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
    rows = sc[3]
    a1, a2, a3, a4, qs, wv, xv, yv, hd, vcur = (
        rows[4],
        rows[5],
        rows[6],
        rows[7],
        rows[8],
        rows[9],
        rows[10],
        rows[11],
        rows[14],
        rows[20],
    )
    w, bias0, m0, bias, m = sc[0], sc[3][18], sc[6], sc[3][0], sc[1]
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
        ok &= _solve(fv, fc, law, fp, vcur, tau, stuck, sdir, bb, mm, sc, rows[4 + st], hd)
    for i in range(n):
        qn[i] = q[i] + (dt / 6.0) * (v[i] + 2.0 * wv[i] + 2.0 * xv[i] + yv[i])
        vn[i] = 0.0 if stuck[i] else v[i] + (dt / 6.0) * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i])
        cross[i] = False
        if law == 0 and not stuck[i]:
            s = np.sign(v[i]) if v[i] != 0.0 else sdir[i]
            cross[i] = min(wv[i] * s, xv[i] * s, yv[i] * s, vn[i] * s) <= 0.0
    return ok


@njit(cache=True)
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


@njit(cache=True)
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
        a1 = rows[4]
        for i in range(n):
            cross[i] = cross[i] and fc[i] > 0.0
            if cross[i]:
                any_cross = True
                if qd[i] * a1[i] < 0.0:
                    frac[i] = min(1.0, abs(qd[i]) / (h * abs(a1[i])))
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


@njit(cache=True)
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
        ok &= _solve(fv, fc, law, fp, qd, tau, stuck, sdir, rows[18], sc[6], sc, rows[4], rows[14])
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


def _by_law(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):  # pragma: no cover
    """One sample under ``law``: an integer code chooses at run time between :func:`_stick_slip`
    and :func:`_smooth` (both compiled), a :func:`friction_law` record at compile time."""
    raise NotImplementedError("compiled only")


@overload(_by_law)
def _by_law_typed(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
    family = getattr(law, "instance_class", None)
    if family is StickSlipLaw:

        def stick_slip(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
            return _stick_slip(ch, pi, fv, fc, arm, fp, q, qd, tau, T, substeps, stuck, sc)

        return stick_slip
    if family is SmoothLaw:

        def smooth(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
            return _smooth(ch, pi, fv, fc, arm, law.code, fp, q, qd, tau, T, substeps, stuck, sc)

        return smooth

    def either(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
        if law == 0:
            return _stick_slip(ch, pi, fv, fc, arm, fp, q, qd, tau, T, substeps, stuck, sc)
        return _smooth(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc)

    return either


def compile_family(ch, pp: PlantParams, q, qd, tau, T: float, substeps: int, stuck, sc) -> None:
    """Compile (or load from numba's cache) the integrator that a compiled step on ``pp`` calls
    (:func:`_stick_slip` or :func:`_smooth`, as :func:`_by_law` chooses), alone, by one step of
    it with these arguments (updated in place), of the types the compiled step passes it: the
    second process of a cold-cache benchmark (:func:`adaptive_dd.closed_loop.precompile.second_process`)
    fills the cache with it without compiling a step around it (the closed loop's own
    compilation inlines the step; numba does not cache :func:`_by_law`'s choice)."""
    law = pp.law
    args = (ch, pp.pi, pp.fv, pp.fc, pp.armature)
    if not isinstance(law, SmoothLaw):  # the stick-slip record, or a code: both compiled then
        _stick_slip(*args, pp.fparams, q, qd, tau, T, substeps, stuck, sc)
    if not isinstance(law, StickSlipLaw):
        _smooth(*args, int(getattr(law, "code", law)), pp.fparams, q, qd, tau, T, substeps, stuck, sc)


@njit(cache=True, inline="always")
def _step(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):  # pragma: no cover
    ok = _by_law(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc)
    for i in range(q.shape[0]):
        ok &= np.isfinite(q[i]) and np.isfinite(qd[i])
    return ok


@njit(cache=True)
def plant_step(ch, pp, q, qd, tau, T, substeps, stuck):  # pragma: no cover - compiled
    """Advance one arm by one sample in place under the held torque ``tau``.

    Parameters
    ----------
    ch : Chain
    pp : PlantParams
    q, qd : ndarray, shape (n,)
        Joint positions [rad or m] and velocities, updated in place.
    tau : ndarray, shape (n,)
        Applied joint torque [N m or N], held over the sample.
    T : float
        Sample period [s].
    substeps : int
        RK4 steps per sample (further split where needed, module docstring).
    stuck : ndarray of bool, shape (n,)
        Output: joints held at rest by Coulomb friction at the end of the sample
        (stick-slip law; False under the smooth laws). Modes are decided anew from
        the velocities at every substep, so its input value is not used.

    Returns
    -------
    bool
        False if a mass matrix was not positive definite or the state is not finite.
    """
    return plant_step_in(ch, pp, q, qd, tau, T, substeps, stuck, _scratch(q.shape[0]))


@njit(cache=True)
def plant_scratch(n):  # pragma: no cover - compiled
    """The scratch arrays of one arm's step (:func:`plant_step_in`), allocated once."""
    return _scratch(n)


@njit(cache=True, inline="always")
def plant_step_in(ch, pp, q, qd, tau, T, substeps, stuck, sc):  # pragma: no cover - compiled
    """:func:`plant_step` with its scratch ``sc`` (:func:`plant_scratch`) given: no
    allocation per sample (a closed loop allocates it once per trial)."""
    return _step(ch, pp.pi, pp.fv, pp.fc, pp.armature, pp.law, pp.fparams, q, qd, tau, T, substeps, stuck, sc)


@njit(cache=True)
def plant_run(ch, pp, q, qd, tau, T, substeps, q_out, qd_out):  # pragma: no cover - compiled
    """Open loop over a torque sequence: ``tau`` (n_samples, n) held one sample each.

    ``q, qd`` (n,) are the initial state (updated in place to the final one);
    ``q_out, qd_out`` (n_samples, n) receive the state after each sample. Returns
    the number of samples completed (< n_samples: the step failed, see
    :func:`plant_step`).
    """
    n = q.shape[0]
    sc = _scratch(n)
    stuck = np.zeros(n, dtype=np.bool_)
    for k in range(tau.shape[0]):
        if not _step(
            ch, pp.pi, pp.fv, pp.fc, pp.armature, pp.law, pp.fparams, q, qd, tau[k], T, substeps, stuck, sc
        ):
            return k
        for i in range(n):
            q_out[k, i] = q[i]
            qd_out[k, i] = qd[i]
    return tau.shape[0]


@njit(cache=True, parallel=True)
def plant_batch(ch, pi, fv, fc, armature, law, fparams, q, qd, tau, T, substeps, stuck):  # pragma: no cover
    """One sample of many trials of the same chain (prange over trials), in place.

    Parameters
    ----------
    pi : ndarray, shape (n_trials, 10 n)
    fv, fc, armature : ndarray, shape (n_trials, n)
    law : int
    fparams : ndarray, shape (3,)
    q, qd, tau : ndarray, shape (n_trials, n)
    stuck : ndarray of bool, shape (n_trials, n)
        Output, as in :func:`plant_step`.

    Returns
    -------
    ndarray of bool, shape (n_trials,)
        False for trials whose step failed (see :func:`plant_step`).
    """
    n_trials, n = q.shape
    ok = np.empty(n_trials, dtype=np.bool_)
    for t in prange(n_trials):
        sc = _scratch(n)
        ok[t] = _step(
            ch, pi[t], fv[t], fc[t], armature[t], law, fparams, q[t], qd[t], tau[t], T, substeps, stuck[t], sc
        )
    return ok
