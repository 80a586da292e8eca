"""Settings of the two-link online estimator: its change detector and its configuration.

:class:`TwoLinkOnlineConfig` (filters, split, RLS, start-up covariance, data selection,
projection) and :class:`ChangeDetector` (the change detector's windows and thresholds), each
checked when built (a :class:`~adaptive_dd.errors.ParameterError` names the field and its value),
and packed for the compiled kernel (:attr:`TwoLinkOnlineConfig.packed`, the slots of
:mod:`adaptive_dd.identification.two_link_online_kernel`). The estimator's state and step are in
:mod:`adaptive_dd.identification.two_link_online`, which re-exports both classes and
:func:`rearm_time`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np
import scipy.linalg.lapack
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError, is_finite_number
from adaptive_dd.identification import two_link_online_kernel as K
from adaptive_dd.identification.estimators import SPLITS
from adaptive_dd.identification.filters import FilterBank, design_filter_bank
from adaptive_dd.identification.rls import RLSConfig
from adaptive_dd.plant.parameters import PROJECTION_J_MIN, PROJECTION_MARGIN, R_MIN

__all__ = [
    "SICE_PAYLOAD_DIRECTION",
    "SPLIT_STAGES",
    "ChangeDetector",
    "TwoLinkOnlineConfig",
    "rearm_time",
]

Array = NDArray[np.float64]

SPLIT_STAGES = {
    name: ((0, 1), ()) if stages is None else ((stages[0][0], stages[1][0]), stages[0][1])
    for name, stages in SPLITS.items()
}
"""Per split: regressor rows of the two stages, and the parameters of the first stage
(the others form the second; docs/paper_reading.md: the splits are cascaded)."""


def _finite(name: str, v: float, lo: float | None = None, hi: float | None = None, strict=True) -> None:
    ok = is_finite_number(v)
    if ok and lo is not None:
        ok = v > lo if strict else v >= lo
    if ok and hi is not None:
        ok = v <= hi
    if not ok:
        rng = (
            f" in ({lo}, {hi}]"
            if hi is not None
            else (f" {'>' if strict else '>='} {lo}" if lo is not None else "")
        )
        raise ParameterError(f"{name} must be a finite number{rng}, got {v!r}")


@dataclass(frozen=True)
class ChangeDetector:
    """Detects a sudden change of the plant (a payload swap) from the prior prediction errors.

    A generalized likelihood ratio (GLR) test of a change of the tip mass, at each of the
    onsets of the last ``16 * glr_spacing``, on the prior errors of both equations weighted by
    their long-run levels; an alarm needs the change to explain the errors (``min_mass``,
    ``min_explained``, both equations alike: ``hetero``), and uses an equation only while its
    joint moves faster than ``speed`` (friction the model lacks lives at low speed). A
    persistence test over ``persist_window`` re-arms the detector after any alarm: a model
    left wrong along the payload direction is found again within :func:`rearm_time` of
    motion. The kernel's ``_detect`` documents the arithmetic. One setting serves every
    shipped scenario and plant friction law (``benchmarks/detector_acceptance.py``).

    Attributes
    ----------
    short_window, long_window : float
        Time constants [s] of the two averages (``0 < short < long``).
    threshold : float
        Ratio of RMS errors that raises an alarm, > 1 (energy test of the paper's construction).
    warmup : float
        No alarm before this time [s] from the start.
    min_learned : int
        Learned samples an equation needs before it may alarm.
    holdoff : float
        No new alarm for this long after one [s].
    freeze : float
        Filter memory after a change, in units of tau_f: the filtered equation
        ``G0 tau = (G0 Phi) sigma`` holds again only once the filters no longer span
        the change. With ``reopen_again`` the covariance is re-opened a second time then;
        otherwise the RLS does not update until then.
    resume : float
        The long-run level resumes learning this many freeze times after an alarm.
    reopen_again : bool
        Keep updating through the change and re-open again after ``freeze``.
    p_mass : float
        Variance [kg^2] re-opened along the payload direction d (a tip disk of mass m
        moves sigma by ``m d``), after clearing the old covariance of J1, J2 and r.
    p_j2 : float
        Extra variance [(kg m^2)^2] on J2 alone (the disk's own inertia).
    direction_window : float
        Time constant [s] of the payload-direction gate of the energy test (paper's construction).
    persist_window : float
        Time constant [s] of the persistence test.
    persist_min : int
        Samples the persistence test needs after it restarted (``resume`` after an alarm).
    min_mass : float
        Smallest payload change [kg] an alarm may claim (``|dm_hat|``).
    min_explained : float
        Fraction of the weighted prior-error energy that a payload change must explain, in (0, 1].
    glr_threshold : float
        Threshold of the GLR score ``A^2 / B`` (weighted errors are coloured by the filters, so it
        is set on the benchmark's false-alarm rate rather than a chi-square quantile): 300, where
        ``benchmarks/detector_acceptance.py`` (five two-link scenarios x six plant friction laws)
        finds no false alarm in 6000 trials (200 seeds), against 29 trials of 1500 at 200 (50
        seeds); every segment's mean, p90 and max ratio is at or below 400's.
    glr_spacing : float
        [s] between the onsets of two GLR candidates (16 candidates).
    glr_min_age : float
        [s] a GLR candidate must have run before it may alarm.
    hetero : float
        The heterogeneity of a candidate over the two equations counts ``1 / hetero`` against it.
    speed : float
        [rad/s] an equation feeds the tests (and the levels) only while its joint is faster ...
    speed_memory : float
        ... and has been for this many tau_f (the filters' memory of the slow phase: 2 tau_f).
        This gate is the detector's own, apart from the RLS's data selection: an equation the
        RLS skips feeds the tests its prior error ``y - phi theta``.
    removal : float
        A GLR alarm may claim removing at most ``removal`` times the payload mass the estimate
        carries (over the start estimate, taken as the arm without payload), plus ``min_mass``:
        a stick event of one joint disturbs the other joint's equation like a payload change of
        either sign, and at no payload only added mass can be a swap. The persistence test is
        not gated (a start estimate that carries a payload is still corrected by it).
    momentum_threshold : float
        Threshold of the momentum test's GLR score ``A^2 / B``
        (:mod:`~adaptive_dd.identification.two_link_momentum_test`: the whitened GLR of a tip-mass
        change on the generalised momentum, beside the filtered equations' GLR, with the exact
        construction). The score is chi-square(1) on the model: its largest value over a 20 s
        trial is 50-70 on the default scenario's stick-slip, tanh, Stribeck and LuGre plants;
        at 100 a creeping plant (tanh, v = 0.1 rad/s) raised false alarms in 6 of 200 trials of
        ``swap_at_reversal.toml``, none at 150 (``benchmarks/detector_acceptance.py``). It waits a
        long window (``long_window``) after any alarm: meanwhile its residual holds what the
        estimate has yet to learn of the last change.

    Notes
    -----
    Re-arming: after any alarm the persistence test is armed again after
    ``max(holdoff, resume * freeze * tau_f + persist_min * T)`` (0.2 s with the defaults at
    1 kHz, counted in samples in which the equations are in use): whatever the long-run level
    learned, a model that stays wrong along the payload direction by ``min_mass`` or more
    raises a new alarm then (:func:`rearm_time`).
    """

    short_window: float = 0.005
    long_window: float = 1.0
    threshold: float = 4.0
    warmup: float = 0.5
    min_learned: int = 200
    holdoff: float = 0.2
    freeze: float = 3.0
    resume: float = 3.0
    reopen_again: bool = True
    p_mass: float = 100.0
    p_j2: float = 1e-3
    direction_window: float = 0.02
    persist_window: float = 0.1
    persist_min: int = 100
    min_mass: float = 0.25
    min_explained: float = 0.5
    glr_threshold: float = 300.0
    glr_spacing: float = 0.003
    glr_min_age: float = 0.005
    hetero: float = 1.0
    speed: float = 0.25
    speed_memory: float = 2.0
    removal: float = 2.0
    momentum_threshold: float = 150.0

    def __post_init__(self) -> None:
        _finite("ChangeDetector.short_window", self.short_window, 0.0)
        _finite("ChangeDetector.long_window", self.long_window, 0.0)
        if not self.short_window < self.long_window:
            raise ParameterError(
                f"ChangeDetector needs short_window < long_window, got "
                f"{self.short_window}, {self.long_window}"
            )
        _finite("ChangeDetector.threshold", self.threshold, 1.0)
        for name in ("warmup", "holdoff", "freeze", "resume", "p_j2"):
            _finite(f"ChangeDetector.{name}", getattr(self, name), 0.0, strict=False)
        _finite("ChangeDetector.p_mass", self.p_mass, 0.0)
        for name in (
            "direction_window",
            "persist_window",
            "min_mass",
            "glr_threshold",
            "glr_spacing",
            "hetero",
            "speed",
            "removal",
            "momentum_threshold",
        ):
            _finite(f"ChangeDetector.{name}", getattr(self, name), 0.0)
        _finite("ChangeDetector.min_explained", self.min_explained, 0.0, 1.0)
        _finite("ChangeDetector.glr_min_age", self.glr_min_age, 0.0, strict=False)
        if (
            not isinstance(self.persist_min, int)
            or isinstance(self.persist_min, bool)
            or self.persist_min < 1
        ):
            raise ParameterError(
                f"ChangeDetector.persist_min must be an integer >= 1, got {self.persist_min!r}"
            )
        if (
            not isinstance(self.min_learned, int)
            or isinstance(self.min_learned, bool)
            or self.min_learned < 1
        ):
            raise ParameterError(
                f"ChangeDetector.min_learned must be an integer >= 1, got {self.min_learned!r}"
            )
        if not isinstance(self.reopen_again, bool):
            raise ParameterError(
                f"ChangeDetector.reopen_again must be true or false, got {self.reopen_again!r}"
            )


SICE_PAYLOAD_DIRECTION = (0.04, 0.04, 0.04, 0.0, 0.0, 0.0, 0.0)
"""d sigma / d m of a point mass at the tip of the SICE arm (l1 = l2 = 0.2 m)."""


@dataclass(frozen=True)
class TwoLinkOnlineConfig:
    """Settings of the online estimator.

    Attributes
    ----------
    sample_period : float
        T [s].
    tau_f : float
        Time constant of the M2 filter bank [s] (eq. 20).
    construction : {"exact", "paper"}
        The filtered regression (see :mod:`~adaptive_dd.identification.regressors`).
    split : {"full", "15", "16"}
        One RLS on all seven parameters, or the paper's cascaded splits (15), (16).
    rls : RLSConfig
        Forgetting (``lam0``, ``mu``), isotropic start-up covariance ``p0`` and trace cap.
    p0_payload : float
        Start-up variance [kg^2] along the payload direction, added to ``p0 I``: the
        prior says the arm may carry an unknown tip mass, and little else is uncertain.
    p0_j2 : float
        Start-up variance added on J2 alone.
    align : bool
        Use ``(tau(t-1) + tau(t)) / 2`` (the torque at the sample instant).
    selection : (float, float) or None
        Data selection ``(threshold [rad/s], memory in units of tau_f)``.
    detector : ChangeDetector or None
    project : {"model", "state", "none"}
        Project the control model only, also the estimator's state, or nothing.
    payload_direction : tuple of 7 floats
        d sigma / d m of a tip payload (from the arm; the re-opening direction).

    Examples
    --------
    >>> from adaptive_dd.identification.two_link_online_config import TwoLinkOnlineConfig
    >>> cfg = TwoLinkOnlineConfig(sample_period=1e-3)
    >>> cfg.tau_f, cfg.construction
    (0.01, 'exact')
    """

    sample_period: float = 1e-3
    tau_f: float = 0.01
    construction: str = "exact"
    split: str = "full"
    rls: RLSConfig = field(default_factory=lambda: RLSConfig(lam0=0.99995, mu=0.0, p0=1e-6, max_trace=30.0))
    p0_payload: float = 25.0
    p0_j2: float = 1e-4
    align: bool = True
    selection: tuple[float, float] | None = (0.05, 6.0)
    detector: ChangeDetector | None = field(default_factory=ChangeDetector)
    project: str = "model"
    payload_direction: tuple[float, ...] = SICE_PAYLOAD_DIRECTION

    def __post_init__(self) -> None:
        _finite("TwoLinkOnlineConfig.sample_period", self.sample_period, 0.0)
        _finite("TwoLinkOnlineConfig.tau_f", self.tau_f, 0.0)
        if self.tau_f < self.sample_period:
            raise ParameterError(
                f"TwoLinkOnlineConfig.tau_f = {self.tau_f} s is shorter than the sample period "
                f"{self.sample_period} s"
            )
        if self.tau_f > 1e4 * self.sample_period:
            raise ParameterError(
                f"TwoLinkOnlineConfig.tau_f = {self.tau_f} s is over 10 000 sample periods "
                f"({self.sample_period} s)"
            )
        if self.construction not in ("exact", "paper"):
            raise ParameterError(
                f"TwoLinkOnlineConfig.construction must be 'exact' or 'paper', got {self.construction!r}"
            )
        det = self.detector
        if self.construction == "exact" and det is not None and det.threshold != ChangeDetector.threshold:
            raise ParameterError(  # (it was accepted and changed nothing: one meaning per name)
                f"ChangeDetector.threshold = {det.threshold}: the energy test of the paper's construction "
                "(construction = 'paper'), which the exact construction's detector does not read: its "
                "alarm is a GLR test, set ChangeDetector.glr_threshold"
            )
        if self.split not in SPLIT_STAGES:
            raise ParameterError(
                f"TwoLinkOnlineConfig.split must be one of {list(SPLIT_STAGES)}, got {self.split!r}"
            )
        if self.project not in ("model", "state", "none"):
            raise ParameterError(
                f"TwoLinkOnlineConfig.project must be 'model', 'state' or 'none', got {self.project!r}"
            )
        if not isinstance(self.rls, RLSConfig):
            raise ParameterError(
                f"TwoLinkOnlineConfig.rls must be an RLSConfig, got {type(self.rls).__name__}"
            )
        _finite("TwoLinkOnlineConfig.p0_payload", self.p0_payload, 0.0, strict=False)
        _finite("TwoLinkOnlineConfig.p0_j2", self.p0_j2, 0.0, strict=False)
        if self.selection is not None:
            if len(self.selection) != 2:
                raise ParameterError(
                    f"TwoLinkOnlineConfig.selection must be (threshold, memory), got {self.selection!r}"
                )
            _finite("TwoLinkOnlineConfig.selection threshold", self.selection[0], 0.0, strict=False)
            _finite("TwoLinkOnlineConfig.selection memory", self.selection[1], 0.0, strict=False)
        d = np.asarray(self.payload_direction, dtype=float)
        if d.shape != (7,) or not np.all(np.isfinite(d)) or np.any(d[3:] != 0) or np.any(d[:3] < 0):
            raise ParameterError(
                f"TwoLinkOnlineConfig.payload_direction must be 7 finite values [dJ1 dJ2 dr 0 0 0 0] >= 0, "
                f"got {self.payload_direction!r}"
            )

    @cached_property
    def bank(self) -> FilterBank:
        return _bank(self.tau_f, self.sample_period)

    @cached_property
    def group(self) -> NDArray[np.int64]:
        """Parameter group (RLS stage) of each of the seven parameters."""
        first = SPLIT_STAGES[self.split][1]
        return np.array([0 if (self.split == "full" or j in first) else 1 for j in range(7)], dtype=np.int64)

    def samples(self, n_tau_f: float) -> int:
        """``n_tau_f`` filter time constants in samples (the one place this conversion is made)."""
        return int(np.ceil(n_tau_f * self.tau_f / self.sample_period - 1e-9))

    @cached_property
    def packed(self) -> tuple:
        """``(ci, cf, A, B, C, D, d, group, split_rows)`` for the compiled kernel."""
        ci = np.zeros(K.N_CI, dtype=np.int64)
        cf = np.zeros(K.N_CF)
        det = self.detector
        T = self.sample_period
        ci[K.I_CONSTRUCTION] = 1 if self.construction == "exact" else 0
        ci[K.I_SPLIT] = {"full": 0, "15": 1, "16": 2}[self.split]
        ci[K.I_ALIGN] = int(self.align)
        ci[K.I_SELECT] = int(self.selection is not None)
        ci[K.I_SEL_MEMORY] = 0 if self.selection is None else self.samples(self.selection[1])
        ci[K.I_TAINT] = self.samples(10.0)
        ci[K.I_PROJECT] = {"none": 0, "model": 1, "state": 2}[self.project]
        cf[K.F_LAM0], cf[K.F_MU] = self.rls.lam0, self.rls.mu
        sizes = np.bincount(self.group, minlength=2)
        for g in range(2):
            cap = self.rls.max_trace if self.rls.max_trace is not None else self.rls.p0 * sizes[g]
            cf[K.F_CAP0 if g == 0 else K.F_CAP1] = cap
        cf[K.F_SEL_THRESHOLD] = 0.0 if self.selection is None else self.selection[0]
        cf[K.F_J_MIN], cf[K.F_MARGIN], cf[K.F_R_MIN] = PROJECTION_J_MIN, PROJECTION_MARGIN, R_MIN
        if det is not None:
            ci[K.I_DETECT] = 1
            ci[K.I_WARMUP] = round(det.warmup / T)
            ci[K.I_MIN_LEARNED] = det.min_learned
            ci[K.I_HOLDOFF] = round(det.holdoff / T)
            ci[K.I_FREEZE] = self.samples(det.freeze)
            ci[K.I_RESUME] = ci[K.I_FREEZE] * det.resume
            ci[K.I_REOPEN_AGAIN] = int(det.reopen_again)
            cf[K.F_ALPHA_SHORT] = min(1.0, T / det.short_window)
            cf[K.F_ALPHA_LONG] = min(1.0, T / det.long_window)
            cf[K.F_THRESHOLD2] = det.threshold**2
            cf[K.F_P_MASS], cf[K.F_P_J2] = det.p_mass, det.p_j2
            cf[K.F_ALPHA_DIR] = min(1.0, T / det.direction_window)
            cf[K.F_ALPHA_PERSIST] = min(1.0, T / det.persist_window)
            cf[K.F_MIN_MASS], cf[K.F_MIN_EXPLAINED] = det.min_mass, det.min_explained
            ci[K.I_PERSIST_MIN] = det.persist_min
            ci[K.I_GLR_SPACING] = max(1, round(det.glr_spacing / T))
            ci[K.I_GLR_MIN_AGE] = round(det.glr_min_age / T)
            cf[K.F_GLR_THRESHOLD] = det.glr_threshold
            cf[K.F_HETERO] = det.hetero
            cf[K.F_DET_SPEED] = det.speed
            ci[K.I_SPEED_MEMORY] = self.samples(det.speed_memory)
            cf[K.F_REMOVAL] = det.removal
            cf[K.F_T] = T
            cf[K.F_MG_THRESHOLD] = det.momentum_threshold if self.construction == "exact" else 0.0
        b = self.bank
        d = np.asarray(self.payload_direction, dtype=float)
        rows = np.array(SPLIT_STAGES[self.split][0], dtype=np.int64)
        mats = (np.ascontiguousarray(b.A), np.ascontiguousarray(b.B[:, 0]), np.ascontiguousarray(b.C))
        # the filters' state under a unit constant input, (I - A)^-1 B, after the settings
        # (slot F_XS0 on): LAPACK's dgesv, the routine numba's np.linalg.solve calls, so the
        # same numbers as solving in the kernel, which then need not compile numba's solve
        xs0 = scipy.linalg.lapack.dgesv(np.eye(mats[0].shape[0]) - mats[0], mats[1])[2]
        cf = np.concatenate((cf, xs0))
        return (ci, cf, *mats, np.ascontiguousarray(b.D[:, 0]), d, self.group, rows)

    def initial_covariance(self) -> Array:
        """``p0 I + p0_payload d d^T + p0_j2 e_J2 e_J2^T`` (d d^T kept within each split group), (7, 7)."""
        d = np.asarray(self.payload_direction, dtype=float)
        same = self.group[:, None] == self.group[None, :]
        p = self.rls.p0 * np.eye(7) + self.p0_payload * np.outer(d, d) * same
        p[1, 1] += self.p0_j2
        return p


def rearm_time(cfg: TwoLinkOnlineConfig) -> float:
    """Longest time [s] after any alarm before the detector can raise the next one.

    ``max(holdoff, resume * freeze * tau_f + persist_min * T)`` in samples in which the
    equations are in use (see :class:`ChangeDetector`, Notes). Raises
    :class:`~adaptive_dd.errors.ParameterError` for a config without a detector.
    """
    det = cfg.detector
    if det is None:
        raise ParameterError("rearm_time: the TwoLinkOnlineConfig has no detector")
    T = cfg.sample_period
    resume = cfg.samples(det.freeze) * det.resume
    return max(round(det.holdoff / T), resume + det.persist_min) * T


@lru_cache(maxsize=32)
def _bank(tau_f: float, sample_period: float) -> FilterBank:
    return design_filter_bank("M2", tau_f, sample_period)
