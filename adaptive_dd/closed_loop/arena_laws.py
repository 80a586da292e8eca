"""The arena's built-in laws for N-joint arms: the field's robust and observer-based laws on the
compiled law kernel (:mod:`adaptive_dd.closed_loop.laws`), beside the built-ins of
:mod:`adaptive_dd.closed_loop.controllers` (whose :class:`~adaptive_dd.closed_loop.controllers.Law`
they subclass). Each says its primary reference, the signals it uses and how its settings follow
from the arm and the scenario's stated uncertainty; ``docs/controllers.md`` gives each equation.
:data:`ARM_LAWS` is every N-joint built-in, name -> class.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.closed_loop.adaptation import ADAPT_CHS, ADAPT_ICL, ADAPT_NATURAL
from adaptive_dd.closed_loop.adaptation_gain import payload_gains
from adaptive_dd.closed_loop.controllers import (
    ARM_CONTROLLERS,
    DEFAULT_PAYLOAD_GAMMA,
    OBSERVER_LEVEL_WINDOW,
    OBSERVER_WARMUP,
    Law,
    SlotineLi,
    observer_bandwidth,
)
from adaptive_dd.closed_loop.laws import (
    KIND_CT,
    KIND_PD_GRAVITY,
    KIND_SLOTINE,
    MODEL_FIXED,
    MODEL_TRIAL,
    MODEL_TRUE,
)
from adaptive_dd.errors import ParameterError
from adaptive_dd.errors import is_finite_number as _is_number

__all__ = [
    "ARENA_CONTROLLERS",
    "ARM_LAWS",
    "Composite",
    "CraigHsuSastry",
    "IntegralConcurrentLearning",
    "MomentumObserverCT",
    "NaturalAdaptive",
    "PDGravity",
    "PDGravityOracle",
    "SlidingMode",
    "parameter_error_bound",
    "payload_bound",
]

Array = NDArray[np.float64]


class PDGravity(Law):
    """PD plus gravity compensation (Takegaki and Arimoto, "A New Feedback Method for Dynamic
    Control of Manipulators", J. Dyn. Sys., Meas., Control 103, 1981):
    ``tau = Kp e + Kd e' + g0(q)``, ``g0`` the nominal model's gravity torque; gains as
    :class:`PDControl` (``Kp = omega^2 M0``, ``Kd = 2 zeta omega M0``, M0 the diagonal of the
    nominal inertia at the middle of the joint ranges). Signals: measured ``q, qd``; the reference
    ``q_d, qd_d``. Asymptotically stable for a constant reference with exact gravity; with a moving
    reference and no inertial feedforward it lags by about ``M qdd_d / Kp``."""

    name = "pd_gravity"
    floor = "pd_gravity_oracle"

    def _pd_gravity(self, sample_period, model):
        m0 = self.arm.nominal_inertia()
        return self._config(
            sample_period, KIND_PD_GRAVITY, model, kp=self.gains.kp * m0, kd=self.gains.kd * m0
        )

    def law_config(self, sample_period):
        return self._pd_gravity(sample_period, MODEL_FIXED)


class PDGravityOracle(PDGravity):
    """:class:`PDGravity` with the true gravity torque at every sample (the floor of ``pd_gravity``)."""

    name = "pd_gravity_oracle"
    floor = None
    needs_true_model = True

    def law_config(self, sample_period):
        return self._pd_gravity(sample_period, MODEL_TRUE)


SLIDING_COM_RADIUS = 0.1
"""[m] ``sliding_mode``'s default bound of the payload's centre of mass about the payload frame
(the shipped scenarios' tools: at most 0.08 m)."""
SLIDING_MAX_MASS = 20.0
"""[kg] ``sliding_mode``'s payload bound when the arm states no ``payload_capacity``."""


def parameter_error_bound(arm, levels: dict | None) -> Array:
    """Bound ``(13 n,)`` of the error of each standard parameter of ``arm`` under the stated
    uncertainty ``levels`` (the keys of ``[plant.uncertainty]``; None or empty: an exact arm):
    ``sum_k |d pi / d u_k| u_max``, linearised about the URDF
    (:func:`~adaptive_dd.identification.arm_prior.perturbed_parameters`), ``u_max`` 1 for uniform
    draws and 3 for normal ones (clipped there)."""
    from adaptive_dd.identification.arm_prior import ArmUncertainty, perturbed_parameters

    n = arm.n_joints
    levels = dict(levels or {})
    u_max = 3.0 if levels.pop("distribution", "uniform") == "normal" else 1.0
    keys = ("mass", "com", "inertia", "viscous", "coulomb", "armature")
    lv = ArmUncertainty(**{k: float(levels.get(k, 0.0)) for k in keys})
    h = 1e-3
    out = np.zeros(13 * n)
    for k in range(8 * n):
        e = np.zeros(8 * n)
        e[k] = h
        d = (perturbed_parameters(arm, e, lv) - perturbed_parameters(arm, -e, lv)) / (2 * h)
        out += np.abs(d)
    return out * u_max


def payload_bound(max_mass: float, com_radius: float) -> Array:
    """Bound ``(10,)`` of the payload's parameters about its frame (``m, m c, I``): a mass up to
    ``max_mass`` [kg] with its centre within ``com_radius`` [m] per axis; the inertia about the frame
    that of the mass spread over that radius (``2 m r^2`` on the diagonal, ``m r^2`` off it)."""
    m, r = float(max_mass), float(com_radius)
    i = m * r * r
    return np.array([m, m * r, m * r, m * r, 2 * i, i, i, 2 * i, i, 2 * i])


class SlidingMode(Law):
    """Robust computed torque with a boundary layer (Slotine, "The Robust Control of Robot
    Manipulators", IJRR 4(2), 1985; Spong, "On the Robust Control of Robot Manipulators", IEEE TAC
    37(11), 1992): Slotine-Li's structure on the nominal model (no payload) plus ``rho sat(s /
    phi)`` per joint, ``rho`` the bound of the model's torque error at this sample,
    ``|Y(q, qd, qd_r, a)| dpi`` (the Slotine-Li regressor's magnitudes times the bound of each
    parameter's error), ``phi = rho / (lam M0_jj)`` (the balance condition ``k = lam phi``,
    Slotine and Li 1991, sec. 7.2). The parameter bound is derived, not tuned: the arm's from the
    scenario's ``[plant.uncertainty]`` (``uncertainty``: :func:`parameter_error_bound`), the
    payload's from ``max_mass`` (default the arm's ``payload_capacity``) and ``com_radius``
    (:func:`payload_bound`). Signals: measured ``q, qd``; the reference with ``qdd_d``."""

    name = "sliding_mode"
    floor = "slotine_li_oracle"
    SETTINGS = frozenset({"uncertainty", "max_mass", "com_radius"})

    def __init__(self, arm, bandwidth=40.0, damping: float = 1.0, **settings) -> None:
        super().__init__(arm, bandwidth, damping, **settings)
        where = f"controllers.{self.name}"
        cap = getattr(arm, "payload_capacity", None)
        self.max_mass = self.settings.get("max_mass", cap if cap is not None else SLIDING_MAX_MASS)
        self.com_radius = self.settings.get("com_radius", SLIDING_COM_RADIUS)
        for key, v in (("max_mass", self.max_mass), ("com_radius", self.com_radius)):
            if not (_is_number(v) and v >= 0):
                raise ParameterError(f"{where}.{key}: a number >= 0, got {v!r}")
        unc = self.settings.get("uncertainty", {})
        if not isinstance(unc, dict):
            raise ParameterError(
                f"{where}.uncertainty: a table of levels (mass, com, inertia, viscous, coulomb, "
                f"armature, distribution), got {unc!r}"
            )
        try:
            self.rho_pi = parameter_error_bound(arm, unc)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"{where}.uncertainty: {exc}") from None
        self.rho_payload = payload_bound(self.max_mass, self.com_radius)

    def law_config(self, sample_period):
        lam, k = self.gains.roots()
        return self._config(
            sample_period, KIND_SLOTINE, MODEL_FIXED, lam=lam, kd=k, robust=True,
            rho_pi=np.ascontiguousarray(self.rho_pi), rho_payload=self.rho_payload,
        )  # fmt: skip


class MomentumObserverCT(Law):
    """Computed torque on the nominal model plus the generalized-momentum observer's estimate of
    the torque the model leaves unexplained (De Luca and Mattone, "Sensorless Robot Collision
    Detection and Hybrid Force/Motion Control", ICRA 2005; De Luca, Albu-Schaeffer, Haddadin and
    Hirzinger, IROS 2006): ``tau = tau_ct(pi0) + r``, ``r`` the residual of
    :mod:`adaptive_dd.closed_loop.residual_observer` (adaptive_ct's observer, its bandwidth derived
    from the sample period: two stages at ``0.4 / T``), fed back in full after its 0.5 s warm-up
    (no soft threshold: adaptive_ct's threshold follows a learnt level that a lasting payload torque
    raises until it passes nothing, while here the observer is the only thing that ever learns the
    payload). Signals: measured ``q, qd``, the applied torque of the samples before. Its floor is
    ``ct_oracle``."""

    name = "momentum_observer_ct"

    def law_config(self, sample_period):
        T = float(sample_period)
        return self._config(
            T, KIND_CT, MODEL_FIXED, observer=True, obs_a=float(np.exp(-observer_bandwidth(T) * T)),
            obs_alpha=min(1.0, T / OBSERVER_LEVEL_WINDOW), obs_warmup=round(OBSERVER_WARMUP / T),
            obs_kappa=0.0,
        )  # fmt: skip


class Composite(SlotineLi):
    """Composite adaptive control (Slotine and Li, "Composite Adaptive Control of Robot
    Manipulators", Automatica 25(4), 1989) on the payload's ten parameters as ``slotine_li`` adapts
    them (the same gains, box and feedback): ``theta' = Gamma (Y_p^T s + W^T R eps)``, ``W`` the
    payload's regressor and ``eps`` the applied torque's prediction error, both through the
    first-order filter ``lam / (s + lam)`` of the dynamics in momentum form (no acceleration:
    :mod:`adaptive_dd.closed_loop.composite`). Derived settings: the filter's rate the tracking
    bandwidth ``min(lam)``; ``R = diag(1 / (k m0))`` (``k m0``, the feedback's gain at the middle of
    the joint ranges, turns a torque error into the ``s`` it leaves: both terms in the same units
    and weight). A constant ``Gamma`` (the paper's time-varying gain is not used). Signals:
    measured ``q, qd``, the applied torque of the samples before, ``qdd_d``."""

    name = "composite"
    floor = "slotine_li_oracle"

    def law_config(self, sample_period):
        cfg = super().law_config(sample_period)
        m0 = self.arm.nominal_inertia()  # armature included
        return cfg._replace(
            composite=True,
            comp_rate=float(np.min(cfg.lam)),
            comp_weight=1.0 / (cfg.kd * np.maximum(m0, 1e-9)),
        )


class CraigHsuSastry(SlotineLi):
    """Adaptive computed torque (Craig, Hsu and Sastry, "Adaptive Control of Mechanical
    Manipulators", IJRR 6(2), 1987) on the payload's ten parameters: the textbook computed torque
    on the estimated model, ``tau = M_hat(q) (qdd_d + Kv e' + Kp e) + n_hat(q, qd)``, whose error
    obeys ``e'' + Kv e' + Kp e = M_hat^-1 W (theta - theta_hat)``, and the adaptation
    ``theta_hat' = Gamma W^T M_hat^-1 E1``, ``E1 = e' + lam e`` (``lam`` the smaller root of the
    gains: ``(s + lam) / (s^2 + Kv s + Kp)`` strictly positive real), ``W`` the payload's regressor
    at the measured velocity and acceleration (the acceleration differentiated from the measured
    velocity and low-passed at the tracking bandwidth ``min(lam)``: the law needs it, the paper
    assumes it measured). The estimate is projected on ``slotine_li``'s box and onto a
    positive semi-definite pseudo-inertia (a physically consistent payload), so that ``M_hat``
    stays positive definite and its inverse exists
    (:func:`~adaptive_dd.closed_loop.adaptation.project_payload`). Derived gain: ``slotine_li``'s
    ``gamma`` times the geometric mean of the nominal inertia's diagonal at the middle of the
    joint ranges (``M_hat^-1`` divides by an inertia that ``Y^T s`` does not). Signals: measured
    ``q, qd`` (and ``qdd`` from them); the reference with ``qdd_d``. Its floor is
    ``ct_oracle_textbook`` (the same law given the true model)."""

    name = "craig_hsu_sastry"
    floor = "ct_oracle_textbook"

    def state_task(self, scenario) -> None:
        """Nothing: its gain stays :data:`DEFAULT_PAYLOAD_GAMMA` times the inertia's mean. The
        gains ``slotine_li`` derives from the task assume the sliding variable's feedback, which this
        law has not (its adaptation reads the measured acceleration through ``M_hat^-1``): with them
        it was 1.8-42x its floor in the unloaded first segment of the exact UR5 and Panda and of
        six drawn arms, and 578x and 1630x in the last segment of two of those arms
        (``benchmarks/adaptation_gains.py``)."""

    def law_config(self, sample_period):
        box = super().law_config(sample_period)
        m0 = np.maximum(self.arm.nominal_inertia(), 1e-9)  # armature included
        g = self.gains
        return self._config(
            sample_period, KIND_CT, MODEL_TRIAL, reference_velocity=False, adapt=True,
            adapt_kind=ADAPT_CHS, gamma=box.gamma * float(np.exp(np.mean(np.log(m0)))), lo=box.lo,
            hi=box.hi, com_radius=box.com_radius, kp=g.kp, kd=g.kd, lam=g.roots()[0],
            comp_rate=float(np.min(g.roots()[0])),
        )  # fmt: skip


ICL_WINDOW_CYCLES = 2.0
"""Integral concurrent learning's window is ``ICL_WINDOW_CYCLES / min(lam)`` [s] (0.05 s at
40 rad/s): long enough for the momentum's change to stand above the measured velocity's noise,
short beside a payload segment."""


class IntegralConcurrentLearning(Composite):
    """Integral concurrent learning (Parikh, Kamalapurkar and Dixon, "Integral concurrent learning:
    Adaptive control with parameter convergence using finite excitation", Int. J. Adapt. Control
    Signal Process. 33(12), 2019) on the payload's ten parameters as ``slotine_li`` adapts them:
    ``theta' = Gamma (Y_p^T s + (1 / N) sum_i Ybar_i^T R (Ubar_i - Ybar_i theta))``, the sum over a
    history stack of windows of the dynamics integrated in momentum form (no acceleration:
    :mod:`adaptive_dd.closed_loop.composite`), the stack's data-selection rule recency (a closed
    window replaces the oldest, so that a swapped payload's data leaves the stack). Derived
    settings: the window ``2 / min(lam)`` (:data:`ICL_WINDOW_CYCLES`), ten windows, ``R`` as
    ``composite``'s. Signals: measured ``q, qd``, the applied torque of the samples before,
    ``qdd_d``."""

    name = "icl"

    def law_config(self, sample_period):
        cfg = super().law_config(sample_period)
        return cfg._replace(
            composite=False, adapt_kind=ADAPT_ICL, icl_window=ICL_WINDOW_CYCLES / float(np.min(cfg.lam))
        )


NATURAL_MAX_MASS = 20.0
"""[kg] ``natural_adaptive``'s bound of the adapted mass when the arm states no ``payload_capacity``."""


class NaturalAdaptive(Law):
    """The natural adaptive law (Lee, Kwon and Park, "A Natural Adaptive Control Law for Robot
    Manipulators", IROS 2018) on Slotine-Li's structure: the inertial parameters ``phi`` of the
    link that carries the payload (link and payload about its joint frame, as the authors' code
    adapts the last link) move along the natural gradient of the log-det divergence of their
    pseudo-inertia, ``J(phi)' = gamma J G J`` with ``G`` the 4x4 form of ``Y_j^T s``
    (:func:`~adaptive_dd.closed_loop.adaptation.natural_step`), stepped so that ``J`` stays
    positive definite: the estimate is physically consistent at every sample, with no box. The
    one gain is derived: ``gamma = gamma_m / (m_j + m_cap / 2)^2``, ``gamma_m`` ``slotine_li``'s
    mass gain, ``m_j`` the nominal link's mass, ``m_cap`` the arm's ``payload_capacity`` (else
    ``max_mass``): with half the rated payload the mass adapts as fast as ``slotine_li``'s, slower
    below and faster above (the natural gradient scales a parameter's rate with its square).
    ``max_mass`` also bounds the mass added. Signals: measured ``q, qd``; the reference with ``qdd_d``."""

    name = "natural_adaptive"
    floor = "slotine_li_oracle"
    SETTINGS = frozenset({"gain", "max_mass"})

    def __init__(self, arm, bandwidth=40.0, damping: float = 1.0, **settings) -> None:
        super().__init__(arm, bandwidth, damping, **settings)
        where = f"controllers.{self.name}"
        cap = getattr(arm, "payload_capacity", None)
        self.max_mass = self.settings.get("max_mass", cap if cap is not None else NATURAL_MAX_MASS)
        if not (_is_number(self.max_mass) and self.max_mass > 0):
            raise ParameterError(f"{where}.max_mass: a number > 0 [kg], got {self.max_mass!r}")
        self.gain = self.settings.get("gain", self._gain(DEFAULT_PAYLOAD_GAMMA[0]))
        if not (_is_number(self.gain) and self.gain > 0):
            raise ParameterError(f"{where}.gain: a number > 0, got {self.gain!r}")

    def _gain(self, mass_gain: float) -> float:
        m_j = float(self.arm.pi[10 * int(self.arm.payload_joint)])
        return mass_gain / (m_j + 0.5 * float(self.max_mass)) ** 2

    def state_task(self, scenario) -> None:
        """Unless ``gain`` is given, the mass gain ``gamma_m`` of ``slotine_li``'s gains derived for
        ``scenario`` (:func:`~adaptive_dd.closed_loop.adaptation_gain.payload_gains`)."""
        if "gain" not in self.settings:
            lam, k = self.gains.roots()
            self.gain = self._gain(float(payload_gains(self.arm, scenario, k, lam)[0]))

    def law_config(self, sample_period):
        lam, k = self.gains.roots()
        hi = np.full(10, np.inf)
        hi[0] = float(self.max_mass)
        return self._config(
            sample_period, KIND_SLOTINE, MODEL_TRIAL, lam=lam, kd=k, adapt=True,
            adapt_kind=ADAPT_NATURAL, nat_gain=float(self.gain), hi=hi,
        )  # fmt: skip


ARENA_CONTROLLERS: dict[str, type[Law]] = {
    "pd_gravity": PDGravity,
    "pd_gravity_oracle": PDGravityOracle,
    "sliding_mode": SlidingMode,
    "momentum_observer_ct": MomentumObserverCT,
    "composite": Composite,
    "craig_hsu_sastry": CraigHsuSastry,
    "icl": IntegralConcurrentLearning,
    "natural_adaptive": NaturalAdaptive,
}
"""The arena's N-joint built-ins, name -> class."""

ARM_LAWS: dict[str, type[Law]] = {**ARM_CONTROLLERS, **ARENA_CONTROLLERS}
"""Every N-joint built-in, name -> class (what :func:`adaptive_dd.controllers.make_controller` builds)."""
