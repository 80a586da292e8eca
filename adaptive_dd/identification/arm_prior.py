"""How far an arm may be from its URDF: stated uncertainty levels, plants drawn around the
URDF, and the prior covariance of the arm's parameters those levels imply.

A URDF from CAD and data sheets is off by about 10 % in link masses, 1 cm in centres of mass,
20 % in inertias and 50 % in friction, 30 % in armature (issue 28). :class:`ArmUncertainty`
states such levels; :func:`perturbed_parameters` moves an arm's standard parameters by given
draws ``u`` in [-1, 1] (per link: mass ``x (1 + mass u)``, centre of mass ``+ com u`` per axis,
inertia tensor about the centre of mass ``x (1 + inertia u)``; per joint: viscous and Coulomb
friction ``x (1 + viscous u)``, ``x (1 + coulomb u)``, armature ``x (1 + armature u)``), which
keeps every link physically consistent for levels below 1; :func:`draw_parameters` draws ``u`` uniformly;
:func:`prior_covariance` is the covariance of the standard parameters under those draws
(linearised about the URDF, ``Var u = 1/3``): the prior the online estimator puts on the arm's
base parameters (``B C B^T``).

:func:`identified_prior_std` is the prior an identification gives instead (``[run] excite``
and ``[model] from = "model.json"``): the sandwich covariance of its weighted least squares
plus the step of its physically consistent fit, and the stated uncertainty where it did not
identify.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError, is_finite_number

__all__ = [
    "ArmUncertainty",
    "draw_parameters",
    "identified_prior_cov",
    "identified_prior_std",
    "perturbed_parameters",
    "prior_covariance",
]

Array = NDArray[np.float64]
_FIELDS = ("mass", "com", "inertia", "viscous", "coulomb", "armature")


@dataclass(frozen=True)
class ArmUncertainty:
    """Relative (``mass``, ``inertia``, ``viscous``, ``coulomb``, ``armature``, in [0, 1)) and
    absolute (``com`` [m], >= 0) half-widths of the uniform errors of a URDF's parameters (the
    keys of the scenario's ``[plant.uncertainty]``; the defaults are the levels of a URDF from CAD
    and data sheets, issue 28)."""

    mass: float = 0.1
    com: float = 0.01
    inertia: float = 0.2
    viscous: float = 0.5
    coulomb: float = 0.5
    armature: float = 0.3

    def __post_init__(self) -> None:
        for name in _FIELDS:
            v = getattr(self, name)
            hi = np.inf if name == "com" else 1.0
            ok = is_finite_number(v) and 0 <= v < hi
            if not ok:
                bound = ">= 0" if name == "com" else "in [0, 1)"
                raise ParameterError(f"ArmUncertainty.{name} must be a finite number {bound}, got {v!r}")

    def scaled(self, factor: float) -> ArmUncertainty:
        """Every level times ``factor``."""
        return ArmUncertainty(*(getattr(self, k) * factor for k in _FIELDS))


def _link_params(m: float, c: Array, Ic: Array) -> Array:
    """Ten parameters about the joint frame (Pinocchio's order) of mass m, com c, inertia Ic about c."""
    S = np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])
    Ib = Ic + m * S.T @ S
    return np.array([m, *(m * c), Ib[0, 0], Ib[0, 1], Ib[1, 1], Ib[0, 2], Ib[1, 2], Ib[2, 2]])


def _link_split(p: Array) -> tuple[float, Array, Array]:
    """Mass, com and inertia about the com of ten parameters (zero mass: com 0, inertia as given)."""
    m = float(p[0])
    c = p[1:4] / m if m > 0 else np.zeros(3)
    Ib = np.array([[p[4], p[5], p[7]], [p[5], p[6], p[8]], [p[7], p[8], p[9]]])
    S = np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])
    return m, c, Ib - m * S.T @ S


def perturbed_parameters(arm, u: Array, levels: ArmUncertainty) -> Array:
    """The arm's standard parameters ``(13 n,)`` moved by draws ``u (8 n,)``.

    ``u`` per link: mass, com x, y, z, inertia (5 n, link-major), then per joint viscous,
    Coulomb, armature (3 n). Each entry in [-1, 1] for a physically consistent result.
    """
    n = arm.n_joints
    u = np.asarray(u, dtype=float)
    if u.shape != (8 * n,):
        raise ParameterError(f"perturbed_parameters: u must have {8 * n} entries, got shape {u.shape}")
    links = np.asarray(arm.pi_links, dtype=float)
    out = np.empty(13 * n)
    ul = u[: 5 * n].reshape(n, 5)
    for j in range(n):
        m, c, Ic = _link_split(links[10 * j : 10 * j + 10])
        m2 = m * (1.0 + levels.mass * ul[j, 0])
        c2 = c + levels.com * ul[j, 1:4]
        out[10 * j : 10 * j + 10] = _link_params(m2, c2, Ic * (1.0 + levels.inertia * ul[j, 4]))
    uf = u[5 * n :].reshape(3, n)
    out[10 * n : 11 * n] = arm.viscous * (1.0 + levels.viscous * uf[0])
    out[11 * n : 12 * n] = arm.coulomb * (1.0 + levels.coulomb * uf[1])
    out[12 * n :] = arm.armature * (1.0 + levels.armature * uf[2])
    return out


