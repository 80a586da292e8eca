"""Built-in controllers for N-joint arms: one class each, owning its Python and compiled forms.

Each class turns its settings into a :class:`~adaptive_dd.closed_loop.laws.LawConfig` of the
computed-torque family (:meth:`Law.law_config`) and, for ``adaptive_ct``, an estimator.
:meth:`Law.compiled_form` returns what the compiled loop runs (the law, its per-trial
state, the estimator hooks); the Python form (:meth:`reset`, :meth:`command`,
:meth:`observe`, the protocol of ``docs/controllers.md``) runs the same compiled form one
sample at a time for the whole batch, so the two paths agree to rounding.

Adding a built-in: a subclass of :class:`Law` here that says its ``law_config`` (and
settings), an entry in :data:`ARM_CONTROLLERS`, and its row in the one registry
(:data:`adaptive_dd.controllers.CONTROLLERS`: what it knows, its settings and defaults per arm).
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.closed_loop.adaptation_gain import DEFAULT_PAYLOAD_GAMMA, given_gains, payload_gains
from adaptive_dd.closed_loop.batches import estimator_batch, shaped_inputs
from adaptive_dd.closed_loop.laws import (
    KIND_CT,
    KIND_PD,
    KIND_SLOTINE,
    MODEL_FIXED,
    MODEL_NONE,
    MODEL_TRIAL,
    MODEL_TRUE,
    LawConfig,
    LawState,
    actuator_limits,
    law_batch,
)
from adaptive_dd.controllers.base import DEFAULT_MODEL_DELAY, delay_samples, model_delay
from adaptive_dd.errors import ParameterError
from adaptive_dd.errors import is_finite_number as _is_number

__all__ = [
    "ARM_CONTROLLERS",
    "AdaptiveCT",
    "CTNominal",
    "CTOracle",
    "CTOracleLate",
    "CTOracleTextbook",
    "CompiledForm",
    "JointGains",
    "Law",
    "PDControl",
    "SlotineLi",
    "SlotineLiOracle",
    "observer_bandwidth",
    "with_stated_uncertainty",
]

Array = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class JointGains:
    """Per-joint bandwidth ``omega (n,)`` [rad/s] and damping ``zeta``.

    Computed torque: ``kp = omega^2``, ``kd = 2 zeta omega``, ``lam`` the smaller root of
    ``x^2 - 2 zeta omega x + omega^2``; Slotine-Li: ``lam`` and ``k`` the two roots (the poles
    of computed torque with a perfect model).
    """

    bandwidth: Array
    damping: float

    @classmethod
    def of(cls, bandwidth, damping: float, n: int) -> JointGains:
        w = np.broadcast_to(np.asarray(bandwidth, dtype=float), (n,)).copy()
        if not (np.all(np.isfinite(w)) and np.all(w > 0)):
            raise ParameterError(f"bandwidth must be > 0 rad/s per joint ({n}), got {bandwidth!r}")
        if not (np.isfinite(damping) and damping > 0):
            raise ParameterError(f"damping must be > 0, got {damping!r}")
        return cls(w, float(damping))

    @property
    def kp(self) -> Array:
        return self.bandwidth**2

    @property
    def kd(self) -> Array:
        return 2.0 * self.damping * self.bandwidth

    def roots(self) -> tuple[Array, Array]:
        """``(lam, k)``: smaller and larger root of ``x^2 - 2 zeta omega x + omega^2``."""
        w, z = self.bandwidth, max(self.damping, 1.0)
        r = w * np.sqrt(z * z - 1.0)
        return w * z - r, w * z + r


class CompiledForm(NamedTuple):
    """What the compiled loop runs for one controller: the law, its per-trial state, the
    estimator's records ``ec, es`` (two arrays when it has none:
    :func:`~adaptive_dd.closed_loop.choices.estimator_sample` is chosen by their type) and whether
    the trial's model is an estimate to record (``estimates``)."""

    cfg: LawConfig
    state: LawState
    ec: Any
    es: Any
    estimates: bool


_NO_EST = (np.zeros(1), np.zeros(1))


