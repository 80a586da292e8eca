"""Row weights of the N-joint estimator from a first pass over the task: weighted least squares with
each equation weighted by its own error, estimated (Gautier and Poignet 2001, "Extended Kalman
filtering and weighted least squares dynamic identification of robot", Control Eng. Pract. 9(12):
a first least-squares pass, each joint's residual standard deviation its weight).

The first pass is a record of the arm following the task's reference for :data:`FIRST_PASS`
seconds, carrying its payload capacity (:func:`pass_mass`), with the sensor noise and the D/A
steps the arm states, through the estimator's equations at the payload the arm carries there
(known): each row's momentum-form error ``G0 tau - G1 p - G0 wv`` (``p = M qd``, ``wv = g + f -
C^T qd`` of the known arm at the measured ``q, qd``), on the samples the data selection keeps (the
joint faster than its threshold). That is what each equation carries besides an unknown payload:
the measured velocity's noise through the momentum, the D/A step, and what the momentum form
leaves on the arm's own motion (its discretisation, the friction's sign), which the sensors' noise
alone does not predict (the UR5's wrist rows: about 0.002 N m on a noise-free record, against
3e-5 N m of velocity noise; weights from the noise alone learnt its payload's centre of mass
twice as slowly). The velocity's noise enters through ``M qd``, which the payload enlarges: on
the paper's arm the elbow row's error is 0.025 N m unloaded and 0.075 N m at its 5 kg capacity.
The pass carries the capacity so that no segment's data count for more than they know.

Each row's weight is its RMS error [N m] over the pass's last two thirds (after the reference's
ramp) times ``sqrt(tau_f / T)``: the recursive least squares take each weighted equation as one
independent unit of noise, and the filtered equations share the filters' memory, ``tau_f / T``
samples. The rows are then in the units of their own noise, and the covariance ``P`` on the scale
of the estimate's error. ``adaptive_ct`` uses them so in mode "arm", whose prior on the arm (a
stated uncertainty, or an identification's covariance: ``[run] excite``, ``[model] from``) is in
the parameters' own units: neither the data nor the prior then counts many times what it knows.
With the rows on the torque limits' scale (the largest 1), a drawn palletizer whose shoulder
equation carries 0.6 N m of noise takes its data for 13 times what they know, and its payload's
centre of mass runs 0.2 m off in the first second after a pick-up.

Payload mode takes the weights over the largest: its priors on the model control uses (the
centred first moments, a payload's presence) are weighed against ``P`` on that scale (on the
noise's scale the paper's arm's 3 kg segment is 1.503 its floor against 1.423, 20 seeds). The
changelog has the figures of both choices.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["FIRST_PASS", "first_pass_row_weights", "momentum_form_error", "pass_mass", "task_row_weights"]

MDOT_STEP = 1e-6
"""[s] The central difference of ``M(q + h qd) qd`` in ``h`` that gives ``Mdot qd``."""

FIRST_PASS = 6.0
"""[s] The first pass's length: a few periods of a scenario's reference (0.1-1 Hz components) after
its ramp."""


def first_pass_row_weights(
    arm, cfg, motion, seed: int = 0, relative: bool = False, mass: float = 0.0
) -> NDArray[np.float64]:
    """Row weights ``(n,)`` [N m]: each equation's RMS momentum-form error on a noisy record of
    ``arm`` along ``motion`` carrying ``mass``, times ``sqrt(tau_f / T)`` (module docstring).

    Parameters
    ----------
    arm : Arm
        The arm the estimator knows, with its stated sensor noise and actuator.
    cfg : OnlineConfig
        The estimator's settings: its filter bank (``tau_f``, ``sample_period``) and its data
        selection's threshold.
    motion : tuple of three (N, n) arrays
        ``q, qd, qdd`` of the task at ``cfg.sample_period`` (e.g. ``scenario.reference.sample(t)``).
    seed : int
        Seed of the record's sensor noise.
    relative : bool
        Each row's error over the largest instead (payload mode's scale).
    mass : float
        [kg] on the payload frame (a disk of the arm's ``payload_radius``), known to the
        equations: 0 the unloaded arm; :func:`task_row_weights` passes the payload capacity.

    Returns
    -------
    ndarray (n,)
        Positive [N m]. A row with no kept sample, or whose error is not finite or is 0, gets its
        torque limit's weight on the scale of the others; the torque limits' weights
        (:func:`~adaptive_dd.identification.online_config.derived_row_weights`) if no row has an
        error.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.identification.online import OnlineConfig
    >>> from adaptive_dd.identification.row_weights import first_pass_row_weights
    >>> from adaptive_dd.plant.arm import Arm
    >>> from adaptive_dd.robots import ROBOTS, robot_urdf
    >>> arm = Arm.from_urdf(robot_urdf("vertical3"), ROBOTS["vertical3"].payload_frame)
    >>> t = np.arange(3000) * 1e-3
    >>> q = 0.3 * np.sin(2 * np.pi * 0.5 * t)[:, None] * np.ones(3)
    >>> motion = (q, np.gradient(q, t, axis=0), np.gradient(np.gradient(q, t, axis=0), t, axis=0))
    >>> w = first_pass_row_weights(arm, OnlineConfig(sample_period=1e-3), motion)
    >>> w.shape, bool(np.all(w > 0))
    ((3,), True)
    """
    return _scaled(arm, cfg, _row_noise(arm, cfg, motion, seed, mass), relative)


def _row_noise(arm, cfg, motion, seed: int, mass: float = 0.0) -> NDArray[np.float64] | None:
    """Each row's RMS momentum-form error [N m] in the first pass with ``mass`` [kg] on the payload
    frame (NaN: no kept sample), or None when no row has a finite, positive one."""
    from adaptive_dd.plant.payload import payload_parameters
    from adaptive_dd.plant.prescribed import prescribed_record

    q, qd, qdd = (np.asarray(x, dtype=float) for x in motion)
    t = np.arange(q.shape[0]) * cfg.sample_period
    pay = payload_parameters(mass, None, radius=arm.payload_radius)  # zeros at 0 kg
    rec = prescribed_record(arm, t, (q, qd, qdd), [pay], rng=np.random.default_rng(seed))
    qm, vm = rec.q_meas, rec.qd_meas
    sigma = arm.sigma_with_payload(mass)  # the equations know the payload the record carries
    err = momentum_form_error(arm, cfg.bank, qm, vm, rec.tau, sigma)[q.shape[0] // 3 :]
    kept = _selected(cfg, vm)[q.shape[0] // 3 :]
    sd = np.full(err.shape[1], np.nan)
    for j in range(err.shape[1]):
        if kept[:, j].any():
            sd[j] = np.sqrt(np.mean(err[kept[:, j], j] ** 2))
    good = np.isfinite(sd) & (sd > 0.0)
    return np.where(good, sd, np.nan) if good.any() else None


def _scaled(arm, cfg, sd, relative: bool) -> NDArray[np.float64]:
    """The weights from the rows' errors ``sd`` (:func:`_row_noise`): ``sqrt(tau_f / T) sd``, or
    ``sd`` over its largest; a row without its own error its torque limit's weight on the scale of
    the others."""
    from adaptive_dd.identification.online_config import derived_row_weights

    w0 = derived_row_weights(arm)
    if sd is None:
        return w0
    good = np.isfinite(sd)
    sd = np.where(good, sd, w0 * np.max(sd[good] / w0[good]))
    return sd / sd.max() if relative else np.sqrt(cfg.tau_f / cfg.sample_period) * sd


def _selected(cfg, qd) -> NDArray[np.bool_]:
    """``(N, n)``: the samples the estimator's data selection keeps for each row, the joint no
    slower than its threshold over the selection's memory (``cfg.selection``: a reversal's Coulomb
    step stays in the filtered equation that long); all of them without a selection."""
    if cfg.selection is None:
        return np.ones(qd.shape, dtype=bool)
    gate, memory = cfg.selection
    slow = np.cumsum(np.abs(qd) < gate, axis=0)
    m = max(cfg.samples(memory), 1)
    recent = slow - np.concatenate([np.zeros((m, qd.shape[1])), slow[:-m]])[: qd.shape[0]]
    return recent == 0


def momentum_form_error(arm, bank, q, qd, tau, sigma=None) -> NDArray[np.float64]:
    """``G0 tau - G1 p - G0 wv`` ``(N, n)`` of the known ``arm`` (with base parameters ``sigma``,
    default its own) over a record ``q, qd, tau (N, n)``: the momentum form's equation error with
    no payload beyond ``sigma``'s (``p = M(q) qd``, ``wv = g + f - C^T qd``,
    ``C^T qd = Mdot qd - C qd`` from a central difference of ``M(q + h qd) qd``), each filter
    started in the steady state of its input's first sample. On an exact record it is the
    filters' discretisation only.

    ``bank`` is the estimator's filter bank (``OnlineConfig.bank``)."""
    from adaptive_dd.identification.regression import filter_pieces

    q, qd, tau = (np.asarray(x, dtype=float) for x in (q, qd, tau))
    zero = np.zeros_like(q)

    def momentum(x):  # M(x) qd: the torque of the acceleration qd without velocity or gravity
        return arm.inverse_dynamics(x, zero, qd, sigma) - arm.inverse_dynamics(x, zero, zero, sigma)

    p = momentum(q)
    mdot_qd = (momentum(q + MDOT_STEP * qd) - momentum(q - MDOT_STEP * qd)) / (2.0 * MDOT_STEP)
    wv = arm.inverse_dynamics(q, qd, zero, sigma) - mdot_qd  # g + f + C qd - (C + C^T) qd

    def filtered(u, k):  # one piece, from the steady state of its first sample
        return filter_pieces(bank, u, None, 0, k)

    return filtered(tau, 0) - filtered(p, 1) - filtered(wv, 0)


