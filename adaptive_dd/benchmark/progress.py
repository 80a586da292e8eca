"""A benchmark's clock and progress bar, with numba's compilation kept apart.

:class:`RunClock` listens to numba's compilation events during a run: it counts the seconds spent
compiling (the report prints them apart from the run's wall time), shows no progress bar until
the first samples have run (none while the kernels compile: its rate and time-to-go would count
the compilation), hides the bar while a later kernel compiles, and moves the bar's clock past
each compilation, so its rate and time-to-go count only the samples' own time.
"""

from __future__ import annotations

import time

from numba.core import event

__all__ = ["RunClock"]


class RunClock(event.Listener):
    """Seconds inside numba's compilations during a run, and the run's progress bar.

    Parameters
    ----------
    total : int
        Samples the run steps, over every controller and trial batch.
    desc : str
        The bar's label.
    show : bool
        Whether to show a bar (a ``tqdm`` one, made at the first :meth:`update`).
    timer : callable
        The clock [s] (the bar's own: ``time.time``).

    Attributes
    ----------
    compile_seconds : float
        Wall time [s] inside at least one numba compilation since the clock started.

    Examples
    --------
    >>> clock = RunClock(1000, "demo", show=False)
    >>> with clock:
    ...     clock.update(1000)
    >>> clock.compile_seconds
    0.0
    """

    def __init__(self, total: int, desc: str, show: bool = True, timer=time.time) -> None:
        self.total, self.desc, self.show, self.timer = int(total), desc, bool(show), timer
        self.bar = None
        self.compile_seconds = 0.0
        self._depth, self._t0 = 0, 0.0
        self._listening = None

    # ------------------------------------------------------------------ numba's events
    def on_start(self, ev) -> None:
        if self._depth == 0:
            self._t0 = self.timer()
            if self.bar is not None:
                self.bar.clear()
        self._depth += 1

    def on_end(self, ev) -> None:
        self._depth = max(self._depth - 1, 0)
        if self._depth == 0:
            spent = self.timer() - self._t0
            self.compile_seconds += spent
            if self.bar is not None:  # the bar's clock moved past the compilation
                self.bar.start_t += spent
                self.bar.last_print_t += spent
                self.bar.refresh()

    def __enter__(self) -> RunClock:
        self._listening = event.install_listener("numba:compile", self)
        self._listening.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        self._listening.__exit__(*exc)
        self.close()

    # ------------------------------------------------------------------ the bar's interface
    def update(self, n: int) -> None:
        """``n`` more samples run (the bar appears at the first)."""
        if self.bar is not None:
            self.bar.update(n)
        elif self.show:
            from tqdm.auto import tqdm

            self.bar = tqdm(
                total=self.total, initial=n, desc=self.desc, unit="sample", mininterval=0.5, unit_scale=True
            )
            self.bar._time = self.timer  # one clock for the bar and the compilations
            self.bar.start_t = self.bar.last_print_t = self.timer()

    def clear(self) -> None:
        if self.bar is not None:
            self.bar.clear()

    def refresh(self) -> None:
        if self.bar is not None:
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