class Law:
    """Base of the built-ins: settings, gains, the arm's nominal model, both forms.

    Parameters
    ----------
    arm : Arm
    bandwidth : float or sequence of n floats
        [rad/s].
    damping : float
    **settings
        The controller's own settings (:attr:`SETTINGS`); others are an error.
    """

    name = "arm_law"
    floor: str | None = "ct_oracle"
    needs_true_model = False
    SETTINGS: frozenset = frozenset()

    def __init__(self, arm, bandwidth=40.0, damping: float = 1.0, **settings) -> None:
        bad = sorted(set(settings) - set(self.SETTINGS))
        if bad:
            raise ParameterError(
                f"controllers.{self.name}: unknown setting(s) {bad}; allowed: {sorted(self.SETTINGS)}"
            )
        self.arm, self.settings = arm, settings
        self.gains = JointGains.of(bandwidth, damping, arm.n_joints)
        self.ch = arm.chain
        self.pi_nominal = np.ascontiguousarray(arm.pi, dtype=float)
        self._B = np.ascontiguousarray(arm.base.B, dtype=float)
        self._form: CompiledForm | None = None

    # ------------------------------------------------------------------ compiled form
    def law_config(self, sample_period: float) -> LawConfig:
        """The typed configuration of this law (subclasses say which)."""
        raise NotImplementedError

    def _config(self, T: float, kind: int, model: int, **kw) -> LawConfig:
        z = np.zeros(self.arm.n_joints)
        g = self.gains
        base = dict(
            kind=kind, model=model, reference_velocity=True, kp=g.kp, kd=g.kd, lam=g.roots()[0],
            pi_fixed=self.pi_nominal, boost_kp=z, boost_kd=z.copy(), boost_samples=0, boost_ramp=0,
            adapt=False,
            gamma=np.zeros(10), lo=np.full(10, -np.inf), hi=np.full(10, np.inf), com_radius=np.inf,
            payload_joint=int(self.arm.payload_joint), payload_map=np.ascontiguousarray(self.arm.payload_map),
            T=float(T), observer=False, obs_a=0.0, obs_stages=2, obs_kappa=OBSERVER_THRESHOLD,
            obs_alpha=1.0,
            obs_warmup=0,
        )  # fmt: skip
        base.update(kw)
        return LawConfig(**base)

    def compiled_form(self, n_trials: int, sample_period: float) -> CompiledForm:
        """The law, a fresh per-trial state and the estimator hooks for ``n_trials`` trials."""
        cfg = self.law_config(sample_period)
        est = cfg.model == MODEL_TRIAL
        return CompiledForm(cfg, LawState.start(cfg, n_trials), *_NO_EST, est)

    # ------------------------------------------------------------------- Python form
    def reset(self, n_trials: int, sample_period: float) -> None:
        self.n_trials, self.T = int(n_trials), float(sample_period)
        self._form = self.compiled_form(n_trials, sample_period)
        self._alarms: list[list[float]] = [[] for _ in range(n_trials)]
        self._k = 0

    takes_pi_true = True
    """The Python path gives ``pi_true`` (each trial's plant) as well as ``sigma_true``."""

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None, pi_true=None) -> Array:
        """Torque command ``(n_trials, n)`` [N m] from measured ``q, qd (n_trials, n)``; an oracle
        uses ``pi_true (n_trials, 13 n)`` if given, else the payload explaining ``sigma_true``."""
        f = self._form
        if f.cfg.model != MODEL_TRUE:
            pi_true = None
        elif pi_true is not None:
            pi_true = np.ascontiguousarray(pi_true, dtype=float)
        else:
            if sigma_true is None:
                raise ValueError(f"{self.name} needs the true model at every sample")
            pi_true = self.pi_from_sigma(sigma_true)
        q, qd, q_d, qd_d, qdd_d = shaped_inputs(self.arm.n_joints, self.n_trials, q, qd, q_d, qd_d, qdd_d)
        return law_batch(self.ch, f.cfg, f.state, q, qd, q_d, qd_d, qdd_d, pi_true)

    def observe(self, q, qd, tau) -> None:
        f = self._form
        alarm = estimator_batch(f.ec, f.es, f.state, q, qd, tau)
        for i in np.flatnonzero(alarm == 1):
            self._alarms[i].append(self._k * self.T)
        self._k += 1

    @property
    def sigma_hat(self) -> Array | None:
        """The trials' models in base parameters ``(n_trials, p)`` (controllers with an estimate)."""
        if self._form is None or not self._form.estimates:
            return None
        return self._form.state.pi_model @ self._B.T

    @property
    def adaptive(self) -> bool:
        return bool(self._form.estimates) if self._form is not None else False

    has_detector = False
    """True for laws whose estimator raises change alarms."""

    @property
    def alarm_times(self) -> list[list[float]] | None:
        return None

    @property
    def skipped_samples(self):
        """Per trial, samples its estimator skipped as non-finite (None without an estimator)."""
        return None if self._form is None else self.skipped(self._form)

    def skipped(self, form: CompiledForm):
        """Samples skipped by the estimator of ``form``, per trial (None without an estimator)."""
        return None

    def pi_from_sigma(self, sigma) -> Array:
        """Standard parameters ``(S, 13 n)`` giving the torques of base parameters ``sigma (S, p)``:
        the nominal model plus the payload that explains ``sigma - sigma_nominal``."""
        arm = self.arm
        d = np.asarray(sigma, dtype=float) - arm.sigma
        pp = d @ np.linalg.pinv(arm.payload_basis, rcond=1e-9).T
        j = arm.payload_joint
        pi = np.broadcast_to(self.pi_nominal, (d.shape[0], self.pi_nominal.size)).copy()
        pi[:, 10 * j : 10 * j + 10] += pp @ arm.payload_map.T
        return pi


