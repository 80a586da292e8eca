"""What a benchmark run produces, and the constants of the two-link loop: one module that the
runner, the compiled path, the metrics and the reports import (none of them imports another
for these).

:class:`BenchmarkResult`'s ``to_frame``, ``summary`` and ``metrics`` are doors to
:mod:`~adaptive_dd.benchmark.results` and :mod:`~adaptive_dd.benchmark.metrics`, imported
when called (those modules import this one).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.benchmark.streaming import (
    MAX_ALARMS,
    SETTLE,
)  # a leaf: metrics needs them without this module

if TYPE_CHECKING:
    from adaptive_dd.benchmark.scenario import Scenario
    from adaptive_dd.closed_loop.types import StreamedSums

__all__ = ["CHUNK", "ENGINES", "MAX_ALARMS", "MAX_ERROR", "SETTLE", "BenchmarkResult", "ControllerRun"]

Array = NDArray[np.float64]
MAX_ERROR = 3.0
"""Tracking error [rad] beyond which a trial counts as diverged."""
ENGINES = ("auto", "python", "compiled")
CHUNK = 1024
"""Samples per block of drawn noise (and per call of the compiled loop)."""


@dataclass
class ControllerRun:
    """One controller's trials.

    Attributes
    ----------
    name : str
    acc : StreamedSums
        Streamed sums per trial and segment, by name (:class:`~adaptive_dd.closed_loop.types.StreamedSums`:
        ``sum_e2 (n_seeds, n_segments)``, ``sum_e2_joint (n_seeds, n_segments, n_joints)``, ``max_e``,
        ``sum_tau2``, ``n_saturated``, ``sum_e2_settled``; ``e_norm`` is :attr:`e_norm`).
    e_norm : ndarray of float32 (n_seeds, n_samples)
        Tracking error norm ``|q_d - q|`` of the true q [rad].
    sigma_end : ndarray (n_seeds, n_segments, 7) or None
        Estimate at the last sample of each segment (controllers with an estimate).
    failed : bool (n_seeds,); failed_at : sample index or -1
    failed_cmd : int (n_seeds,) or None
        The joint (from 0) whose command was not finite at the failed sample, or -1.
    error : message if the controller raised, else ""
    alarm_times : per trial, the times [s] a change detector fired (or None)
    floor : name of the controller this one is measured against (or None)
    q, qd, tau, saturated, sigma_hat : trajectories ``(n_kept, n_samples, ...)`` of the first
        seeds (true q [rad] and qd [rad/s], applied torque [N m], saturation, estimate), or None
    engine : "python" or "compiled"
    dropped : int (n_seeds,)
        Samples whose measurement was lost (scenario ``noise.dropout``); the control law gets
        the last good measurement, the estimator the NaN (skipped and counted).
    skipped : int (n_seeds,) or None
        Samples the controller's estimator skipped as non-finite.
    failed_why : dict
        Why each failed trial (by index) failed (:meth:`explain_failures`).

    Examples
    --------
    >>> from adaptive_dd import run_benchmark
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> sc = parse_scenario({"run": {"duration": 1.0, "seeds": 2,
    ...                              "controllers": ["ct_nominal", "ct_oracle"]},
    ...                      "payload": [{"at": 0.5, "mass": 2.0}]})
    >>> run = run_benchmark(sc, progress=False).runs["ct_nominal"]  # compiles on a cold cache
    >>> run.floor, run.engine, run.e_norm.shape  # 2 seeds x 1000 samples
    ('ct_oracle', 'compiled', (2, 1000))
    >>> run.failed
    array([False, False])
    """

    name: str
    acc: StreamedSums
    e_norm: NDArray[np.float32]
    sigma_end: Array | None
    failed: NDArray[np.bool_]
    failed_at: NDArray[np.int_]
    error: str = ""
    alarm_times: list | None = None
    floor: str | None = None
    q: Array | None = None
    qd: Array | None = None
    tau: Array | None = None
    saturated: NDArray[np.bool_] | None = None
    sigma_hat: Array | None = None
    engine: str = "python"
    dropped: NDArray[np.int_] | None = None
    skipped: NDArray[np.int_] | None = None
    failed_why: dict = field(default_factory=dict)
    failed_cmd: NDArray[np.int_] | None = None

    def explain_failures(self, max_error: float, max_speed: float) -> None:
        """Say why every failed trial without a reason yet failed: the controller's error, else
        from the error norm at the failed sample (the divergence rule's tracking error), else the
        runaway rule. A non-finite command is named with its joint (the Python path names it,
        with its value, as it happens)."""
        for i in np.flatnonzero(self.failed):
            i = int(i)
            if i in self.failed_why:
                continue
            k = int(self.failed_at[i])
            if self.error or k < 0:
                self.failed_why[i] = self.error or "the controller failed"
                continue
            e = float(self.e_norm[i, k]) if k < self.e_norm.shape[1] else float("nan")
            joint = -1 if self.failed_cmd is None else int(self.failed_cmd[i])
            if joint >= 0:
                self.failed_why[i] = f"non-finite torque command (joint {joint + 1})"
            elif e > max_error:
                self.failed_why[i] = f"tracking error |e| = {e:.3g} rad, beyond max_error = {max_error:g} rad"
            else:
                at = f"|e| = {e:.3g} rad, within max_error" if np.isfinite(e) else "|e| not finite"
                self.failed_why[i] = (
                    "runaway: the arm's state became non-finite or a joint exceeded "
                    f"{max_speed:g} rad/s ({at})"
                )

    def failures(self, sample_period: float, seed_indices=None) -> list[dict]:
        """``[{"seed", "t", "why"}]`` of the failed trials (``t`` [s] of the failed sample, None if
        the controller failed before any)."""
        idx = range(self.failed.size) if seed_indices is None else seed_indices
        out = []
        for i, seed in enumerate(idx):
            if self.failed[i]:
                k = int(self.failed_at[i])
                t = round(k * sample_period, 9) if k >= 0 else None
                out.append({"seed": int(seed), "t": t, "why": self.failed_why.get(i, self.error or "")})
        return out


@dataclass
class BenchmarkResult:
    """Everything a benchmark run produced; see :mod:`adaptive_dd.benchmark.metrics`.

    Attributes
    ----------
    scenario : Scenario
        What was run.
    t : ndarray, shape (N,)
        Sample instants [s].
    q_d : ndarray, shape (N, n)
        The reference [rad].
    sigma_true : ndarray, shape (N, p)
        The true base parameters over time, payload included (7 on the two-link arm).
    mass : ndarray, shape (N,)
        The payload carried [kg].
    runs : dict of str to ControllerRun
        Each controller's trials, by label.
    wall_time : float
        Seconds the runs took, numba's compilation during them left out (``compile_time``).
    compile_time : float
        Seconds numba spent compiling kernels during the runs (0 when every kernel came from
        its cache).
    seed_indices : tuple of int
        The seeds run.
    plant : dict or None
        The plants the trials met when the plant is not the model; None: the plant is the arm.
    excitation : dict or None
        The excitation phase's identification (``[run] excite``); None without.

    Examples
    --------
    >>> from adaptive_dd import run_benchmark
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> sc = parse_scenario({"run": {"duration": 1.0, "seeds": 2,
    ...                              "controllers": ["ct_nominal", "ct_oracle"]},
    ...                      "payload": [{"at": 0.5, "mass": 2.0}]})
    >>> res = run_benchmark(sc, progress=False)  # compiles the closed loop on a cold cache
    >>> res.t.shape, res.q_d.shape, res.sigma_true.shape  # 1000 samples of the two-link arm
    ((1000,), (1000, 2), (1000, 7))
    >>> float(res.mass[0]), float(res.mass[-1])  # the payload carried [kg]
    (0.0, 2.0)
    >>> len(res.to_frame())  # 2 controllers x 2 seeds x 2 segments
    8
    """

    scenario: Scenario
    t: Array
    q_d: Array
    sigma_true: Array  # (n_samples, p): 7 for the two-link arm, arm.base.count for a URDF arm
    mass: Array  # (n_samples,)
    runs: dict = field(default_factory=dict)
    wall_time: float = 0.0
    compile_time: float = 0.0
    seed_indices: tuple = ()
    plant: dict | None = None
    """The plants the trials met when the plant is not the model
    (:func:`~adaptive_dd.closed_loop.runner.plant_record`); None: the plant is the arm."""
    excitation: dict | None = None
    """The excitation phase's identification (``[run] excite``,
    :meth:`~adaptive_dd.closed_loop.excitation_phase.ExcitationReport.to_dict`); None without."""
    cache: dict = field(default_factory=dict, repr=False, compare=False)
    """Derived per-seed arrays, computed once (``metrics.per_seed_segment_metrics``)."""

    def to_frame(self):
        """One row per controller x seed x segment (pandas DataFrame; see
        :func:`adaptive_dd.benchmark.results.to_frame`)."""
        from adaptive_dd.benchmark.results import to_frame

        return to_frame(self)

    def summary(self):
        """Per controller and segment: mean, median, p90, max of the per-seed ratio to the floor."""
        from adaptive_dd.benchmark.results import summary_frame

        return summary_frame(self)

    def metrics(self) -> dict:
        """The metrics of :func:`adaptive_dd.benchmark.metrics.compute_metrics` (the JSON layout)."""
        from adaptive_dd.benchmark.metrics import compute_metrics

        return compute_metrics(self)
