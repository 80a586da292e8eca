"""Sampled-data simulator of the arm: ZOH torque, RK4 substeps, sticking friction.

Friction model
--------------
Viscous plus Coulomb friction of eqs. (5)-(6), with *sticking*. A joint at rest
(velocity exactly 0) either sticks, which is consistent while the torque needed
to hold it, ``|tau_i - (C qd)_i - (M qdd)_i|`` with the other joint's motion taken
into account, is at most ``d_i``; or it slides from rest in a direction s, which
is consistent if its acceleration has the sign of s. The modes of the joints at
rest are chosen jointly (the coupled 2x2 problem: at most 9 combinations, sticking
first) at the start of every integration substep; within a substep the modes are
fixed and moving joints see ``d_i sgn(qd_i)``. When a moving joint's velocity
reaches zero within a substep, the substep is split there, the modes are decided
anew and the rest of the substep is integrated. This hybrid model has no
chattering at zero velocity, unlike integrating ``sgn(qd)`` directly.

Sampling
--------
Each call of :meth:`ArmSimulator.step` holds the torque constant for one sample
period ``T`` (zero-order hold) and integrates with ``substeps`` classical RK4 steps.
Nothing stateful (controller, estimator, sensor) runs inside the substeps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.plant.dynamics import as_joint_array
from adaptive_dd.plant.parameters import (
    TABLE1_SIGMA,
    TORQUE_LIMITS,
    payload_sigma_delta,
    validate_sigma,
)

__all__ = [
    "ActuatorConfig",
    "ArmSimulator",
    "PayloadSchedule",
    "SensorConfig",
    "SimulationResult",
    "plant_step",
    "simulate_open_loop",
]

Array = NDArray[np.float64]

MAX_SPEED = 200.0
"""|qd| [rad/s] above which a trial counts as runaway (diverged)."""


# ------------------------------------------------------------------ actuators
@dataclass(frozen=True)
class ActuatorConfig:
    """Torque path from command to joint.

    Attributes
    ----------
    torque_limit : (float, float)
        Saturation torques [N m] of joints 1, 2 (70, 15 for the SICE arm).
    saturate : bool
        Clip commands to +-torque_limit.
    quantize : bool
        Model the 12-bit D/A over +-8 V: the torque is rounded to a step of
        ``2 * torque_limit / 2**dac_bits``.
    dac_bits : int
        D/A resolution.
    """

    torque_limit: tuple[float, float] = TORQUE_LIMITS
    saturate: bool = True
    quantize: bool = True
    dac_bits: int = 12

    def __post_init__(self) -> None:
        if len(self.torque_limit) != 2 or min(self.torque_limit) <= 0:
            raise ParameterError(f"torque_limit must be two positive values, got {self.torque_limit}")
        if self.dac_bits < 1:
            raise ParameterError(f"dac_bits must be >= 1, got {self.dac_bits}")

    @cached_property
    def _lim(self) -> Array:
        return np.asarray(self.torque_limit, dtype=float)

    @cached_property
    def _lsb(self) -> Array:
        return 2.0 * self._lim / 2**self.dac_bits

    def apply(self, tau_cmd: Array) -> tuple[Array, NDArray[np.bool_]]:
        """Return the applied torque and a per-joint flag of saturation."""
        lim = self._lim
        sat = np.abs(tau_cmd) > lim
        tau = np.clip(tau_cmd, -lim, lim) if self.saturate else tau_cmd
        if self.quantize:
            tau = np.round(tau / self._lsb) * self._lsb
            if self.saturate:  # the top code of a two's-complement D/A is lim - lsb
                tau = np.minimum(tau, lim - self._lsb)
        return tau, sat


# --------------------------------------------------------------------- sensors
@dataclass(frozen=True)
class SensorConfig:
    """Measurement of q (encoder) and qd (F/V conversion).

    Attributes
    ----------
    encoder_counts : (int, int)
        Pulses per revolution (614400 and 507904 on the SICE arm).
    quantize : bool
        Round the position to the encoder resolution before adding noise.
    position_variance : (float, float)
        Variance [rad^2] of additive white noise on q (Table 2).
    velocity_variance : (float, float)
        Variance [(rad/s)^2] of additive white noise on qd (Table 4).
    """

    encoder_counts: tuple[int, int] = (614400, 507904)
    quantize: bool = True
    position_variance: tuple[float, float] = (1e-8, 1e-7)
    velocity_variance: tuple[float, float] = (5e-5, 1e-4)

    def __post_init__(self) -> None:
        for name in ("encoder_counts", "position_variance", "velocity_variance"):
            v = getattr(self, name)
            if len(v) != 2 or not all(np.isfinite(v)):
                raise ParameterError(f"SensorConfig.{name} must be two finite values, got {v}")
        if min(self.encoder_counts) <= 0:
            raise ParameterError(f"encoder_counts must be > 0, got {self.encoder_counts}")
        if min(self.position_variance) < 0 or min(self.velocity_variance) < 0:
            raise ParameterError(
                f"noise variances must be >= 0, got position {self.position_variance}, "
                f"velocity {self.velocity_variance}"
            )

    @cached_property
    def resolution(self) -> Array:
        """Encoder step [rad] of each joint."""
        return 2.0 * np.pi / np.asarray(self.encoder_counts, dtype=float)

    @cached_property
    def noise_std(self) -> Array:
        """Standard deviations ``[sq1, sq2, sqd1, sqd2]``."""
        return np.sqrt(np.concatenate((self.position_variance, self.velocity_variance)))

    def measure(self, q: Array, qd: Array, noise: Array) -> tuple[Array, Array]:
        """Measured ``(q, qd)`` from true values and standard normal ``noise (..., 4)``."""
        qm = np.round(q / self.resolution) * self.resolution if self.quantize else q
        e = noise * self.noise_std
        return qm + e[..., :2], qd + e[..., 2:]


# -------------------------------------------------------------------- payloads
@dataclass(frozen=True)
class PayloadSchedule:
    """Payload disks that appear, change or vanish at given times.

    ``masses[k]`` [kg] holds from ``times[k]`` on; before ``times[0]`` the mass is
    ``initial_mass``. Masses may carry a trailing batch axis (one value per trial).

    Raises
    ------
    ParameterError
        Times not strictly increasing or negative; masses negative or non-finite.
    """

    times: tuple[float, ...] = ()
    masses: tuple = ()
    initial_mass: float | Sequence[float] = 0.0
    radius: float = 0.05

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
        if not np.isfinite(self.radius) or self.radius < 0:
            raise ParameterError(f"payload radius must be >= 0, got {self.radius}")

    def mass_at(self, t: float) -> Array:
        """Payload mass [kg] at time t (scalar or per-trial array)."""
        k = int(np.searchsorted(np.asarray(self.times, dtype=float), t + 1e-9, side="right"))
        m = self.initial_mass if k == 0 else self.masses[k - 1]
        return np.asarray(m, dtype=float)

    def sigma_at(self, t: float, sigma0: Array) -> Array:
        """Base parameters at time t: ``sigma0`` plus the disk (``(..., 7)``)."""
        return sigma0 + payload_sigma_delta(self.mass_at(t), self.radius)


# ------------------------------------------------------------------ pure step
@njit(cache=True, fastmath=False)
def _accel_hold(q2, v1, v2, t1, t2, sg, st1, st2, sl1, sl2):  # pragma: no cover - compiled
    """Accelerations with stuck joints held, and the torque friction must supply (one arm)."""
    j1, j2, r, b1, b2, d1, d2 = sg[0], sg[1], sg[2], sg[3], sg[4], sg[5], sg[6]
    c2, s2 = np.cos(q2), np.sin(q2)
    m11 = j1 + j2 + 2.0 * r * c2
    m12 = j2 + r * c2
    m22 = j2
    cor1 = -r * s2 * v2 * (2.0 * v1 + v2)
    cor2 = r * s2 * v1 * v1
    sgn1 = np.sign(v1) if v1 != 0.0 else sl1
    sgn2 = np.sign(v2) if v2 != 0.0 else sl2
    r1 = t1 - cor1 - b1 * v1 - d1 * sgn1
    r2 = t2 - cor2 - b2 * v2 - d2 * sgn2
    if st1 and st2:
        a1, a2 = 0.0, 0.0
    elif st1:
        a1, a2 = 0.0, r2 / m22
    elif st2:
        a1, a2 = r1 / m11, 0.0
    else:
        det = m11 * m22 - m12 * m12
        a1 = (m22 * r1 - m12 * r2) / det
        a2 = (m11 * r2 - m12 * r1) / det
    h1 = t1 - cor1 - m11 * a1 - m12 * a2
    h2 = t2 - cor2 - m12 * a1 - m22 * a2
    return a1, a2, h1, h2


@njit(cache=True, fastmath=False)
def _rk4(p1, p2, v1, v2, dt, t1, t2, sg, st1, st2, sl1, sl2):  # pragma: no cover - compiled
    """One classical RK4 step of length dt with the stuck set fixed."""
    a11, a12, _, _ = _accel_hold(p2, v1, v2, t1, t2, sg, st1, st2, sl1, sl2)
    w1, w2 = v1 + 0.5 * dt * a11, v2 + 0.5 * dt * a12
    a21, a22, _, _ = _accel_hold(p2 + 0.5 * dt * v2, w1, w2, t1, t2, sg, st1, st2, sl1, sl2)
    x1, x2 = v1 + 0.5 * dt * a21, v2 + 0.5 * dt * a22
    a31, a32, _, _ = _accel_hold(p2 + 0.5 * dt * w2, x1, x2, t1, t2, sg, st1, st2, sl1, sl2)
    y1, y2 = v1 + dt * a31, v2 + dt * a32
    a41, a42, _, _ = _accel_hold(p2 + dt * x2, y1, y2, t1, t2, sg, st1, st2, sl1, sl2)
    n1 = p1 + (dt / 6.0) * (v1 + 2.0 * w1 + 2.0 * x1 + y1)
    n2 = p2 + (dt / 6.0) * (v2 + 2.0 * w2 + 2.0 * x2 + y2)
    u1 = 0.0 if st1 else v1 + (dt / 6.0) * (a11 + 2.0 * a21 + 2.0 * a31 + a41)
    u2 = 0.0 if st2 else v2 + (dt / 6.0) * (a12 + 2.0 * a22 + 2.0 * a32 + a42)
    # a velocity that changes sign in any stage has met the Coulomb discontinuity:
    # the step is then not to be trusted (the caller splits it at the crossing)
    s1 = np.sign(v1) if v1 != 0.0 else sl1
    s2 = np.sign(v2) if v2 != 0.0 else sl2
    c1 = (not st1) and min(w1 * s1, x1 * s1, y1 * s1, u1 * s1) <= 0.0
    c2 = (not st2) and min(w2 * s2, x2 * s2, y2 * s2, u2 * s2) <= 0.0
    return n1, n2, u1, u2, c1, c2, a11, a12


@njit(cache=True, fastmath=False)
def _resolve(p2, v1, v2, t1, t2, sg, r1, r2, sl1, sl2):  # pragma: no cover - compiled
    """Friction mode of the joints at rest (``r_i``: qd_i == 0), decided jointly.

    Each joint at rest either sticks (consistent if its holding torque is at most
    d_i) or slides from rest in direction s (consistent if its acceleration has
    the sign of s). The combinations are tried, sticking first, and the first
    consistent one is taken; the 2x2 case has at most 9.
    """
    for m1 in range(3 if r1 else 1):
        for m2 in range(3 if r2 else 1):
            st1 = r1 and m1 == 0
            st2 = r2 and m2 == 0
            s1 = 1.0 if (r1 and m1 == 1) else (-1.0 if (r1 and m1 == 2) else sl1)
            s2 = 1.0 if (r2 and m2 == 1) else (-1.0 if (r2 and m2 == 2) else sl2)
            a1, a2, h1, h2 = _accel_hold(p2, v1, v2, t1, t2, sg, st1, st2, s1, s2)
            ok = True
            if r1:
                ok = ok and (abs(h1) <= sg[5] if st1 else a1 * s1 > 0.0)
            if r2:
                ok = ok and (abs(h2) <= sg[6] if st2 else a2 * s2 > 0.0)
            if ok:
                return st1, st2, s1, s2
    return r1, r2, sl1, sl2  # numerically borderline: hold them this substep


@njit(cache=True, fastmath=False)
def _plant_step_kernel(q, qd, stuck, slip, tau, sigma, T, substeps):  # pragma: no cover
    n = q.shape[0]
    h = T / substeps
    for i in range(n):
        sg = sigma[i]
        p1, p2, v1, v2 = q[i, 0], q[i, 1], qd[i, 0], qd[i, 1]
        st1, st2, sl1, sl2 = stuck[i, 0], stuck[i, 1], slip[i, 0], slip[i, 1]
        t1, t2 = tau[i, 0], tau[i, 1]
        cz1, cz2 = sg[5] > 0.0, sg[6] > 0.0  # joints with Coulomb friction
        for _ in range(substeps):
            r1, r2 = v1 == 0.0 and cz1, v2 == 0.0 and cz2
            st1, st2 = False, False
            if r1 or r2:
                st1, st2, sl1, sl2 = _resolve(p2, v1, v2, t1, t2, sg, r1, r2, sl1, sl2)
            n1, n2, u1, u2, c1, c2, a1, a2 = _rk4(p1, p2, v1, v2, h, t1, t2, sg, st1, st2, sl1, sl2)
            c1 = c1 and cz1
            c2 = c2 and cz2
            if c1 or c2:
                # a velocity reaches zero: step to the first crossing (located from the
                # initial acceleration), decide the friction modes there, finish the substep
                f1 = min(1.0, abs(v1) / (h * abs(a1))) if c1 and v1 * a1 < 0.0 else (0.0 if c1 else 1.0)
                f2 = min(1.0, abs(v2) / (h * abs(a2))) if c2 and v2 * a2 < 0.0 else (0.0 if c2 else 1.0)
                f = min(f1, f2)
                if f > 0.0:
                    p1, p2, v1, v2, _, _, _, _ = _rk4(p1, p2, v1, v2, f * h, t1, t2, sg, st1, st2, sl1, sl2)
                if c1 and f1 <= f:
                    v1 = 0.0
                if c2 and f2 <= f:
                    v2 = 0.0
                st1, st2, sl1, sl2 = _resolve(
                    p2, v1, v2, t1, t2, sg, v1 == 0.0 and cz1, v2 == 0.0 and cz2, sl1, sl2
                )
                n1, n2, u1, u2, z1, z2, _, _ = _rk4(
                    p1, p2, v1, v2, (1.0 - f) * h, t1, t2, sg, st1, st2, sl1, sl2
                )
                # another crossing within the same substep: rest there (decided next substep)
                if z1 and cz1 and f < 1.0:
                    u1 = 0.0
                if z2 and cz2 and f < 1.0:
                    u2 = 0.0
            p1, p2, v1, v2 = n1, n2, u1, u2
        q[i, 0], q[i, 1], qd[i, 0], qd[i, 1] = p1, p2, v1, v2
        stuck[i, 0], stuck[i, 1] = st1 and v1 == 0.0, st2 and v2 == 0.0
        slip[i, 0], slip[i, 1] = sl1, sl2


def plant_step(
    q: Array,
    qd: Array,
    stuck: NDArray[np.bool_],
    slip: Array,
    tau: Array,
    sigma: Array,
    T: float,
    substeps: int = 2,
) -> tuple[Array, Array, NDArray[np.bool_], Array]:
    """Advance the arm by one sample with torque ``tau`` held constant (pure function).

    Compiled with numba: one loop over the batch, scalar 2x2 algebra inside.

    Parameters
    ----------
    q, qd : ndarray, shape (..., 2)
        State at the start of the sample.
    stuck : ndarray of bool, shape (..., 2)
        Joints currently stuck by Coulomb friction.
    slip : ndarray, shape (..., 2)
        Direction (+-1) a joint last broke away in; used as sgn(qd) while qd == 0.
    tau : ndarray, shape (..., 2)
        Applied torque [N m], held over the sample.
    sigma : ndarray, shape (..., 7)
        True base parameters.
    T : float
        Sample period [s].
    substeps : int
        RK4 steps per sample.

    Returns
    -------
    q, qd, stuck, slip : the state after ``T`` (new arrays; inputs are not changed).
    """
    shape = np.broadcast_shapes(q.shape, qd.shape, tau.shape, (*sigma.shape[:-1], 2))
    flat = (-1, 2)
    q_ = np.ascontiguousarray(np.broadcast_to(q, shape), dtype=float).reshape(flat).copy()
    qd_ = np.ascontiguousarray(np.broadcast_to(qd, shape), dtype=float).reshape(flat).copy()
    st_ = np.ascontiguousarray(np.broadcast_to(stuck, shape), dtype=np.bool_).reshape(flat).copy()
    sl_ = np.ascontiguousarray(np.broadcast_to(slip, shape), dtype=float).reshape(flat).copy()
    tau_ = np.ascontiguousarray(np.broadcast_to(tau, shape), dtype=float).reshape(flat)
    sig_ = np.ascontiguousarray(np.broadcast_to(sigma, (*shape[:-1], 7)), dtype=float).reshape(-1, 7)
    _plant_step_kernel(q_, qd_, st_, sl_, tau_, sig_, float(T), int(substeps))
    return q_.reshape(shape), qd_.reshape(shape), st_.reshape(shape), sl_.reshape(shape)


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


def _noise_for(rng: np.random.Generator | Sequence[np.random.Generator], n_trials: int, n: int):
    if isinstance(rng, np.random.Generator):
        return rng.standard_normal((n_trials, n, 4))
    rngs = list(rng)
    if len(rngs) != n_trials:
        raise ParameterError(f"need one Generator per trial: {n_trials} trials, {len(rngs)} rngs")
    return np.stack([g.standard_normal((n, 4)) for g in rngs])


class ArmSimulator:
    """A batch of arms stepped at the sample rate (stateful wrapper of :func:`plant_step`).

    Parameters
    ----------
    n_trials : int
        Batch size.
    n_samples : int
        Number of samples the run will take (sensor noise is drawn up front so a
        trial's noise depends only on its own generator).
    rng : numpy.random.Generator or sequence of them
        One shared generator, or one per trial (reproducible trial by trial).
    sigma0 : array_like (7,) or (n_trials, 7)
        Base parameters without payload.
    payload : PayloadSchedule, optional
    sample_period : float
        T [s], > 0.
    substeps : int
        RK4 steps per sample.
    actuator, sensor : ActuatorConfig, SensorConfig
    q0, qd0 : array_like (2,) or (n_trials, 2)
        Initial state; the arm starts stuck where qd0 == 0.
    """

    def __init__(
        self,
        n_trials: int,
        n_samples: int,
        rng: np.random.Generator | Sequence[np.random.Generator],
        sigma0: ArrayLike = TABLE1_SIGMA,
        payload: PayloadSchedule | None = None,
        sample_period: float = 0.001,
        substeps: int = 2,
        actuator: ActuatorConfig | None = None,
        sensor: SensorConfig | None = None,
        q0: ArrayLike = (0.0, 0.0),
        qd0: ArrayLike = (0.0, 0.0),
    ) -> None:
        if not np.isfinite(sample_period) or sample_period <= 0:
            raise ParameterError(f"sample_period T must be > 0, got {sample_period}")
        if int(substeps) < 1:
            raise ParameterError(f"substeps must be >= 1, got {substeps}")
        if n_trials < 1 or n_samples < 1:
            raise ParameterError(f"n_trials and n_samples must be >= 1, got {n_trials}, {n_samples}")
        self.n_trials, self.n_samples = int(n_trials), int(n_samples)
        self.T, self.substeps = float(sample_period), int(substeps)
        self.sigma0 = np.broadcast_to(validate_sigma(sigma0, "sigma0"), (n_trials, 7)).copy()
        self.payload = payload or PayloadSchedule()
        self.actuator = actuator or ActuatorConfig()
        self.sensor = sensor or SensorConfig()
        shape = (self.n_trials, 2)
        self.q = np.broadcast_to(as_joint_array(q0, "q0"), shape).copy()
        self.qd = np.broadcast_to(as_joint_array(qd0, "qd0"), shape).copy()
        self.stuck = np.ascontiguousarray(self.qd == 0.0)
        self.slip = np.ones(shape)
        self.failed = np.zeros(self.n_trials, dtype=bool)
        self.failed_at = np.full(self.n_trials, -1)
        self.k = 0
        self._noise = _noise_for(rng, self.n_trials, self.n_samples)
        # a swap at time `at` takes effect at the first sample k with k T >= at
        self._swap_samples = {int(np.ceil(at / self.T - 1e-9)) for at in self.payload.times}
        self._update_sigma()

    @property
    def t(self) -> float:
        return self.k * self.T

    def _update_sigma(self) -> None:
        self.mass = np.broadcast_to(self.payload.mass_at(self.t), (self.n_trials,))
        self.sigma = np.ascontiguousarray(self.sigma0 + payload_sigma_delta(self.mass, self.payload.radius))

    def measure(self) -> tuple[Array, Array]:
        """Measured (q, qd) at the current sample."""
        if self.k >= self.n_samples:
            raise SignalError(f"simulator was built for {self.n_samples} samples; asked for sample {self.k}")
        return self.sensor.measure(self.q, self.qd, self._noise[:, self.k])

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
        _plant_step_kernel(
            self.q,
            self.qd,
            self.stuck,
            self.slip,
            np.ascontiguousarray(tau),
            self.sigma,
            self.T,
            self.substeps,
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
        Passed to :class:`ArmSimulator` (sigma0, payload, sample_period, ...).
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
    return rec.result(sim)


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