class PDControl(Law):
    """``tau = Kp e + Kd e'`` with ``Kp = omega^2 M0``, ``Kd = 2 zeta omega M0`` (M0: the diagonal of
    the nominal inertia at the middle of the joint ranges); no model, no gravity compensation."""

    name = "pd"

    def law_config(self, sample_period):
        m0 = self.arm.nominal_inertia()
        return self._config(sample_period, KIND_PD, MODEL_NONE, kp=self.gains.kp * m0, kd=self.gains.kd * m0)


class CTNominal(Law):
    """Computed torque (reference velocity) with the arm's model without payload."""

    name = "ct_nominal"

    def law_config(self, sample_period):
        return self._config(sample_period, KIND_CT, MODEL_FIXED)


class CTOracle(Law):
    """Computed torque with the true model at every sample; Coriolis and friction at the reference
    velocity ``qd_d + lam e`` (the floor of ``adaptive_ct``)."""

    name = "ct_oracle"
    floor = None
    needs_true_model = True

    def law_config(self, sample_period):
        return self._config(sample_period, KIND_CT, MODEL_TRUE)


class CTOracleLate(CTOracle):
    """:class:`CTOracle` told of each swap ``delay`` [s] late: its true model switches that long
    after the swap (the floor of a law that knows each payload that late; measured against
    ``ct_oracle``)."""

    name = "ct_oracle_late"
    floor = "ct_oracle"
    SETTINGS = frozenset({"delay"})

    def __init__(self, arm, bandwidth=40.0, damping: float = 1.0, **settings) -> None:
        super().__init__(arm, bandwidth, damping, **settings)
        self.model_delay = model_delay(self.settings.get("delay", DEFAULT_MODEL_DELAY), self.name)

    def law_config(self, sample_period):
        late = delay_samples(self.model_delay, sample_period, self.name)
        return self._config(sample_period, KIND_CT, MODEL_TRUE, model_delay=late)


class CTOracleTextbook(CTOracle):
    """The textbook computed torque with the true model: Coriolis and friction at the measured ``qd``."""

    name = "ct_oracle_textbook"

    def law_config(self, sample_period):
        return self._config(sample_period, KIND_CT, MODEL_TRUE, reference_velocity=False)


