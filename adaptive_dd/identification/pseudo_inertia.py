"""Physical consistency of a rigid body's ten inertial parameters: projection of its pseudo-inertia.

A body's parameters ``[m, m c (3), Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` (about its frame's origin,
Pinocchio's order) are physically consistent exactly when its 4 x 4 pseudo-inertia
``J = [[tr(I)/2 1 - I, m c], [m c^T, m]]`` is positive semidefinite (Wensing, Kim and
Slotine, "Linear matrix inequalities for physically consistent inertial parameter
identification", IEEE RA-L 3(1), 2018). :func:`project_payload` clips J's eigenvalues: the
nearest consistent body in J's Frobenius norm; given a radius R, it then also bounds the body to
a ball of radius R about its frame (the bounding-ellipsoid constraint of the same paper,
``tr(Sigma) <= m R^2`` for J's second-moment block ``Sigma``, which implies ``|c| <= R``).
Compiled (a per-sample step calls it).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["parameters_of", "project_payload", "project_payload_in", "pseudo_inertia"]


@njit(cache=True)
def pseudo_inertia(phi, J):  # pragma: no cover - compiled
    """``J (4, 4)``, the pseudo-inertia of ``phi = [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz,
    Izz]`` (about one frame): ``[[tr(I)/2 1 - I, h], [h^T, m]]``."""
    half = 0.5 * (phi[4] + phi[6] + phi[9])
    J[0, 0], J[1, 1], J[2, 2] = half - phi[4], half - phi[6], half - phi[9]
    J[0, 1] = J[1, 0] = -phi[5]
    J[0, 2] = J[2, 0] = -phi[7]
    J[1, 2] = J[2, 1] = -phi[8]
    for r in range(3):
        J[r, 3] = J[3, r] = phi[1 + r]
    J[3, 3] = phi[0]


@njit(cache=True)
def parameters_of(J, phi):  # pragma: no cover - compiled
    """The inverse of :func:`pseudo_inertia`: ``phi (10,)`` of ``J (4, 4)`` (``I = tr(S) 1 - S``)."""
    tr = J[0, 0] + J[1, 1] + J[2, 2]
    phi[0] = J[3, 3]
    for r in range(3):
        phi[1 + r] = 0.5 * (J[r, 3] + J[3, r])
    phi[4], phi[6], phi[9] = tr - J[0, 0], tr - J[1, 1], tr - J[2, 2]
    phi[5] = -0.5 * (J[0, 1] + J[1, 0])
    phi[7] = -0.5 * (J[0, 2] + J[2, 0])
    phi[8] = -0.5 * (J[1, 2] + J[2, 1])


@njit(cache=True)
def _eigh4(J):  # pragma: no cover - compiled
    """Eigenvalues and eigenvectors (columns) of a symmetric 4 x 4 matrix (``J``'s leading block) by
    cyclic Jacobi rotations: :func:`_eigh4_in` into new arrays, ``(lam, V)``."""
    lam, V = np.empty(4), np.empty((4, 4))
    _eigh4_in(J, np.empty((4, 4)), V, lam)
    return lam, V


@njit(cache=True)
def _eigh4_in(J, A, V, lam):  # pragma: no cover - compiled
    """:func:`_eigh4` into ``lam (4,)`` and ``V (4, 4)`` (columns), ``A (4, 4)`` scratch (none of
    them overlapping ``J``'s leading block): no allocation (the estimator's step calls it).

    Cheaper than LAPACK through numba for this size; converges quadratically (a handful of
    sweeps to the last bits).
    """
    for a in range(4):  # J's leading 4 x 4 block (J may be a larger scratch)
        for b in range(4):
            A[a, b] = J[a, b]
            V[a, b] = 1.0 if a == b else 0.0
    for _ in range(30):
        off = 0.0
        scale = 0.0
        for a in range(4):
            scale += A[a, a] * A[a, a]
            for b in range(a + 1, 4):
                off += A[a, b] * A[a, b]
        if off <= 1e-32 * scale or off == 0.0:
            break
        for a in range(3):
            for b in range(a + 1, 4):
                if A[a, b] == 0.0:
                    continue
                theta = (A[b, b] - A[a, a]) / (2.0 * A[a, b])
                t = np.sign(theta) / (abs(theta) + np.sqrt(theta * theta + 1.0)) if theta != 0.0 else 1.0
                cs = 1.0 / np.sqrt(t * t + 1.0)
                sn = t * cs
                for k in range(4):  # A <- A G (columns a, b)
                    x, y = A[k, a], A[k, b]
                    A[k, a] = cs * x - sn * y
                    A[k, b] = sn * x + cs * y
                for k in range(4):  # A <- G^T A (rows a, b)
                    x, y = A[a, k], A[b, k]
                    A[a, k] = cs * x - sn * y
                    A[b, k] = sn * x + cs * y
                for k in range(4):
                    x, y = V[k, a], V[k, b]
                    V[k, a] = cs * x - sn * y
                    V[k, b] = sn * x + cs * y
    for k in range(4):
        lam[k] = A[k, k]


@njit(cache=True)
def _positive_definite(J, shift):  # pragma: no cover - compiled
    """True if ``J[:4, :4] - shift I`` is positive definite (a Cholesky factorisation succeeds);
    the factor is written into ``J[4:8, :4]`` (scratch; each entry read only after it is written)."""
    for a in range(4):
        for b in range(a + 1):
            acc = J[a, b] - (shift if a == b else 0.0)
            for k in range(b):
                acc -= J[4 + a, k] * J[4 + b, k]
            if a == b:
                if not acc > 0.0:
                    return False
                J[4 + a, a] = np.sqrt(acc)
            else:
                J[4 + a, b] = acc / J[4 + b, b]
    return True


@njit(cache=True)
def _bound_ball(dst, radius):  # pragma: no cover - compiled
    """:func:`_bound_ball_in` with its scratch made for this call."""
    _bound_ball_in(dst, radius, np.empty((3, 3)), np.empty(3))


@njit(cache=True)
def _bound_ball_in(dst, radius, S, h):  # pragma: no cover - compiled
    """Bound a consistent payload (10,) in place to a ball of ``radius`` [m] about its frame.

    With ``Sigma = tr(I)/2 1 - I`` (J's second-moment block) and ``h = m c``: if
    ``|c| > R``, h is scaled to ``|c| = R``; then the Schur complement
    ``S = Sigma - h h^T / m`` (positive semidefinite for a consistent body) is scaled by
    ``s in [0, 1]`` so that ``tr(Sigma) <= m R^2`` (Wensing, Kim and Slotine, RA-L 2018,
    bounding ellipsoid; a ball here). Scaling S keeps J positive semidefinite; as ``m -> 0``
    the first and second moments go to 0 with it. A payload within the ball is unchanged.
    """
    m = dst[0]
    r2 = radius * radius
    if not m > 0.0:
        for k in range(10):
            dst[k] = 0.0
        return
    hh = dst[1] * dst[1] + dst[2] * dst[2] + dst[3] * dst[3]
    tr_sigma = 0.5 * (dst[4] + dst[6] + dst[9])
    if hh <= m * m * r2 and tr_sigma <= m * r2:
        return
    S[0, 0], S[1, 1], S[2, 2] = tr_sigma - dst[4], tr_sigma - dst[6], tr_sigma - dst[9]
    S[0, 1] = S[1, 0] = -dst[5]
    S[0, 2] = S[2, 0] = -dst[7]
    S[1, 2] = S[2, 1] = -dst[8]
    for k in range(3):
        h[k] = dst[1 + k]
    if hh > m * m * r2:  # centre of mass beyond the ball: onto its surface
        f = np.sqrt(m * m * r2 / hh)
        for k in range(3):
            h[k] *= f
        hh = m * m * r2
    tr_s = 0.0
    for a in range(3):
        for b in range(3):
            S[a, b] -= h[a] * h[b] / m
        tr_s += S[a, a]
    room = m * r2 - hh / m  # what the spread about the centre of mass may add to tr(Sigma)
    scale = 1.0
    if tr_s > room and tr_s > 0.0:  # (no spread to scale when tr_s is 0: room < 0 by round-off only)
        scale = max(room, 0.0) / tr_s
    for a in range(3):
        for b in range(3):
            S[a, b] = h[a] * h[b] / m + scale * S[a, b]
    tr = S[0, 0] + S[1, 1] + S[2, 2]
    for k in range(3):
        dst[1 + k] = h[k]
    dst[4] = tr - S[0, 0]
    dst[5] = -S[0, 1]
    dst[6] = tr - S[1, 1]
    dst[7] = -S[0, 2]
    dst[8] = -S[1, 2]
    dst[9] = tr - S[2, 2]


@njit(cache=True)
def project_payload(src, dst, eig_min, radius=0.0):  # pragma: no cover - compiled
    """Nearest physically consistent payload (10,) -> dst: clip the pseudo-inertia's eigenvalues.

    ``src = [m, m c (3), Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` about the payload frame. The 4 x 4
    pseudo-inertia ``J = [[tr(I)/2 1 - I, m c], [m c^T, m]]`` (Wensing, Kim and Slotine,
    RA-L 2018) is made positive semidefinite by clipping its eigenvalues at ``eig_min``
    (the Frobenius-nearest such J); mass ``J[3, 3] >= 0`` follows. If ``radius`` [m] > 0,
    the result is then bounded to a ball of that radius about the payload frame
    (:func:`_bound_ball`): ``|c| <= radius`` and ``tr(Sigma) <= m radius^2``.
    """
    project_payload_in(src, dst, eig_min, radius, np.empty((10, 8)))


@njit(cache=True)
def project_payload_in(src, dst, eig_min, radius, J):  # pragma: no cover - compiled
    """:func:`project_payload` with its scratch given, ``J`` (at least 10 x 8: the pseudo-inertia in
    its first four rows, a Cholesky factor in the next four, the eigenvectors and eigenvalues and
    the ball's bound in the rest; no allocation: the estimator's step calls it every sample)."""
    _project_psd(src, dst, eig_min, J)
    if radius > 0.0 and np.isfinite(dst[0]):
        _bound_ball_in(dst, radius, J[4:7, 4:7], J[8, 4:7])  # (J's content is dead by then)


@njit(cache=True)
def _project_psd(src, dst, eig_min, J):  # pragma: no cover - compiled
    """Eigenvalue clipping of :func:`project_payload` (without the ball); ``J`` scratch as
    :func:`project_payload_in`'s."""
    pseudo_inertia(src, J)
    ok = True
    for a in range(4):
        for b in range(4):
            if not np.isfinite(J[a, b]):
                ok = False
    if not ok:
        for k in range(10):
            dst[k] = np.nan
        return
    if _positive_definite(J, eig_min):  # already consistent (the common case): unchanged
        for k in range(10):
            dst[k] = src[k]
        return
    lam, V = J[8, 0:4], J[4:8, 4:8]
    _eigh4_in(J, J[0:4, 4:8], V, lam)
    if lam.min() >= eig_min:
        for k in range(10):
            dst[k] = src[k]
        return
    for k in range(4):
        lam[k] = max(lam[k], eig_min)
    for a in range(4):
        for b in range(4):
            acc = 0.0
            for k in range(4):
                acc += V[a, k] * lam[k] * V[b, k]
            J[a, b] = acc
    parameters_of(J, dst)  # its off-diagonal terms the mean of J's two (symmetric to the last bit)
