"""What the scenario reader and its checks share: the documented bounds (:data:`LIMITS`), the
tables and keys a scenario file may hold (:data:`KEYS`), the reference trajectory
(:class:`Reference`) and the size estimate of a run (:func:`run_estimate`).

:mod:`~adaptive_dd.benchmark.scenario` and :mod:`~adaptive_dd.benchmark.scenario_checks` both
import this module; neither imports the other's private names.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["KEYS", "LIMITS", "Reference", "RunEstimate", "run_estimate"]

Array = NDArray[np.float64]

LIMITS = {
    "min_sample_period": 1e-5,  # s
    "max_sample_period": 0.1,  # s
    "max_seeds": 10_000,
    "seed_bound": 2**63,
    "max_substeps": 100,
    "max_bandwidth_T": 0.2,  # bandwidth [rad/s] * T [s]
    # a boost's bandwidth * T: half the limit of a sampled, critically damped PD on a double
    # integrator (held command: stable up to bandwidth * T = 1); the built-in 300 rad/s at 1 ms is 0.3
    "max_boost_bandwidth_T": 0.5,
    "max_damping": 10.0,
    "max_mass": 50.0,  # kg
    "max_radius": 0.5,  # m
    "max_com": 2.0,  # m, a payload's centre of mass from its frame (as far as the longest link)
    "max_angle": 10.0,  # rad, |offset| + sum |amplitude|
    "max_phase": 100.0,  # rad
    "max_terms": 50,
    "max_swaps": 1000,
    "max_variance": 1.0,
    "nyquist_fraction": 0.1,  # f <= nyquist_fraction / T; the Nyquist limit is 0.5 / T
    "max_bytes": 4 * 2**30,
    "max_seconds": 24 * 3600.0,
    "large_seconds": 60.0,  # the CLI prints the estimate above this
    "max_ramp": 3600.0,  # s
    "max_setting": 1e6,  # |any number| in a built-in controller's [controllers.NAME] table
    "max_excite": 3600.0,  # s, [run] excite
}
"""Documented bounds of the scenario checks (see the module docstring)."""

KEYS = {
    "run": {"duration", "sample_period", "seeds", "seed", "substeps", "controllers", "excite"},
    "control": {"bandwidth", "damping"},
    "reference": None,  # ramp and one entry per joint, checked against the arm
    "payload": {"at", "mass", "radius", "com", "inertia"},
    "noise": {"position_variance", "velocity_variance", "dropout"},
    "controllers": None,  # one sub-table per controller, free keys
    "arm": None,  # checked by adaptive_dd.plant.arm_tables.arm_from_tables
    "plant": None,  # adaptive_dd.plant.arm_tables.arm_from_tables, adaptive_dd.plant.uncertainty.parse_plant
    "model": None,  # adaptive_dd.plant.uncertainty.parse_model
}

# Kept per trial and sample by the runner: the error norm as float32 (metrics stream; full
# trajectories only for the first few seeds); wall time per sample and controller (the
# per-block overhead) and per trial-sample on the compiled path. Fitted to warm runs of
# `python benchmarks/estimate_check.py SCENARIO --cli --seeds 1 10` (and 100 for the paper's, 50
# for the UR5) on a quiet 2-core machine (load 1-2; a busy one stretches the wall time): the
# paper's default scenario 2.8, 3.8 and 11.6 s wall (7 controllers, 20 s).
_BYTES_PER_SAMPLE_TRIAL = 5
_SECONDS_PER_SAMPLE_CONTROLLER = 9e-6
_SECONDS_PER_SAMPLE_TRIAL = 6.3e-7
# N-joint (URDF) arms: per trial-sample a + b n_joints^2 (the estimator's fixed part, and its
# rows times its parameters), fitted to the same runs of vertical3_payload (3 joints: 5.5 and
# 9.7 s), ur5_tool_swap (6: 8.7, 18.6 and 57.0 s with 50 seeds) and panda_payload (7: 9.3 and
# 20.5 s), each with its 7 controllers.
_SECONDS_PER_SAMPLE_TRIAL_GENERAL = 2.6e-6
_SECONDS_PER_SAMPLE_TRIAL_JOINT2 = 1.7e-7
# The excitation phase ([run] excite, adaptive_dd.closed_loop.excitation_phase): its closed loop at
# the rates above (one controller, every seed), plus the excitation's design (once) and one
# identification per seed, both per n_joints^2 (the identification also per sample of the record);
# fitted to `identify_excitation` timed in a warm process on 1 and 4 seeds of
# benchmarks/scenarios/example_robot_data/z1_drawn.toml (6 joints: 7.0 and 14.6 s, its design
# 2.4 s) and benchmarks/scenarios/gen3_excite.toml (7 joints: 11.5 and 25.6 s, design 5.5 s), 20 s
# at 1 ms; `python benchmarks/estimate_check.py --cli --seeds 1 4 10 SCENARIO` compares the whole.
_EXCITE_DESIGN_SECONDS_JOINT2 = 0.09
_IDENTIFY_SECONDS_PER_SAMPLE_JOINT2 = 4.2e-6
# What a warm `adaptive-dd benchmark` spends around the closed loop, once per run: imports,
# loading the cached kernels, the arm, the report and its figures; the runs above less their
# closed loops: the paper's arm on its closed forms 1.45 s, an N-joint arm s0 + s1 n_joints^2
# (sice_general, 2 joints, 3.3 s; vertical3 4.0; the UR5 6.2; the Panda 7.05).
_SETUP_SECONDS = 1.45
_SETUP_SECONDS_GENERAL = 2.97
_SETUP_SECONDS_JOINT2 = 0.083


@dataclass(frozen=True)
class Reference:
    """``q_d(t) = offset + w(t) sum_k a_k sin(2 pi f_k t + phase_k)`` per joint, w a C^2 ramp."""

    offset: tuple[float, ...]
    amplitude: tuple[tuple[float, ...], ...]
    frequency: tuple[tuple[float, ...], ...]
    phase: tuple[tuple[float, ...], ...]
    ramp: float = 0.0

    @property
    def n_joints(self) -> int:
        return len(self.offset)

    def sample(self, t: Array) -> tuple[Array, Array, Array]:
        """``q_d, qd_d, qdd_d`` at times t, each of shape ``(len(t), n_joints)``."""
        t = np.asarray(t, dtype=float)
        w, dw, ddw = self._ramp(t)
        out = np.zeros((3, t.size, self.n_joints))
        for j in range(self.n_joints):
            s = ds = dds = np.zeros_like(t)
            for a, f, p in zip(self.amplitude[j], self.frequency[j], self.phase[j], strict=True):
                om = 2 * np.pi * f
                s = s + a * np.sin(om * t + p)
                ds = ds + a * om * np.cos(om * t + p)
                dds = dds - a * om**2 * np.sin(om * t + p)
            out[0, :, j] = self.offset[j] + w * s
            out[1, :, j] = dw * s + w * ds
            out[2, :, j] = ddw * s + 2 * dw * ds + w * dds
        return out[0], out[1], out[2]

    def _ramp(self, t: Array) -> tuple[Array, Array, Array]:
        if self.ramp <= 0:
            one = np.ones_like(t)
            return one, 0 * one, 0 * one
        x = np.clip(t / self.ramp, 0.0, 1.0)
        inside = (t > 0) & (t < self.ramp)
        w = 10 * x**3 - 15 * x**4 + 6 * x**5
        dw = np.where(inside, (30 * x**2 - 60 * x**3 + 30 * x**4) / self.ramp, 0.0)
        ddw = np.where(inside, (60 * x - 180 * x**2 + 120 * x**3) / self.ramp**2, 0.0)
        return w, dw, ddw


@dataclass(frozen=True)
class RunEstimate:
    """Size of a benchmark run: samples per trial, trials, memory [bytes] and wall time [s]
    (``compile_seconds`` of it the one-time compilation of a cold cache)."""

    n_samples: int
    trials: int
    bytes: float
    seconds: float
    compile_seconds: float = 0.0
    excite_seconds: float = 0.0
    setup_seconds: float = 0.0
    """Of ``seconds``, what a run spends once around its trials (imports, loading the kernels)."""

    @property
    def large(self) -> bool:
        """True when the CLI should print the estimate before running."""
        return self.seconds > LIMITS["large_seconds"]

    def __str__(self) -> str:
        return (
            f"{self.n_samples} samples x {self.trials} trials: about {_size(self.bytes)} "
            f"and {_duration(self.seconds)}"
            + (
                f" (of which about {_duration(self.compile_seconds)} compiling the kernels, once: "
                "numba's cache is cold)"
                if self.compile_seconds
                else ""
            )
            + (
                f" (excitation phase included: about {_duration(self.excite_seconds)} for its closed loop "
                "on every seed, its design and one identification per seed)"
                if self.excite_seconds
                else ""
            )
        )


def _size(n_bytes: float) -> str:
    """Bytes in the largest binary unit up to TiB that keeps the figure below 1024 (3 digits)."""
    for unit, scale in (("TiB", 2**40), ("GiB", 2**30)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{n_bytes / 2**20:.3g} MiB"


def _duration(s: float) -> str:
    if s < 120:
        return f"{s:.3g} s"
    return f"{s / 60:.3g} min" if s < 7200 else f"{s / 3600:.3g} h"


def run_estimate(
    n_samples: int,
    n_seeds: int,
    n_controllers: int,
    n_joints: int | None = None,
    compile_seconds: float = 0.0,
    excite_samples: int = 0,
) -> RunEstimate:
    """Rough memory and wall time of a closed-loop run (a guide, not a promise).

    Parameters
    ----------
    n_samples : int
        Samples per trial.
    n_seeds : int
        Trials per controller.
    n_controllers : int
        Controllers run.
    n_joints : int, optional
        The joints of an N-joint (URDF) arm; None for the two-link arm's closed forms.
    compile_seconds : float
        One-time compilation [s] added to the time (as is what a run spends around the closed
        loop: imports, loading the kernels, the report; ``_SETUP_SECONDS``, on the general
        kernels ``_SETUP_SECONDS_GENERAL`` plus ``_SETUP_SECONDS_JOINT2`` per joint squared).
    excite_samples : int
        The samples of an excitation phase (``[run] excite`` / T, an N-joint arm's): its closed
        loop (one controller, every seed) at the task's rates, the design once
        (``_EXCITE_DESIGN_SECONDS_JOINT2`` x n_joints^2) and an identification per seed
        (``_IDENTIFY_SECONDS_PER_SAMPLE_JOINT2`` x samples x n_joints^2)
        are added to the time (``excite_seconds`` of it); the memory is the task's (the
        excitation's records are freed before the task runs).

    Returns
    -------
    RunEstimate
        Samples, trials, bytes and seconds; its ``str`` is the line ``validate`` prints.

    Examples
    --------
    >>> from adaptive_dd.benchmark.scenario import run_estimate
    >>> est = run_estimate(n_samples=20_000, n_seeds=10, n_controllers=7)
    >>> est.trials
    70
    >>> est.seconds > 0 and est.bytes > 0
    True
    """
    trials = n_seeds * n_controllers
    nbytes = float(n_samples) * trials * _BYTES_PER_SAMPLE_TRIAL
    n2 = 0 if n_joints is None else n_joints**2
    per = (
        _SECONDS_PER_SAMPLE_TRIAL
        if n_joints is None
        else _SECONDS_PER_SAMPLE_TRIAL_GENERAL + _SECONDS_PER_SAMPLE_TRIAL_JOINT2 * n2
    )
    secs = float(n_samples) * (n_controllers * _SECONDS_PER_SAMPLE_CONTROLLER + trials * per)
    excite = 0.0
    if excite_samples > 0:
        nj2 = (n_joints or 2) ** 2
        loop = float(excite_samples) * (_SECONDS_PER_SAMPLE_CONTROLLER + n_seeds * per)
        ident = n_seeds * float(excite_samples) * nj2 * _IDENTIFY_SECONDS_PER_SAMPLE_JOINT2
        excite = loop + _EXCITE_DESIGN_SECONDS_JOINT2 * nj2 + ident
    setup = _SETUP_SECONDS if n_joints is None else _SETUP_SECONDS_GENERAL + _SETUP_SECONDS_JOINT2 * n2
    total = setup + secs + excite + compile_seconds
    return RunEstimate(int(n_samples), int(trials), nbytes, total, float(compile_seconds), excite, setup)
