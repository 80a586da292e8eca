"""One trial in your own loop: step the arm of a scenario with your own torques.

::

    from adaptive_dd import Simulation, load_scenario

    sim = Simulation(load_scenario(), seed_index=0)
    meas = sim.reset()
    while not sim.done:
        tau = my_law(meas.q, meas.qd, meas.q_d, meas.qd_d, meas.qdd_d)
        meas = sim.step(tau)
    sim.q_true, sim.sigma_true, sim.payload_mass   # the truth, for analysis

It works on any arm (the two-link arm or an arm from a URDF: ``q, tau`` then have one entry
per joint) and is the same simulator, noise and payload schedule as trial ``seed_index`` of
``adaptive-dd benchmark`` on that scenario; :func:`run_trial` runs a controller object
over it and returns a result of the benchmark's kind.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import Scenario, load_scenario
from adaptive_dd.benchmark.trials import payload_schedule, sensor_of, trial_rngs
from adaptive_dd.errors import ParameterError, RunWarning, SignalError
from adaptive_dd.plant.simulator import ArmSimulator

__all__ = ["Measurement", "Simulation", "run_trial"]

Array = NDArray[np.float64]


class Measurement(NamedTuple):
    """What a controller sees at sample k (``n`` joints).

    After the last sample (``k == n_samples``) it is the measurement of the final state and the
    reference continued to that time.

    Attributes
    ----------
    k : int
        The sample's index.
    t : float
        Its time [s].
    q, qd : ndarray, shape (n,)
        The measured joint positions [rad] and velocities [rad/s] (noise and encoder included).
    q_d, qd_d, qdd_d : ndarray, shape (n,)
        The reference's position [rad], velocity [rad/s] and acceleration [rad/s^2].

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.simulation import Measurement
    >>> m = Measurement(k=0, t=0.0, q=np.zeros(2), qd=np.zeros(2), q_d=np.full(2, 0.1),
    ...                 qd_d=np.zeros(2), qdd_d=np.zeros(2))
    >>> m.q_d - m.q  # the tracking error a law acts on [rad]
    array([0.1, 0.1])
    """

    k: int
    t: float
    q: Array
    qd: Array
    q_d: Array
    qd_d: Array
    qdd_d: Array


def error_bound(tau: Array, q_d: Array, q: Array) -> Array:
    """``tau (S, n)`` with NaN in the rows of the trials whose true joint angles ``q (S, n)`` are
    beyond the benchmark's error bound of the reference ``q_d (n,)``
    (:data:`~adaptive_dd.closed_loop.types.MAX_ERROR`): the paper's arm's plant fails a trial on a
    NaN command and stops it there, as the compiled loop fails it. The stepping paths of the paper's
    arm (:class:`Simulation`, the Gymnasium vector environment) apply it before each step."""
    from adaptive_dd.closed_loop.types import MAX_ERROR

    bad = np.any(np.abs(q_d - q) > MAX_ERROR, axis=-1)
    return np.where(bad[:, None], np.nan, tau) if bad.any() else tau


class _TwoLinkTrial:
    """One trial of the two-link arm: :class:`~adaptive_dd.plant.simulator.ArmSimulator`."""

    def __init__(self, sc: Scenario, seed_index: int, q0: Array, qd0: Array) -> None:
        # one sample more than the run, so that the final state can be measured too (the
        # generator fills in order: the first n_samples draws are the benchmark's)
        self.sim = ArmSimulator(
            1,
            sc.n_samples + 1,
            trial_rngs(sc.seed, [seed_index]),
            arm=sc.closed_forms,
            payload=payload_schedule(sc),
            sample_period=sc.sample_period,
            substeps=sc.substeps,
            sensor=sensor_of(sc),
            q0=q0,
            qd0=qd0,
        )

    @property
    def k(self) -> int:
        return self.sim.k

    def measure(self) -> tuple[Array, Array]:
        qm, qdm = self.sim.measure()
        return qm[0], qdm[0]

    def step(self, tau: Array) -> tuple[Array, NDArray[np.bool_]]:
        applied, sat = self.sim.step(tau[None])
        return applied[0], sat[0]

    def truth(self) -> tuple[Array, Array, Array, float, bool]:
        s = self.sim
        return s.q[0].copy(), s.qd[0].copy(), s.sigma[0].copy(), float(s.mass[0]), bool(s.failed[0])


class _ChainTrial:
    """One trial of an N-joint arm: the closed loop's per-sample glue
    (:func:`~adaptive_dd.closed_loop.batches.measure_batch`,
    :func:`~adaptive_dd.closed_loop.batches.apply_batch`),
    the benchmark's Python path for one trial."""

    def __init__(self, sc: Scenario, seed_index: int) -> None:
        from adaptive_dd.closed_loop.noise import NoiseBlocks
        from adaptive_dd.closed_loop.runner import _records, true_parameters
        from adaptive_dd.closed_loop.types import io_of, plant_of, run_constants, true_models

        self.sc = sc
        self.rc, self.io, self.pl = run_constants(sc), io_of(sc), plant_of(sc, [seed_index])
        _, self.ts, self.acc, self.rec = _records("trial", None, sc, self.rc, self.pl, 1, 1, False, "python")
        self.seg, _, self.masses = true_parameters(sc)
        # the trial's true base parameters per segment (its plant's draw, if the scenario has one)
        self.pis = true_models(self.pl)[0]  # (G, 13 n): the trial's standard parameters per segment
        self.sigmas = (self.pis @ sc.arm.base.B.T)[self.seg]
        self.noise = NoiseBlocks(sc, [seed_index], 2 * sc.n_joints)
        self.k, self._buf, self._at = 0, None, 0

    def measure(self) -> tuple[Array, Array]:
        from adaptive_dd.benchmark.types import CHUNK
        from adaptive_dd.closed_loop.batches import measure_batch

        if self._buf is None or self._at >= self._buf[0].shape[1]:
            self._buf, self._at = self.noise.block(CHUNK), 0
        noise, drop = self._buf
        lost = drop[:, self._at] if drop.shape[1] else np.zeros(1, dtype=np.bool_)
        qm, qdm, _, _ = measure_batch(self.io, self.ts, noise[:, self._at], lost)
        self._at += 1
        return qm[0], qdm[0]

    def step(self, tau: Array) -> tuple[Array, NDArray[np.bool_]]:
        from adaptive_dd.closed_loop.batches import apply_batch

        applied, _ = apply_batch(self.rc, self.io, self.pl, self.ts, self.acc, self.rec, self.k, tau[None])
        sat = self.rec.saturated[0, self.k].copy()
        self.k += 1
        return applied[0], sat

    def truth(self) -> tuple[Array, Array, Array, float, bool]:
        k = min(self.k, self.sc.n_samples - 1)
        q, qd, failed = self.ts.q[0].copy(), self.ts.qd[0].copy(), bool(self.ts.failed[0])
        return q, qd, self.sigmas[k].copy(), float(self.masses[k]), failed


