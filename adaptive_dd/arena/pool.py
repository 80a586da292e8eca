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
"""

from __future__ import annotations

import os
import pickle
from contextlib import contextmanager

__all__ = ["largest_first", "run_units"]

_ONE_THREAD = {"NUMBA_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


@contextmanager
def _environment(values: dict[str, str]):
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


def run_units(run_unit, units: list, controllers, seeds, progress: bool, workers: int, costs=None) -> list:
    """``[(cells, compile_seconds, run_seconds), ...]`` of ``run_unit(unit, controllers, seeds,
    progress)`` (:func:`~adaptive_dd.arena.leaderboard.run_unit`, passed in: a module-level function
    the workers import by name) for each unit, in order; ``workers > 1``: in that many processes (a
    unit that cannot be sent to one runs in this process), handed out by :func:`largest_first` of
    ``costs`` (each unit's expected CPU time in any unit; default: in order)."""
    if workers <= 1 or len(units) <= 1:
        return [run_unit(u, controllers, seeds, progress) for u in units]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    out: list = [None] * len(units)
    here = [i for i, u in enumerate(units) if not _picklable(u)]
    sent = [i for i in largest_first(costs or [0.0] * len(units)) if i not in here]
    ctx = multiprocessing.get_context("spawn")
    with _environment(_ONE_THREAD), ProcessPoolExecutor(min(workers, len(sent)), mp_context=ctx) as pool:
        futures = {i: pool.submit(run_unit, units[i], controllers, seeds, False) for i in sent}
        for i in here:
            out[i] = run_unit(units[i], controllers, seeds, progress)
        for i, f in futures.items():
            out[i] = f.result()
    return out