class SlotineLiOracle(Law):
    """Slotine-Li with the true model and no adaptation (the floor of ``slotine_li``)."""

    name = "slotine_li_oracle"
    floor = None
    needs_true_model = True

    def law_config(self, sample_period):
        lam, k = self.gains.roots()
        return self._config(sample_period, KIND_SLOTINE, MODEL_TRUE, lam=lam, kd=k)


class SlotineLi(Law):
    """Slotine-Li adapting the payload's ten parameters from the nominal arm (gradient law on the
    link's Slotine-Li regressor times the payload map), projected on a box
    (``max_mass`` [kg], ``com_radius`` [m]) with ``m >= 0`` and ``|c| <= com_radius``."""

    name = "slotine_li"
    floor = "slotine_li_oracle"
    SETTINGS = frozenset({"gamma", "max_mass", "com_radius"})

    def __init__(self, arm, bandwidth=40.0, damping: float = 1.0, **settings) -> None:
        super().__init__(arm, bandwidth, damping, **settings)
        where = f"controllers.{self.name}"
        self.gamma = given_gains(where, self.settings.get("gamma", DEFAULT_PAYLOAD_GAMMA))
        for key, default in (("max_mass", 20.0), ("com_radius", 0.3)):
            v = self.settings.get(key, default)
            if not (_is_number(v) and v > 0):
                raise ParameterError(f"{where}.{key}: a number > 0, got {v!r}")
        self.max_mass = float(self.settings.get("max_mass", 20.0))
        self.com_radius = float(self.settings.get("com_radius", 0.3))

    def state_task(self, scenario) -> None:
        """Unless ``gamma`` is given, the adaptation gains derived from the arm and ``scenario``'s
        reference (:func:`~adaptive_dd.closed_loop.adaptation_gain.payload_gains`: each parameter
        adapted at the same rate, the fastest mode at half the feedback's ``lambda``); without a
        task, :data:`DEFAULT_PAYLOAD_GAMMA`."""
        if "gamma" in self.settings:
            return
        lam, k = self.gains.roots()
        self.gamma = payload_gains(self.arm, scenario, k, lam)

    def law_config(self, sample_period):
        lam, k = self.gains.roots()
        m_max, r, gamma = self.max_mass, self.com_radius, self.gamma
        i_max = m_max * r * r * 2.0
        hi = np.array([m_max, *(m_max * r,) * 3, i_max, i_max / 2, i_max, i_max / 2, i_max / 2, i_max])
        lo = np.array([0.0, *(-m_max * r,) * 3, 0.0, -i_max / 2, 0.0, -i_max / 2, -i_max / 2, 0.0])
        return self._config(
            sample_period, KIND_SLOTINE, MODEL_TRIAL, lam=lam, kd=k, adapt=True, gamma=gamma, lo=lo, hi=hi,
            com_radius=r,
        )  # fmt: skip


def _estimator_table(name: str, settings: dict) -> dict:
    """The ``estimator`` table with the detector's settings in it: ``detector = {...}`` (or
    ``false``) is taken at the top of ``[controllers.NAME]`` as on the two-link arm, or inside
    ``estimator``; both at once is an error."""
    est = dict(settings.get("estimator", {}))
    if "detector" in settings:
        if "detector" in est:
            raise ParameterError(
                f"controllers.{name}: 'detector' given twice (at the top and in 'estimator'); keep one"
            )
        est["detector"] = settings["detector"]
    return est


OBSERVER_POLE = 0.4
"""The residual observer's bandwidth is ``OBSERVER_POLE / T`` (400 rad/s at 1 kHz): each of its two
stages' pole at ``exp(-0.4)``, half a step passed after about four samples. One constant for every
arm, measured at 0.1 / 0.2 / 0.4 / 0.8 on vertical3 and the iiwa (docs/change_detection.md, "The
residual observer")."""
OBSERVER_THRESHOLD = 3.0
"""The observer's output is soft-thresholded at this many times its own learnt RMS level."""
OBSERVER_LEVEL_WINDOW = 1.0
"""[s] window of the observer's learnt level (the detector's long window)."""
OBSERVER_WARMUP = 0.5
"""[s] the observer learns its level this long before it feeds the command (the detector's warm-up)."""


