"""What a two-link built-in controller hands the compiled loop: its law and gains as a typed tuple.

Each built-in class owns its form (a ``compiled_spec(sample_period)`` method returning a
:class:`CompiledSpec`); :func:`compiled_spec` asks the controller for it. The compiled loop
(:func:`~adaptive_dd.closed_loop.glue.trial_samples`, with the two-link choices of
:mod:`adaptive_dd.benchmark.compiled`) runs the law ``TwoLinkGains.law`` names with those
gains through :func:`command_trial`, the one dispatch on the law, kept here beside the codes
and the gains (a new law: its class, and here its code, gains and branch). A controller
without the method (a plug-in), or of a subclass that does not define it itself (its Python
form may differ), runs on the Python path.

Why a branch here and not a law function that each class hands over: numba compiles a
function that takes another jitted function (or a gains tuple of a type of its own) once per
such argument, so the whole sample loop (``trial_samples``; its compile time is printed by
``benchmarks/two_link_compile_time.py``) would be compiled once per law; a first-class function
type (a pointer) is never inlined into the sample loop, and numba's caching of functions that
take one is an open problem (numba issues 9237, 10280).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from adaptive_dd.controllers.laws import boost_within_trial, ct_trial, pd_trial, slotine_li_trial

__all__ = [
    "LAW_ADAPTIVE",
    "LAW_CT",
    "LAW_CT_ORACLE",
    "LAW_PD",
    "LAW_SLOTINE",
    "LAW_SLOTINE_ORACLE",
    "CompiledSpec",
    "TwoLinkGains",
    "boost_command",
    "command_trial",
    "compiled_spec",
    "two_link_gains",
]

Array = NDArray[np.float64]

LAW_PD, LAW_CT, LAW_CT_ORACLE, LAW_ADAPTIVE, LAW_SLOTINE, LAW_SLOTINE_ORACLE = 0, 1, 2, 3, 4, 5


class TwoLinkGains(NamedTuple):
    """A two-link built-in law and its gains (the fields a law does not use are zero).

    Attributes
    ----------
    law : int
        ``LAW_*``: PD, computed torque on the fixed / true / estimated model (the last is
        ``adaptive_ct``), Slotine-Li adapting / on the true model.
    kp, kd, lam : float
        Computed-torque gains [1/s^2], [1/s], and the reference filter's ``lam`` [1/s]
        (< 0: the textbook law); Slotine-Li: ``kd`` and ``lam``.
    pd_kp, pd_kd : ndarray (2,)
        PD gains per joint [N m/rad], [N m s/rad].
    boost_kp, boost_kd : float
        Feedback added during a boost after an alarm (``adaptive_ct``), through M0(q).
    boost_samples : float
        Samples a boost lasts after an alarm (0: no boost).
    boost_lim : ndarray (2,)
        The arm's torque limits [N m] the boost keeps the command within (inf: none;
        :func:`~adaptive_dd.controllers.laws.boost_within_trial`).
    sigma : ndarray (7,)
        The fixed model (computed torque), the nominal one (``adaptive_ct``: start and boost),
        the start of the estimate and the model of M0 (Slotine-Li).
    gamma, lo, hi : ndarray (7,)
        Slotine-Li's adaptation gains and box.
    projection : ndarray (3,)
        Slotine-Li's projection constants (:data:`~adaptive_dd.controllers.slotine_li.PROJECTION`).
    observer : bool
        ``adaptive_ct`` adds its residual observer's torque
        (:mod:`~adaptive_dd.controllers.two_link_observer`); the fields below are its settings,
        named as :class:`~adaptive_dd.closed_loop.laws.LawConfig`'s (the observer reads them there).
    T : float
        Sample period [s].
    obs_a, obs_stages, obs_kappa, obs_alpha, obs_warmup : float, int, float, float, int
        ``exp(-beta T)``; stages; soft threshold in RMS levels; a sample's weight in the level;
        updates before the observer feeds the command.
    model_delay : int
        Samples after each swap before an oracle's true model switches (``ct_oracle_late``; 0).
    """

    law: int
    kp: float
    kd: float
    lam: float
    pd_kp: Array
    pd_kd: Array
    boost_kp: float
    boost_kd: float
    boost_samples: float
    boost_lim: Array
    sigma: Array
    gamma: Array
    lo: Array
    hi: Array
    projection: Array
    observer: bool
    T: float
    obs_a: float
    obs_stages: int
    obs_kappa: float
    obs_alpha: float
    obs_warmup: int
    model_delay: int


class CompiledSpec(NamedTuple):
    """What the compiled loop needs of a controller: its law and gains, its estimator
    (an :class:`~adaptive_dd.identification.two_link_online_config.TwoLinkOnlineConfig` at the run's
    sample period, or None)."""

    gains: TwoLinkGains
    online: object

    @property
    def law(self) -> int:
        return self.gains.law

    @property
    def sigma(self) -> Array:
        return self.gains.sigma


def two_link_gains(law: int, sigma=None, **gains) -> TwoLinkGains:
    """``TwoLinkGains`` of ``law`` with the model ``sigma (7,)`` and the named ``gains``; the rest zero."""
    z2, z7 = np.zeros(2), np.zeros(7)
    fields = dict(
        law=law, kp=0.0, kd=0.0, lam=0.0, pd_kp=z2, pd_kd=z2, boost_kp=0.0, boost_kd=0.0,
        boost_samples=0.0, boost_lim=np.full(2, np.inf),
        sigma=z7 if sigma is None else np.array(sigma, dtype=float),
        gamma=z7, lo=z7, hi=z7, projection=np.zeros(3), observer=False, T=0.0, obs_a=0.0, obs_stages=2,
        obs_kappa=0.0, obs_alpha=0.0, obs_warmup=0, model_delay=0,
    )  # fmt: skip
    fields.update(gains)
    return TwoLinkGains(**fields)


def compiled_spec(ctrl, sample_period: float) -> CompiledSpec | None:
    """``ctrl.compiled_spec(sample_period)`` if ``ctrl``'s own class defines it, else None (run
    it on the Python path: a plug-in, or a subclass of a built-in whose Python form may differ)."""
    if "compiled_spec" not in vars(type(ctrl)):
        return None
    return ctrl.compiled_spec(sample_period)


@njit(cache=True, inline="always")
def command_trial(g, T, sg_true, sg_model, since_alarm, q, qd, q_d, qd_d, qdd_d, out):  # pragma: no cover
    """One trial's command of law ``g.law`` into ``out (2,)`` [N m] (the compiled loop's only
    dispatch on the law, inlined into its sample loop).

    ``T`` sample period [s]; ``sg_true (7,)`` the true base parameters over the sample (oracles);
    ``sg_model (7,)`` the trial's estimate (``adaptive_ct``: the estimator's model; Slotine-Li:
    its ``theta``, adapted in place); ``since_alarm`` samples since the detector's last alarm
    (unused here: ``adaptive_ct``'s boost is :func:`boost_command`, added after its residual
    observer's torque); ``q, qd (2,)`` measured; ``q_d, qd_d, qdd_d (2,)`` the reference.
    A new law is a ``LAW_*`` code, its gains in :class:`TwoLinkGains` and its branch here.
    """
    law = g.law
    if law == LAW_SLOTINE:
        slotine_li_trial(
            q, qd, q_d, qd_d, qdd_d, sg_model, g.sigma, g.lam, g.kd, T, g.gamma, g.lo, g.hi, g.projection, out
        )  # fmt: skip
    elif law == LAW_SLOTINE_ORACLE:
        th = sg_true.copy()
        slotine_li_trial(
            q, qd, q_d, qd_d, qdd_d, th, g.sigma, g.lam, g.kd, T, g.gamma[0:0], g.lo, g.hi, g.projection, out
        )  # fmt: skip
    elif law == LAW_PD:
        pd_trial(q, qd, q_d, qd_d, g.pd_kp, g.pd_kd, out)
    elif law == LAW_CT:
        ct_trial(q, qd, q_d, qd_d, qdd_d, g.sigma, g.kp, g.kd, g.lam, out)
    elif law == LAW_CT_ORACLE:
        ct_trial(q, qd, q_d, qd_d, qdd_d, sg_true, g.kp, g.kd, g.lam, out)
    else:
        ct_trial(q, qd, q_d, qd_d, qdd_d, sg_model, g.kp, g.kd, g.lam, out)


@njit(cache=True, inline="always")
def boost_command(g, since_alarm, q, qd, q_d, qd_d, out):  # pragma: no cover - compiled
    """``adaptive_ct``'s boost for ``boost_samples`` after an alarm, added to its whole command
    ``out (2,)`` (computed torque and the residual observer's torque) within ``g.boost_lim``."""
    if g.law == LAW_ADAPTIVE and g.boost_samples > 0 and since_alarm < g.boost_samples:
        boost_within_trial(q, qd, q_d, qd_d, g.sigma, g.boost_kp, g.boost_kd, g.kp, g.kd, g.boost_lim, out)
