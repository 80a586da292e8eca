"""Online identification for any serial arm (N joints): a compiled pure step.

The N-joint generalisation of :mod:`~adaptive_dd.identification.two_link_online`::

    c, s = est_init(cfg, arm, n_trials)               # EstCfg (read-only), EstState (in place)
    alarm = est_step_trial(c, s, i, q, qd, tau)       # compiled: one sample of trial i
    est_model_trial(c, s, i, pi_out)                  # compiled: the model control uses (13 n,)
    w = est_work(n, p)                                # scratch of a trial, reused from sample to sample:
    est_step_trial_in(c, s, i, q, qd, tau, w); est_model_trial_in(c, s, i, pi_out, w)  # (no allocation)
    info = est_step(c, s, q, qd, tau)                 # Python: every trial, the same kernel
    rec = run_online(arm, cfg, q, qd, tau)     # a whole record; equals stepping

Two modes (:class:`OnlineConfig`):

``"payload"`` (default)
    The arm is known (its standard parameters ``arm.pi``); the ten parameters of the
    payload about its frame are estimated, as industrial payload identification does.
    Equation: ``y = G0 tau - tau_arm(qf, qdf, qddf) = phi theta`` with
    ``phi = body_regressor(link jp) @ payload_map`` (n x 10).
``"arm"``
    The arm's base parameters (prior covariance from the URDF's stated uncertainty,
    :mod:`~adaptive_dd.identification.arm_prior`; never re-opened) and the payload's ten
    parameters apart (columns: the payload link's through ``payload_map``; re-opened alone at
    an alarm). Equation: the momentum form of every link plus friction and armature columns
    (``docs/learning_the_arm.md``).

Payload mode can evaluate the regressor at the filtered signals of the M2 method (eq. 20, Tustin):
``qf = G0 q``, ``qdf = G0 qd``, ``qddf = G1 qd``, Coulomb column ``G0 sgn(qd)``, and
``y = G0 tau``. The estimator is RLS with the variable forgetting factor of eq. (14),
one scalar update per joint equation (the paper's splits generalised: each row is a
split; the forgetting factor advances once per sample). The change detector, the
re-opening along the payload subspace, the start-up covariance shaped along the payload
subspace and the projection of the control model (not of the estimator's state) follow
the lessons of ``payload-swap-adaptation.md`` (see :func:`~adaptive_dd.identification.
online_kernel._detect`).

**Re-arm bound.** After any alarm, the next alarm is possible as soon as
``since_alarm > holdoff`` and one used row has been seen ``min_learned`` times from
``resume`` samples after the alarm on: at most ``max(holdoff, resume + min_learned)``
samples in which that row is in use; the level established before the alarm serves no longer
than ``resume + min_learned`` samples after it (``OnlineConfig.rearm_samples``). The level
does not learn from a sample whose squared error exceeds ``gate^2`` times it, so a
change that happens while the detector re-learns is still detected at re-arm.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.arm_prior import ArmUncertainty, prior_covariance
from adaptive_dd.identification.filters import (
    FilterBank,
    design_filter_bank,
    filter_record,
    summing_realisation,
)
from adaptive_dd.identification.online_kernel import (
    EstCfg,
    EstState,
    compact_prior,
    est_detect_trial,
    est_force_alarm_trial,
    est_model_trial,
    est_model_trial_in,
    est_payload_trial,
    est_step_trial,
    est_step_trial_in,
    est_work,
)
from adaptive_dd.identification.pseudo_inertia import project_payload
from adaptive_dd.plant.arm import Arm

__all__ = [
    "Detector",
    "EstCfg",
    "EstInfo",
    "EstState",
    "OnlineConfig",
    "OnlineRecord",
    "compact_prior",
    "derived_row_weights",
    "est_detect_trial",
    "est_force_alarm_trial",
    "est_init",
    "est_model",
    "est_model_trial",
    "est_model_trial_in",
    "est_payload_trial",
    "est_step",
    "est_step_trial",
    "est_step_trial_in",
    "est_work",
    "payload_prior",
    "project_payload",
    "reopen_mass_std",
    "run_online",
    "state_alarms",
    "state_skipped",
]

Array = NDArray[np.float64]
MODES = ("payload", "arm")
REGRESSIONS = ("signals", "momentum")


def _num(owner: str, name: str, v, lo=None, hi=None, strict=True) -> None:
    ok = isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v)
    if ok and lo is not None:
        ok = v > lo if strict else v >= lo
    if ok and hi is not None:
        ok = v <= hi
    if not ok:
        cond = ""
        if lo is not None:
            cond = f" {'>' if strict else '>='} {lo}"
        if hi is not None:
            cond += f" and <= {hi}"
        raise ParameterError(f"{owner}.{name} must be a finite number{cond}, got {v!r}")


def _int(owner: str, name: str, v, lo: int) -> None:
    if not isinstance(v, int | np.integer) or isinstance(v, bool) or v < lo:
        raise ParameterError(f"{owner}.{name} must be an integer >= {lo}, got {v!r}")


def _bool(owner: str, name: str, v) -> None:
    if not isinstance(v, bool):
        raise ParameterError(f"{owner}.{name} must be true or false, got {v!r}")


@dataclass(frozen=True)
class Detector:
    """Change detector on the rows' prior errors (one per joint equation).

    Attributes
    ----------
    short_window, long_window : float
        Time constants [s] of the short average and the long-run level (short < long).
    threshold : float
        RMS ratio short / level that raises an alarm, > 1.
    slow_factor : float
        The threshold is this many times higher while another row is out of use.
    warmup : float or None
        No alarm before this time [s]. None (default): :data:`WARMUP` in payload mode,
        :data:`WARMUP_ARM` in mode ``"arm"``, whose residual while the arm's error is learnt is
        no level yet (Panda, uncertain arm, 20 seeds: 1 trial with a false alarm at
        0.89 s with 0.5 s, none with 1 s, the same ratios to 0.003).
    min_learned : int
        Samples a row must have been seen since the last alarm before it may alarm.
    holdoff : float
        No alarm for this long after one [s].
    freeze : float
        Filter memory after a change, in units of tau_f (the second re-opening).
    resume : float
        The level resumes learning this many freeze times after an alarm.
    gate : float
        RMS ratio above which a sample is not learned by the level.
    gate_after : int
        Learned samples before the gate applies.
    reopen_again : bool
        Re-open the covariance again ``freeze`` after an alarm.
    reopen_mass_std : float or None
        Standard deviation [kg] of the payload mass re-opened on an alarm (the other
        payload parameters scale with it, see :func:`payload_prior`). None (default): derived,
        :data:`REOPEN_CAPACITY` times the arm's rated payload (``arm.payload_capacity``), or
        :data:`REOPEN_GENERIC` kg when the arm does not state one.
    floor : float
        Floor [N m, RMS, in the units of the weighted equation] of the long-run level:
        an error below ``threshold * floor`` never alarms.
    fast_window : float or None
        Time constant [s] of a second, faster average of the squared errors, which alarms
        above ``fast_threshold`` (the same rows, levels and ``min_rows``): a large change is
        detected before the short average has risen. A window of one sample period or less is
        the error of the sample itself (default 1 ms: one sample at 1 kHz). None or 0: no fast
        average. It is armed only on a row whose level it has learnt itself over one
        ``long_window`` (not the level kept from before an alarm, nor one still being learnt):
        after an alarm the short average alone re-arms the detector. One sample at 7x against
        the 4 ms average at 6x, 50 seeds each, per segment and in detection delay:
        ``docs/change_detection.md`` ("The N-joint detector's speed").
    fast_threshold : float
        RMS ratio fast / level that raises an alarm, > 1. Default 7: one constant for every
        arm, the lowest at which the one-sample test raised no more false alarms than the 4 ms
        average did (Panda, drawn plant, 50 seeds: 4 trials at 6x, 1 at 7x and at 8x, 1 before).
    min_rows : int
        An alarm also needs this many rows above half the threshold (RMS), >= 1. A payload
        change moves every joint the payload's weight and inertia load at once; friction the
        model lacks (Stribeck, soft friction) errs at one joint near rest. 1: any row alone.
    speed : float
        [rad/s] A joint no faster than this within the data selection's memory creeps: its row
        raises an alarm only when its error (short or fast average, RMS, in N m) also exceeds
        ``creep_margin`` times the joint's Coulomb friction in the model (it still feeds the
        estimate, its level and ``min_rows``). Friction the model lacks (Stribeck, soft
        friction, a wrong Coulomb level) errs near rest, and by about the friction itself; a
        payload's weight does not care. One constant for every arm, the two-link detector's
        speed gate; ``docs/change_detection.md`` ("Creeping joints"). 0: the selection's
        threshold.
    creep_margin : float
        See ``speed``; >= 0 (0: a creeping row alarms as any other).
    hold_above : float
        A row whose short average rises above this fraction of the threshold (RMS; 0.5, the
        half-threshold at which ``min_rows`` counts a row as raised) is judged, for
        ``hold_time`` after that, against the level it had when it rose; its level learns on.
        Only a level established over ``min_learned`` learned samples since the last alarm is
        held. A change's error rises over the filters' time in samples each below ``gate``, and
        the level learnt it as it rose (the paper's arm on the N-joint path, the put-down at
        15 s: the alarm 141 ms after the swap, the segment 1.908 against 1.020 held, 20 seeds);
        the estimate's own error after a one-joint error persists past the rise, and is learnt
        as before. 0: no hold. ``docs/change_detection.md``, "Issue 28's gate round".
    hold_time : float or None
        [s] How long a risen row is judged against its level of before. None (default):
        derived, :attr:`OnlineConfig.rise_samples` (the samples a step change's error takes to
        reach 95 % of its final value in the short average of its square through the filters'
        ``G0``: 94 at 1 kHz, ``tau_f`` 10 ms and the 20 ms short window).

    Examples
    --------
    >>> from adaptive_dd.identification.online import Detector
    >>> d = Detector()
    >>> d.short_window, d.fast_window, d.fast_threshold, d.slow_factor  # [s], [s], x, x
    (0.02, 0.001, 7.0, 1.5)
    """

    short_window: float = 0.02
    long_window: float = 1.0
    threshold: float = 4.0
    slow_factor: float = 1.5
    warmup: float | None = None
    min_learned: int = 200
    holdoff: float = 0.2
    freeze: float = 3.0
    resume: float = 10.0
    gate: float = 8.0
    gate_after: int = 20
    reopen_again: bool = True
    reopen_mass_std: float | None = None
    floor: float = 0.05
    min_rows: int = 1
    fast_window: float | None = 0.001
    fast_threshold: float = 7.0
    speed: float = 0.25
    creep_margin: float = 0.5
    hold_above: float = 0.5
    hold_time: float | None = None

    def __post_init__(self) -> None:
        o = "Detector"
        _num(o, "short_window", self.short_window, 0.0)
        _num(o, "long_window", self.long_window, 0.0)
        if not self.short_window < self.long_window:
            raise ParameterError(
                f"{o} needs short_window < long_window, got {self.short_window}, {self.long_window}"
            )
        _num(o, "threshold", self.threshold, 1.0)
        _num(o, "slow_factor", self.slow_factor, 1.0, strict=False)
        _num(o, "gate", self.gate, 1.0)
        if self.warmup is not None:
            _num(o, "warmup", self.warmup, 0.0, strict=False)
        for name in ("holdoff", "freeze", "resume"):
            _num(o, name, getattr(self, name), 0.0, strict=False)
        if self.reopen_mass_std is not None:
            _num(o, "reopen_mass_std", self.reopen_mass_std, 0.0)
        _num(o, "floor", self.floor, 0.0, strict=False)
        _int(o, "min_learned", self.min_learned, 1)
        _int(o, "gate_after", self.gate_after, 1)
        _int(o, "min_rows", self.min_rows, 1)
        if self.fast_window == 0 and not isinstance(self.fast_window, bool):
            object.__setattr__(self, "fast_window", None)  # 0: off (TOML has no None)
        if self.fast_window is not None:
            _num(o, "fast_window", self.fast_window, 0.0)
            if not self.fast_window < self.short_window:
                raise ParameterError(
                    f"{o} needs fast_window < short_window, got {self.fast_window}, {self.short_window}"
                )
        _num(o, "fast_threshold", self.fast_threshold, 1.0)
        _num(o, "speed", self.speed, 0.0, strict=False)
        _num(o, "creep_margin", self.creep_margin, 0.0, strict=False)
        _num(o, "hold_above", self.hold_above, 0.0, strict=False)
        if self.hold_time is not None:
            _num(o, "hold_time", self.hold_time, 0.0)
        _bool(o, "reopen_again", self.reopen_again)


DEFAULT_PRIOR_RADIUS = 0.05
"""[m] The compact-payload prior's radius in payload mode (``OnlineConfig.prior_radius``)."""


