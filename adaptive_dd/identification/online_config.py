"""Settings of the N-joint online estimator (:mod:`~adaptive_dd.identification.online`).

:class:`Detector` and :class:`OnlineConfig` (frozen, checked on construction), and the defaults
derived from them and from the arm: the warm-up (:data:`WARMUP`, :data:`WARMUP_ARM`), the
re-opened payload prior (:func:`reopen_mass_std`, :func:`payload_prior`) and the row weights
(:func:`derived_row_weights`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, is_finite_number
from adaptive_dd.identification.arm_prior import ArmUncertainty
from adaptive_dd.identification.filters import (
    FilterBank,
    design_filter_bank,
    filter_record,
)
from adaptive_dd.plant.arm import Arm

Array = NDArray[np.float64]
MODES = ("payload", "arm")


def _num(owner: str, name: str, v, lo=None, hi=None, strict=True) -> None:
    ok = is_finite_number(v)
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
    relearn_factor : float
        The threshold is this many times higher, >= 1, for a row judged against a level it has not
        established since the last alarm: the level kept from before that alarm, while the
        estimate may still be converging, or one learnt since over fewer samples than
        ``min_learned`` (a row out of use through the alarm). Not while another row is out of use:
        a joint's friction enters its own equation only.
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
    floor : float or None
        Floor [N m, RMS] of the long-run level on the row of the largest weight, the other rows'
        in proportion to their weights: an error below ``threshold * floor`` never alarms. None
        (default): derived where the run knows its task (``AdaptiveCT.state_task``): the heaviest
        row's noise in the estimator's first pass over the reference (the row weights' pass,
        :func:`~adaptive_dd.identification.row_weights.task_row_weights`) over ``threshold``, at most
        :data:`FLOOR_MAX`, so that an error within that row's own noise cannot alarm on a light arm
        either; :data:`FLOOR_MAX` without a task.
    fast_window : float or None
        Time constant [s] of a second, faster average of the squared errors, which alarms
        above ``fast_threshold`` (the same rows and levels): a large change is
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
        With the level following the posture, 6.5 detects a little sooner
        (vertical3 exact, 1 kg segment 2.197 -> 2.087, 50 seeds; no false alarm on 100 drawn arms
        x 10 seeds) but the drawn Panda alarms falsely in 3 of 200 trials against 1 at 7.
    speed : float
        [rad/s] A joint no faster than this within the data selection's memory creeps: its row
        raises an alarm only when its error (short or fast average, RMS, in N m) also exceeds
        ``creep_margin`` times the joint's Coulomb friction in the model (it still feeds the
        estimate and its level). Friction the model lacks (Stribeck, soft
        friction, a wrong Coulomb level) errs near rest, and by about the friction itself; a
        payload's weight does not care. One constant for every arm, the two-link detector's
        speed gate; ``docs/change_detection.md`` ("Creeping joints"). 0: the selection's
        threshold.
    creep_margin : float
        See ``speed``; >= 0 (0: a creeping row alarms as any other).
    hold_above : float
        A row whose short average rises above this fraction of the threshold (RMS; 0.5) is
        judged, for
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
    >>> d.short_window, d.fast_window, d.fast_threshold  # [s], [s], x
    (0.02, 0.001, 7.0)
    """

    short_window: float = 0.02
    long_window: float = 1.0
    threshold: float = 4.0
    relearn_factor: float = 1.5
    warmup: float | None = None
    min_learned: int = 200
    holdoff: float = 0.2
    freeze: float = 3.0
    resume: float = 10.0
    gate: float = 8.0
    gate_after: int = 20
    reopen_again: bool = True
    reopen_mass_std: float | None = None
    floor: float | None = None
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
        _num(o, "relearn_factor", self.relearn_factor, 1.0, strict=False)
        _num(o, "gate", self.gate, 1.0)
        if self.warmup is not None:
            _num(o, "warmup", self.warmup, 0.0, strict=False)
        for name in ("holdoff", "freeze", "resume"):
            _num(o, name, getattr(self, name), 0.0, strict=False)
        if self.reopen_mass_std is not None:
            _num(o, "reopen_mass_std", self.reopen_mass_std, 0.0)
        if self.floor is not None:
            _num(o, "floor", self.floor, 0.0, strict=False)
        _int(o, "min_learned", self.min_learned, 1)
        _int(o, "gate_after", self.gate_after, 1)
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
    p0_arm : float
        Mode ``"arm"``: start-up variance of every base parameter added to the prior (isotropic
        part of P0), >= 0. The hand-off of an identification sets it to 0
        (:func:`~adaptive_dd.closed_loop.model_prior.identified_prior`: its covariance as it is).
    max_trace : float or None
        Cap on trace(P); None: the trace of the start-up or re-opened covariance, whichever is larger.
    align : bool
        Use ``(tau(t-1) + tau(t)) / 2``: the torque at the sample instant under zero-order hold.
    selection : (float, float) or None
        Data selection ``(threshold [rad/s], memory in units of tau_f)``.
    taint : float
        Filter memory [units of tau_f] during which a non-finite sample keeps the equations out of use.
    row_weights : tuple of float or None
        Equation j is divided by ``row_weights[j]`` [N m]: the recursive least squares take each
        weighted equation as one unit of noise, so weights on the scale of the equations' noise
        keep ``P`` on the scale of the priors. None: derived from the arm's torque resolution
        (:func:`derived_row_weights`, the largest 1); ``adaptive_ct`` in a scenario sets each
        row's noise from a first pass over the task
        (:func:`~adaptive_dd.identification.row_weights.task_row_weights`).
    detector : Detector or None
    project : bool or None
        Project the model control uses onto physically consistent payloads (the
        estimator's state stays unprojected). None (default): :attr:`payload_priors` (not in mode
        ``"arm"`` from a stated uncertainty, whose payload block also carries what is left of
        the arm's error along the payload's directions: projecting it clipped that, UR5 with an
        uncertain arm, 10 seeds, the put-down segment 1.09 -> 2.56x the floor).
    eig_min : float
        Smallest eigenvalue [kg m^2] of the projected pseudo-inertia, >= 0.
    bound_radius : float or None
        Radius R [m] of a ball about the payload frame that holds the payload: the projected
        model also has ``|c| <= R`` and ``tr(Sigma) <= m R^2`` (Sigma: the pseudo-inertia's
        second-moment block), so a vanishing mass carries vanishing first moments and
        inertia. None: no bound (positive semidefiniteness only).
    prior_radius : float or None
        Radius rho [m] of a compact-payload prior on the model control uses (not on the
        estimator's state): the payload's inertia about its frame is taken, a priori, as a
        solid sphere of radius rho at the estimated centre of mass, each inertia component
        with standard deviation ``m rho^2``
        (:func:`~adaptive_dd.identification.online_kernel.compact_prior`).
        After a swap the data fix the mass and centre of mass within tens of ms but the
        inertia only over about a second; the prior holds the model at a plausible inertia
        until then. None or 0: no prior. ``"auto"`` (default): :data:`DEFAULT_PRIOR_RADIUS`,
        where :attr:`payload_priors`, else none.
    prior_noise : float, "auto" or None
        How the compact-payload prior is weighed against the estimate: the recursive least
        squares take each weighted equation's error as of variance 1 and the equations as
        independent, so their ``P`` is the covariance only up to a factor. The prior is combined
        with ``P`` times ``prior_noise`` times the rows' noise level (the mean over the joint
        equations of the squared prior error the change detector has learned, else the level it
        had before the last alarm; 1 while none has one). ``"auto"`` (default): ``tau_f /
        sample_period``, the filters' memory in samples, which successive equations share, where
        :attr:`payload_priors`, else 0. None or 0: ``P`` as it is. On an arm whose equations'
        noise is far above 1 (in their weighted units), ``P`` claimed the inertia known within
        tens of milliseconds of a swap while it was off by several times itself (a drawn 5-joint
        arm's 30 % segment 1.85x its floor without the prior, 1.12x with it:
        ``tests/test_compact_prior_noise.py``; ``docs/random_arms.md``).
    arm_uncertainty : ArmUncertainty, dict or None
        Mode ``"arm"``: how far the arm may be from its URDF
        (:class:`~adaptive_dd.identification.arm_prior.ArmUncertainty`; a table of its levels);
        the arm's base parameters start with the covariance ``B C B^T`` those levels imply
        (:func:`~adaptive_dd.identification.arm_prior.prior_covariance`). None in mode
        ``"arm"``: the default levels (masses 10 %, com 1 cm, inertias 20 %, friction 50 %,
        armature 30 %).
    arm_prior_cov : tuple of tuples of float or None
        Mode ``"arm"``: the covariance ``(p, p)`` of the arm's base parameters (in the order of
        ``arm.base``) about the model, in place of the covariance ``arm_uncertainty`` implies:
        what an identification knows, with its correlations
        (:func:`~adaptive_dd.identification.arm_prior.identified_prior_cov`, what ``[run] excite``
        passes for each seed). Given, the mode defaults to ``"arm"``.

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
    prior_noise: float | str | None = "auto"
    arm_uncertainty: ArmUncertainty | None = None
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
        if self.arm_prior_cov is not None:
            C = np.asarray(self.arm_prior_cov, dtype=float)
            ok = C.ndim == 2 and C.shape[0] == C.shape[1] and C.size > 0 and np.all(np.isfinite(C))
            if not ok or not np.allclose(C, C.T, rtol=1e-9, atol=0.0) or np.any(np.diag(C) < 0):
                raise ParameterError(
                    f"{o}.arm_prior_cov must be a symmetric square table of finite values (one row "
                    f"per base parameter), got shape {C.shape}"
                )
            object.__setattr__(self, "arm_prior_cov", tuple(tuple(float(x) for x in row) for row in C))
            if self.arm_uncertainty is not None:
                raise ParameterError(f"{o}: give arm_uncertainty or arm_prior_cov, not both")
        if self.mode is None:
            learnt = self.arm_uncertainty is not None or self.arm_prior_cov is not None
            object.__setattr__(self, "mode", "arm" if learnt else "payload")
        # the payload block holds a payload (not the arm's error too) unless the arm is learnt from
        # a stated uncertainty: after an identification what is left of the arm's error is its
        # covariance, small against a payload (payload_priors)
        priors = self.payload_priors
        if self.project is None:  # the payload block also carries the arm's residual along the
            object.__setattr__(self, "project", priors)  # payload's directions: not a payload
        if isinstance(self.prior_radius, str) and self.prior_radius == "auto":
            object.__setattr__(self, "prior_radius", DEFAULT_PRIOR_RADIUS if priors else None)
        _num(o, "sample_period", self.sample_period, 0.0)
        _num(o, "tau_f", self.tau_f, 0.0)
        if self.tau_f < self.sample_period or self.tau_f > 1e4 * self.sample_period:
            raise ParameterError(
                f"{o}.tau_f = {self.tau_f} s must lie between the sample period {self.sample_period} s "
                "and 10 000 of them"
            )
        if self.mode not in MODES:
            raise ParameterError(f"{o}.mode must be one of {MODES}, got {self.mode!r}")
        _num(o, "lam0", self.lam0, 0.0, 1.0)
        _num(o, "mu", self.mu, 0.0, 1.0, strict=False)
        _num(o, "payload_mass_std", self.payload_mass_std, 0.0, strict=False)
        _num(o, "p0_arm", self.p0_arm, 0.0, strict=False)
        if self.max_trace is not None:
            _num(o, "max_trace", self.max_trace, 0.0)
        _bool(o, "align", self.align)
        _bool(o, "project", self.project)
        _num(o, "taint", self.taint, 0.0, strict=False)
        _num(o, "eig_min", self.eig_min, 0.0, strict=False)
        if self.bound_radius is not None:
            _num(o, "bound_radius", self.bound_radius, 0.0)
        if self.prior_radius is not None:
            _num(o, "prior_radius", self.prior_radius, 0.0, strict=False)
        if isinstance(self.prior_noise, str) and self.prior_noise == "auto":
            # the filters' memory in samples (successive equations share it)
            object.__setattr__(self, "prior_noise", self.tau_f / self.sample_period if priors else 0.0)
        if self.prior_noise is None:
            object.__setattr__(self, "prior_noise", 0.0)
        _num(o, "prior_noise", self.prior_noise, 0.0, strict=False)
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
    def payload_priors(self) -> bool:
        """Whether the model control uses takes the payload block as a payload: the centred and
        compact priors and the projection onto physically consistent payloads. In mode
        ``"payload"``, and in mode ``"arm"`` after an identification (``arm_prior_cov``): what is
        left of the arm's error along the payload's directions is then the identification's
        covariance, small against a payload (``known_payload_mass_std``: random:14 after a 20 s
        excitation, 0.02 kg of its 7.46 kg capacity), while from a stated uncertainty it is the
        draw's (the UR5 drawn, its put-down segment 1.09 -> 2.56x the floor projected). Without
        them a pick-up's first tens of milliseconds gave the model a centre of mass 0.6 m off and
        an inertia that was not positive definite (random:14 on the drawn population: the wrist
        at its torque limit, sign flipping, for 0.2 s)."""
        return self.mode == "payload" or self.arm_prior_cov is not None

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
FLOOR_MAX = 0.05
"""[N m] The change detector's level floor on the heaviest row, at most (``Detector.floor`` None):
the constant it was for every arm, measured on the shipped arms and the drawn population (whose
heaviest rows carry 0.1-1.2 N m of noise); on an arm lighter than that the heaviest row's own
noise over the threshold (the SO-101 of example-robot-data: 0.005 N m)."""