def _scenario_of(who: str, scenario) -> Scenario:
    """``scenario``, the default one for None; anything else that is not a Scenario (a path) is a
    :class:`ParameterError` saying how to load one."""
    if scenario is None:
        return load_scenario()
    if not isinstance(scenario, Scenario):
        raise ParameterError(
            f"{who}: scenario must be a Scenario, got {type(scenario).__name__} {scenario!r:.80}; load a "
            "file with adaptive_dd.load_scenario(path)"
        )
    return scenario


class Simulation:
    """One arm of a scenario (the two-link arm or any arm from a URDF), stepped by the caller
    at the sample rate.

    Parameters
    ----------
    scenario : Scenario, optional
        Default: the shipped payload-swap scenario.
    seed_index : int
        Noise of seed ``(scenario.seed, seed_index)``, as in the benchmark.

    Attributes
    ----------
    scenario : Scenario
        The scenario stepped.
    applied_torque : ndarray, shape (n,)
        The torque the actuators applied at the last step [N m] (saturated, quantised).
    saturated : ndarray of bool, shape (n,)
        Which joints' commands were at a torque limit at the last step.

    Examples
    --------
    The loop, with your own law (``reset`` compiles the arm's step on its first call)::

        sim = Simulation(load_scenario(), seed_index=0)
        meas = sim.reset()
        while not sim.done:
            meas = sim.step(my_law(meas.q, meas.qd, meas.q_d, meas.qd_d, meas.qdd_d))
        sim.q_true, sim.sigma_true, sim.payload_mass  # the truth, for analysis

    A step before ``reset`` is an error that says what to do:

    >>> import numpy as np
    >>> from adaptive_dd import Simulation, load_scenario
    >>> sim = Simulation(load_scenario())
    >>> sim.n_joints, sim.done
    (2, False)
    >>> sim.step(np.zeros(2))
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.SignalError: call reset() before step()
    """

    def __init__(self, scenario: Scenario | None = None, seed_index: int = 0) -> None:
        self.scenario = _scenario_of("Simulation", scenario)
        if isinstance(seed_index, bool) or not isinstance(seed_index, int | np.integer) or seed_index < 0:
            raise ParameterError(
                f"Simulation: seed_index must be an integer >= 0 (a benchmark trial), got {seed_index!r}"
            )
        self.seed_index = int(seed_index)
        sc = self.scenario
        t = np.arange(sc.n_samples + 1) * sc.sample_period  # the final state's time too
        self._ref = sc.reference.sample(t)
        self._trial: _TwoLinkTrial | _ChainTrial | None = None
        self.applied_torque = np.zeros(sc.n_joints)
        self.saturated = np.zeros(sc.n_joints, dtype=bool)
        self.failed_at: float | None = None
        """[s] The sample whose command or state failed the trial (None: it has not failed)."""
        self.failure: str | None = None
        """Why the trial failed, in the benchmark's words (None: it has not failed)."""

    @property
    def arm(self):
        """The scenario's arm."""
        return self.scenario.arm

    @property
    def n_joints(self) -> int:
        """The arm's joints ``n``."""
        return self.scenario.n_joints

    def reset(self) -> Measurement:
        """Start (again) at t = 0, on the reference, at rest if it is; return the first measurement."""
        sc = self.scenario
        q_d, qd_d, _ = self._ref
        if sc.closed_forms is not None:  # the paper's arm: its closed forms
            self._trial = _TwoLinkTrial(sc, self.seed_index, q_d[0], qd_d[0])
        else:
            self._trial = _ChainTrial(sc, self.seed_index)
        self.applied_torque = np.zeros(sc.n_joints)
        self.saturated = np.zeros(sc.n_joints, dtype=bool)
        self.failed_at, self.failure = None, None
        return self._measure()

    def _measure(self) -> Measurement:
        tr = self._trial
        k = tr.k
        qm, qdm = tr.measure()
        return Measurement(k, k * self.scenario.sample_period, qm, qdm, *(r[k] for r in self._ref))

    def step(self, tau: ArrayLike) -> Measurement:
        """Apply the torque command ``tau (n,)`` [N m] for one sample; return the next measurement.

        The benchmark's failure rule holds here too: a non-finite command, a position error beyond
        the run's divergence bound or a runaway speed fails the trial. The arm is then stopped
        where it was (zero torque from then on) and :attr:`failed` is True; the steps go on (so
        that a Gymnasium episode can end on it) and nothing is raised: check ``sim.failed``;
        ``sim.failed_at`` [s] and ``sim.failure`` say when and why.
        """
        if self._trial is None:
            raise SignalError("call reset() before step()")
        if self.done:
            raise SignalError(f"the scenario's {self.scenario.n_samples} samples are done; call reset()")
        tau = np.asarray(tau, dtype=float)
        n = self.scenario.n_joints
        if tau.shape != (n,):
            raise SignalError(f"tau must have shape ({n},) (one torque per joint), got {tau.shape}")
        k, was = self._trial.k, self.failed
        raw = tau
        if isinstance(self._trial, _TwoLinkTrial):  # the N-joint glue applies the error bound itself
            tau = error_bound(tau[None], self._ref[0][self._trial.k], self._trial.truth()[0][None])[0]
        self.applied_torque, self.saturated = self._trial.step(tau)
        if self.failed and not was:
            self.failed_at, self.failure = k * self.scenario.sample_period, self._why(raw, k)
        return self._measure()

    def _why(self, tau: Array, k: int) -> str:
        """Why the trial failed at sample ``k`` under command ``tau``: the benchmark's rules' words."""
        from adaptive_dd.closed_loop.types import MAX_ERROR, MAX_SPEED

        bad = np.flatnonzero(~np.isfinite(tau))
        if bad.size:
            return f"non-finite torque command (joint {int(bad[0]) + 1})"
        e = np.abs(self._ref[0][k] - self._trial.truth()[0])
        if np.all(np.isfinite(e)) and e.max() > MAX_ERROR:
            j = int(np.argmax(e))
            return f"tracking error of joint {j + 1} {e[j]:.6g} rad, above max_error = {MAX_ERROR:g} rad"
        return f"runaway: the arm's state became non-finite or a joint exceeded {MAX_SPEED:g} rad/s"

    def _truth(self):
        if self._trial is None:
            raise SignalError("call reset() first")
        return self._trial.truth()

    @property
    def done(self) -> bool:
        """All the scenario's samples have been stepped (``reset`` starts again)."""
        return self._trial is not None and self._trial.k >= self.scenario.n_samples

    @property
    def failed(self) -> bool:
        """The arm diverged (non-finite or runaway) and was stopped."""
        return self._truth()[4]

    @property
    def q_true(self) -> Array:
        """The true joint positions now ``(n,)`` [rad], without sensor noise."""
        return self._truth()[0]

    @property
    def qd_true(self) -> Array:
        """The true joint velocities now ``(n,)`` [rad/s], without sensor noise."""
        return self._truth()[1]

    @property
    def sigma_true(self) -> Array:
        """The true base parameters now, payload included ``(p,)`` (7 on the two-link arm)."""
        return self._truth()[2]

    @property
    def payload_mass(self) -> float:
        """The payload carried now [kg]."""
        return self._truth()[3]

    @property
    def pi_true(self) -> Array | None:
        """The trial's true standard parameters now, payload included ``(13 n,)`` (each seed's drawn
        plant when the scenario draws one); None on the paper's closed forms (``sigma_true``)."""
        tr = self._trial
        if not isinstance(tr, _ChainTrial):
            return None
        k = min(tr.k, self.scenario.n_samples - 1)
        return tr.pis[tr.seg[k]].copy()


