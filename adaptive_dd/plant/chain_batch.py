"""The serial-chain kernels over a batch of states: ``(..., n)`` arrays in, one compiled loop.

Each ``*_batch`` function broadcasts its joint arrays to one batch shape, checks they are
finite, and runs the one-state kernel of :mod:`adaptive_dd.plant.chain_dynamics` or
:mod:`adaptive_dd.plant.chain_regressor` over the flattened batch in a compiled loop. The
arrays it passes are writable and contiguous (a read-only one is another numba type), so
each kernel is compiled once for all its callers (``tests/test_compile_once.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant.chain_dynamics import (
    coriolis_matrix,
    forward_dynamics,
    mass_matrix_in,
    rnea_in,
    rnea_ref_in,
    workspace,
)
from adaptive_dd.plant.chain_regressor import _regressor_blocks_in

if TYPE_CHECKING:
    from adaptive_dd.plant.chain import Chain

__all__ = [
    "coriolis_matrix_batch",
    "forward_dynamics_batch",
    "mass_matrix_batch",
    "regressor_batch",
    "rnea_batch",
    "rnea_ref_batch",
    "slotine_li_regressor_batch",
]


@njit(cache=True)
def _rnea_loop(ch, pi, q, qd, qdd, out):  # pragma: no cover - compiled
    w = workspace(q.shape[1])  # one scratch for the batch
    for b in range(q.shape[0]):
        rnea_in(ch, pi, q[b], qd[b], qdd[b], w, out[b])


@njit(cache=True)
def _rnea_ref_loop(ch, pi, q, qd, qdr, qddr, out):  # pragma: no cover - compiled
    w = workspace(q.shape[1])
    for b in range(q.shape[0]):
        rnea_ref_in(ch, pi, q[b], qd[b], qdr[b], qddr[b], w, out[b])


@njit(cache=True)
def _mass_loop(ch, pi, q, out):  # pragma: no cover - compiled
    w = workspace(q.shape[1])
    for b in range(q.shape[0]):
        mass_matrix_in(ch, pi, q[b], w, out[b])


@njit(cache=True)
def _coriolis_loop(ch, pi, q, qd, out):  # pragma: no cover - compiled
    for b in range(q.shape[0]):
        coriolis_matrix(ch, pi, q[b], qd[b], out[b])


@njit(cache=True)
def _fd_loop(ch, pi, armature, q, qd, tau, out):  # pragma: no cover - compiled
    ok = True
    for b in range(q.shape[0]):
        ok &= forward_dynamics(ch, pi, armature, q[b], qd[b], tau[b], out[b])
    return ok


@njit(cache=True)
def _regressor_loop(ch, q, qd, qdr, qddr, same, out):  # pragma: no cover - compiled
    """:func:`~adaptive_dd.plant.chain_regressor.regressor` (``same``: ``qdr`` is ``qd``) or
    :func:`~adaptive_dd.plant.chain_regressor.slotine_li_regressor` over the batch."""
    n = q.shape[1]
    w, a = workspace(n), np.empty((6, 10))
    for b in range(q.shape[0]):
        _regressor_blocks_in(ch, q[b], qd[b], qdr[b], qddr[b], same, np.int64(0), n, w, a, out[b], 0)


def _states(ch: Chain, *arrays: NDArray) -> tuple[tuple[int, ...], list[NDArray]]:
    """Broadcast joint arrays (..., n) to one batch shape and flatten them to (B, n), finite checked."""
    n = ch.jtype.shape[0]
    arrs = [np.asarray(a, dtype=np.float64) for a in arrays]
    for k, a in enumerate(arrs):
        if a.ndim == 0 or a.shape[-1] != n:
            raise SignalError(f"joint array {k} has shape {a.shape}, expected (..., {n})")
        if not np.all(np.isfinite(a)):
            raise SignalError(f"joint array {k} has non-finite values")
    batch = np.broadcast_shapes(*(a.shape[:-1] for a in arrs))
    # writable copies where needed: a read-only view (broadcast_to's) is another numba type, and
    # each kernel would be compiled once more for it than the closed loop compiles it
    flat = [np.require(np.broadcast_to(a, (*batch, n)).reshape(-1, n), requirements="CW") for a in arrs]
    return batch, flat


def _pi(ch: Chain, pi: NDArray) -> NDArray[np.float64]:
    pi = np.require(pi, dtype=np.float64, requirements="CW")
    if pi.shape != (10 * ch.jtype.shape[0],):
        raise ParameterError(f"pi has shape {pi.shape}, expected ({10 * ch.jtype.shape[0]},)")
    return pi


def rnea_batch(ch: Chain, pi: NDArray, q: NDArray, qd: NDArray, qdd: NDArray) -> NDArray[np.float64]:
    """:func:`~adaptive_dd.plant.chain_dynamics.rnea` over a batch: q, qd, qdd (..., n) -> torques
    (..., n)."""
    batch, (q, qd, qdd) = _states(ch, q, qd, qdd)
    out = np.empty_like(q)
    _rnea_loop(ch, _pi(ch, pi), q, qd, qdd, out)
    return out.reshape(batch + out.shape[1:])


def rnea_ref_batch(
    ch: Chain, pi: NDArray, q: NDArray, qd: NDArray, qdr: NDArray, qddr: NDArray
) -> NDArray[np.float64]:
    """:func:`~adaptive_dd.plant.chain_dynamics.rnea_ref` over a batch: (..., n) arrays -> torques
    (..., n)."""
    batch, (q, qd, qdr, qddr) = _states(ch, q, qd, qdr, qddr)
    out = np.empty_like(q)
    _rnea_ref_loop(ch, _pi(ch, pi), q, qd, qdr, qddr, out)
    return out.reshape(batch + out.shape[1:])


def mass_matrix_batch(ch: Chain, pi: NDArray, q: NDArray) -> NDArray[np.float64]:
    """:func:`~adaptive_dd.plant.chain_dynamics.mass_matrix` over a batch: q (..., n) -> M (..., n, n)."""
    batch, (q,) = _states(ch, q)
    n = q.shape[1]
    out = np.empty((q.shape[0], n, n))
    _mass_loop(ch, _pi(ch, pi), q, out)
    return out.reshape((*batch, n, n))


def coriolis_matrix_batch(ch: Chain, pi: NDArray, q: NDArray, qd: NDArray) -> NDArray[np.float64]:
    """:func:`coriolis_matrix` over a batch: q, qd (..., n) -> C (..., n, n)."""
    batch, (q, qd) = _states(ch, q, qd)
    n = q.shape[1]
    out = np.empty((q.shape[0], n, n))
    _coriolis_loop(ch, _pi(ch, pi), q, qd, out)
    return out.reshape((*batch, n, n))


def forward_dynamics_batch(
    ch: Chain, pi: NDArray, armature: NDArray, q: NDArray, qd: NDArray, tau: NDArray
) -> NDArray[np.float64]:
    """:func:`forward_dynamics` over a batch: (..., n) arrays -> qdd (..., n).

    Raises
    ------
    SignalError
        If the mass matrix is not positive definite or the result not finite in some state.
    """
    batch, (q, qd, tau) = _states(ch, q, qd, tau)
    arm = np.ascontiguousarray(armature, dtype=np.float64)
    if arm.shape != (q.shape[1],):
        raise ParameterError(f"armature has shape {arm.shape}, expected ({q.shape[1]},)")
    out = np.empty_like(q)
    if not _fd_loop(ch, _pi(ch, pi), arm, q, qd, tau, out):
        bad = np.flatnonzero(~np.all(np.isfinite(out), axis=1))
        raise SignalError(f"forward dynamics failed (mass matrix not positive definite?) at states {bad[:5]}")
    return out.reshape(batch + out.shape[1:])


def regressor_batch(ch: Chain, q: NDArray, qd: NDArray, qdd: NDArray) -> NDArray[np.float64]:
    """:func:`~adaptive_dd.plant.chain_regressor.regressor` over a batch: (..., n) arrays -> Y
    (..., n, 10 n)."""
    batch, (q, qd, qdd) = _states(ch, q, qd, qdd)
    n = q.shape[1]
    out = np.empty((q.shape[0], n, 10 * n))
    _regressor_loop(ch, q, qd, qd, qdd, np.bool_(True), out)
    return out.reshape((*batch, n, 10 * n))


def slotine_li_regressor_batch(
    ch: Chain, q: NDArray, qd: NDArray, qdr: NDArray, qddr: NDArray
) -> NDArray[np.float64]:
    """:func:`~adaptive_dd.plant.chain_regressor.slotine_li_regressor` over a batch: (..., n) arrays -> Y
    (..., n, 10 n)."""
    batch, (q, qd, qdr, qddr) = _states(ch, q, qd, qdr, qddr)
    n = q.shape[1]
    out = np.empty((q.shape[0], n, 10 * n))
    _regressor_loop(ch, q, qd, qdr, qddr, np.bool_(False), out)
    return out.reshape((*batch, n, 10 * n))