def observer_bandwidth(sample_period: float) -> float:
    """The residual observer's bandwidth [rad/s] for a sample period [s]: ``0.4 / T``."""
    return OBSERVER_POLE / sample_period


class AdaptiveCT(Law):
    """Computed torque on the N-joint online estimator's projected model
    (:mod:`adaptive_dd.identification.online`), the feedback raised to ``boost_bandwidth``
    (300 rad/s at most; per joint the largest whose noise torque stays inside the torque limit,
    once a scenario states the task, :meth:`state_task`; at each sample scaled down as far as the
    command's limits need: :mod:`~adaptive_dd.closed_loop.boost`) through the nominal inertia for
    ``boost_duration`` (1 s)
    after an alarm, plus the residual observer's torque (``observer``, on by default; bandwidth
    ``observer_bandwidth``, default ``0.4 / T``): the torque the current model leaves
    unexplained, beyond three times its own noise level (:mod:`adaptive_dd.closed_loop.laws`).
    With the observer on, adaptive_ct is no longer only "computed torque given an estimated
    model": it also feeds the measured residual forward until the estimate explains it;
    ``observer = false`` is that law.

    The boost holds the arm while the new payload is learnt: the mass is known within tens of
    ms after an alarm, its centre of mass and inertia over a few hundred. With 0.2 s the UR5
    and Panda scenarios' loaded segments were 1.09-1.16x their floor, with 1 s 1.03-1.07 (20
    seeds); the same boost on the true model (``ct_oracle_textbook`` told 1 ms late) stays at
    1.00-1.01x: high gains alone do not beat the floor, they pass more sensor noise
    (``studies/boost_ablation.py`` of commit d41702f)."""

    name = "adaptive_ct"
    SETTINGS = frozenset(
        {
            "boost_bandwidth",
            "boost_duration",
            "boost_ramp",
            "estimator",
            "detector",
            "observer",
            "observer_bandwidth",
        }
    )
    BOOST_RAMP = 0.25
    """[s] default ``boost_ramp``: after ``boost_duration`` the boost's added bandwidth falls
    linearly to none over this long (0: it ends at once). An abrupt end left a bump in the
    tracking error 1 s after each swap: adaptive_ct / ct_oracle in the window 0.9-2.6 s after
    each swap 1.08-1.14 on the UR5 and 1.11-1.17 on the Panda; ramped over 0.25 s, 0.98-1.03
    and 1.00-1.03 (10 seeds, ``studies/boost_end.py`` of commit d41702f; docs/change_detection.md).
    A longer ramp lowers the ratios further (1 s: 0.87-0.93, below the floor), but only by running gains above
    the oracle's for longer: the ramp is sized to remove the step, not to beat the floor."""
    BOOST_DURATION = 1.0
    """[s] default ``boost_duration``; the two-link ``adaptive_ct`` keeps 0.2 s on purpose (its
    estimator learns the paper's sigma within tens of ms; an N-joint payload's centre of mass
    and inertia take a few hundred: see the class docstring)."""

    def __init__(self, arm, bandwidth=40.0, damping: float = 1.0, **settings) -> None:
        super().__init__(arm, bandwidth, damping, **settings)
        from adaptive_dd.identification import online

        self._est = online
        est = _estimator_table(self.name, self.settings)
        det = est.get("detector", {})
        try:
            if det is False:
                est["detector"] = None
            elif isinstance(det, dict):
                est["detector"] = online.Detector(**det)
            self.online = online.OnlineConfig(**est)
        except TypeError as exc:
            raise ParameterError(f"controllers.{self.name}.estimator: {exc}") from None
        self.boost_bandwidth = float(self.settings.get("boost_bandwidth", 300.0))
        self.boost_duration = float(self.settings.get("boost_duration", self.BOOST_DURATION))
        self.boost_ramp = float(self.settings.get("boost_ramp", self.BOOST_RAMP))
        if not (self.boost_bandwidth > 0 and self.boost_duration >= 0 and self.boost_ramp >= 0):
            raise ParameterError(
                f"controllers.{self.name}: boost_bandwidth > 0, boost_duration >= 0 and boost_ramp >= 0, got "
                f"{self.boost_bandwidth!r}, {self.boost_duration!r}, {self.boost_ramp!r}"
            )
        self.observer, self.observer_bw = _observer_settings(self.name, self.settings)
        self.task: tuple[Array, Array] | None = None

    def state_task(self, scenario) -> None:
        """Take the task from ``scenario``: its postures and torque limits
        (:func:`~adaptive_dd.closed_loop.boost.task_room`), from which with the sensors' noise the
        boost's bandwidth per joint follows (:meth:`boost_bandwidths`), and, unless given, the
        estimator's row weights from a first pass over its reference with the payload capacity
        (:func:`~adaptive_dd.identification.row_weights.task_row_weights`): each row's noise in
        mode "arm", over the largest in payload mode; and, unless given, the change detector's
        level floor from the same pass (:func:`~adaptive_dd.identification.online_config.detector_floor`)."""
        from adaptive_dd.closed_loop.boost import task_room

        self.task = task_room(scenario, self.arm)
        o = self.online
        derive_floor = o.detector is not None and o.detector.floor is None
        if o.row_weights is None or derive_floor:
            from adaptive_dd.identification.online_config import detector_floor
            from adaptive_dd.identification.row_weights import task_row_weights

            # mode "arm" on the noise's scale, payload mode over the largest (row_weights module
            # docstring); the pass is made once and kept with the arm
            if o.row_weights is None:
                rows = task_row_weights(self.arm, o, scenario, relative=o.mode == "payload")
                o = dataclasses.replace(o, row_weights=tuple(float(x) for x in rows))
            if derive_floor:  # at most the heaviest row's own noise [N m] over the threshold
                w = task_row_weights(self.arm, o, scenario)  # sqrt(tau_f / T) x each row's noise
                noise = float(w.max()) / np.sqrt(o.tau_f / float(scenario.sample_period))
                o = dataclasses.replace(
                    o, detector=dataclasses.replace(o.detector, floor=detector_floor(o.detector, noise))
                )
            self.online = o

    def boost_bandwidths(self) -> Array:
        """The boost's bandwidth per joint [rad/s]: ``boost_bandwidth`` on every joint without a
        task; with one, the largest up to it whose noise torque stays inside the torque limit at
        every posture of the reference (:mod:`adaptive_dd.closed_loop.boost`)."""
        w = np.asarray(self.gains.bandwidth, dtype=float)
        if self.task is None:
            return np.maximum(self.boost_bandwidth, w)
        from adaptive_dd.closed_loop.boost import boost_bandwidths

        q, room = self.task
        var_q = np.broadcast_to(self.arm.sensor.position_variance, w.shape)
        var_qd = np.broadcast_to(self.arm.sensor.velocity_variance, w.shape)
        inertia = self.arm.mass_matrix(q)
        return boost_bandwidths(self.boost_bandwidth, w, self.gains.damping, inertia, room, var_q, var_qd)

    def law_config(self, sample_period):
        w, z = self.gains.bandwidth, self.gains.damping
        wb = self.boost_bandwidths()
        T = float(sample_period)
        beta = self.observer_bw if self.observer_bw is not None else observer_bandwidth(T)
        return self._config(
            sample_period, KIND_CT, MODEL_TRIAL, boost_kp=wb**2 - w**2, boost_kd=2.0 * z * (wb - w),
            boost_samples=round(self.boost_duration / sample_period),
            boost_ramp=round(self.boost_ramp / sample_period), observer=self.observer,
            obs_a=float(np.exp(-beta * T)), obs_alpha=min(1.0, T / OBSERVER_LEVEL_WINDOW),
            obs_warmup=round(OBSERVER_WARMUP / T), torque_limit=actuator_limits(self.arm),
        )  # fmt: skip

    def compiled_form(self, n_trials, sample_period):
        cfg = self.law_config(sample_period)
        online = self.online
        if hasattr(online, "sample_period") and online.sample_period != sample_period:
            online = dataclasses.replace(online, sample_period=sample_period)
        ec, es = self._est.est_init(online, self.arm, n_trials)
        state = LawState.start(cfg, n_trials)
        for i in range(n_trials):
            self._est.est_model_trial(ec, es, i, state.pi_model[i])
        return CompiledForm(cfg, state, ec, es, True)

    @property
    def has_detector(self) -> bool:
        return self.online.detector is not None

    @property
    def alarm_times(self):
        return self._alarms if self.has_detector else None

    def skipped(self, form: CompiledForm):
        return self._est.state_skipped(form.es)


