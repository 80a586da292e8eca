"""Fisher information and Cramér-Rao bounds for identifying sigma from an experiment.

Measurement model
-----------------
The arm starts in a known state and is driven by a known torque record (the applied
torque, held over each sample). At every sample the measured signals are
``y_k = [q_k, qd_k] + e_k`` (or the subset named by ``measured``), ``e_k`` white Gaussian
with the variances of Table 2 / Table 4. The Fisher information of sigma is then

    F = sum_k S_k^T R^-1 S_k,        S_k = d[q_k, qd_k] / d sigma   (output sensitivities)

and no unbiased estimator has a covariance below ``F^-1`` (Cramér-Rao):
``crb_std = sqrt(diag(F^-1))`` is the smallest standard deviation any unbiased estimator
of each parameter can reach from this record, with the others unknown too. The
sensitivities come from :mod:`adaptive_dd.identification.sensitivity` (forward
sensitivity equations, or central differences through the compiled stick-slip step).

Torque noise
------------
With white noise of variance ``torque_variance`` on the applied torque (not measured),
the outputs are no longer independent; the information is then that of the innovations
of a Kalman filter on the model linearised along the nominal trajectory:
``F = sum_k E_k^T S_k^-1 E_k`` with ``E_k = -C dxhat_k/dsigma`` the sensitivity of the
innovation and ``S_k`` its covariance (the term from ``dS_k/dsigma`` is left out).
Without torque noise this is the formula above.

Encoder quantization
--------------------
Rounding the position to the encoder step ``Delta = 2 pi / counts`` adds a uniform error
of variance ``Delta^2 / 12`` (3e-6 rad std for 614400 counts per revolution), which
over a moving arm is close to white and independent of the Gaussian noise; with
``encoder_counts`` given it is added to the position variance (1e-8 + 9e-12 rad^2 on
joint 1: it changes the bound by 0.04 %).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.experiments import TABLE2
from adaptive_dd.identification.sensitivity import (
    chain_sensitivities,
    finite_difference_sensitivities,
    local_sensitivities,
    simulate_trajectory,
)
from adaptive_dd.plant.parameters import SIGMA_NAMES, payload_mass_from_sigma, validate_sigma

__all__ = [
    "SIGNALS",
    "FisherResult",
    "crb_from_fisher",
    "fisher_from_sensitivities",
    "fisher_information",
    "innovation_fisher",
    "linear_gaussian_crb",
    "mass_information_time",
    "output_variances",
]

Array = NDArray[np.float64]

SIGNALS = ("q", "qd")
"""Measurable signals: joint angles and joint velocities."""


@dataclass(frozen=True)
class FisherResult:
    """Fisher information of sigma for one experiment, and the Cramér-Rao bounds.

    Attributes
    ----------
    information : ndarray (7, 7)
        Fisher information F [1 / unit(sigma_i) unit(sigma_j)].
    crb_std : ndarray (7,)
        ``sqrt(diag(F^-1))``: the smallest standard deviation of any unbiased estimate
        of each parameter (units of sigma).
    crb_std_pct : ndarray (7,)
        The same in % of sigma.
    condition_number : float
        Condition number of ``diag(sigma) F diag(sigma)`` (the information about the
        relative parameters: scale-free, a measure of how well the excitation separates them).
    sigma : ndarray (7,)
        Where the information was evaluated.
    method : str
        ``"sensitivity"`` or ``"finite_difference"``.
    n_samples : int
    """

    information: Array
    crb_std: Array
    crb_std_pct: Array
    condition_number: float
    sigma: Array
    method: str
    n_samples: int

    def to_dict(self) -> dict:
        """Plain-JSON form: per-parameter ``crb_std`` and ``crb_std_pct``, and the condition number."""
        return {
            "method": self.method,
            "n_samples": self.n_samples,
            "condition_number": float(self.condition_number),
            "crb_std": dict(zip(SIGMA_NAMES, map(float, self.crb_std), strict=True)),
            "crb_std_pct": dict(zip(SIGMA_NAMES, map(float, self.crb_std_pct), strict=True)),
        }

    def format(self) -> str:
        """Two lines: the bound per parameter [%] and the condition number."""
        head = " ".join(f"{n:>9s}" for n in SIGMA_NAMES)
        vals = " ".join(f"{v:9.2g}" for v in self.crb_std_pct)
        return f"{'':>12s} {head}\n{'CRB std [%]':>12s} {vals}\ncondition number {self.condition_number:.3g}"


def linear_gaussian_crb(phi: ArrayLike, noise_variance: float) -> Array:
    """Closed-form bound of ``y = Phi sigma + e``, ``e ~ N(0, s^2 I)``: ``sqrt(diag(s^2 (Phi^T Phi)^-1))``.

    Least squares attains it (it is the efficient estimator of this model).

    Parameters
    ----------
    phi : array_like (n, p)
    noise_variance : float
        ``s^2``.
    """
    phi = np.asarray(phi, dtype=float)
    if phi.ndim != 2 or not noise_variance > 0:
        raise ParameterError(f"need phi (n, p) and noise_variance > 0, got {phi.shape}, {noise_variance}")
    return np.sqrt(np.diag(noise_variance * np.linalg.inv(phi.T @ phi)))


def output_variances(
    position_variance: ArrayLike = TABLE2["position_variance"],
    velocity_variance: ArrayLike = TABLE2["velocity_variance"],
    measured: tuple[str, ...] = SIGNALS,
    encoder_counts: ArrayLike | None = None,
) -> Array:
    """Noise variances of ``[q1, q2, qd1, qd2]`` (4,), ``inf`` for signals not measured.

    ``encoder_counts`` adds the quantization variance ``(2 pi / counts)^2 / 12`` to q.
    """
    bad = [m for m in measured if m not in SIGNALS]
    if bad or not measured:
        raise ParameterError(f"measured must name some of {SIGNALS}, got {measured}")
    pv = np.broadcast_to(np.asarray(position_variance, dtype=float), (2,)).copy()
    vv = np.broadcast_to(np.asarray(velocity_variance, dtype=float), (2,)).copy()
    if encoder_counts is not None:
        pv = pv + (2.0 * np.pi / np.asarray(encoder_counts, dtype=float)) ** 2 / 12.0
    var = np.concatenate((pv, vv))
    if np.any(~np.isfinite(var)) or np.any(var <= 0):
        raise ParameterError(
            f"noise variances must be finite and > 0, got position {pv}, velocity {vv} "
            "(a noise-free measurement carries infinite information)"
        )
    var[:2] = var[:2] if "q" in measured else np.inf
    var[2:] = var[2:] if "qd" in measured else np.inf
    return var


def fisher_from_sensitivities(sens: ArrayLike, variances: ArrayLike) -> Array:
    """``F = sum_k S_k^T R^-1 S_k`` for white outputs with variances ``R = diag(variances)``.

    Parameters
    ----------
    sens : array_like (..., N, m, p)
        Output sensitivities ``dy_k / dtheta``.
    variances : array_like (m,)
        Output noise variances; ``inf`` for an output not measured.
    """
    s = np.asarray(sens, dtype=float)
    w = 1.0 / np.asarray(variances, dtype=float)
    if s.ndim < 3 or s.shape[-2] != w.shape[-1]:
        raise SignalError(f"sens must be (..., N, m, p) with m = {w.shape[-1]}, got {s.shape}")
    return np.einsum("...kia,i,...kib->...ab", s, w, s)


def innovation_fisher(a: Array, g: Array, p: Array, variances: Array, torque_variance: ArrayLike) -> Array:
    """Fisher information with white torque noise (innovations form, module docstring).

    Parameters
    ----------
    a, g, p : ndarray (N-1, 4, 4), (N-1, 4, 2), (N-1, 4, 7)
        Per-sample Jacobians from :func:`local_sensitivities`.
    variances : ndarray (4,)
        Output noise variances, ``inf`` for a signal not measured.
    torque_variance : array_like (2,)
        Variance of the white noise on the applied torque [(N m)^2].
    """
    rows = np.isfinite(variances)
    c = np.eye(4)[rows]
    r = np.diag(variances[rows])
    qt = np.diag(np.broadcast_to(np.asarray(torque_variance, dtype=float), (2,)))
    cov, d = np.zeros((4, 4)), np.zeros((4, p.shape[-1]))
    info = np.zeros((p.shape[-1], p.shape[-1]))
    for k in range(a.shape[0] + 1):
        if k > 0:
            ak = a[k - 1]
            d = ak @ d + p[k - 1]
            cov = ak @ cov @ ak.T + g[k - 1] @ qt @ g[k - 1].T
        e = c @ d
        s = c @ cov @ c.T + r
        s_inv = np.linalg.inv(s)
        info += e.T @ s_inv @ e
        gain = cov @ c.T @ s_inv
        d = d - gain @ e
        cov = cov - gain @ c @ cov
    return info


def crb_from_fisher(information: ArrayLike, sigma: ArrayLike, method: str, n_samples: int) -> FisherResult:
    """Bounds and condition number from a Fisher information matrix (7, 7).

    The bound of parameter i is ``sqrt((F^-1)_ii)``, F inverted on its own scale (``D^-1 F D^-1``,
    ``D = sqrt(diag F)``), so that a parameter that is 0 (friction may be) keeps its bound; a
    parameter the record does not inform (in a direction of F's null space) has an infinite bound,
    not 0. The percentage is of ``|sigma_i|`` (NaN where it is 0); the condition number is that of
    the information relative to sigma, ``diag(sigma) F diag(sigma)`` (infinite where a parameter is
    0 or not informed)."""
    f = np.asarray(information, dtype=float)
    sg = validate_sigma(sigma)
    std = np.full(sg.shape, np.inf)
    d = np.sqrt(np.clip(np.diag(f), 0.0, None))
    ok = d > 0
    if ok.any():
        w, V = np.linalg.eigh(f[np.ix_(ok, ok)] / np.outer(d[ok], d[ok]))
        keep = w > 1e-12 * max(float(w[-1]), 0.0)
        Vk = V[:, keep]
        rel = np.sqrt(np.einsum("ik,k,ik->i", Vk, 1.0 / w[keep], Vk)) / d[ok]
        blind = np.linalg.norm(V[:, ~keep], axis=1) > 1e-6  # a component in F's null space
        std[ok] = np.where(blind, np.inf, rel)
    with np.errstate(divide="ignore", invalid="ignore"):
        pct = np.where(sg != 0, 100.0 * std / np.abs(sg), np.nan)
    eig = np.linalg.eigvalsh(sg[:, None] * f * sg[None, :])
    cond = float(eig[-1] / eig[0]) if eig[0] > 0 else float("inf")
    return FisherResult(f, std, pct, cond, sg, method, int(n_samples))


def fisher_information(
    sigma: ArrayLike,
    tau: ArrayLike,
    sample_period: float = TABLE2["sample_period"],
    position_variance: ArrayLike = TABLE2["position_variance"],
    velocity_variance: ArrayLike = TABLE2["velocity_variance"],
    *,
    measured: tuple[str, ...] = SIGNALS,
    torque_variance: ArrayLike | None = None,
    q0: ArrayLike = (0.0, 0.0),
    qd0: ArrayLike = (0.0, 0.0),
    substeps: int = 2,
    method: str = "sensitivity",
    encoder_counts: ArrayLike | None = None,
    rel_step: float = 1e-6,
    initial_state: str = "known",
) -> FisherResult:
    """Fisher information and Cramér-Rao bounds of sigma for an open- or closed-loop record.

    Parameters
    ----------
    sigma : array_like (7,)
        True (or estimated) base parameters, where the bound is evaluated.
    tau : array_like (N, 2)
        Applied torque held over each sample [N m]: the excitation, or a recorded
        closed-loop torque (then the bound is that of the recorded motion, torque known).
    sample_period : float
        T [s]; the duration is ``N T``.
    position_variance, velocity_variance : array_like (2,)
        Sensor noise variances [rad^2], [(rad/s)^2] (defaults: Table 2 and Table 4).
    measured : tuple of {"q", "qd"}
        Signals measured.
    torque_variance : array_like (2,), optional
        White noise on the applied torque [(N m)^2] (innovations form; only with
        ``method="sensitivity"``).
    q0, qd0 : array_like (2,)
        Known initial state.
    substeps : int
        RK4 steps per sample of the simulation.
    method : {"sensitivity", "finite_difference"}
        Forward sensitivity equations, or central differences through the compiled step.
    encoder_counts : array_like (2,), optional
        Add encoder quantization as white noise of variance ``Delta^2 / 12``.
    rel_step : float
        Relative step of the finite differences.
    initial_state : {"known", "unknown"}
        ``"unknown"``: the state at sample 0 is estimated from the data too (a nuisance
        parameter; the information about sigma is the Schur complement). Knowing that the
        arm starts at rest is worth a lot: on Table 2 the bound on d2 is 0.008 % with the
        initial state known, 0.025 % without. Only with ``method="sensitivity"`` and no
        torque noise.
    """
    sg = validate_sigma(sigma)
    tau = np.asarray(tau, dtype=float)
    if tau.ndim != 2 or tau.shape[-1] != 2 or tau.shape[0] < 2 or not np.all(np.isfinite(tau)):
        raise SignalError(f"tau must be a finite (N >= 2, 2) record, got shape {tau.shape}")
    var = output_variances(position_variance, velocity_variance, measured, encoder_counts)
    if method == "sensitivity":
        q, qd = simulate_trajectory(sg, tau, sample_period, q0, qd0, substeps)
        a, g, p = local_sensitivities(q, qd, tau, sg, sample_period, substeps)
        info = _sensitivity_information(a, g, p, var, torque_variance, initial_state)
    elif method == "finite_difference":
        if torque_variance is not None or initial_state != "known":
            raise ParameterError(
                "torque_variance and initial_state='unknown' need method='sensitivity' (innovations form)"
            )
        sens = finite_difference_sensitivities(sg, tau, sample_period, q0, qd0, substeps, rel_step)
        info = fisher_from_sensitivities(sens, var)
    else:
        raise ParameterError(f"method must be 'sensitivity' or 'finite_difference', got {method!r}")
    return crb_from_fisher(info, sg, method, tau.shape[0])


def _sensitivity_information(a, g, p, var, torque_variance, initial_state: str) -> Array:
    """Fisher information (7, 7) of sigma from the local sensitivities ``a, g, p`` of the step:
    the innovations form with torque noise, the Schur complement over an unknown initial
    state, or the sum over the chained sensitivities."""
    if initial_state not in ("known", "unknown"):
        raise ParameterError(f"initial_state must be 'known' or 'unknown', got {initial_state!r}")
    if torque_variance is not None:
        return innovation_fisher(a, g, p, var, torque_variance)
    if initial_state == "unknown":
        s0 = np.concatenate((np.eye(4), np.zeros((4, 7))), axis=-1)
        full = fisher_from_sensitivities(chain_sensitivities(a, np.concatenate((0 * a, p), -1), s0), var)
        # pinv: a state the outputs never see (q1 with velocities alone measured) leaves the state
        # block singular; F being positive semidefinite, its cross block lies in that block's range
        return full[4:, 4:] - full[4:, :4] @ np.linalg.pinv(full[:4, :4], hermitian=True) @ full[:4, 4:]
    return fisher_from_sensitivities(chain_sensitivities(a, p), var)


def _mass_functional() -> Array:
    """Coefficients c with ``payload_mass_from_sigma(sigma0 + d) == c @ d`` (7,)."""
    return payload_mass_from_sigma(np.eye(7), sigma0=np.zeros(7))


def mass_information_time(
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    k_swap: int,
    sample_period: float,
    sigma_after: ArrayLike,
    payload_direction: ArrayLike,
    position_variance: ArrayLike = TABLE2["position_variance"],
    velocity_variance: ArrayLike = TABLE2["velocity_variance"],
    rel: float = 0.05,
    *,
    mass: float,
    others: str = "known",
    z: float = 1.96,
    measured: tuple[str, ...] = SIGNALS,
    substeps: int = 2,
) -> float | None:
    """Time after a payload swap at which the information limit knows the mass within ``rel``.

    Definition: the first time ``t = (k - k_swap) T`` at which ``z * crb_std(m) <= rel * mass``
    (``z = 1.96``: a 95 % interval of an efficient estimator within +-5 % of the mass),
    with the information of the measurements at samples ``k_swap + 1 .. k``, the state at
    the swap and the applied torque known.

    ``others="known"`` (default): the arm without payload is known (identified before),
    only the payload mass ``m`` is unknown, and ``sigma = sigma_after + (m - mass)
    payload_direction``. This is the limit for the question the swap asks (how fast can
    the new payload be known), and the one an estimator that knows what changes could
    reach. ``others="unknown"``: all seven base parameters are unknown and the mass is read
    from them as :func:`~adaptive_dd.plant.parameters.payload_mass_from_sigma` does (least
    squares on the changes of J1 and r), the limit of an estimator that relearns all of
    sigma, as the adaptive controllers do.

    Parameters
    ----------
    q, qd : array_like (N, 2)
        Recorded *true* trajectory (stuck joints with qd exactly 0).
    tau : array_like (N, 2)
        Applied torque [N m].
    k_swap : int
        First sample with the new payload.
    sample_period : float
        T [s].
    sigma_after : array_like (7,)
        Base parameters after the swap.
    payload_direction : array_like (7,)
        ``d sigma / d m`` [per kg], e.g. ``payload_sigma_delta(1.0, radius)``.
    position_variance, velocity_variance : array_like (2,)
    rel : float
        Relative accuracy (0.05: 5 %).
    mass : float
        The mass whose ``rel`` is the target [kg] (the payload after the swap; for a
        removal, pass the removed mass).
    others : {"known", "unknown"}
    z : float
        Width of the interval in standard deviations.

    Returns
    -------
    float or None
        Seconds after the swap, or None if the record ends first.
    """
    if others not in ("known", "unknown"):
        raise ParameterError(f"others must be 'known' or 'unknown', got {others!r}")
    if not (mass > 0 and rel > 0 and z > 0):
        raise ParameterError(f"need mass > 0, rel > 0, z > 0; got {mass}, {rel}, {z}")
    q, qd, tau = (np.asarray(x, dtype=float) for x in (q, qd, tau))
    n = q.shape[0]
    if not 0 <= k_swap < n - 1:
        raise ParameterError(f"k_swap must lie in [0, {n - 2}] for a record of {n} samples, got {k_swap}")
    sg = validate_sigma(sigma_after)
    var = output_variances(position_variance, velocity_variance, measured)
    a, _, p = local_sensitivities(q[k_swap:], qd[k_swap:], tau[k_swap:], sg, sample_period, substeps)
    if others == "known":
        var_m = _mass_variance_known(a, p, 1.0 / var, payload_direction)
    else:
        var_m = _mass_variance_unknown(a, p, 1.0 / var)
    hit = np.flatnonzero(z * np.sqrt(var_m) <= rel * mass)
    return None if hit.size == 0 else float(hit[0] * sample_period)


def _mass_variance_known(a, p, w, payload_direction) -> Array:
    """Cramér-Rao variance of the mass at each sample after the swap, the arm without payload
    known (the information along ``payload_direction`` only); inf before any information."""
    s = chain_sensitivities(a, p @ np.asarray(payload_direction, float)[:, None])[..., 0]
    info = np.cumsum(np.einsum("ki,i,ki->k", s, w, s))
    with np.errstate(divide="ignore"):
        return np.where(info > 0, 1.0 / np.where(info > 0, info, 1.0), np.inf)


def _mass_variance_unknown(a, p, w) -> Array:
    """Cramér-Rao variance of the mass read from all seven estimated base parameters
    (:func:`_mass_functional`) at each sample after the swap; inf while the information is singular."""
    s = chain_sensitivities(a, p)
    info = np.cumsum(np.einsum("kia,i,kib->kab", s, w, s), axis=0)
    c = _mass_functional()
    ok = np.linalg.matrix_rank(info, hermitian=True) == 7
    var_m = np.full(info.shape[0], np.inf)
    var_m[ok] = np.einsum("i,kij,j->k", c, np.linalg.inv(info[ok]), c)
    return var_m
