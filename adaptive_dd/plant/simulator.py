"""Sampled-data simulator of the arm: actuators, sensors, payload swaps, batches.

:class:`ArmSimulator` steps a batch of arms at the sample rate: the command goes
through the actuator model (saturation, D/A), is held for one sample while
:func:`~adaptive_dd.plant.two_link_integrator.two_link_plant_step` integrates (RK4 substeps, sticking
Coulomb friction), and the sensors measure the new state (encoder quantization,
noise). Nothing stateful runs inside the substeps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant.devices import ActuatorConfig, SensorConfig
from adaptive_dd.plant.dynamics import as_joint_array
from adaptive_dd.plant.kind import require_two_link
from adaptive_dd.plant.parameters import validate_sigma
from adaptive_dd.plant.sampling import first_sample
from adaptive_dd.plant.two_link import ClosedFormTwoLink
from adaptive_dd.plant.two_link_integrator import step_kernel

__all__ = [
    "ActuatorConfig",
    "ArmSimulator",
    "PayloadSchedule",
    "SensorConfig",
    "SimulationResult",
    "simulate_open_loop",
]

Array = NDArray[np.float64]

MAX_SPEED = 200.0
"""|qd| [rad/s] above which a trial counts as runaway (diverged)."""

NOISE_CHUNK = 1024
"""Samples of sensor noise drawn at a time per trial generator."""


# -------------------------------------------------------------------- payloads
@dataclass(frozen=True)
class PayloadSchedule:
    """Payload disks that appear, change or vanish at given times.

    ``masses[k]`` [kg] holds from ``times[k]`` on; before ``times[0]`` the mass is
    ``initial_mass``. Masses may carry a trailing batch axis (one value per trial).
    ``radius`` [m] of the disks; None means the arm's :attr:`ClosedFormTwoLink.payload_radius`.
    Where the disk mounts (``l1``, ``l2``) is the arm's.

    Raises
    ------
    ParameterError
        Times not strictly increasing or negative; masses negative or non-finite.
    """

    times: tuple[float, ...] = ()
    masses: tuple = ()
    initial_mass: float | Sequence[float] = 0.0
    radius: float | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=float)
        if t.ndim != 1 or len(self.masses) != t.size:
            raise ParameterError(
                f"PayloadSchedule needs one mass per time, got times={self.times}, masses={self.masses}"
            )
        if t.size and (t[0] < 0 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t))):
            raise ParameterError(f"payload swap times must be >= 0 and strictly increasing, got {self.times}")
        for m in (self.initial_mass, *self.masses):
            a = np.asarray(m, dtype=float)
            if np.any(~np.isfinite(a)) or np.any(a < 0):
                raise ParameterError(f"payload mass must be finite and >= 0, got {m}")
        if self.radius is not None and (not np.isfinite(self.radius) or self.radius < 0):
            raise ParameterError(f"payload radius must be >= 0, got {self.radius}")

    def mass_at(self, t: float) -> Array:
        """Payload mass [kg] at time t (scalar or per-trial array)."""
        k = int(np.searchsorted(np.asarray(self.times, dtype=float), t + 1e-9, side="right"))
        m = self.initial_mass if k == 0 else self.masses[k - 1]
        return np.asarray(m, dtype=float)


# ------------------------------------------------------------- stateful wrapper
@dataclass
class SimulationResult:
    """Record of a simulated batch of trials; arrays are ``(n_trials, n_samples, ...)``.

    Attributes
    ----------
    t : ndarray (n_samples,)
        Sample times [s]; sample k holds ``q(t_k)`` and the torque applied over
        ``[t_k, t_k + T)``.
    q, qd : ndarray (n_trials, n_samples, 2)
        True joint angles [rad] and velocities [rad/s].
    q_meas, qd_meas : ndarray (n_trials, n_samples, 2)
        Measured (quantized, noisy) angles and velocities.
    tau_cmd, tau : ndarray (n_trials, n_samples, 2)
        Commanded and applied (saturated, quantized) torque [N m].
    saturated : ndarray of bool (n_trials, n_samples, 2)
        Command beyond the actuator limit.
    mass : ndarray (n_trials, n_samples)
        Payload mass [kg].
    sigma : ndarray (n_trials, n_samples, 7)
        True base parameters.
    failed : ndarray of bool (n_trials,)
        The trial diverged (non-finite or runaway) and was stopped.
    failed_at : ndarray (n_trials,)
        Index of the sample where it was stopped (-1 if not).
    """

    t: Array
    q: Array
    qd: Array
    q_meas: Array
    qd_meas: Array
    tau_cmd: Array
    tau: Array
    saturated: NDArray[np.bool_]
    mass: Array
    sigma: Array
    failed: NDArray[np.bool_]
    failed_at: NDArray[np.int_]
    sample_period: float = 0.001
    meta: dict = field(default_factory=dict)

    @property
    def n_trials(self) -> int:
        return self.q.shape[0]

    def save(self, path: str) -> None:
        """Write all arrays to a NumPy ``.npz`` file (documented in the README)."""
        arrays = {k: v for k, v in self.__dict__.items() if isinstance(v, np.ndarray)}
        np.savez_compressed(path, sample_period=self.sample_period, **arrays)


class _NoiseSource:
    """Standard normal sensor noise ``(n_trials, 4)`` per sample, drawn in chunks.

    With one generator per trial, ``NOISE_CHUNK`` samples are drawn at a time per
    trial: the same numbers as one ``g.standard_normal((n_samples, 4))`` per trial
    (the generator fills arrays in order), with memory that does not grow with the
    horizon. One shared generator for several trials draws the whole
    ``(n_trials, n_samples, 4)`` block up front, as before (its numbers depend on
    that order); pass one generator per trial to bound memory.
    """

    def __init__(self, rng, n_trials: int, n_samples: int) -> None:
        self.n_samples = n_samples
        if isinstance(rng, np.random.Generator):
            if n_trials == 1:
                self.rngs = [rng]
            else:
                self.rngs = None
                self.block = rng.standard_normal((n_trials, n_samples, 4))
                self.start = 0
                return
        else:
            self.rngs = list(rng)
            if len(self.rngs) != n_trials:
                raise ParameterError(
                    f"need one Generator per trial: {n_trials} trials, {len(self.rngs)} rngs"
                )
        self.start, self.block = 0, np.zeros((n_trials, 0, 4))

    def at(self, k: int) -> Array:
        """Noise of sample k; samples must be asked for in increasing order."""
        if self.rngs is None:
            return self.block[:, k]
        if not self.start <= k < self.start + self.block.shape[1]:
            if k < self.start:
                raise SignalError(f"sensor noise of sample {k} was already discarded (now at {self.start})")
            self.start = self.start + self.block.shape[1]
            n = min(NOISE_CHUNK, self.n_samples - self.start)
            self.block = np.stack([g.standard_normal((n, 4)) for g in self.rngs])
        return self.block[:, k - self.start]


class ArmSimulator:
    """A batch of arms stepped at the sample rate (stateful wrapper of :func:`two_link_plant_step`).

    Parameters
    ----------
    n_trials : int
        Batch size.
    n_samples : int
        Number of samples the run will take.
    rng : numpy.random.Generator or sequence of them
        One shared generator, or one per trial (reproducible trial by trial; the
        noise is then drawn in chunks of ``NOISE_CHUNK`` samples).
    arm : ClosedFormTwoLink, optional
        The plant: base parameters, payload geometry, actuator, sensors and
        friction law (default :meth:`ClosedFormTwoLink.sice`).
    payload : PayloadSchedule, optional
        Payload disks over time (mounted at the arm's ``l2``).
    sample_period : float
        T [s], > 0.
    substeps : int
        RK4 steps per sample.
    q0, qd0 : array_like (2,) or (n_trials, 2)
        Initial state; the arm starts stuck where qd0 == 0.
    sigma0 : array_like (7,) or (n_trials, 7), optional
        Base parameters without payload in place of ``arm.sigma`` (e.g. one per trial).
    actuator, sensor : ActuatorConfig, SensorConfig, optional
        In place of the arm's.
    """

    def __init__(
        self,
        n_trials: int,
        n_samples: int,
        rng: np.random.Generator | Sequence[np.random.Generator],
        arm: ClosedFormTwoLink | None = None,
        payload: PayloadSchedule | None = None,
        sample_period: float = 0.001,
        substeps: int = 2,
        q0: ArrayLike = (0.0, 0.0),
        qd0: ArrayLike = (0.0, 0.0),
        *,
        sigma0: ArrayLike | None = None,
        actuator: ActuatorConfig | None = None,
        sensor: SensorConfig | None = None,
    ) -> None:
        if not np.isfinite(sample_period) or sample_period <= 0:
            raise ParameterError(f"sample_period T must be > 0, got {sample_period}")
        if int(substeps) < 1:
            raise ParameterError(f"substeps must be >= 1, got {substeps}")
        if n_trials < 1 or n_samples < 1:
            raise ParameterError(f"n_trials and n_samples must be >= 1, got {n_trials}, {n_samples}")
        self.arm = ClosedFormTwoLink.sice() if arm is None else require_two_link(arm, "ArmSimulator(arm=...)")
        self.n_trials, self.n_samples = int(n_trials), int(n_samples)
        self.T, self.substeps = float(sample_period), int(substeps)
        s0 = self.arm.sigma if sigma0 is None else validate_sigma(sigma0, "sigma0")
        self.sigma0 = np.broadcast_to(s0, (n_trials, 7)).copy()
        self.payload = payload or PayloadSchedule()
        self.actuator = actuator or self.arm.actuator
        self.sensor = sensor or self.arm.sensor
        shape = (self.n_trials, 2)
        self.q = np.broadcast_to(as_joint_array(q0, "q0"), shape).copy()
        self.qd = np.broadcast_to(as_joint_array(qd0, "qd0"), shape).copy()
        self.stuck = np.ascontiguousarray(self.qd == 0.0)
        self.slip = np.ones(shape)
        self.z = np.zeros(shape)  # LuGre bristle deflection [rad] (relaxed at the start)
        self.failed = np.zeros(self.n_trials, dtype=bool)
        self.failed_at = np.full(self.n_trials, -1)
        self.k = 0
        self._noise = _NoiseSource(rng, self.n_trials, self.n_samples)
        # a swap at time `at` takes effect at the first sample k with k T >= at
        self._swap_samples = {first_sample(at, self.T) for at in self.payload.times}
        self._update_sigma()

    @property
    def t(self) -> float:
        return self.k * self.T

    def _update_sigma(self) -> None:
        self.mass = np.broadcast_to(self.payload.mass_at(self.t), (self.n_trials,))
        self.sigma = np.ascontiguousarray(
            self.arm.sigma_with_payload(self.mass, self.payload.radius, self.sigma0)
        )

    def measure(self) -> tuple[Array, Array]:
        """Measured (q, qd) at the current sample."""
        if self.k >= self.n_samples:
            raise SignalError(f"simulator was built for {self.n_samples} samples; asked for sample {self.k}")
        return self.sensor.measure(self.q, self.qd, self._noise.at(self.k))

    def step(self, tau_cmd: ArrayLike) -> tuple[Array, NDArray[np.bool_]]:
        """Apply ``tau_cmd (n_trials, 2)`` for one sample; return applied torque and saturation.

        A trial whose command is non-finite, or whose state becomes non-finite or
        faster than ``MAX_SPEED``, is marked failed and frozen at its last good
        state; the other trials go on.
        """
        tau_cmd = np.asarray(tau_cmd, dtype=float)
        if tau_cmd.shape != (self.n_trials, 2):
            raise SignalError(f"tau_cmd must have shape ({self.n_trials}, 2), got {tau_cmd.shape}")
        bad_cmd = ~np.isfinite(tau_cmd).all(axis=-1)
        if bad_cmd.any():
            tau_cmd = np.where(bad_cmd[:, None], 0.0, tau_cmd)
        tau, sat = self.actuator.apply(tau_cmd)
        if self.failed.any():
            tau = np.where(self.failed[:, None], 0.0, tau)
        q_prev = self.q.copy()
        step_kernel(
            self.q,
            self.qd,
            self.stuck,
            self.slip,
            np.ascontiguousarray(tau),
            self.sigma,
            self.T,
            self.substeps,
            self.arm.friction_code,
            self.arm.friction_params,
            self.z,
        )
        ok = np.isfinite(self.q).all(axis=-1) & (np.abs(self.qd) < MAX_SPEED).all(axis=-1)
        bad = bad_cmd | ~ok
        if bad.any():
            self.failed_at[bad & ~self.failed] = self.k
            self.failed |= bad
            f = self.failed
            self.q[f], self.qd[f], self.stuck[f] = (
                np.where(np.isfinite(q_prev[f]), q_prev[f], 0.0),
                0.0,
                True,
            )
        self.k += 1
        if self.k in self._swap_samples:
            self._update_sigma()
        return tau, sat


def simulate_open_loop(
    tau_cmd: ArrayLike,
    rng: np.random.Generator | Sequence[np.random.Generator],
    **kwargs,
) -> SimulationResult:
    """Simulate a batch driven by a torque record.

    Parameters
    ----------
    tau_cmd : array_like, shape (n_trials, n_samples, 2)
        Commanded torque per sample [N m].
    rng : Generator or sequence of Generators
        Sensor noise source(s).
    **kwargs
        Passed to :class:`ArmSimulator` (arm, payload, sample_period, sensor, ...).
    """
    tau_cmd = np.asarray(tau_cmd, dtype=float)
    if tau_cmd.ndim != 3 or tau_cmd.shape[-1] != 2:
        raise SignalError(f"tau_cmd must have shape (n_trials, n_samples, 2), got {tau_cmd.shape}")
    if not np.all(np.isfinite(tau_cmd)):
        bad = np.argwhere(~np.isfinite(tau_cmd))[0]
        raise SignalError(f"tau_cmd has a non-finite value at index {tuple(bad)}")
    n_trials, n, _ = tau_cmd.shape
    sim = ArmSimulator(n_trials, n, rng, **kwargs)
    rec = _Recorder(n_trials, n)
    for k in range(n):
        qm, qdm = sim.measure()
        rec.before(k, sim, qm, qdm)
        tau, sat = sim.step(tau_cmd[:, k])
        rec.after(k, tau_cmd[:, k], tau, sat)
    return rec.result(sim, arm=sim.arm.to_dict())


class _Recorder:
    """Preallocated arrays for a run; shared by open- and closed-loop simulation."""

    def __init__(self, n_trials: int, n: int) -> None:
        z = np.zeros((n_trials, n, 2))
        self.q, self.qd, self.q_meas, self.qd_meas = z.copy(), z.copy(), z.copy(), z.copy()
        self.tau_cmd, self.tau = z.copy(), z
        self.saturated = np.zeros((n_trials, n, 2), dtype=bool)
        self.mass = np.zeros((n_trials, n))
        self.sigma = np.zeros((n_trials, n, 7))
        self.n = n

    def before(self, k: int, sim: ArmSimulator, qm: Array, qdm: Array) -> None:
        self.q[:, k], self.qd[:, k] = sim.q, sim.qd
        self.q_meas[:, k], self.qd_meas[:, k] = qm, qdm
        self.mass[:, k], self.sigma[:, k] = sim.mass, sim.sigma

    def after(self, k: int, tau_cmd: Array, tau: Array, sat: NDArray[np.bool_]) -> None:
        self.tau_cmd[:, k], self.tau[:, k], self.saturated[:, k] = tau_cmd, tau, sat

    def result(self, sim: ArmSimulator, **meta) -> SimulationResult:
        return SimulationResult(
            t=np.arange(self.n) * sim.T,
            q=self.q,
            qd=self.qd,
            q_meas=self.q_meas,
            qd_meas=self.qd_meas,
            tau_cmd=self.tau_cmd,
            tau=self.tau,
            saturated=self.saturated,
            mass=self.mass,
            sigma=self.sigma,
            failed=sim.failed.copy(),
            failed_at=sim.failed_at.copy(),
            sample_period=sim.T,
            meta=dict(meta),
        )
