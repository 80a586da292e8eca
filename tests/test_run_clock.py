"""The benchmark's progress bar: none while numba compiles, its clock moved past each compilation,
and the compilation's seconds counted apart from the run's (:mod:`adaptive_dd.benchmark.progress`)."""

from __future__ import annotations

import pytest

from adaptive_dd.benchmark.progress import RunClock


class FakeClock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def test_no_bar_while_the_kernels_compile_and_the_bar_clock_skips_later_compilations(capsys):
    clock = FakeClock()
    rc = RunClock(10_000, "demo", show=True, timer=clock)
    rc.on_start(None)  # the first kernel compiles: 120 s, nested compilations inside
    rc.on_start(None)
    clock.t += 100.0
    rc.on_end(None)
    clock.t += 20.0
    rc.on_end(None)
    assert rc.bar is None  # nothing shown (a bar here would count the compilation in its rate)
    assert rc.compile_seconds == pytest.approx(120.0)
    rc.update(1000)  # the first block ran: the bar appears, its clock starting now
    assert rc.bar is not None and rc.bar.n == 1000
    start = rc.bar.start_t
    clock.t += 2.0
    rc.update(1000)
    rc.on_start(None)  # a second kernel compiles mid-run: 50 s
    clock.t += 50.0
    rc.on_end(None)
    assert rc.bar.start_t == pytest.approx(start + 50.0)  # its rate counts the samples' time only
    assert rc.bar.format_dict["elapsed"] == pytest.approx(2.0)
    assert rc.compile_seconds == pytest.approx(170.0)
    rc.close()


def test_no_bar_when_not_shown():
    rc = RunClock(100, "demo", show=False, timer=FakeClock())
    rc.update(100)
    rc.clear()
    rc.refresh()
    rc.close()
    assert rc.bar is None and rc.compile_seconds == 0.0
