"""A payload's mass, centre of mass and inertia from identified base parameters.

A rigid body on the payload frame moves the base parameters along
:attr:`Arm.payload_basis` ``P (p, 10)``: ``sigma_loaded = sigma_unloaded + P pi_p``.

* **From a pair** of records (loaded, unloaded), each identified with its covariance:
  generalised least squares ``pi_p = (P^T C^-1 P)^-1 P^T C^-1 (sigma_L - sigma_U)``,
  ``C = C_L + C_U``, covariance ``(P^T C^-1 P)^-1``, when ``C`` is known (Cramér-Rao); when it
  is estimated from the records' residuals, ``C^-1`` replaced by ``diag(C)^-1`` and the
  covariance the sandwich ``B C B^T`` (:func:`pair_difference`).
* **From one record with the arm known**: output error on the ten payload parameters
  alone (:func:`~adaptive_dd.identification.output_error.fit_output_error`
  with ``E = P``), covariance the inverse of their Fisher information.

Either way the result carries the constrained (physically consistent) fit of
:mod:`adaptive_dd.identification.consistency`, and mass, centre of mass [m] (in the
payload frame) and inertia about the centre of mass with first-order standard deviations.

On an arm whose base parameters determine only some of the ten (a planar arm: the mass, the
in-plane centre of mass and the inertia about the joints' axis, :attr:`Arm.payload_identifiable`),
those are fitted alone and the others, which do not act on the arm, are reported as not determined
(NaN) and held at 0 in the fit; no consistent fit is taken then (it needs the whole body).
:func:`payload_seen` refuses an arm whose determined directions mix parameters it cannot name one
by one.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.consistency import ConsistentFit, consistent_fit

__all__ = [
    "PayloadResult",
    "pair_difference",
    "payload_from_pair",
    "payload_from_params",
    "payload_from_record",
    "payload_record",
    "payload_seen",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class PayloadResult:
    """An identified payload.

    Attributes
    ----------
    params : ndarray (10,)
        Unconstrained estimate about the payload frame.
    cov : ndarray (10, 10)
        Its covariance (Cramér-Rao when the inputs were).
    mass, mass_std : float
        [kg].
    com, com_std : ndarray (3,)
        Centre of mass in the payload frame [m] (constrained fit) and its std; NaN when the mass is
        not positive (``com_defined`` False: a massless body has no centre of mass).
    inertia_com : ndarray (3, 3)
        Inertia about the centre of mass [kg m^2] (constrained fit).
    consistent : ConsistentFit

    Examples
    --------
    Made by :func:`payload_from_pair` (whose example makes one) and
    :func:`payload_from_record`; ``mass``, ``com`` and their standard deviations are what
    ``adaptive-dd identify --payload-only`` and ``--baseline`` print.

    >>> from adaptive_dd.identification.payload_pair import PayloadResult
    >>> {"mass", "com", "mass_std", "com_std"} <= set(PayloadResult.__dataclass_fields__)
    True
    """

    params: Array
    cov: Array
    mass: float
    mass_std: float
    com: Array
    com_std: Array
    inertia_com: Array
    consistent: ConsistentFit
    com_defined: bool = True
    """False when the constrained fit's mass is not positive: ``com`` and ``com_std`` are then NaN, and
    ``identify`` prints the centre of mass as undefined."""
    fit: Any = None
    """:func:`payload_from_record`'s output-error fit (its ``converged``, ``iterations``, ``cost``,
    ``n_residuals``); None from a pair."""
    determined: Any = None
    """``(10,)`` bool: the parameters the records determine (None: all ten); the others are NaN in
    ``params``, ``cov``, ``com`` and ``inertia_com`` where they enter, and ``consistent`` is None."""
    inertia_com_std: Any = None
    """``(3, 3)``: first-order standard deviation of ``inertia_com`` (from ``cov``; NaN where not
    determined)."""


def payload_record(pr: PayloadResult, source: str) -> dict:
    """``pr`` as JSON-ready data (``identify``'s ``payload.json``): the fit as printed, its ten
    parameters and covariance, and ``scenario_payload``, a ``[[payload]]`` entry's ``mass``, ``com``
    and ``inertia`` (about the centre of mass, ``[ixx, iyy, izz, ixy, ixz, iyz]``) to paste into a
    scenario (``com`` and ``inertia`` left out when the mass is not positive)."""
    ic = pr.inertia_com
    inertia = six(ic)
    entry = {"mass": round(max(pr.mass, 0.0), 6)}
    if pr.com_defined:
        entry |= {"com": [round(float(x), 6) for x in np.nan_to_num(pr.com)], "inertia": _filled(inertia)}
    fit = pr.fit

    def plain(x):  # NaN (not determined) -> null
        return [None if not np.isfinite(v) else float(v) for v in np.ravel(x)]

    out = {
        "source": source,
        "mass_kg": pr.mass,
        "mass_std_kg": pr.mass_std,
        "com_m": plain(pr.com) if pr.com_defined else None,
        "com_std_m": plain(pr.com_std) if pr.com_defined else None,
        "inertia_com_kg_m2": plain(inertia),
        "inertia_com_std_kg_m2": None if pr.inertia_com_std is None else plain(six(pr.inertia_com_std)),
        "physical_as_estimated": None if pr.consistent is None else bool(pr.consistent.was_physical),
        "params": plain(pr.params),
        "params_order": "m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz (about the payload frame)",
        "cov": [plain(r) for r in pr.cov],
        "output_error": None
        if fit is None
        else {"converged": bool(fit.converged), "iterations": int(fit.iterations)},
        "scenario_payload": entry,
    }
    if pr.determined is not None:
        out["determined"] = [n for n, ok in zip(PARAM_NAMES, pr.determined, strict=True) if ok]
        out["scenario_payload_note"] = (
            "the parameters this arm does not determine do not act on it: scenario_payload holds 0 for "
            "their centre of mass, the determined diagonal inertia (at least 0) for the others on the "
            "diagonal and 0 off it (a valid body with the same effect on this arm)"
        )
    return out


def _filled(inertia: list) -> list[float]:
    """``[ixx, iyy, izz, ixy, ixz, iyz]`` with its undetermined (NaN) entries filled so that the
    whole is a body (:func:`payload_record`'s note): diagonal ones by the largest determined one, off
    the diagonal by 0."""
    v = np.asarray(inertia, float)
    diag = np.where(np.isfinite(v[:3]), np.maximum(v[:3], 0.0), np.nan)  # noise about a small one: 0
    fill = float(np.nanmax(diag)) if np.isfinite(diag).any() else 0.0
    v[:3] = np.where(np.isfinite(diag), diag, fill)
    v[3:] = np.nan_to_num(v[3:])
    return [float(x) for x in v]


INERTIA_ENTRIES = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
"""The six entries of an inertia matrix in a ``[[payload]]`` entry's order ``[ixx, iyy, izz, ixy,
ixz, iyz]``."""


def six(M: ArrayLike) -> list[float]:
    """``[ixx, iyy, izz, ixy, ixz, iyz]`` of a ``(3, 3)`` inertia (:data:`INERTIA_ENTRIES`)."""
    return [float(M[i][j]) for i, j in INERTIA_ENTRIES]


def _inertia_about_com(p: Array) -> Array:
    """Inertia about the centre of mass from the ten parameters ``p``, entry by entry, so that an
    undetermined parameter (NaN) makes NaN only the entries it enters; a body of no positive mass
    taken at the payload frame's origin."""
    m = p[0]
    c = p[1:4] / m if m > 0 else np.zeros(3)
    Io = np.array([[p[4], p[5], p[7]], [p[5], p[6], p[8]], [p[7], p[8], p[9]]])
    shift = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            shift[i, j] = sum(c[k] ** 2 for k in range(3) if k != i) if i == j else -c[i] * c[j]
    return Io - m * shift


PARAM_NAMES = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
"""The payload's ten parameters in :attr:`Arm.payload_basis`'s order (first moments ``m c``,
inertia about the payload frame)."""


def payload_seen(arm, what: str) -> NDArray[np.bool_]:
    """The payload parameters the arm's base parameters determine, ``(10,)`` bool; a
    :class:`ParameterError` naming ``what`` when they are not a set of whole parameters (a direction
    that mixes one the arm determines with one it does not)."""
    P = arm.payload_basis
    seen = np.asarray(arm.payload_identifiable, bool)
    if np.linalg.matrix_rank(P[:, seen], tol=1e-9 * np.abs(P).max()) != arm.payload_rank:
        missing = [nm for nm, ok in zip(PARAM_NAMES, seen, strict=True) if not ok]
        raise ParameterError(
            f"on this arm the base parameters determine {arm.payload_rank} combinations of the payload's "
            f"10 parameters that mix {missing} with the others; {what} cannot give them one by one"
        )
    return seen


def _inertia_std(q: Array, C: Array, seen: NDArray[np.bool_]) -> Array:
    """First-order std of :func:`_inertia_about_com` at ``q`` from ``C`` over the parameters
    ``seen`` (central differences; NaN where an entry depends on one not seen)."""
    k = np.flatnonzero(seen)
    J = np.empty((9, k.size))
    for c, i in enumerate(k):
        h = 1e-6 * max(abs(q[i]), 1e-3)
        up, dn = q.copy(), q.copy()
        up[i] += h
        dn[i] -= h
        J[:, c] = ((_inertia_about_com(up) - _inertia_about_com(dn)) / (2 * h)).ravel()
    var = np.einsum("ij,jk,ik->i", J, C[np.ix_(k, k)], J)
    return np.where(np.isfinite(_inertia_about_com(q)), np.sqrt(np.maximum(var, 0.0)).reshape(3, 3), np.nan)


def payload_from_params(
    params: ArrayLike, cov: ArrayLike, determined: ArrayLike | None = None
) -> PayloadResult:
    """Mass, com and inertia (with stds and the consistent fit) from ten parameters and their
    covariance; ``determined`` ``(10,)`` bool: the ones the records determine (default all), the
    others reported NaN with no consistent fit (module docstring)."""
    p = np.asarray(params, dtype=float)
    C = np.asarray(cov, dtype=float)
    if determined is not None and not np.all(determined):
        return _partial(p, C, np.asarray(determined, bool))
    fit = consistent_fit(p, np.linalg.pinv(C, rcond=1e-12, hermitian=True))
    q = fit.params
    m = q[0]
    defined = bool(m > 0)
    com, com_std = np.full(3, np.nan), np.full(3, np.nan)  # a massless body has no centre of mass
    if defined:
        com = q[1:4] / m
        # d c / d [m, h] = [-h/m^2, 1/m]
        for k in range(3):
            g = np.zeros(10)
            g[0], g[1 + k] = -q[1 + k] / m**2, 1.0 / m
            com_std[k] = np.sqrt(max(g @ C @ g, 0.0))
    inertia_std = _inertia_std(q, C, np.ones(10, bool)) if defined else np.full((3, 3), np.nan)
    return PayloadResult(
        p, C, float(m), float(np.sqrt(C[0, 0])), com, com_std, _inertia_about_com(q), fit,
        com_defined=defined, inertia_com_std=inertia_std,
    )  # fmt: skip


def _partial(p: Array, C: Array, seen: NDArray[np.bool_]) -> PayloadResult:
    """:func:`payload_from_params` for the parameters ``seen`` alone (the others NaN)."""
    if not seen[0]:
        raise ParameterError("the records do not determine the payload's mass")
    q = np.where(seen, p, np.nan)
    cov = np.where(np.outer(seen, seen), C, np.nan)
    m = q[0]
    # no consistent fit to say whether there is a body: the mass must stand out of its own noise
    defined = bool(m > 1.96 * np.sqrt(max(C[0, 0], 0.0)))
    com, com_std = np.full(3, np.nan), np.full(3, np.nan)
    inertia, inertia_std = np.full((3, 3), np.nan), np.full((3, 3), np.nan)
    if defined:
        com = q[1:4] / m
        for k in range(3):
            if seen[1 + k]:
                g = np.zeros(10)
                g[0], g[1 + k] = -q[1 + k] / m**2, 1.0 / m
                k2 = np.flatnonzero(g)
                com_std[k] = np.sqrt(max(g[k2] @ C[np.ix_(k2, k2)] @ g[k2], 0.0))
        inertia = _inertia_about_com(q)
        inertia_std = _inertia_std(q, C, seen)
    return PayloadResult(
        q, cov, float(m), float(np.sqrt(C[0, 0])), com, com_std, inertia, None, com_defined=defined,
        determined=seen, inertia_com_std=inertia_std,
    )  # fmt: skip


def payload_from_pair(
    arm,
    sigma_loaded: ArrayLike,
    cov_loaded: ArrayLike,
    sigma_unloaded: ArrayLike,
    cov_unloaded: ArrayLike,
    *,
    weighting: str = "gls",
) -> PayloadResult:
    """The payload from a loaded and an unloaded identification (module docstring).

    ``weighting="gls"`` weights the difference ``d`` by ``C^-1``, the efficient choice when ``C`` is
    known (a Cramér-Rao covariance). When ``C`` is itself estimated from the records' residuals (the
    Newey-West sandwich of :func:`~adaptive_dd.identification.log_fit.fit_log`, from a few hundred
    independent samples for tens of parameters), ``C^-1`` picks the combinations whose estimated
    variance happens to be low, and the GLS variance ``(P^T C^-1 P)^-1`` is then far too small (on
    simulated UR5 pairs the truth fell within +- 1.96 std in 76 % of cases): ``"diagonal"`` weights
    each base parameter by ``1 / C_kk`` alone and gives the covariance as the sandwich
    ``B C B^T``, ``B = (P^T W P)^-1 P^T W``, which holds whatever the weighting.


    Parameters
    ----------
    arm : Arm
        The arm both identifications are of.
    sigma_loaded, sigma_unloaded : array_like, shape (p,)
        Base parameters identified with and without the payload.
    cov_loaded, cov_unloaded : array_like, shape (p, p)
        Their covariances.

    Returns
    -------
    PayloadResult
        The payload's ten parameters about the payload frame, unconstrained and physically
        consistent, with their standard deviations.


    Examples
    --------
    Base parameters of a UR5 with and without a 2 kg tool 4 cm off the flange's axis give the
    tool back:

    >>> import numpy as np
    >>> from adaptive_dd.identification.payload_pair import payload_from_pair
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> ur5 = Arm.from_urdf(robot_urdf("ur5"))
    >>> cov = 1e-10 * np.eye(ur5.base.count)
    >>> tool = payload_from_pair(ur5, ur5.sigma_with_payload(2.0, com=[0.0, 0.04, 0.0]), cov,
    ...                          ur5.sigma, cov)
    >>> round(tool.mass, 6), (tool.com.round(6) + 0.0).tolist()
    (2.0, [0.0, 0.04, 0.0])

    Raises
    ------
    ParameterError
        If the base parameters determine combinations of the payload parameters that mix
        determined and undetermined ones (:func:`payload_seen`).
    """
    seen = payload_seen(arm, "a pair of records")
    P = arm.payload_basis[:, seen]
    n = P.shape[0]
    shapes = [np.shape(x) for x in (sigma_loaded, cov_loaded, sigma_unloaded, cov_unloaded)]
    if shapes != [(n,), (n, n), (n,), (n, n)]:
        raise ParameterError(
            f"payload_from_pair: the estimates must have the arm's {n} base parameters and their "
            f"covariances {n} x {n}; got shapes {shapes} (loaded, its covariance, unloaded, its covariance)"
        )
    d = np.asarray(sigma_loaded, float) - np.asarray(sigma_unloaded, float)
    C = np.asarray(cov_loaded, float) + np.asarray(cov_unloaded, float)
    if not (np.all(np.isfinite(d)) and np.all(np.isfinite(C))):
        raise ParameterError("the loaded or unloaded estimate or its covariance is not finite")
    pi, cov = pair_difference(
        P, d, C, weighting, names=[n for n, ok in zip(PARAM_NAMES, seen, strict=True) if ok]
    )
    return payload_from_params(*_whole(pi, cov, seen), None if seen.all() else seen)


def _whole(pi: Array, cov: Array, seen: NDArray[np.bool_]) -> tuple[Array, Array]:
    """The ten parameters and their covariance from those ``seen`` (0 elsewhere: not determined)."""
    p, C = np.zeros(10), np.zeros((10, 10))
    p[seen] = pi
    C[np.ix_(seen, seen)] = cov
    return p, C


def pair_difference(
    P: ArrayLike, d: ArrayLike, C: ArrayLike, weighting: str = "gls", names=PARAM_NAMES
) -> tuple[Array, Array]:
    """The ten payload parameters ``(10,)`` and their covariance ``(10, 10)`` from the difference
    ``d (p,)`` of a loaded and an unloaded estimate with covariance ``C (p, p)``, ``d = P pi + e``
    (:func:`payload_from_pair`'s linear step; ``weighting`` as there).

    Raises
    ------
    ParameterError
        A payload direction the difference does not see (named), or an unknown ``weighting``.
    """
    P, d, C = (np.asarray(x, dtype=float) for x in (P, d, C))
    if weighting == "gls":
        Ci = np.linalg.pinv(C, rcond=1e-14, hermitian=True)
    elif weighting == "diagonal":  # the held parameters (variance 0) carry no weight, as in C's pinv
        c = np.diag(C)
        Ci = np.diag(np.where(c > 1e-14 * max(c.max(), 1e-300), 1.0 / np.maximum(c, 1e-300), 0.0))
    else:
        raise ParameterError(f"payload_from_pair: weighting {weighting!r} is not 'gls' or 'diagonal'")
    info = 0.5 * (P.T @ Ci @ P + (P.T @ Ci @ P).T)
    lam, V = np.linalg.eigh(info)
    weak = lam <= 1e-10 * max(lam.max(), 1e-300)
    if weak.any():  # directions of the payload the two estimates do not see (their covariances are 0
        # or infinite there: channels left out, parameters held at the URDF's values)
        v = V[:, np.flatnonzero(weak)]
        missing = [names[k] for k in np.flatnonzero(np.linalg.norm(v, axis=1) > 0.3)]
        raise ParameterError(
            f"the pair does not determine the payload's {', '.join(missing)}: the identified base "
            "parameters that would carry them are not seen by the fitted torque channels (or not excited); "
            "fit more channels or move the joints near the payload more"
        )
    B = (V / lam) @ V.T @ P.T @ Ci  # (10, p): the payload from the difference
    cov = B @ C @ B.T if weighting == "diagonal" else (V / lam) @ V.T
    return B @ d, 0.5 * (cov + cov.T)


def payload_from_record(
    arm,
    model,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    std: ArrayLike,
    sigma_arm: ArrayLike | None = None,
    **oe_kw,
) -> PayloadResult:
    """The payload from one loaded record with the arm known (``sigma_arm``, default the URDF's).

    Raises
    ------
    ParameterError
        The arm's base parameters determine combinations that mix parameters (:func:`payload_seen`).
    """
    from adaptive_dd.identification.output_error import fit_output_error

    seen = payload_seen(arm, "one loaded record")
    s0 = model.sigma_ref if sigma_arm is None else np.asarray(sigma_arm, float)
    fit = fit_output_error(model, q, qd, tau, s0, std, E=arm.payload_basis[:, seen], **oe_kw)
    pi, cov = _whole(fit.theta, np.linalg.inv(fit.information), seen)
    return dataclasses.replace(payload_from_params(pi, cov, None if seen.all() else seen), fit=fit)
