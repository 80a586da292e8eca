"""The local sweep cluster's worker preload: a worker ignores Ctrl-C.

Ctrl-C in a terminal reaches every process of its group, the cluster's workers too, which then
printed a traceback each before the sweep's own "interrupted" line. The sweep (the parent)
handles the interrupt: it closes the cluster, whose nannies stop the workers; finished tasks'
cells are kept and the next run resumes from them (:mod:`adaptive_dd.sweep`).
"""

from __future__ import annotations

import signal
import threading

__all__ = ["dask_setup"]


def dask_setup(worker) -> None:
    """Dask's preload hook, run as each worker starts: ignore SIGINT (main thread only)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
