"""Identification records of any :class:`Arm` simulated with a known truth.

The experiment
--------------
The arm (its URDF parameters plus an optional rigid payload on the payload frame)
tracks a reference ``q_d(t)`` (a scenario's ``[reference]``, e.g. a designed
excitation from :mod:`adaptive_dd.identification.excitation`) under **computed torque
with the plant's own model** (the URDF's parameters and the payload: a well-tuned
controller, so that the arm follows the reference whatever the payload), at the sample
rate with zero-order hold::

    tau_cmd = M(q_m) (qdd_d + 2 w (qd_d - qd_m) + w^2 (q_d - q_m)) + h(q_m, qd_m)

``w`` the bandwidth [rad/s], ``q_m, qd_m`` the measured signals (encoder quantization and
white Gaussian noise of the arm's :class:`~adaptive_dd.plant.devices.SensorConfig`, through
:func:`adaptive_dd.plant.sampling.measure_batch`), the command through the actuator's
saturation and D/A (:func:`adaptive_dd.plant.sampling.actuate_batch`). The record holds
the measured ``q, qd`` and the **applied** torque (known, as a drive's current loop
reports it). The plant is, by default (``plant="model"``), RK4 (``substeps`` per sample)
over the compiled forward dynamics with smooth friction ``fv qd + fc tanh(qd / v_f)``:
exactly the model of :mod:`adaptive_dd.identification.model`, so that estimators are
held to the bound without model error. ``plant="benchmark"`` runs the closed-loop benchmark's
plant instead (:func:`adaptive_dd.plant.integrator.plant_step` with the arm's
friction law, stick-slip by default): a record the model does not describe exactly near
zero velocity.

Trials run as one batch (axis 0), each with its own noise from its own generator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.identification.model import Model, arm_model, pi_with_payload, rk4_step
from adaptive_dd.plant.chain import rnea_batch

__all__ = ["Record", "SyntheticLog", "inverse_dynamics_pi", "simulate_record", "synthetic_log"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Record:
    """Simulated records of one arm, trial axis first.

    Attributes
    ----------
    t : ndarray (N,)
        Sample instants [s].
    q, qd : ndarray (S, N, n)
        Measured joint positions [rad] and velocities [rad/s].
    tau : ndarray (S, N, n)
        Applied torque held over each sample [N m].
    q_true, qd_true : ndarray (S, N, n)
        The plant's state at the sample instants.
    pi_true : ndarray (13 n,)
        Standard parameters of the simulated plant (payload included).
    sigma_true : ndarray (p,)
        Its base parameters.
    payload : ndarray (10,)
        The payload's parameters about the payload frame (zeros: none).
    sample_period : float
    saturated : ndarray (S, n)
        Fraction of samples with the command saturated, per joint.

    Examples
    --------
    Made by :func:`simulate_record`; two noisy records of 0.2 s of the three-joint arm:

    >>> import numpy as np
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.identification.records import simulate_record
    >>> ref = {"joint1": {"offset": 0.3, "amplitude": [0.4], "frequency": [0.3]},
    ...        "joint2": {"offset": -0.6, "amplitude": [0.5], "frequency": [0.4]},
    ...        "joint3": {"offset": 0.4, "amplitude": [0.6], "frequency": [0.5]}}
    >>> sc = parse_scenario({"arm": {"robot": "vertical3"}, "reference": ref})
    >>> rngs = [np.random.default_rng(0), np.random.default_rng(1)]
    >>> rec = simulate_record(sc.arm, sc.reference, 0.2, rngs)  # compiles on a cold cache
    >>> rec.q.shape, rec.tau.shape  # records x samples x joints
    ((2, 200, 3), (2, 200, 3))
    >>> bool(np.isclose(rec.t[1] - rec.t[0], rec.sample_period))  # [s]
    True
    """

    t: Array
    q: Array
    qd: Array
    tau: Array
    q_true: Array
    qd_true: Array
    pi_true: Array
    sigma_true: Array
    payload: Array
    sample_period: float
    saturated: Array


def inverse_dynamics_pi(model: Model, pi: Array, q: Array, qd: Array, qdd: Array) -> Array:
    """Joint torques ``(..., n)`` of standard parameters ``pi (13 n,)`` (friction, armature included)."""
    n = model.n
    links, fv, fc, ia = pi[: 10 * n], pi[10 * n : 11 * n], pi[11 * n : 12 * n], pi[12 * n :]
    tau = rnea_batch(model.chain, links, q, qd, qdd)
    return tau + ia * qdd + fv * qd + fc * np.tanh(qd / model.friction_velocity)


def simulate_record(
    arm,
    reference,
    duration: float,
    rngs: list[np.random.Generator],
    *,
    sample_period: float = 1e-3,
    payload: ArrayLike | None = None,
    bandwidth: float = 40.0,
    substeps: int = 2,
    noise: bool = True,
    quantize: bool = True,
    plant: str = "model",
) -> Record:
    """Simulate ``len(rngs)`` identification records of ``arm`` tracking ``reference``.

    Parameters
    ----------
    arm : Arm
    reference : object with ``sample(t) -> (q_d, qd_d, qdd_d)``, each ``(N, n)``
        E.g. :class:`adaptive_dd.benchmark.scenario.Reference`.
    duration : float
        [s].
    rngs : list of numpy.random.Generator
        One per trial (the sensor noise); a single Generator: one record.
    sample_period : float
        T [s].
    payload : array_like (10,), optional
        Rigid payload about the payload frame
        (:func:`adaptive_dd.plant.arm.payload_parameters`).
    bandwidth : float
        Computed-torque bandwidth w [rad/s] (``w T <= 0.2``).
    substeps : int
        RK4 steps per sample.
    noise, quantize : bool
        Sensor noise; encoder and D/A quantization.
    plant : {"model", "benchmark"}
        The identification model's RK4 (default) or the benchmark's compiled plant with the arm's
        friction law (module docstring; ``"serial"``, its old name, warns and is read as it).


    Returns
    -------
    Record
        One trial per generator, trial axis first.

    Raises
    ------
    ParameterError
        Bad duration, period, bandwidth, or a reference for another number of joints.
    SignalError
        If the simulated state becomes non-finite.

    Examples
    --------
    Two noisy records of 0.2 s of the three-joint arm tracking a sine per joint:

    >>> import numpy as np
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.identification.records import simulate_record
    >>> ref = {"joint1": {"offset": 0.3, "amplitude": [0.4], "frequency": [0.3]},
    ...        "joint2": {"offset": -0.6, "amplitude": [0.5], "frequency": [0.4]},
    ...        "joint3": {"offset": 0.4, "amplitude": [0.6], "frequency": [0.5]}}
    >>> sc = parse_scenario({"arm": {"robot": "vertical3"}, "reference": ref})
    >>> rngs = [np.random.default_rng(0), np.random.default_rng(1)]
    >>> rec = simulate_record(sc.arm, sc.reference, 0.2, rngs)  # compiles on a cold cache
    >>> rec.q.shape, rec.tau.shape  # records x samples x joints
    ((2, 200, 3), (2, 200, 3))
    >>> rec.sigma_true.shape == (sc.arm.base.count,)
    True
    """
    _check_timing(duration, sample_period, bandwidth)
    if isinstance(rngs, np.random.Generator):  # one record: its generator alone
        rngs = [rngs]
    if not len(rngs) or not all(isinstance(r, np.random.Generator) for r in rngs):
        raise ParameterError(
            f"simulate_record: rngs is a list of numpy Generators, one per record, got {rngs!r}: e.g. "
            "[np.random.default_rng(0)]"
        )
    t, ref = _reference_samples(reference, duration, sample_period, arm.n_joints)
    model = arm_model(arm)
    pp = np.zeros(10) if payload is None else np.asarray(payload, dtype=float)
    if pp.size != 10:
        raise ParameterError(
            f"simulate_record: payload is its 10 inertial parameters about the payload frame "
            f"(adaptive_dd.plant.payload_parameters(mass, com, inertia)), got {payload!r}"
        )
    pp = pp.reshape(10)
    pi_true = pi_with_payload(arm, model.pi_ref, pp)
    step = _plant_step(plant, arm, model, pi_true, len(rngs), sample_period, substeps)
    out, sat_count = _track(arm, model, pi_true, ref, rngs, step, bandwidth, noise, quantize)
    return Record(
        t=t,
        pi_true=pi_true,
        sigma_true=model.B @ pi_true,
        payload=pp,
        sample_period=float(sample_period),
        saturated=sat_count / t.size,
        **out,
    )


def _check_timing(duration: float, sample_period: float, bandwidth: float) -> None:
    if not (np.isfinite(duration) and duration >= 10 * sample_period and sample_period > 0):
        raise ParameterError(f"need duration >= 10 samples of T > 0, got {duration} s, T = {sample_period} s")
    if not (0 < bandwidth * sample_period <= 0.2):
        raise ParameterError(f"bandwidth {bandwidth} rad/s with T = {sample_period} s: need 0 < w T <= 0.2")


def _reference_samples(reference, duration: float, sample_period: float, n: int):
    """The sample instants ``t (N,)`` and the reference ``(q_d, qd_d, qdd_d)`` there, each ``(N, n)``."""
    N = round(duration / sample_period)
    t = np.arange(N) * sample_period
    ref = reference.sample(t)
    if ref[0].shape != (N, n):
        raise ParameterError(f"the reference has {ref[0].shape[-1]} joints, the arm {n}")
    return t, ref


def _plant_step(plant: str, arm, model: Model, pi_true: Array, S: int, T: float, substeps: int):
    """``step(q, qd, tau) -> (q, qd)`` over one sample: the model's RK4 or the benchmark's plant."""
    if plant == "serial":
        import warnings

        warnings.warn("plant='serial' is deprecated; use plant='benchmark'", FutureWarning, 3)
        plant = "benchmark"
    if plant not in ("model", "benchmark"):
        raise ParameterError(f"plant must be 'model' or 'benchmark', got {plant!r}")
    if plant == "benchmark":
        return _stepper(arm, model, pi_true, S, T, substeps)
    return lambda q, qd, tau: rk4_step(model, pi_true, q, qd, tau, T, substeps)


def _track(arm, model: Model, pi_true: Array, ref, rngs, step, bandwidth: float, noise: bool, quantize: bool):
    """Computed torque along ``ref = (q_d, qd_d, qdd_d)`` (each ``(N, n)``), sample by sample, from
    the reference's first state; ``step(q, qd, tau) -> (q, qd)`` advances the plant one sample.

    Returns the measured, applied and true signals ``q, qd, tau, q_true, qd_true`` (each
    ``(S, N, n)``, a dict) and the count of saturated samples ``(S, n)``; a non-finite
    measurement is an error.
    """
    from adaptive_dd.plant.sampling import actuate_batch, measure_batch

    q_d, qd_d, qdd_d = ref
    (N, n), S = q_d.shape, len(rngs)
    sensor, act = arm.sensor, arm.actuator
    std = sensor.noise_std if noise else np.zeros(2 * n)
    res = sensor.resolution
    lim, lsb = (
        np.asarray(act.torque_limit, float),
        2.0 * np.asarray(act.torque_limit, float) / 2**act.dac_bits,
    )
    q = np.repeat(q_d[:1], S, axis=0).copy()
    qd = np.repeat(qd_d[:1], S, axis=0).copy()
    out = {k: np.empty((S, N, n)) for k in ("q", "qd", "tau", "q_true", "qd_true")}
    sat_count = np.zeros((S, n))
    kp, kd = bandwidth**2, 2.0 * bandwidth
    block = 1024
    for k in range(N):
        if k % block == 0:  # noise drawn in blocks, each trial from its own generator
            m = min(block, N - k)
            z = np.stack([g.standard_normal((m, 2 * n)) for g in rngs], axis=1)  # (m, S, 2n)
        qm, qdm = np.empty_like(q), np.empty_like(qd)
        measure_batch(q, qd, np.ascontiguousarray(z[k % block]), res, std, quantize, qm, qdm)
        a = qdd_d[k] + kd * (qd_d[k] - qdm) + kp * (q_d[k] - qm)
        cmd = inverse_dynamics_pi(model, pi_true, qm, qdm, a)
        tau = np.empty_like(cmd)
        sat = np.empty(cmd.shape, dtype=np.bool_)
        actuate_batch(np.array(cmd, order="C"), lim, lsb, act.saturate, quantize, tau, sat)  # writable
        sat_count += sat
        for key, v in (("q", qm), ("qd", qdm), ("tau", tau), ("q_true", q), ("qd_true", qd)):
            out[key][:, k] = v
        q, qd = step(q, qd, tau)
    if not np.all(np.isfinite(out["q"])):
        raise SignalError("simulate_record: non-finite measurement")
    return out, sat_count


def _stepper(arm, model: Model, pi: Array, S: int, T: float, substeps: int):
    """A function ``(q, qd, tau) (S, n) -> (q, qd)`` through the compiled benchmark plant."""
    from adaptive_dd.plant.integrator import plant_params, plant_step

    n = model.n
    lugre = arm.friction == "lugre"
    # one record per trial under LuGre: each carries its trial's bristles
    pps = [
        plant_params(
            model.chain,
            pi[: 10 * n],
            pi[10 * n : 11 * n],
            pi[11 * n : 12 * n],
            pi[12 * n :],
            law=arm.friction,
            friction_velocity=arm.friction_velocity,
            stribeck_ratio=arm.stribeck_ratio,
            stribeck_velocity=arm.stribeck_velocity,
            lugre_stiffness=arm.lugre_stiffness if lugre else None,
            lugre_damping=arm.lugre_sigma1 if lugre else None,
        )
        for _ in range(S if lugre else 1)
    ]
    stuck = np.zeros((S, n), dtype=np.bool_)

    def step(q, qd, tau):
        q, qd = np.ascontiguousarray(q).copy(), np.ascontiguousarray(qd).copy()
        for s in range(S):
            pp = pps[s if lugre else 0]
            if not plant_step(
                model.chain, pp, q[s], qd[s], np.ascontiguousarray(tau[s]), T, substeps, stuck[s]
            ):
                raise SignalError(f"simulate_record: the plant failed (trial {s})")
        return q, qd

    return step


@dataclass(frozen=True)
class SyntheticLog:
    """A log computed by inverse dynamics along a multi-sine (:func:`synthetic_log`).

    Attributes
    ----------
    t : ndarray (N,)
        [s].
    q, qd, tau : ndarray (N, n)
        Exact positions and velocities; torque with coloured, heteroscedastic noise [N m].
    sigma_true : ndarray (p,)
        Base parameters of the arm (payload included) in the identification model's Coulomb law.
    payload : ndarray (10,)
    """

    t: Array
    q: Array
    qd: Array
    tau: Array
    sigma_true: Array
    payload: Array


def synthetic_log(
    arm,
    duration: float,
    sample_period: float,
    rng: np.random.Generator,
    *,
    payload: ArrayLike | None = None,
    noise: float = 0.02,
    correlation: float = 0.05,
    heteroscedastic: float = 1.0,
    amplitude: float = 0.6,
    noise_rng: np.random.Generator | None = None,
) -> SyntheticLog:
    """A log of ``arm`` whose model is the identification's, with noise like a real log's residual.

    Each joint follows three sines (0.1-0.6 Hz, random phases from ``rng``) of total amplitude
    ``amplitude`` [rad, m x 0.1 for a prismatic joint] about the middle of its limits; the torque is
    the model's (:func:`~adaptive_dd.identification.model.arm_model`, ``fc tanh(qd / v_f)``, payload
    ``payload`` on the payload frame) plus noise: per channel ``noise`` times the channel's torque
    rms, an AR(1) of time constant ``correlation`` [s] (coloured), scaled by ``1 + heteroscedastic
    |qd_j| / max |qd_j|`` (its level changes with the motion). Positions and velocities are exact,
    so that the estimate's error is the torque noise's alone and its bound can be checked. The noise
    is drawn from ``noise_rng`` when given (default ``rng``): one motion with noise drawn again.

    Raises
    ------
    ParameterError
        A duration under 10 samples or a non-positive period, noise or correlation.
    """
    from adaptive_dd.identification.model import base_regressor

    if not (sample_period > 0 and duration >= 10 * sample_period and noise >= 0 and correlation > 0):
        raise ParameterError(
            f"synthetic_log: need T > 0, duration >= 10 T, noise >= 0, correlation > 0; got T = "
            f"{sample_period}, duration = {duration}, noise = {noise}, correlation = {correlation}"
        )
    model = arm_model(arm)
    n = model.n
    t = np.arange(round(duration / sample_period)) * sample_period
    lim = np.asarray(arm.position_limits, dtype=float)
    mid = np.where(np.isfinite(lim).all(axis=1), lim.mean(axis=1), 0.0)
    scale = np.where(np.asarray(arm.joint_kinds) == "prismatic", 0.1, 1.0) * amplitude / 3.0
    w = 2 * np.pi * rng.uniform(0.1, 0.6, (3, n))
    ph = rng.uniform(0, 2 * np.pi, (3, n))
    arg = w[:, None, :] * t[None, :, None] + ph[:, None, :]  # (3, N, n)
    q = mid + scale * np.sin(arg).sum(axis=0)
    qd = scale * (w[:, None, :] * np.cos(arg)).sum(axis=0)
    qdd = -scale * (w[:, None, :] ** 2 * np.sin(arg)).sum(axis=0)
    pp = np.zeros(10) if payload is None else np.asarray(payload, dtype=float).reshape(10)
    sigma = model.B @ pi_with_payload(arm, model.pi_ref, pp)
    tau = base_regressor(model, q, qd, qdd) @ sigma
    a = np.exp(-sample_period / correlation)
    nr = rng if noise_rng is None else noise_rng
    z = nr.standard_normal(tau.shape) * np.sqrt(1 - a * a)
    e = np.empty_like(z)
    e[0] = nr.standard_normal(n)
    for k in range(1, t.size):
        e[k] = a * e[k - 1] + z[k]
    level = noise * np.sqrt(np.mean(tau**2, axis=0))
    speed = np.abs(qd) / np.maximum(np.abs(qd).max(axis=0), 1e-300)
    return SyntheticLog(t, q, qd, tau + level * (1 + heteroscedastic * speed) * e, sigma, pp)