def detector_floor(det: Detector, heaviest_noise: float | None = None) -> float:
    """The level floor [N m] on the row of the largest weight: ``det.floor`` when given, else
    :data:`FLOOR_MAX`, at most ``heaviest_noise / det.threshold`` when the heaviest row's noise
    [N m, RMS] is known (the estimator's first pass over the task)."""
    if det.floor is not None:
        return float(det.floor)
    if heaviest_noise is None or not np.isfinite(heaviest_noise) or heaviest_noise <= 0:
        return FLOOR_MAX
    return float(min(FLOOR_MAX, heaviest_noise / det.threshold))


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


@lru_cache(maxsize=32)
def _bank(tau_f: float, sample_period: float) -> FilterBank:
    return design_filter_bank("M2", tau_f, sample_period)


def payload_prior(mass_std: float, size: float, shape: ArrayLike | None = None) -> Array:
    """Covariance (10, 10) of a payload prior: ``s^2 d d^T + diag(0, (s r)^2 x3, (s r^2)^2 x6)``.

    A body of up to about ``s`` = ``mass_std`` [kg] shaped as ``shape`` (``d``: its ten
    parameters per kg about the payload frame, :func:`~adaptive_dd.plant.payload.payload_parameters`
    order; default a point mass at the frame's origin), its centre of mass within about ``r`` =
    ``size`` [m] of that origin: the inertias move with the mass as the shape's do, and the first
    moments and inertias have an uncertainty ``s r`` and ``s r^2`` of their own.

    Examples
    --------
    >>> from adaptive_dd.identification.online_config import payload_prior
    >>> from adaptive_dd.plant.payload import payload_parameters
    >>> d = payload_parameters(1.0, radius=0.05)  # a disk of 5 cm per kg: Izz = 0.00125 kg m^2
    >>> P = payload_prior(3.0, 0.0, d)  # up to about 3 kg, centred on the frame
    >>> float(P[0, 0]), float(P[0, 9]), float(P[1, 1])  # mass, mass with Izz, a first moment
    (9.0, 0.01125, 0.0)
    """
    s, r = float(mass_std), float(size)
    d = np.eye(10)[0] if shape is None else np.asarray(shape, dtype=float).reshape(10)
    return s**2 * np.outer(d, d) + np.diag([0.0] + [(s * r) ** 2] * 3 + [(s * r * r) ** 2] * 6)