def draw_parameters(arm, levels: ArmUncertainty, rng: np.random.Generator) -> Array:
    """One plant's standard parameters ``(13 n,)`` drawn around the arm's (u uniform in [-1, 1])."""
    return perturbed_parameters(arm, rng.uniform(-1.0, 1.0, 8 * arm.n_joints), levels)


def prior_covariance(arm, levels: ArmUncertainty) -> Array:
    """Covariance ``(13 n, 13 n)`` of the standard parameters under :func:`draw_parameters`,
    linearised about the URDF (central differences in ``u``, ``Var u = 1/3``)."""
    n = arm.n_joints
    J = np.empty((13 * n, 8 * n))
    h = 1e-3
    for k in range(8 * n):
        e = np.zeros(8 * n)
        e[k] = h
        J[:, k] = (perturbed_parameters(arm, e, levels) - perturbed_parameters(arm, -e, levels)) / (2 * h)
    return J @ J.T / 3.0


def identified_prior_std(
    cov: Array,
    sigma_wls: Array,
    sigma_fit: Array,
    identified=None,
    stated_var: Array | None = None,
    model_error_var: Array | None = None,
) -> Array:
    """What an identification knows of each base parameter about the model it hands on ``(p,)``:
    ``sqrt(cov_kk + (fit_k - wls_k)^2 + model_error_var_k)``.

    ``cov (p, p)`` is the covariance of the weighted least squares ``sigma_wls``: the Newey-West
    sandwich of :func:`~adaptive_dd.identification.log_fit.fit_log` (what ``adaptive-dd identify``
    writes to ``model.json``), which holds when the residual is coloured by the filters and
    carries model error, not the white-residual formula (on the drawn iiwa the latter's
    standard deviations were 4.5-6x too small: the identified parameters' errors against the
    plant 5-10 of them in the median, up to 40, and the online estimator, trusting them, could
    not correct the arm; ``docs/learning_the_arm.md``). ``sigma_fit`` is the physically
    consistent fit the controllers are given; its step from ``sigma_wls`` is model error the
    data showed. ``model_error_var (p,)``: the squared differences from ``sigma_wls`` of estimates
    that agree with it up to noise when the model is the plant's law
    (:func:`~adaptive_dd.identification.model_error.model_error_variance`): model error, which the
    sandwich, a variance about the misspecified model's best fit, does not hold. On the drawn iiwa (10
    seeds, 62 base parameters) the errors against the plant were 1.9 of the sandwich's standard
    deviations rms (3.5 per parameter in the Mahalanobis norm; friction worst: the model's
    ``tanh`` Coulomb law against the plant's stick-slip), 1.05 (0.8) with the filter and weighting
    differences added. Parameters not ``identified`` (held at the URDF's) take ``stated_var (p,)``,
    the variance the stated uncertainty implies (``diag(B C B^T)``, :func:`prior_covariance`).

    Raises
    ------
    ParameterError
        Shapes disagree, values are not finite, or a parameter not identified has no stated
        variance.
    """
    C = np.asarray(cov, dtype=float)
    wls, fit = np.asarray(sigma_wls, dtype=float), np.asarray(sigma_fit, dtype=float)
    p = wls.shape[0]
    if C.shape != (p, p) or fit.shape != (p,):
        raise ParameterError(
            f"identified_prior_std: need a ({p}, {p}) covariance and {p} fitted values, "
            f"got {C.shape}, {fit.shape}"
        )
    if not (np.all(np.isfinite(C)) and np.all(np.isfinite(wls)) and np.all(np.isfinite(fit))):
        raise ParameterError("identified_prior_std: the covariance or the estimates are not finite")
    extra = np.zeros(p) if model_error_var is None else np.asarray(model_error_var, dtype=float)
    if extra.shape != (p,) or not np.all(np.isfinite(extra) & (extra >= 0)):
        raise ParameterError(f"identified_prior_std: model_error_var must be {p} finite values >= 0")
    var = np.abs(np.diag(C)) + (fit - wls) ** 2 + extra
    K = np.ones(p, dtype=bool) if identified is None else np.asarray(identified, dtype=bool)
    if not K.all():
        if stated_var is None:
            raise ParameterError(
                "identified_prior_std: some base parameters were not identified and no stated "
                "uncertainty gives their variance"
            )
        var = np.where(K, var, np.asarray(stated_var, dtype=float))
    return np.sqrt(var)


def identified_prior_cov(
    cov: Array,
    sigma_wls: Array,
    sigma_fit: Array,
    identified=None,
    stated_var: Array | None = None,
    model_error_var: Array | None = None,
) -> Array:
    """The prior of :func:`identified_prior_std` with the correlations the identification knows
    ``(p, p)``: the sandwich covariance ``cov`` with its diagonal replaced by
    ``identified_prior_std(...)**2`` (the fit's step and the model error, whose directions the
    sandwich does not know, stay on the diagonal); rows and columns of the base parameters not
    ``identified`` zero but for their stated variance. The hand-off of a diagonal prior forgets
    which combinations of base parameters the excitation fixed, and the online estimator then
    moves them on its own, noisier, data.

    Raises
    ------
    ParameterError
        As :func:`identified_prior_std`.
    """
    std = identified_prior_std(cov, sigma_wls, sigma_fit, identified, stated_var, model_error_var)
    C = np.asarray(cov, dtype=float)
    C = 0.5 * (C + C.T)
    K = np.ones(len(std), dtype=bool) if identified is None else np.asarray(identified, dtype=bool)
    C = np.where(np.outer(K, K), C, 0.0)
    C[np.diag_indices_from(C)] = std**2
    return C
