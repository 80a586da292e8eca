"""Directions of the base parameters a record cannot see, held at their prior.

A base parameter set found by QR at a tight tolerance is exact for the URDF, but a record may
still carry almost nothing about some combinations of it: the Kinova Gen3's URDF writes its
right angles rounded (``3.1416``, ``1.5708``), which leaves three base parameters (``mx1``,
``my1``'s group, ``Ia2``) whose columns are 3e-6 of the largest, seen only through the rounding.
Weighted least squares estimates them anyway (``Ia2`` = 1672 +- 2200 kg m^2 on a 20 s designed
record, the plant's 0.16), and the physically consistent fit, pulled by those values, moved
well-known groups far off (docs/any_arm.md, the Gen3's section).

The rule (:func:`hold_unseen`). Each base parameter has a prior: the URDF's value with the
standard deviation the stated uncertainty implies (:func:`base_prior_std`: ``diag(B C B^T)`` of
:func:`~adaptive_dd.identification.arm_prior.prior_covariance`, the scenario's
``[plant.uncertainty]`` levels or issue 28's defaults). In the prior's units (each parameter
divided by its prior std) the estimate's covariance ``cov`` (the Newey-West sandwich of
:func:`~adaptive_dd.identification.log_fit.fit_log`) has eigenvectors along which the estimate's
errors are uncorrelated; along each, the ratio ``r`` of the estimate's variance to the prior's is
the inverse of the record's information relative to the prior's. A direction with ``r >``
:data:`HOLD_RATIO` (= 1: the record's estimate would be further from the truth, in expectation,
than the URDF's value) is held at the prior: the estimate's component along it is replaced by
the URDF's, and its variance by the prior's. Since the components are uncorrelated, the others
need no re-estimation: the result is the least squares estimate constrained to the prior along
the held directions.

The Cramér-Rao bound of a held direction is not a bound on an estimate (there is none): the
reports print ``held`` and the prior's standard deviation instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError

__all__ = [
    "HOLD_RATIO",
    "Held",
    "base_prior_std",
    "hold_unseen",
    "prior_conflict",
    "prior_scale",
    "stated_levels",
    "unit_class",
]

Array = NDArray[np.float64]
HOLD_RATIO = 1.0
"""A direction is held when the estimate's variance along it exceeds this many times the prior's."""
SEEN_RATIO = 0.1
"""Directions whose estimate's variance is below this fraction of the prior's are those the record
sees well: the URDF's distance from the estimate there checks the prior's scale (:func:`prior_scale`)."""
MIN_SEEN = 3
PRIOR_CONFLICT_P = 1e-3
"""The prior is contradicted by the record (:func:`prior_conflict`) when the URDF's distance from
the estimate along the well-seen directions is this improbable under the stated uncertainty."""
"""At least this many well-seen directions for :func:`prior_scale` to widen the prior."""
NO_PRIOR = 1e6
"""A parameter without a prior (its class has no stated uncertainty: friction a URDF leaves at 0)
takes this many times its estimate's std as its prior's: never held."""


def unit_class(name: str) -> str:
    """The unit of a base parameter from its name's first term: ``kg`` (``m3``), ``kg m``
    (``mx1``), ``kg m^2`` (``Ixx2``, ``Ia2``), ``N m s`` (``fv1``), ``N m`` (``fc1``)."""
    head = name.split()[0]
    if head.startswith("fv"):
        return "N m s"
    if head.startswith("fc"):
        return "N m"
    if head.startswith("I"):
        return "kg m^2"
    if head[:2] in ("mx", "my", "mz"):
        return "kg m"
    return "kg"


def base_prior_std(model, levels=None) -> Array:
    """``(p,)`` The prior standard deviation of each base parameter about the URDF's value: the
    square root of ``diag(B C B^T)``, ``C`` the standard parameters' covariance under the stated
    uncertainty ``levels`` (:class:`~adaptive_dd.identification.arm_prior.ArmUncertainty`; its
    defaults when None). Parameters the levels leave at zero (a product of inertia, which the
    stated uncertainty scales with the whole tensor; friction or armature the URDF gives as 0)
    take the median of the non-zero ones of their unit (:func:`unit_class`), or none (``inf``)
    when their unit has none."""
    from types import SimpleNamespace

    from adaptive_dd.identification.arm_prior import ArmUncertainty, prior_covariance

    n = model.n
    pi = np.asarray(model.pi_ref, dtype=float)
    arm = SimpleNamespace(
        n_joints=n,
        pi_links=pi[: 10 * n],
        viscous=pi[10 * n : 11 * n],
        coulomb=pi[11 * n : 12 * n],
        armature=pi[12 * n :],
    )
    C = prior_covariance(arm, levels if levels is not None else ArmUncertainty())
    B = np.asarray(model.B, dtype=float)
    std = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", B, C, B), 0.0))
    units = np.array([unit_class(nm) for nm in model.names])
    out = std.copy()
    for u in set(units):
        k = units == u
        tiny = std[k] <= 1e-9 * max(std.max(), 1e-300)
        floor = np.median(std[k][~tiny]) if (~tiny).any() else np.inf
        out[np.flatnonzero(k)[tiny]] = floor
    return out


def stated_levels(uncertainty):
    """The :class:`~adaptive_dd.identification.arm_prior.ArmUncertainty` of a scenario's
    ``[plant.uncertainty]`` (a :class:`~adaptive_dd.plant.uncertainty.Uncertainty`; a normal draw's
    levels times ``sqrt(3)``, the uniform levels of the same variance), or issue 28's defaults
    when the scenario states none (None)."""
    from adaptive_dd.identification.arm_prior import _FIELDS, ArmUncertainty

    if uncertainty is None:
        return ArmUncertainty()
    scale = np.sqrt(3.0) if uncertainty.distribution == "normal" else 1.0
    return ArmUncertainty(**{k: min(float(getattr(uncertainty, k)) * scale, 0.99) for k in _FIELDS})


@dataclass(frozen=True)
class Held:
    """What :func:`hold_unseen` held.

    Attributes
    ----------
    prior_std : ndarray (p,)
        The prior's standard deviation of each base parameter (``inf``: none).
    directions : ndarray (h, p)
        Each held direction, in the prior's units (unit vectors: the weight of parameter ``k`` is
        ``directions[i, k] ** 2``).
    ratio : ndarray (h,)
        The estimate's variance along each over the prior's (above :data:`HOLD_RATIO`).
    projector : ndarray (p, p)
        ``sigma = ref + projector (estimate - ref)``: the estimate with the held components at the prior.
    share : ndarray (p,)
        The part of each parameter's variance (after holding) that is the prior's along the held
        directions, in [0, 1].
    scale2 : float
        ``kappa^2``, the prior's variance over the stated one (:func:`prior_scale`; 1: as stated).
    """

    prior_std: Array
    directions: Array
    ratio: Array
    projector: Array
    share: Array
    scale2: float = 1.0
    conflict: bool = False
    """The record contradicts the prior (:func:`prior_conflict`): nothing held, every direction estimated."""

    @property
    def count(self) -> int:
        """The number of held directions."""
        return int(self.ratio.size)

    def apply(self, estimate: Array, ref: Array) -> Array:
        """Another estimate ``(p,)`` of the same record held along the same directions."""
        ref = np.asarray(ref, dtype=float)
        return ref + self.projector @ (np.asarray(estimate, dtype=float) - ref)

    def describe(self, names, short=str) -> list[str]:
        """One line per held direction: its main base parameters with their weights, and the ratio."""
        lines = []
        for v, r in zip(self.directions, self.ratio, strict=True):
            order = np.argsort(-(v**2))
            top = [k for k in order[:3] if v[k] ** 2 >= 0.05] or [int(order[0])]
            what = " + ".join(f"{short(names[k])} ({100 * v[k] ** 2:.0f} %)" for k in top)
            lines.append(f"{what}: the record's std {np.sqrt(r):.3g}x the prior's")
        return lines


def hold_unseen(sigma, cov, ref, prior_std, identified=None) -> tuple[Array, Array, Held]:
    """The estimate ``sigma (p,)`` and its covariance ``cov (p, p)`` with the directions the record
    cannot see held at the prior ``ref (p,)`` (the URDF's values) of standard deviations
    ``prior_std (p,)`` (module docstring). Only the ``identified`` parameters (default all) take
    part; the others keep their values and covariance.

    The prior's scale is checked on the record first: where the URDF is further from the estimate
    along the directions the record sees well than the stated uncertainty allows, the prior is
    widened to match (:func:`prior_scale`), so a URDF far from a real robot is held less.

    Returns
    -------
    sigma, cov : ndarray (p,), (p, p)
        Held: along the held directions the prior's value and variance.
    held : Held

    Raises
    ------
    ParameterError
        Shapes disagree, or the values are not finite.
    """
    x, C, r0 = (np.asarray(a, dtype=float) for a in (sigma, cov, ref))
    p = x.shape[0]
    s0 = np.asarray(prior_std, dtype=float)
    K = np.ones(p, dtype=bool) if identified is None else np.asarray(identified, dtype=bool)
    if C.shape != (p, p) or r0.shape != (p,) or s0.shape != (p,) or K.shape != (p,):
        raise ParameterError(
            f"hold_unseen: need {p} values, a ({p}, {p}) covariance, {p} prior values and stds; got "
            f"{C.shape}, {r0.shape}, {s0.shape}, {K.shape}"
        )
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(C)) and np.all(np.isfinite(r0))):
        raise ParameterError("hold_unseen: the estimate, its covariance or the prior is not finite")
    Ck = 0.5 * (C[np.ix_(K, K)] + C[np.ix_(K, K)].T)
    data_std = np.sqrt(np.abs(np.diag(Ck)))
    sk = np.where(np.isfinite(s0[K]) & (s0[K] > 0), s0[K], NO_PRIOR * data_std + 1e-300)
    Z = Ck / np.outer(sk, sk)
    mu, V = np.linalg.eigh(Z)
    z = V.T @ ((x[K] - r0[K]) / sk)
    kappa2 = prior_scale(mu, z)
    if prior_conflict(mu, z):  # the URDF is not within the stated uncertainty: no prior to hold at
        none = np.zeros((0, p))
        return x.copy(), C.copy(), Held(s0.copy(), none, np.zeros(0), np.eye(p), np.zeros(p), kappa2, True)
    hold = mu > HOLD_RATIO * kappa2
    Vk, Vh = V[:, ~hold], V[:, hold] * np.sqrt(kappa2)
    Pk = (sk[:, None] * (Vk @ Vk.T)) / sk[None, :]
    proj = np.eye(p)
    proj[np.ix_(K, K)] = Pk
    kept = Pk @ Ck @ Pk.T
    prior = (sk[:, None] * Vh) @ (sk[:, None] * Vh).T
    out_cov = C.copy()
    out_cov[np.ix_(K, K)] = kept + prior
    out = r0 + proj @ (x - r0)
    out[~K] = x[~K]
    share = np.zeros(p)
    share[K] = np.diag(prior) / np.maximum(np.diag(kept + prior), 1e-300)
    dirs = np.zeros((int(hold.sum()), p))
    dirs[:, K] = Vh.T
    order = np.argsort(-mu[hold])
    held = Held(s0.copy(), dirs[order] / np.sqrt(kappa2), mu[hold][order] / kappa2, proj, share, kappa2)
    return out, out_cov, held


def prior_conflict(mu: Array, z: Array) -> bool:
    """Whether the record contradicts the prior: along the directions it sees well (``mu <``
    :data:`SEEN_RATIO`, at least :data:`MIN_SEEN` of them) the URDF's distance from the estimate,
    ``sum z^2 / (1 + mu)``, is above the chi-square quantile of :data:`PRIOR_CONFLICT_P` (a robot
    drawn from the stated uncertainty crosses it once in a thousand records). Then the stated
    uncertainty says nothing of where the robot is along the directions the record cannot see,
    and holding them there made things worse: on the TIAGo's real log (the URDF about 12 times
    further than issue 28's levels) the held-out prediction 3 % worse and the reported std of the
    estimated parameters 7-9 times below their spread over disjoint windows
    (``benchmarks/real_log.py``)."""
    from scipy.stats import chi2

    seen = mu < SEEN_RATIO
    if seen.sum() < MIN_SEEN:
        return False
    stat = float(np.sum(z[seen] ** 2 / (1.0 + mu[seen])))
    return stat > float(chi2.isf(PRIOR_CONFLICT_P, int(seen.sum())))


def prior_scale(mu: Array, z: Array) -> float:
    """``kappa^2 >= 1``: how much wider the prior must be than stated for the URDF's distance from
    the record along the directions the record sees well (``mu <`` :data:`SEEN_RATIO`, in the
    prior's units: the estimate's components ``z`` and their variances ``mu``): the mean of
    ``z^2 - mu`` over them (each ``E z^2 = kappa^2 + mu`` when the URDF's error is a draw of the
    prior scaled by ``kappa``), 1 with fewer than :data:`MIN_SEEN` such directions. A simulated
    robot drawn from the stated uncertainty gives about 1; the TIAGo's real log about 140 (its URDF
    is about 12 times further from the robot than issue 28's levels say)."""
    seen = mu < SEEN_RATIO
    if seen.sum() < MIN_SEEN:
        return 1.0
    return float(max(1.0, np.mean(z[seen] ** 2 - mu[seen])))