@dataclass(frozen=True)
class OnlineConfig:
    """Settings of the N-joint online estimator.

    Attributes
    ----------
    sample_period : float
        T [s].
    tau_f : float
        Time constant of the M2 filters [s] (eq. 20).
    mode : {"payload", "arm"} or None
        Estimate the payload's ten parameters (arm known), or the arm's base parameters and the
        payload's ten apart (``"arm"``: the arm learnt from its stated
        uncertainty and kept across swaps, the payload re-opened at each; ``docs/learning_the_arm.md``).
        None (default): ``"arm"`` when ``arm_uncertainty`` is given, else ``"payload"``.
    lam0, mu : float
        Forgetting factor lambda(0) in (0, 1] and its rate towards 1, mu in [0, 1] (eq. 14).
    payload_mass_std : float
        Start-up standard deviation [kg] of the payload mass (shapes P0 along the payload).
    payload_size : float
        Length scale r [m] of the payload prior: first moments ``m c`` have standard
        deviation ``payload_mass_std r``, inertias ``payload_mass_std r^2``.
    p0_arm : float
        Mode ``"arm"``: start-up variance of every base parameter added to the prior (isotropic
        part of P0), >= 0.
    max_trace : float or None
        Cap on trace(P); None: the trace of the start-up or re-opened covariance, whichever is larger.
    align : bool
        Use ``(tau(t-1) + tau(t)) / 2``: the torque at the sample instant under zero-order hold.
    selection : (float, float) or None
        Data selection ``(threshold [rad/s], memory in units of tau_f)``.
    taint : float
        Filter memory [units of tau_f] during which a non-finite sample keeps the equations out of use.
    row_weights : tuple of float or None
        Equation j is divided by ``row_weights[j]``. None (default): derived from the arm's
        torque resolution (:func:`derived_row_weights`).
    detector : Detector or None
    project : bool or None
        Project the model control uses onto physically consistent payloads (the
        estimator's state stays unprojected). None (default): except in mode ``"arm"``, whose
        payload block also carries what is left of the arm's error along the payload's
        directions (projecting it clipped that: UR5 with an uncertain arm, 10 seeds, the
        put-down segment 1.09 -> 2.56x the floor).
    eig_min : float
        Smallest eigenvalue [kg m^2] of the projected pseudo-inertia, >= 0.
    bound_radius : float or None
        Radius R [m] of a ball about the payload frame that holds the payload: the projected
        model also has ``|c| <= R`` and ``tr(Sigma) <= m R^2`` (Sigma: the pseudo-inertia's
        second-moment block), so a vanishing mass carries vanishing first moments and
        inertia. None: no bound (positive semidefiniteness only).
    regression : {"momentum", "signals"} or None
        How the filtered equation is built; None (default): ``"momentum"``. In mode ``"arm"``
        the momentum form is written for every link (and friction, armature columns).
        ``"signals"``: the regressor evaluated at the filtered signals (the paper's M2
        construction). It is not the filtered torque: ``Y(G0 q, G0 qd, G1 qd) != G0 Y(q,
        qd, qdd)`` for a nonlinear Y, an equation error that grows with speed and with 1/tau_f.
        ``"momentum"``: the dynamics in momentum form ``tau = d/dt (M qd) + g - C^T qd``
        (:func:`~adaptive_dd.plant.chain.momentum_form`), both sides filtered:
        ``G0 tau = G1 (M qd) + G0 (g - C^T qd)``, exact for any tau_f, no acceleration. Its
        filters restart on an alarm (momentum held, the rest from zero), which keeps the
        equation exact from the sample after an alarm on (the filters keep no memory of
        the old payload; the re-openings forget what was learnt between the change and its
        detection). UR5 tool-swap scenario, 20 seeds, adaptive_ct / ct_oracle
        means per segment 1.009 / 1.033 / 1.065 / 1.032 against 1.009 / 1.038 / 1.068 /
        1.074 with ``"signals"``; Panda 1.031 / 1.051 / 1.052 / 1.047 against 1.031 /
        1.051 / 1.070 / 1.055 (``studies/regression_ablation.py [SCENARIO]`` of commit d41702f; with
        adaptive_ct's boost of 0.2 s the UR5's were 1.089 / 1.158 / 1.075 against 1.130 /
        1.351 / 1.172).
    prior_radius : float or None
        Radius rho [m] of a compact-payload prior on the model control uses (not on the
        estimator's state): the payload's inertia about its frame is taken, a priori, as a
        solid sphere of radius rho at the estimated centre of mass, each inertia component
        with standard deviation ``m rho^2``
        (:func:`~adaptive_dd.identification.online_kernel.compact_prior`).
        After a swap the data fix the mass and centre of mass within tens of ms but the
        inertia only over about a second; the prior holds the model at a plausible inertia
        until then. None or 0: no prior. ``"auto"`` (default): :data:`DEFAULT_PRIOR_RADIUS`,
        none in mode ``"arm"``.
    arm_uncertainty : ArmUncertainty, dict or None
        Mode ``"arm"``: how far the arm may be from its URDF
        (:class:`~adaptive_dd.identification.arm_prior.ArmUncertainty`; a table of its levels);
        the arm's base parameters start with the covariance ``B C B^T`` those levels imply
        (:func:`~adaptive_dd.identification.arm_prior.prior_covariance`). None in mode
        ``"arm"``: the default levels (masses 10 %, com 1 cm, inertias 20 %, friction 50 %,
        armature 30 %).
    arm_prior_std : tuple of float or None
        Mode ``"arm"``: the standard deviations ``(p,)`` of the arm's base parameters (in the
        order of ``arm.base``) about the model, in place of the covariance ``arm_uncertainty``
        implies: what an identification knows (``[run] excite`` passes each seed's,
        :func:`~adaptive_dd.closed_loop.excitation_phase.identify_excitation`). Given, the mode
        defaults to ``"arm"``.
    arm_prior_cov : tuple of tuples of float or None
        Mode ``"arm"``: the whole covariance ``(p, p)`` of the arm's base parameters about the
        model, in place of ``arm_prior_std`` (its diagonal): an identification's correlations
        (:func:`~adaptive_dd.identification.arm_prior.identified_prior_cov`, what ``[run] excite``
        passes). Given, the mode defaults to ``"arm"``.
    reset_payload : bool
        Mode ``"arm"``: an alarm also sets the payload block to zero (a new payload, nothing
        known of it but its prior). Off by default: it loses what the block had absorbed of
        the arm's residual (UR5, uncertain arm, 10 seeds: 1.06 / 1.08 / 1.40 -> 1.10 / 1.25 /
        8.5x the floor, signals form).

    Examples
    --------
    >>> from adaptive_dd.identification.online import OnlineConfig
    >>> cfg = OnlineConfig()
    >>> cfg.mode  # the arm known, the payload's ten parameters estimated
    'payload'
    """

    sample_period: float = 1e-3
    tau_f: float = 0.01
    mode: str | None = None
    lam0: float = 0.99995
    mu: float = 0.0
    payload_mass_std: float = 5.0
    payload_size: float = 0.1
    p0_arm: float = 1e-6
    max_trace: float | None = None
    align: bool = True
    selection: tuple[float, float] | None = (0.05, 6.0)
    taint: float = 10.0
    row_weights: tuple[float, ...] | None = None
    detector: Detector | None = field(default_factory=Detector)
    project: bool | None = None
    eig_min: float = 0.0
    bound_radius: float | None = 0.25
    prior_radius: float | str | None = "auto"
    regression: str | None = None
    arm_uncertainty: ArmUncertainty | None = None
    reset_payload: bool = False
    arm_prior_std: tuple[float, ...] | None = None
    arm_prior_cov: tuple[tuple[float, ...], ...] | None = None

    def __post_init__(self) -> None:
        o = "OnlineConfig"
        if isinstance(self.arm_uncertainty, dict):
            try:
                object.__setattr__(self, "arm_uncertainty", ArmUncertainty(**self.arm_uncertainty))
            except TypeError as exc:
                raise ParameterError(f"{o}.arm_uncertainty: {exc}") from None
        if self.arm_uncertainty is not None and not isinstance(self.arm_uncertainty, ArmUncertainty):
            raise ParameterError(
                f"{o}.arm_uncertainty must be a table of levels (mass, com, inertia, viscous, coulomb, "
                f"armature) or None, got {self.arm_uncertainty!r}"
            )
        # what the scenario states decides: an arm known only to its stated uncertainty is learnt
        if self.arm_prior_std is not None:
            v = np.asarray(self.arm_prior_std, dtype=float)
            if v.ndim != 1 or v.size == 0 or not np.all(np.isfinite(v) & (v >= 0)):
                raise ParameterError(
                    f"{o}.arm_prior_std must be a list of finite values >= 0 (one per base parameter), "
                    f"got {self.arm_prior_std!r}"
                )
            object.__setattr__(self, "arm_prior_std", tuple(float(x) for x in v))
            if self.arm_uncertainty is not None:
                raise ParameterError(f"{o}: give arm_uncertainty or arm_prior_std, not both")
        if self.arm_prior_cov is not None:
            C = np.asarray(self.arm_prior_cov, dtype=float)
            ok = C.ndim == 2 and C.shape[0] == C.shape[1] and C.size > 0 and np.all(np.isfinite(C))
            if not ok or not np.allclose(C, C.T, rtol=1e-9, atol=0.0) or np.any(np.diag(C) < 0):
                raise ParameterError(
                    f"{o}.arm_prior_cov must be a symmetric square table of finite values (one row "
                    f"per base parameter), got shape {C.shape}"
                )
            object.__setattr__(self, "arm_prior_cov", tuple(tuple(float(x) for x in row) for row in C))
            if self.arm_uncertainty is not None or self.arm_prior_std is not None:
                raise ParameterError(f"{o}: give one of arm_uncertainty, arm_prior_std, arm_prior_cov")
        if self.mode is None:
            learnt = (
                self.arm_uncertainty is not None
                or self.arm_prior_std is not None
                or self.arm_prior_cov is not None
            )
            object.__setattr__(self, "mode", "arm" if learnt else "payload")
        arm_mode = self.mode == "arm"
        if self.project is None:  # the payload block also carries the arm's residual along the
            object.__setattr__(self, "project", not arm_mode)  # payload's directions: not a payload
        if isinstance(self.prior_radius, str) and self.prior_radius == "auto":
            object.__setattr__(self, "prior_radius", None if arm_mode else DEFAULT_PRIOR_RADIUS)
        _num(o, "sample_period", self.sample_period, 0.0)
        _num(o, "tau_f", self.tau_f, 0.0)
        if self.tau_f < self.sample_period or self.tau_f > 1e4 * self.sample_period:
            raise ParameterError(
                f"{o}.tau_f = {self.tau_f} s must lie between the sample period {self.sample_period} s "
                "and 10 000 of them"
            )
        if self.mode not in MODES:
            raise ParameterError(f"{o}.mode must be one of {MODES}, got {self.mode!r}")
        if self.regression is not None and self.regression not in REGRESSIONS:
            raise ParameterError(
                f"{o}.regression must be one of {REGRESSIONS} or None, got {self.regression!r}"
            )
        _num(o, "lam0", self.lam0, 0.0, 1.0)
        _num(o, "mu", self.mu, 0.0, 1.0, strict=False)
        _num(o, "payload_mass_std", self.payload_mass_std, 0.0, strict=False)
        _num(o, "payload_size", self.payload_size, 0.0)
        _num(o, "p0_arm", self.p0_arm, 0.0, strict=False)
        if self.max_trace is not None:
            _num(o, "max_trace", self.max_trace, 0.0)
        _bool(o, "align", self.align)
        _bool(o, "project", self.project)
        _bool(o, "reset_payload", self.reset_payload)
        _num(o, "taint", self.taint, 0.0, strict=False)
        _num(o, "eig_min", self.eig_min, 0.0, strict=False)
        if self.bound_radius is not None:
            _num(o, "bound_radius", self.bound_radius, 0.0)
        if self.prior_radius is not None:
            _num(o, "prior_radius", self.prior_radius, 0.0, strict=False)
        if self.selection is not None:
            if not isinstance(self.selection, tuple | list) or len(self.selection) != 2:
                raise ParameterError(
                    f"{o}.selection must be (threshold, memory) or None, got {self.selection!r}"
                )
            _num(o, "selection[0] (threshold)", self.selection[0], 0.0, strict=False)
            _num(o, "selection[1] (memory)", self.selection[1], 0.0, strict=False)
        if self.row_weights is not None:
            w = np.asarray(self.row_weights, dtype=float)
            if w.ndim != 1 or not np.all(np.isfinite(w)) or np.any(w <= 0):
                raise ParameterError(f"{o}.row_weights must be finite values > 0, got {self.row_weights!r}")
        if self.detector is not None and not isinstance(self.detector, Detector):
            raise ParameterError(
                f"{o}.detector must be a Detector or None, got {type(self.detector).__name__}"
            )
        if self.payload_mass_std == 0:
            raise ParameterError(f"{o}.payload_mass_std must be > 0, got 0")

    @property
    def regression_form(self) -> str:
        """The regression used: ``regression``, or the mode's default when it is None."""
        return self.regression if self.regression is not None else "momentum"

    @property
    def bank(self) -> FilterBank:
        return _bank(self.tau_f, self.sample_period)

    def samples(self, n_tau_f: float) -> int:
        """``n_tau_f`` filter time constants in samples (the one place this conversion is made)."""
        return int(np.ceil(n_tau_f * self.tau_f / self.sample_period - 1e-9))

    def seconds(self, t: float) -> int:
        """``t`` seconds in samples."""
        return int(np.ceil(t / self.sample_period - 1e-9))

    @property
    def rearm_samples(self) -> int:
        """Bound on the samples (with a row in use) after an alarm before the next may be raised."""
        d = self.detector
        if d is None:
            return 0
        resume = self.samples(d.freeze) * d.resume
        return int(max(self.seconds(d.holdoff) + 1, np.ceil(resume) + d.min_learned))

    @property
    def rise_samples(self) -> int:
        """Samples a step change's prior error takes to reach 95 % of its final value in the
        detector's short average (of the squared error, through the filters' ``G0``): the
        rise a detector must wait for before it has seen a change whole."""
        d = self.detector
        if d is None:
            return 0
        a = min(1.0, self.sample_period / d.short_window)
        n = self.samples(20.0) + self.seconds(20 * d.short_window)
        short = 0.0
        for k, g in enumerate(filter_record(self.bank, np.ones(n))[:, 0]):
            short += a * (g * g - short)
            if short >= 0.95:
                return k + 1
        return n


