"""The leaderboard's units of work (a scenario, or one drawn arm) run in worker processes.

A unit is everything the leaderboard does for one scenario or one drawn arm: the arm's set-up
(its URDF, the excitation phase and each seed's identification, done once for every controller)
and every controller's trials (:func:`~adaptive_dd.arena.leaderboard.run_unit`). Units share
nothing, so ``workers = N`` runs them in N processes (``spawn``: each a fresh interpreter; numba's
cache is shared and its compile lock, :mod:`adaptive_dd._numba_cache`, keeps two processes from
compiling the same kernel), each on one numba thread and one BLAS thread so that N workers use N
cores. The units are handed out largest first (:func:`largest_first`: a drawn arm with an
excitation phase before a scenario without, more joints first), so that the last units to finish
are short and no core idles long at the end. The cells come back in the units' order and the rows
(and their bootstrap draws) are made in the parent, so the table depends neither on ``workers``
nor on that order.

Every unit runs with the C library's allocator keeping freed memory for reuse
(:func:`reused_memory`): a drawn arm's identification makes and frees arrays of tens of MB
(a 20 s record's regressors, ``(samples, joints, base parameters)``), each of which the
allocator would otherwise map afresh from the kernel and fault in page by page (system CPU
time, more of it the busier the machine).
"""

from __future__ import annotations

import os
import pickle
from contextlib import contextmanager

__all__ = ["environment", "largest_first", "reused_memory", "run_units"]

_ONE_THREAD = {"NUMBA_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


@contextmanager
def environment(values: dict[str, str]):
    """``os.environ`` with ``values`` set for the block (the worker processes it spawns inherit it)."""
    old = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


_M_TRIM_THRESHOLD, _M_MMAP_MAX = -1, -4  # mallopt's parameters (glibc's malloc.h)
_DEFAULT_TRIM, _DEFAULT_MMAP_MAX = 128 * 1024, 65536  # glibc's defaults


def _libc():
    """glibc through ctypes, or None (another C library: :func:`reused_memory` does nothing)."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        return libc if hasattr(libc, "mallopt") and hasattr(libc, "malloc_trim") else None
    except OSError:
        return None


@contextmanager
def reused_memory():
    """Within the block, glibc's ``malloc`` serves large arrays from its heap and keeps what is
    freed for the next one (no ``mmap`` per array, no trimming), instead of mapping each array of
    more than its threshold afresh (zero pages faulted in one by one, system CPU time); after it,
    glibc's default values again (its mmap threshold then fixed at them, no longer adapting to
    the sizes freed) and the heap's free memory returned (``malloc_trim``). Results do not
    change (the same arithmetic on memory from another place); elsewhere than glibc, nothing."""
    libc = _libc()
    if libc is None:
        yield
        return
    libc.mallopt(_M_MMAP_MAX, 0)
    libc.mallopt(_M_TRIM_THRESHOLD, 2**30)
    try:
        yield
    finally:
        libc.mallopt(_M_MMAP_MAX, _DEFAULT_MMAP_MAX)
        libc.mallopt(_M_TRIM_THRESHOLD, _DEFAULT_TRIM)
        libc.malloc_trim(0)


def _run_reused(run_unit, unit, controllers, seeds, progress, design=None):
    """``run_unit(unit, controllers, seeds, progress)`` (and ``design=`` when given) within
    :func:`reused_memory`."""
    with reused_memory():
        if design is None:
            return run_unit(unit, controllers, seeds, progress)
        return run_unit(unit, controllers, seeds, progress, design=design)


def _result_or_none(future):
    """The future's result, or None if it raised (the unit then does that part itself, and raises
    there as it would have)."""
    try:
        return future.result()
    except Exception:
        return None


def _picklable(unit) -> bool:
    try:
        pickle.dumps(unit)
    except Exception:  # a Scenario object holding something pickle cannot carry: run it here
        return False
    return True


def largest_first(costs: list[float]) -> list[int]:
    """The units' indices by decreasing ``costs`` (ties in the units' order): the order in which
    :func:`run_units` hands them to its workers (longest processing time first)."""
    return sorted(range(len(costs)), key=lambda i: (-costs[i], i))


def run_units(
    run_unit, units: list, controllers, seeds, progress: bool, workers: int, costs=None, design=None
) -> list:
    """``[(cells, compile_seconds, run_seconds), ...]`` of ``run_unit(unit, controllers, seeds,
    progress)`` (:func:`~adaptive_dd.arena.leaderboard.run_unit`, passed in: a module-level function
    the workers import by name) for each unit, in order; ``workers > 1``: in that many processes (a
    unit that cannot be sent to one runs in this process), handed out by :func:`largest_first` of
    ``costs`` (each unit's expected CPU time in any unit; default: in order).

    ``design`` (:func:`~adaptive_dd.arena.leaderboard.unit_design`, module-level): with workers, the
    part of each unit after the first that needs no compiled closed loop (a drawn arm's excitation
    design), run as tasks of their own queued right after the first unit and handed to their units
    (``run_unit(..., design=...)``). On a cold cache the first unit compiles the closed loop (minutes,
    one process) while the other workers would wait for it: they make the designs meanwhile. The
    same function on the same arm: the table is the same."""
    if workers <= 1 or len(units) <= 1:
        return [_run_reused(run_unit, u, controllers, seeds, progress) for u in units]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    out: list = [None] * len(units)
    here = [i for i, u in enumerate(units) if not _picklable(u)]
    sent = [i for i in largest_first(costs or [0.0] * len(units)) if i not in here]
    ctx = multiprocessing.get_context("spawn")
    with environment(_ONE_THREAD), ProcessPoolExecutor(min(workers, len(sent)), mp_context=ctx) as pool:

        def submit(i, d=None):
            return pool.submit(_run_reused, run_unit, units[i], controllers, seeds, False, d)

        if design is None or len(sent) < 2:
            futures = {i: submit(i) for i in sent}
        else:
            futures = {sent[0]: submit(sent[0])}
            made = {i: pool.submit(design, units[i]) for i in sent[1:]}
            for i in sent[1:]:  # each unit queued once its design is back (in order: largest first)
                futures[i] = submit(i, _result_or_none(made[i]))
        for i in here:
            out[i] = _run_reused(run_unit, units[i], controllers, seeds, progress)
        for i, f in futures.items():
            out[i] = f.result()
    return out