def run_trial(controller, scenario: Scenario | None = None, seed_index: int = 0, name: str | None = None):
    """Run one controller object on trial ``seed_index`` of a scenario.

    Parameters
    ----------
    controller : Controller
        A controller object (a built-in from :func:`~adaptive_dd.controllers.make_controller`,
        or your own class with ``reset``, ``command`` and ``observe``).
    scenario : Scenario, optional
        Default: the shipped ``payload_swap``.
    seed_index : int
        Which of the benchmark's trials: the same noise and drawn robot as that seed there.
    name : str, optional
        The label in the result (default the controller's ``name``).

    Returns
    -------
    BenchmarkResult
        A benchmark result of one controller and one trial (a trial that diverged is a result).

    Raises
    ------
    SignalError
        The controller raised (its error, with where: a two-link class on an N-joint arm, say).

    Examples
    --------
    One trial of a controller object, the same noise as seed 1 of the benchmark (compiles the closed
    loop on a cold cache):

    >>> from adaptive_dd import make_controller, run_trial
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> sc = parse_scenario({"run": {"duration": 1.0, "seeds": 2},
    ...                      "payload": [{"at": 0.5, "mass": 2.0}]})
    >>> res = run_trial(make_controller("ct_oracle"), sc, seed_index=1)
    >>> list(res.runs), res.seed_indices
    (['ct_oracle'], (1,))
    >>> res.runs["ct_oracle"].e_norm.shape  # one trial x 1000 samples
    (1, 1000)
    """
    import warnings

    from adaptive_dd.controllers.plugins import check_controller_object

    check_controller_object("run_trial", "controller", controller)
    sc = _scenario_of("run_trial", scenario)
    label = name or getattr(controller, "name", type(controller).__name__)
    # the floor's warning would speak of run_benchmark's controllers=: said below
    one = {label: controller}
    res = run_benchmark(
        sc, progress=False, controllers=one, seed_indices=[seed_index], warn_missing_floors=False
    )
    if res.runs[label].error:  # the controller raised: one trial asked for, no result to hand back
        raise SignalError(f"run_trial: {label} on trial {seed_index}: {res.runs[label].error}")
    floor = res.runs[label].floor
    if floor is not None and floor not in res.runs:
        warnings.warn(
            f"run_trial: {label}'s floor {floor} is not run by run_trial (one controller): its ratio to "
            f"the floor is NaN; run_benchmark(scenario, controllers={{{label!r}: ..., {floor!r}: "
            f"make_controller({floor!r})}}, seed_indices=[{seed_index}]) runs both",
            RunWarning,
            stacklevel=2,
        )
    return res