WARMUP = 0.5
"""[s] No alarm before this time (``Detector.warmup`` None, payload mode)."""
WARMUP_ARM = 1.0
"""[s] The same in mode ``"arm"``."""
REOPEN_CAPACITY = 0.6
"""Re-opened payload mass standard deviation per kg of rated payload: a change from nothing to the
rated payload lies 1.7 standard deviations out (hand-tuned on the shipped arms: UR5 3 kg of 5,
Panda 2 of 3, vertical3 1)."""
REOPEN_GENERIC = 10.0
"""[kg] The re-opened payload mass standard deviation of an arm without a stated capacity."""


def reopen_mass_std(det: Detector, arm: Arm) -> float:
    """The re-opened payload mass standard deviation [kg]: the detector's own, else
    :data:`REOPEN_CAPACITY` times ``arm.payload_capacity``, else :data:`REOPEN_GENERIC`."""
    if det.reopen_mass_std is not None:
        return float(det.reopen_mass_std)
    cap = getattr(arm, "payload_capacity", None)
    return REOPEN_CAPACITY * cap if cap is not None else REOPEN_GENERIC


def derived_row_weights(arm: Arm) -> Array:
    """Row weights ``(n,)`` from the torque resolution: joint j's D/A step is its torque limit over
    the same number of counts, so ``w_j = limit_j / max(limit)`` (1 for every joint without a
    finite limit). A light wrist's rows, nearly noise-free, then count as much as the shoulder's
    (hand-tuned before: UR5 1 / 0.2, Panda 1 / 0.14, vertical3 1 / 0.4 / 0.1)."""
    lim = np.asarray(arm.actuator.torque_limit, dtype=float)
    if not np.all(np.isfinite(lim) & (lim > 0)):
        return np.ones(arm.n_joints)
    return lim / lim.max()


