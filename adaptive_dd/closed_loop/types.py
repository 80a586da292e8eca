"""What travels into the compiled closed loop: NamedTuples of arrays, one per concern.

numba compiles NamedTuples of arrays (and scalars) as structs, so every kernel takes a
handful of named records instead of dozens of positional arguments, and nothing is read
by slot number. Shapes use ``n`` joints, ``S`` trials, ``N`` samples, ``G`` payload
segments, ``p`` base parameters, ``K`` trials whose trajectories are recorded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.plant.sampling import first_sample

if TYPE_CHECKING:
    from adaptive_dd.plant.integrator import LugreLaw, SmoothLaw, StickSlipLaw

__all__ = [
    "MAX_ERROR",
    "MAX_SPEED",
    "SETTLE",
    "Io",
    "Plant",
    "Recording",
    "RunConstants",
    "StreamedSums",
    "TrialState",
    "io_of",
    "pi_with_payload",
    "plant_of",
    "plant_record",
    "reset_plant",
    "run_constants",
    "sample_bounds",
    "segment_starts",
    "true_models",
]

Array = NDArray[np.float64]

MAX_ERROR = 3.0
"""Tracking error [rad] (any joint) beyond which a trial counts as diverged."""
MAX_SPEED = 1e3
"""Joint speed [rad/s] beyond which a trial counts as diverged (runaway)."""
SETTLE = 0.5
"""[s] left out at the start of each segment for the settled RMS error."""


class RunConstants(NamedTuple):
    """The run's timing, reference and segments (the same for every trial).

    Attributes
    ----------
    T : float
        Sample period [s].
    max_error, max_speed : float
        Divergence thresholds [rad], [rad/s].
    q_d, qd_d, qdd_d : ndarray (N, n)
        Reference [rad, rad/s, rad/s^2] at every sample.
    seg_start, seg_end, seg_settled : ndarray of int64 (G,)
        First sample of each segment (:func:`~adaptive_dd.benchmark.scenario_checks.first_sample`
        of the swap time), one past its last, first sample counted in the settled RMS.
    ee_index, ee_links, ee_ref : ndarray
        The tool frame's kinematics and the reference's placements
        (:class:`~adaptive_dd.closed_loop.tool_frame.ToolTables`: ``index``, ``links``, ``ref``),
        from which the loop streams the tool frame's error.
    """

    T: float
    max_error: float
    max_speed: float
    q_d: Array
    qd_d: Array
    qdd_d: Array
    seg_start: NDArray[np.int64]
    seg_end: NDArray[np.int64]
    seg_settled: NDArray[np.int64]
    ee_index: NDArray[np.int64]
    ee_links: Array
    ee_ref: Array


class Io(NamedTuple):
    """Actuator (saturation, D/A) and sensor (encoder, noise) of the arm, per joint.

    ``lim, lsb (n,)`` [N m]; ``res (n,)`` encoder step [rad]; ``std (2 n,)`` noise standard
    deviations of q then qd.
    """

    lim: Array
    lsb: Array
    saturate: bool
    quantize_dac: bool
    res: Array
    std: Array
    quantize_encoder: bool


class Plant(NamedTuple):
    """The simulated arm of each trial: link parameters per payload segment and the joints' friction.

    Attributes
    ----------
    pi_seg : ndarray (S, G, 10 n)
        Standard link parameters of trial i's plant with each segment's payload.
    fv, fc, armature : ndarray (S, n)
        Viscous [N m s], Coulomb [N m] friction and armature [kg m^2] of trial i's plant.
    friction_law : StickSlipLaw or SmoothLaw or LugreLaw
        :func:`~adaptive_dd.plant.integrator.friction_law` of :attr:`Arm.friction_code` (0 stick-slip,
        1 tanh, 2 Stribeck, 3 LuGre): the law's family a compile-time choice; LuGre's record holds
        every trial's bristle state ``z (S, n)``, which each controller's run starts at rest
        (:func:`reset_plant`).
    fparams : ndarray (3,) or (3 + 2 n,)
        Friction velocity, Stribeck ratio, Stribeck velocity (:attr:`Arm.friction_params`: LuGre's
        bristle stiffness and damping per joint after them).
    substeps : int
        RK4 substeps per sample.
    chain : Chain
        The arm's kinematics (:class:`~adaptive_dd.plant.chain.Chain`).
    """

    pi_seg: Array
    fv: Array
    fc: Array
    armature: Array
    friction_law: StickSlipLaw | SmoothLaw | LugreLaw
    fparams: Array
    substeps: int
    chain: Any


class TrialState(NamedTuple):
    """Per-trial state of the loop, updated in place.

    ``q, qd (S, n)`` true state; ``stuck (S, n)`` stick-slip flags; ``failed (S,)``,
    ``failed_at (S,)`` (sample or -1); ``held_q, held_qd (S, n)`` last good measurement
    (dropouts); ``n_dropped (S,)``; ``failed_cmd (S,)`` the joint (from 0) whose command was not
    finite at the failed sample, or -1 (the failure had another cause, or none yet).
    """

    q: Array
    qd: Array
    stuck: NDArray[np.bool_]
    failed: NDArray[np.bool_]
    failed_at: NDArray[np.int64]
    held_q: Array
    held_qd: Array
    n_dropped: NDArray[np.int64]
    failed_cmd: NDArray[np.int64]


class StreamedSums(NamedTuple):
    """Metrics accumulated per trial and segment as the run streams.

    Attributes
    ----------
    sum_e2 : (S, G)
        Sum over the segment's samples of ``|e|^2`` [rad^2] (e on the true q).
    sum_e2_joint : (S, G, n)
        The same per joint.
    max_e : (S, G)
        Max ``|e|`` [rad].
    sum_tau2 : (S, G)
        Sum of ``|tau|^2`` of the applied torque [N^2 m^2].
    n_saturated : (S, G)
        Samples with a joint's command beyond its limit.
    sum_e2_settled : (S, G)
        Sum of ``|e|^2`` from ``seg_settled`` on.
    e_norm : float32 (S, N)
        ``|e|`` at every sample (settling times).
    ee_sum_p2 : (S, G)
        Sum of the tool frame's squared position error ``|p(q_d) - p(q)|^2`` [m^2]
        (:mod:`~adaptive_dd.closed_loop.tool_frame`).
    ee_max_p : (S, G)
        Its peak ``max |p(q_d) - p(q)|`` [m].
    ee_sum_th2 : (S, G)
        Sum of the squared angle of ``R(q_d)^T R(q)`` [rad^2]. The three None: not streamed
        (sums built by hand); the loops always stream them (:meth:`zeros`).
    first_saturated : (S, G)
        The sample index of the segment's first sample with a joint's command beyond its limit
        (NaN: none; None: not streamed, as the three above).
    """

    sum_e2: Array
    sum_e2_joint: Array
    max_e: Array
    sum_tau2: Array
    n_saturated: Array
    sum_e2_settled: Array
    e_norm: NDArray[np.float32]
    ee_sum_p2: Array | None = None
    ee_max_p: Array | None = None
    ee_sum_th2: Array | None = None
    first_saturated: Array | None = None

    @classmethod
    def zeros(cls, S: int, G: int, n: int, N: int) -> StreamedSums:
        z = np.zeros((S, G))
        return cls(
            z, np.zeros((S, G, n)), z.copy(), z.copy(), z.copy(), z.copy(), np.zeros((S, N), np.float32),
            z.copy(), z.copy(), z.copy(), np.full((S, G), np.nan),
        )  # fmt: skip


class Recording(NamedTuple):
    """Trajectories of the first ``K`` trials and the estimate at each segment's end.

    ``q, qd, tau (K, N, n)`` true state and applied torque; ``saturated (K, N, n)``;
    ``sigma (K', N, p)`` the estimate in base parameters (K' = K for controllers with an
    estimate, else 0); ``sigma_end (S, G, p)`` the estimate at each segment's last sample.
    """

    q: Array
    qd: Array
    tau: Array
    saturated: NDArray[np.bool_]
    sigma: Array
    sigma_end: Array


# ---------------------------------------------------------------------------- builders
def segment_starts(scenario) -> NDArray[np.int64]:
    """First sample of each payload segment (0, then each swap's ``first_sample``)."""
    T = scenario.sample_period
    return np.array([0, *(first_sample(t, T) for t in scenario.swap_times)], dtype=np.int64)


def sample_bounds(scenario) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Per payload segment ``(G,)`` each: its first sample, its end (exclusive) and its first settled
    sample (``seg_start``, ``seg_end``, ``seg_settled`` of :func:`run_constants`, which takes them
    from here), without sampling the reference and the tool frame along it."""
    N, T = scenario.n_samples, scenario.sample_period
    start = segment_starts(scenario)
    end = np.append(start[1:], N).astype(np.int64)
    settled = np.minimum(end - 1, start + round(SETTLE / T)).astype(np.int64)
    return start, end, settled


def run_constants(scenario) -> RunConstants:
    """Timing, reference and segment bounds of a scenario."""
    N, T = scenario.n_samples, scenario.sample_period
    q_d, qd_d, qdd_d = scenario.reference.sample(np.arange(N) * T)
    start, end, settled = sample_bounds(scenario)
    c = np.ascontiguousarray
    from adaptive_dd.closed_loop.tool_frame import tool_tables

    tool = tool_tables(scenario.arm, q_d)
    return RunConstants(float(T), MAX_ERROR, MAX_SPEED, c(q_d), c(qd_d), c(qdd_d), start, end, settled, *tool)


def io_of(scenario) -> Io:
    """Actuator and sensor of the scenario's arm, with the scenario's noise."""
    act, sens = scenario.arm.actuator, scenario.arm.sensor
    std = np.sqrt(np.concatenate((scenario.position_variance, scenario.velocity_variance)))
    return Io(
        act._lim, act._lsb, bool(act.saturate), bool(act.quantize), sens.resolution, std, bool(sens.quantize)
    )


def pi_with_payload(arm, payload: dict | None, pi_links=None) -> Array:
    """Standard link parameters ``(10 n,)`` of ``arm`` (or of links ``pi_links (10 n,)`` on its
    kinematics) carrying ``payload`` (keyword arguments of
    :func:`~adaptive_dd.plant.arm.payload_parameters`; None: no payload)."""
    from adaptive_dd.plant.arm import payload_parameters

    pi = np.array(arm.pi_links if pi_links is None else pi_links, dtype=float)
    if payload is None:
        return pi
    j = arm.payload_joint
    pp = payload_parameters(
        payload["mass"], payload.get("com"), payload.get("inertia"), payload.get("radius", arm.payload_radius)
    )
    pi[10 * j : 10 * j + 10] += arm.payload_map @ pp
    return pi


def plant_of(scenario, seed_indices=(0,)) -> Plant:
    """The simulated arm of each trial (seed indices ``seed_indices``), with every segment's payload:
    ``scenario.arm`` itself, or the plant of ``scenario.plant`` drawn for that seed
    (:func:`~adaptive_dd.plant.uncertainty.plant_draws`)."""
    from adaptive_dd.plant.integrator import friction_law
    from adaptive_dd.plant.uncertainty import plant_draws

    arm = scenario.arm
    draws = plant_draws(scenario, seed_indices)
    payloads = [None, *(scenario.payload_of(i) for i in range(len(scenario.swap_times)))]
    once: dict = {}  # an exact plant is one object for every trial: its segments are built once
    for d in draws:
        if id(d) not in once:
            once[id(d)] = [pi_with_payload(arm, p, d.pi_links) for p in payloads]
    pi_seg = [once[id(d)] for d in draws]
    c = np.ascontiguousarray
    return Plant(
        c(np.reshape(pi_seg, (len(draws), len(payloads), -1))),
        c([d.viscous for d in draws], dtype=float),
        c([d.coulomb for d in draws], dtype=float),
        c([d.armature for d in draws], dtype=float),
        friction_law(arm.friction_code, np.zeros((len(draws), arm.n_joints))),
        np.array(arm.friction_params, dtype=float),
        int(scenario.substeps),
        arm.chain,
    )


def reset_plant(pl: Plant) -> None:
    """The plant's own state at rest before a controller's trials: LuGre's bristles (the other laws
    keep none; their modes are in :class:`TrialState`)."""
    z = getattr(pl.friction_law, "z", None)
    if z is not None:
        z[...] = 0.0


def true_models(pl: Plant) -> np.ndarray:
    """``(S, G, 13 n)``: trial i's true model in every segment (its plant's links with the payload,
    its plant's friction and armature): what the oracles are given, and only they."""
    S, G, _ = pl.pi_seg.shape
    fr = np.concatenate((pl.fv, pl.fc, pl.armature), axis=1)
    return np.ascontiguousarray(
        np.concatenate((pl.pi_seg, np.broadcast_to(fr[:, None, :], (S, G, fr.shape[1]))), 2)
    )


def plant_record(scenario, idx) -> dict:
    """The plants the trials met (JSON-ready): the nominal plant, the draw's levels and, per seed
    index, the drawn parameters (:meth:`~adaptive_dd.plant.uncertainty.PlantDraw.to_dict`)."""
    import dataclasses

    from adaptive_dd.plant.uncertainty import plant_draws

    spec = scenario.plant
    unc = None if spec.uncertainty is None else dataclasses.asdict(spec.uncertainty)
    return {
        "urdf": spec.urdf,
        "model_urdf": str(scenario.arm.urdf),
        "uncertainty": unc,
        "seed_rule": "numpy.random.default_rng([scenario.seed, seed_index, 2])",
        "nominal": spec.nominal().to_dict(),
        "seeds": {int(i): d.to_dict() for i, d in zip(idx, plant_draws(scenario, idx), strict=True)},
    }