def pass_mass(arm, scenario) -> float:
    """[kg] The payload the first pass carries: the arm's stated ``payload_capacity``, else the
    heaviest of ``scenario``'s payloads (0 with none)."""
    if arm.payload_capacity is not None:
        return float(arm.payload_capacity)
    return float(max((*scenario.swap_masses, 0.0)))


def task_row_weights(arm, cfg, scenario, relative: bool = False) -> NDArray[np.float64]:
    """:func:`first_pass_row_weights` over ``scenario``'s reference, its first :data:`FIRST_PASS`
    seconds at its sample period, the arm carrying :func:`pass_mass`; the pass is kept with ``arm``
    (a scenario's controllers are built more than once: ``validate``, the runner,
    ``--controllers``), named by the filter, the data selection, the mass and the motion's bytes."""
    import dataclasses
    import hashlib

    T = float(scenario.sample_period)
    t = np.arange(round(min(FIRST_PASS, scenario.duration) / T)) * T
    first = dataclasses.replace(cfg, sample_period=T)
    motion = tuple(np.ascontiguousarray(x, dtype=float) for x in scenario.reference.sample(t))
    digest = hashlib.sha1(b"".join(x.tobytes() for x in motion)).hexdigest()
    mass = pass_mass(arm, scenario)
    key = f"first_pass_row_noise:{first.tau_f!r}:{T!r}:{first.selection!r}:{mass!r}:{digest}"
    sd = arm._cached(key, lambda: _row_noise(arm, first, motion, 0, mass))
    return _scaled(arm, first, sd, relative)  # the kept pass is read, never written