def _detector_velocity_variance(arm: Arm) -> Array:
    """The sensor's velocity noise variance per joint [(rad/s)^2] the detector weighs the rows'
    noise by (``EstCfg.vdet``); all equal when the arm states none."""
    v = np.asarray(arm.sensor.velocity_variance, dtype=float) * np.ones(arm.n_joints)
    if not (np.all(np.isfinite(v)) and v.max() > 0.0):
        v = np.ones(arm.n_joints)
    return np.maximum(v, 1e-6 * v.max())


@lru_cache(maxsize=32)
def _bank(tau_f: float, sample_period: float) -> FilterBank:
    return design_filter_bank("M2", tau_f, sample_period)


def payload_prior(mass_std: float, size: float) -> Array:
    """Covariance (10, 10) of a payload prior: ``diag(s^2, (s r)^2 x3, (s r^2)^2 x6)``.

    ``s`` = ``mass_std`` [kg], ``r`` = ``size`` [m]: a body of up to about ``s`` kg within
    ``r`` of the payload frame.
    """
    s, r = float(mass_std), float(size)
    return np.diag([s**2] + [(s * r) ** 2] * 3 + [(s * r * r) ** 2] * 6)


def _pack(cfg: OnlineConfig, arm: Arm) -> tuple[EstCfg, Array]:
    n = arm.n_joints
    pi0 = np.ascontiguousarray(arm.pi, dtype=float)
    pmap = np.ascontiguousarray(arm.payload_map)
    jp = arm.payload_joint
    S0 = payload_prior(cfg.payload_mass_std, cfg.payload_size)
    det = cfg.detector
    S1 = payload_prior(reopen_mass_std(det, arm) if det else 0.0, cfg.payload_size)
    if cfg.mode == "payload":
        p = 10
        indep = np.arange(10, dtype=np.int64)
        Bpinv = np.zeros((13 * n, 10))
        sigma0 = np.zeros(10)
        pbasis = np.eye(10)
        pbasis_pinv = np.eye(10)
        U = np.eye(10)
        P0, Pr = S0, S1
        n_rows = jp + 1  # joints after the payload's link do not feel it
    else:
        B = arm.base.B
        pb = B.shape[0]
        p = pb + 10
        indep = np.asarray(arm.base.independent, dtype=np.int64)
        Bb = np.linalg.pinv(B)
        Bpinv = np.hstack((Bb, Bb @ arm.payload_basis))  # the payload block enters through B
        sigma0 = np.concatenate((B @ pi0, np.zeros(10)))
        pbasis = np.vstack((np.zeros((pb, 10)), np.eye(10)))
        pbasis_pinv = pbasis.T.copy()
        U = pbasis.copy()
        P0 = np.zeros((p, p))
        if cfg.arm_prior_cov is not None:  # what an identification knows, with its correlations
            C = np.asarray(cfg.arm_prior_cov, dtype=float)
            if C.shape != (pb, pb):
                raise ParameterError(
                    f"OnlineConfig.arm_prior_cov is {C.shape[0]} x {C.shape[1]}; this arm has {pb} "
                    "base parameters"
                )
            P0[:pb, :pb] = cfg.p0_arm * np.eye(pb) + C
        elif cfg.arm_prior_std is not None:  # what an identification knows of the arm
            if len(cfg.arm_prior_std) != pb:
                raise ParameterError(
                    f"OnlineConfig.arm_prior_std has {len(cfg.arm_prior_std)} values; this arm has "
                    f"{pb} base parameters"
                )
            P0[:pb, :pb] = cfg.p0_arm * np.eye(pb) + np.diag(np.square(cfg.arm_prior_std))
        else:
            levels = cfg.arm_uncertainty if cfg.arm_uncertainty is not None else ArmUncertainty()
            P0[:pb, :pb] = cfg.p0_arm * np.eye(pb) + B @ prior_covariance(arm, levels) @ B.T
        P0[pb:, pb:] = S0
        Pr = np.zeros((p, p))
        Pr[pb:, pb:] = S1
        n_rows = n
    cap = cfg.max_trace if cfg.max_trace is not None else max(np.trace(P0), np.trace(Pr))
    w = derived_row_weights(arm) if cfg.row_weights is None else np.asarray(cfg.row_weights, dtype=float)
    if w.shape != (n,):
        raise ParameterError(f"OnlineConfig.row_weights must have {n} values (joints), got {w.shape[0]}")
    b = cfg.bank
    ints = np.zeros(K.N_I, dtype=np.int64)
    fl = np.zeros(K.N_F)
    T = cfg.sample_period
    ints[K.I_ALIGN] = int(cfg.align)
    ints[K.I_SELECT] = int(cfg.selection is not None)
    ints[K.I_SEL_MEMORY] = 0 if cfg.selection is None else cfg.samples(cfg.selection[1])
    ints[K.I_TAINT] = cfg.samples(cfg.taint)
    ints[K.I_PROJECT] = int(cfg.project)
    ints[K.I_N_ROWS] = n_rows
    ints[K.I_MOMENTUM] = int(cfg.regression_form == "momentum")
    fl[K.F_LAM0], fl[K.F_MU], fl[K.F_CAP] = cfg.lam0, cfg.mu, cap
    fl[K.F_SEL_THRESHOLD] = 0.0 if cfg.selection is None else cfg.selection[0]
    fl[K.F_EIG_MIN] = cfg.eig_min
    fl[K.F_RADIUS] = 0.0 if cfg.bound_radius is None else cfg.bound_radius
    fl[K.F_PRIOR_RADIUS] = 0.0 if cfg.prior_radius is None else cfg.prior_radius
    if cfg.mode == "payload":  # a carried payload's mass: the re-opened prior's (sized by the capacity)
        fl[K.F_PRESENT2] = (reopen_mass_std(det, arm) if det else cfg.payload_mass_std) ** 2
    if det is not None:
        ints[K.I_DETECT] = 1
        warm = det.warmup if det.warmup is not None else (WARMUP_ARM if cfg.mode == "arm" else WARMUP)
        ints[K.I_WARMUP] = cfg.seconds(warm)
        ints[K.I_MIN_LEARNED] = det.min_learned
        ints[K.I_HOLDOFF] = cfg.seconds(det.holdoff)
        ints[K.I_FREEZE] = cfg.samples(det.freeze)
        ints[K.I_RESUME] = int(np.ceil(ints[K.I_FREEZE] * det.resume))
        # the momentum form restarts its filters on an alarm: no memory to wait for
        ints[K.I_REOPEN_AGAIN] = int(det.reopen_again)
        ints[K.I_GATE_AFTER] = det.gate_after
        fl[K.F_ALPHA_SHORT] = min(1.0, T / det.short_window)
        fl[K.F_ALPHA_LONG] = min(1.0, T / det.long_window)
        fl[K.F_THRESHOLD2] = det.threshold**2
        fl[K.F_SLOW2] = det.slow_factor**2
        fl[K.F_GATE2] = det.gate**2
        fl[K.F_FLOOR2] = det.floor**2
        if det.fast_window is not None:
            ints[K.I_FAST] = 1
            fl[K.F_ALPHA_FAST] = min(1.0, T / det.fast_window)
            fl[K.F_FAST2] = det.fast_threshold**2
            ints[K.I_FAST_LEARNED] = cfg.seconds(det.long_window)
        if det.min_rows > n_rows:
            raise ParameterError(
                f"Detector.min_rows = {det.min_rows} exceeds the {n_rows} joint equations that "
                "carry the payload"
            )
        ints[K.I_MIN_ROWS] = det.min_rows
        fl[K.F_DET_SPEED] = max(det.speed, fl[K.F_SEL_THRESHOLD])
        fl[K.F_CREEP_MARGIN] = det.creep_margin
        if det.hold_above > 0.0:
            fl[K.F_HOLD_ABOVE2] = det.hold_above**2
            hold = cfg.rise_samples if det.hold_time is None else cfg.seconds(det.hold_time)
            ints[K.I_HOLD] = max(hold, 1)
        ints[K.I_RESET_PAYLOAD] = int(cfg.mode == "arm" and cfg.reset_payload)
        # payload mode: control keeps the starting payload until the first alarm (the kernel's
        # _keep_start); in mode "arm" the payload block also takes up the arm's error meanwhile
        ints[K.I_KEEP_START] = int(cfg.mode == "payload")
    xs0 = np.linalg.solve(np.eye(b.order) - b.A, b.B[:, 0])
    Am, Bm, Cm, Dm = summing_realisation(b)
    xm1 = np.linalg.solve(np.eye(b.order) - Am, Bm[:, 1])
    c = np.ascontiguousarray
    return EstCfg(
        ch=arm.chain,
        mode=K.MODE_PAYLOAD if cfg.mode == "payload" else K.MODE_ARM,
        pi0=pi0,
        jp=int(jp),
        pmap=pmap,
        indep=indep,
        Bpinv=c(Bpinv),
        sigma0=c(sigma0),
        pbasis=c(pbasis),
        pbasis_pinv=c(pbasis_pinv),
        U=U,
        P_reopen=c(Pr),
        A=c(b.A),
        Bf=c(b.B[:, 0]),
        C=c(b.C),
        D=c(b.D[:, 0]),
        xs0=xs0,
        Am=Am,
        Bm=Bm,
        Cm=Cm,
        Dm=Dm,
        xm1=xm1,
        w=c(w),
        ints=ints,
        floats=fl,
        vdet=c(_detector_velocity_variance(arm)),
    ), P0