def _observer_settings(name: str, settings: dict) -> tuple[bool, float | None]:
    """``observer`` (a boolean, default true) and ``observer_bandwidth`` (a number > 0 [rad/s], or
    absent: derived from the sample period) of ``[controllers.NAME]``; a bad value is an error
    naming the key."""
    on = settings.get("observer", True)
    if not isinstance(on, bool | np.bool_):
        raise ParameterError(
            f"controllers.{name}.observer: true or false (the residual observer fed forward), got {on!r}"
        )
    bw = settings.get("observer_bandwidth")
    if bw is not None and not (_is_number(bw) and bw > 0):
        raise ParameterError(
            f"controllers.{name}.observer_bandwidth: a number > 0 [rad/s] (leave it out for 0.4 / T), "
            f"got {bw!r}"
        )
    return bool(on), None if bw is None else float(bw)


ARM_CONTROLLERS: dict[str, type[Law]] = {
    "pd": PDControl,
    "ct_nominal": CTNominal,
    "ct_oracle": CTOracle,
    "ct_oracle_textbook": CTOracleTextbook,
    "ct_oracle_late": CTOracleLate,
    "adaptive_ct": AdaptiveCT,
    "slotine_li": SlotineLi,
    "slotine_li_oracle": SlotineLiOracle,
}
"""The N-joint form of each built-in, name -> class. Build controllers with
:func:`adaptive_dd.controllers.make_controller` (the one entry point for every arm: its table
:data:`adaptive_dd.controllers.CONTROLLERS` says what each name knows, its settings and defaults
on each arm, and which arms it runs on)."""


