"""The threads of the BLAS libraries numpy and scipy ship (OpenBLAS), set for a block of code.

The leaderboard's identification and excitation design call BLAS on small matrices (a few
hundred rows by ~60 columns in the design's cost, a record's ~10^5 rows in its least squares)
many thousands of times. On a shared machine OpenBLAS's worker threads then spin waiting for a
core: timed by hand (``time.process_time`` around the calls) on 2 cores at a load of ~10, the
design's information matrix of a 6-joint drawn arm took 23.7 CPU ms per call with 2 threads
against 0.71 with one, a (140 000 x 60) QR 2.1 CPU s against 0.54. :func:`single_thread_blas` holds
every OpenBLAS found loaded to one thread for the block (what ``OPENBLAS_NUM_THREADS=1`` does at
start-up) and restores the count after; where none is found (another BLAS), it does nothing.
"""

from __future__ import annotations

import contextlib
import ctypes
import glob
import os

__all__ = ["blas_libraries", "single_thread_blas"]

_SYMBOLS = (  # (get, set) pairs, by how numpy's and scipy's wheels and plain OpenBLAS name them
    ("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
    ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
    ("openblas_get_num_threads64_", "openblas_set_num_threads64_"),
    ("openblas_get_num_threads", "openblas_set_num_threads"),
)
_FOUND: list | None = None


def blas_libraries() -> list[tuple[object, object]]:
    """``[(get, set), ...]``: the thread-count functions of each OpenBLAS that numpy and scipy
    load (their wheels' ``*.libs`` folders), found once."""
    global _FOUND
    if _FOUND is not None:
        return _FOUND
    import numpy
    import scipy

    found = []
    for pkg in (numpy, scipy):
        folder = os.path.join(os.path.dirname(os.path.dirname(pkg.__file__)), pkg.__name__ + ".libs")
        for path in sorted(glob.glob(os.path.join(folder, "*openblas*"))):
            try:
                lib = ctypes.CDLL(path)
            except OSError:
                continue
            for get, set_ in _SYMBOLS:
                if hasattr(lib, get) and hasattr(lib, set_):
                    found.append((getattr(lib, get), getattr(lib, set_)))
                    break
    _FOUND = found
    return found


@contextlib.contextmanager
def single_thread_blas():
    """Run the block with every OpenBLAS found (:func:`blas_libraries`) on one thread."""
    libs = blas_libraries()
    before = [int(get()) for get, _ in libs]
    for _, set_ in libs:
        set_(1)
    try:
        yield
    finally:
        for (_, set_), n in zip(libs, before, strict=True):
            set_(n)
