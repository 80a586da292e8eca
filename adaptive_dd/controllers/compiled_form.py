"""What a two-link built-in controller hands the compiled loop: its law and gains as a typed tuple.

Each built-in class owns its form (a ``compiled_spec(sample_period)`` method returning a
:class:`CompiledSpec`); :func:`compiled_spec` asks the controller for it. The compiled loop
(:mod:`adaptive_dd.benchmark.compiled`) runs the law ``TwoLinkGains.law`` names with those
gains. A controller without the method (a plug-in), or of a subclass that does not define it
itself (its Python form may differ), runs on the Python path.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "LAW_ADAPTIVE",
    "LAW_CT",
    "LAW_CT_ORACLE",
    "LAW_PD",
    "LAW_SLOTINE",
    "LAW_SLOTINE_ORACLE",
    "CompiledSpec",
    "TwoLinkGains",
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
    sigma : ndarray (7,)
        The fixed model (computed torque), the nominal one (``adaptive_ct``: start and boost),
        the start of the estimate and the model of M0 (Slotine-Li).
    gamma, lo, hi : ndarray (7,)
        Slotine-Li's adaptation gains and box.
    projection : ndarray (3,)
        Slotine-Li's projection constants (:data:`~adaptive_dd.controllers.slotine_li.PROJECTION`).
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
    sigma: Array
    gamma: Array
    lo: Array
    hi: Array
    projection: Array


class CompiledSpec(NamedTuple):
    """What the compiled loop needs of a controller: its law and gains, its estimator
    (an :class:`~adaptive_dd.identification.online.OnlineConfig` at the run's sample period, or None)."""

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
        boost_samples=0.0, sigma=z7 if sigma is None else np.array(sigma, dtype=float),
        gamma=z7, lo=z7, hi=z7, projection=np.zeros(3),
    )  # fmt: skip
    fields.update(gains)
    return TwoLinkGains(**fields)


def compiled_spec(ctrl, sample_period: float) -> CompiledSpec | None:
    """``ctrl.compiled_spec(sample_period)`` if ``ctrl``'s own class defines it, else None (run
    it on the Python path: a plug-in, or a subclass of a built-in whose Python form may differ)."""
    if "compiled_spec" not in vars(type(ctrl)):
        return None
    return ctrl.compiled_spec(sample_period)