def with_stated_uncertainty(name: str, options: dict, scenario) -> dict:
    """``adaptive_ct``'s options with its estimator's ``arm_uncertainty`` the model's stated
    uncertainty (:func:`~adaptive_dd.plant.uncertainty.stated_uncertainty`: ``[model] uncertainty``,
    by default the plant's draw levels) when its own table says neither
    ``arm_uncertainty`` nor ``mode``: an estimator told how far its model may be from the robot
    learns the arm, whatever the plant is (``docs/learning_the_arm.md``). Normal levels (clipped
    at 3) are given the uniform levels of the same variance (``level * sqrt(3)``). Other
    controllers' options, and a model stated exact, are returned as they are, but for
    ``sliding_mode``'s, given the same stated levels as its ``uncertainty`` (the bound of its model
    error) unless its own table gives one."""
    from adaptive_dd.plant.uncertainty import stated_uncertainty

    unc = stated_uncertainty(scenario)
    if name == "sliding_mode" and unc is not None and "uncertainty" not in (options or {}):
        keys = ("mass", "com", "inertia", "viscous", "coulomb", "armature", "distribution")
        return {**(options or {}), "uncertainty": {k: getattr(unc, k) for k in keys if hasattr(unc, k)}}
    est = (options or {}).get("estimator", {})
    if name != "adaptive_ct" or unc is None or not isinstance(est, dict):
        return options
    if {"arm_uncertainty", "mode", "arm_prior_cov"} & est.keys():
        return options
    scale = np.sqrt(3.0) if getattr(unc, "distribution", "uniform") == "normal" else 1.0
    keys = ("mass", "com", "inertia", "viscous", "coulomb", "armature")
    levels = {k: float(getattr(unc, k, 0.0)) * scale for k in keys}
    return {**options, "estimator": {**est, "arm_uncertainty": levels}}