def _channels(cfg: OnlineConfig, n: int) -> int:
    """Filter channels of the configured regression form, n joints."""
    if cfg.regression_form != "momentum":
        return K.SIGNAL_CHANNELS * n
    return K.arm_momentum_channels(n) if cfg.mode == "arm" else K.MOMENTUM_CHANNELS * n


def est_init(
    cfg: OnlineConfig, arm: Arm, n_trials: int, sigma_nominal: ArrayLike | None = None
) -> tuple[EstCfg, EstState]:
    """Compiled configuration and initial state of ``n_trials`` estimators.

    Parameters
    ----------
    cfg : OnlineConfig
    arm : Arm
        The arm (its standard parameters ``arm.pi`` are the known part in payload mode).
    n_trials : int
    sigma_nominal : array_like (p,) or (n_trials, p), optional
        Nominal base parameters: in mode ``"arm"`` the initial estimate (default ``arm.sigma``,
        its payload in the payload block); in payload mode the initial payload is the one it implies
        (``arm.payload_from_sigma``; default no payload).

    Returns
    -------
    EstCfg, EstState
    """
    if not isinstance(cfg, OnlineConfig):
        raise ParameterError(f"cfg must be a OnlineConfig, got {type(cfg).__name__}")
    if not isinstance(n_trials, int | np.integer) or isinstance(n_trials, bool) or n_trials < 1:
        raise ParameterError(f"n_trials must be an integer >= 1, got {n_trials!r}")
    c, P0 = _pack(cfg, arm)
    n = arm.n_joints
    p = P0.shape[0]
    if sigma_nominal is None:
        th0 = np.zeros(10) if cfg.mode == "payload" else np.concatenate((arm.sigma, np.zeros(10)))
    else:
        s = np.asarray(sigma_nominal, dtype=float)
        if s.shape[-1] != arm.base.count or not np.all(np.isfinite(s)):
            raise ParameterError(
                f"sigma_nominal must be {arm.base.count} finite base parameters, got shape {s.shape}"
            )
        pay = arm.payload_from_sigma(s).params
        # mode "arm": the nominal arm known to the prior, its payload in the payload block
        th0 = pay if cfg.mode == "payload" else np.concatenate((s - pay @ arm.payload_basis.T, pay))
    theta = np.broadcast_to(th0, (n_trials, p)).copy()
    cnt = np.zeros((n_trials, K.N_CNT), dtype=np.int64)
    cnt[:, K.C_SINCE_ALARM] = K.BIG
    cnt[:, K.C_LAST_ALARM] = -1
    cnt[:, K.C_REOPEN_AT] = -1
    m = n_trials
    state = EstState(
        xf=np.zeros((m, _channels(cfg, n), cfg.bank.order)),
        u_last=np.zeros((m, 4 * n)),
        tau_prev=np.zeros((m, n)),
        cnt=cnt,
        since_slow=np.zeros((m, n), dtype=np.int64),
        seen=np.zeros((m, n), dtype=np.int64),
        learned=np.zeros((m, n), dtype=np.int64),
        theta=theta,
        P=np.broadcast_to(P0, (m, p, p)).copy(),
        lam=np.full(m, cfg.lam0),
        short=np.zeros((m, n)),
        long=np.zeros((m, n)),
        ref=np.zeros((m, n)),
        eps=np.full((m, n), np.nan),
        fast=np.zeros((m, n)),
        since_crawl=np.zeros((m, n), dtype=np.int64),
        hold=np.zeros((m, n)),
        held=np.zeros((m, n), dtype=np.int64),
        ref_pay=np.zeros((m, 10)),
        ref_rise=np.ones((m, n)),
        start_pay=np.zeros((m, 10)),
        start_mass=theta[:, p - 10].copy(),
    )
    for i in range(m):  # the payload the model control uses at the start
        K.est_payload_trial(c, state, i, state.start_pay[i])
    return c, state


class EstInfo(NamedTuple):
    """What one :func:`est_step` did, per trial: ``alarm (m,)`` bool, weighted prior errors
    ``eps (m, n)`` (NaN where a row was not used), forgetting factor ``lam (m,)``."""

    alarm: NDArray[np.bool_]
    eps: Array
    lam: Array


def _sample(x: ArrayLike, shape: tuple, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != shape:
        raise SignalError(f"{name} must have shape {shape}, got {a.shape}")
    return np.ascontiguousarray(a)


def est_step(c: EstCfg, s: EstState, q: ArrayLike, qd: ArrayLike, tau: ArrayLike) -> EstInfo:
    """One sample of every trial (``q, qd, tau (m, n)``), updating ``s`` in place.

    The same compiled :func:`est_step_trial` as the closed loop. Non-finite values are
    skipped and counted (``state_skipped(s)``).
    """
    shape = s.eps.shape
    q, qd, tau = (_sample(x, shape, nm) for x, nm in ((q, "q"), (qd, "qd"), (tau, "tau")))
    alarm = np.zeros(shape[0], dtype=np.int64)
    K.est_step_batch(c, s, q, qd, tau, alarm)
    return EstInfo(alarm.astype(bool), s.eps.copy(), s.lam.copy())


def est_model(c: EstCfg, s: EstState) -> Array:
    """The model control uses, standard parameters ``(m, 13 n)`` (see :func:`est_model_trial`)."""
    out = np.empty((s.theta.shape[0], c.pi0.shape[0]))
    for i in range(out.shape[0]):
        est_model_trial(c, s, i, out[i])
    return out


def state_alarms(s: EstState) -> NDArray[np.int64]:
    """Alarms raised so far, per trial."""
    return s.cnt[:, K.C_ALARMS].copy()


def state_skipped(s: EstState) -> NDArray[np.int64]:
    """Samples skipped as non-finite, per trial."""
    return s.cnt[:, K.C_SKIPPED].copy()


@dataclass(frozen=True)
class OnlineRecord:
    """The estimator run over records; arrays ``(n_trials, n_samples, ...)``.

    Attributes
    ----------
    t : (n_samples,) sample times [s]
    theta : (..., p) the estimator's estimate after each sample
    payload : (..., 10) the payload it implies (projected if ``cfg.project``), about the payload frame
    alarm : bool (...) a change alarm at that sample
    eps : (..., n) weighted prior errors (NaN where a row was not used)
    lam : (...) forgetting factor
    n_skipped : (n_trials,) samples skipped as non-finite
    """

    t: Array
    theta: Array
    payload: Array
    alarm: NDArray[np.bool_]
    eps: Array
    lam: Array
    n_skipped: NDArray[np.int64]

    @property
    def mass(self) -> Array:
        """Payload mass [kg], ``(n_trials, n_samples)``."""
        return self.payload[..., 0]

    @property
    def com(self) -> Array:
        """Payload centre of mass [m] in its frame, ``(n_trials, n_samples, 3)`` (NaN at zero mass)."""
        m = self.payload[..., :1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(m > 0, self.payload[..., 1:4] / m, np.nan)

    def alarm_times(self) -> list[list[float]]:
        """Per trial, the times [s] of the alarms."""
        return [list(self.t[np.flatnonzero(a)]) for a in self.alarm]


def run_online(
    arm: Arm,
    cfg: OnlineConfig,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    sigma_nominal: ArrayLike | None = None,
) -> OnlineRecord:
    """Run the estimator over whole records ``q, qd, tau (n_samples, n)`` or ``(n_trials, n_samples, n)``.

    Equals :func:`est_step` sample by sample, bit for bit (one compiled loop per trial
    over the same :func:`est_step_trial`).
    """
    q, qd, tau = (np.ascontiguousarray(np.asarray(x, dtype=float)) for x in (q, qd, tau))
    if q.ndim == 2:
        q, qd, tau = q[None], qd[None], tau[None]
    n = arm.n_joints
    if q.ndim != 3 or q.shape[-1] != n or qd.shape != q.shape or tau.shape != q.shape:
        raise SignalError(
            f"q, qd and tau must share a shape (n_trials, n_samples, {n}), "
            f"got {q.shape}, {qd.shape}, {tau.shape}"
        )
    m, N, _ = q.shape
    c, s = est_init(cfg, arm, m, sigma_nominal)
    p = s.theta.shape[1]
    theta = np.empty((m, N, p))
    payload = np.empty((m, N, 10))
    eps = np.empty((m, N, n))
    alarm = np.zeros((m, N), dtype=np.int64)
    lam = np.empty((m, N))
    for i in range(m):
        K.est_run_trial(c, s, i, q[i], qd[i], tau[i], theta[i], payload[i], eps[i], alarm[i], lam[i])
    t = np.arange(N) * cfg.sample_period
    return OnlineRecord(t, theta, payload, alarm.astype(bool), eps, lam, state_skipped(s))
