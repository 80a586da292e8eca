"""The exact filtered regression of any serial arm, and weighted least squares on it.

The two-link "exact" construction (:mod:`adaptive_dd.identification.regressors`) filters
the whole equation of motion so that no acceleration is needed. For N joints the same
holds through the generalised momentum ``p = M(q) qd``, linear in the parameters:

    tau = d/dt [Y_p(q, qd)] sigma + Y_r(q, qd) sigma,
    Y_p(q, qd) = W(q, 0, qd) - W(q, 0, 0)                      (momentum regressor)
    Y_r(q, qd) = W(q, qd, 0) - dY_p/dq (q, qd) qd              (Coriolis, gravity, friction)

(``W`` the base regressor; ``Y_p`` is linear in ``qd``, so ``d/dt Y_p = dY_p/dq qd +
Y_p(q, qdd)`` and ``W(q, qd, qdd) = W(q, qd, 0) + Y_p(q, qdd)``). The directional derivative
``dY_p/dq qd`` is a central difference along the motion, ``(Y_p(q + e qd) - Y_p(q - e qd)) /
2e`` with ``e = 1e-4`` s (error ~ e^2, below 1e-8 relative). Filtering with
``G0 = 1/(1 + tau_f s)^2`` and ``G1 = s G0`` (method M2, Tustin, as the two-link path):

    G0 tau = (G1 Y_p + G0 Y_r) sigma =: Phi sigma,

exact for the noise-free signals up to the discretisation of the filters (the applied
torque is held over each sample, so the filter is fed the mean of neighbouring samples,
which Tustin's trapezoidal rule integrates back to the held value). Weighted least
squares then weights each joint's equations by the inverse std of its residuals (two
passes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import DataError, SignalError
from adaptive_dd.identification.filters import design_filter_bank, filter_record
from adaptive_dd.identification.model import Model, _friction_columns
from adaptive_dd.plant.chain import regressor_batch

__all__ = [
    "Regression",
    "WlsResult",
    "check_excitation",
    "check_motion",
    "filter_pieces",
    "filtered_regression",
    "momentum_regressors",
    "weighted_least_squares",
]

Array = NDArray[np.float64]
DIRECTION_STEP = 1e-4
"""e [s] of the central difference along the motion."""


@dataclass(frozen=True)
class Regression:
    """``y[k] = phi[k] @ sigma`` (+ error) over one record, transient cut.

    Attributes
    ----------
    phi : ndarray (N', n, p)
    y : ndarray (N', n)
        ``G0 tau`` [N m].
    start : int
        First sample kept of each piece (the filters' transient of 10 tau_f is cut).
    tau_f : float
    pieces : tuple of (int, int) or None
        The record's continuous pieces ``[a, b)`` (sample indices) the rows come from, in order,
        each filtered on its own and its first ``start`` samples cut; None: one piece, the record.
    """

    phi: Array
    y: Array
    start: int
    tau_f: float
    pieces: tuple[tuple[int, int], ...] | None = None

    def row_bounds(self) -> list[tuple[int, int]]:
        """``[(r0, r1), ...]``: the rows of ``phi`` and ``y`` of each piece."""
        if self.pieces is None:
            return [(0, self.y.shape[0])]
        out, r = [], 0
        for a, b in self.pieces:
            m = b - a - min(self.start, b - a - 1)
            out.append((r, r + m))
            r += m
        return out

    def samples(self) -> NDArray[np.int64]:
        """``(N',)``: the record's sample index of each row."""
        if self.pieces is None:
            return np.arange(self.start, self.start + self.y.shape[0])
        return np.concatenate([np.arange(a + min(self.start, b - a - 1), b) for a, b in self.pieces])


def momentum_regressors(model: Model, q: ArrayLike, qd: ArrayLike) -> tuple[Array, Array]:
    """``Y_p(q, qd)`` and ``Y_r(q, qd)``, each ``(..., n, p)`` (module docstring).

    ``Y_p(x, qd) = W(x, 0, qd) - W(x, 0, 0)`` is the links' regressor under no gravity (it enters
    as the base's acceleration, linearly with ``qdd``), one evaluation of the compiled regressor
    at each of ``q`` and ``q +- e qd``, plus the armature's column ``qd`` (the friction's are 0);
    ``Y_r``'s friction columns are ``qd`` and ``tanh(qd / v_f)`` (those of ``dY_p/dq qd`` are 0)."""
    q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
    q, qd = np.broadcast_arrays(q, qd)
    n, ind = model.n, model.independent
    links = ind < 10 * n  # the links' base columns, then friction and armature (ind is sorted)
    cols, r = ind[links], int(links.sum())
    free = model.chain._replace(gravity=np.zeros(3))
    zero = np.zeros_like(q)

    def yp(x):
        return regressor_batch(free, x, zero, qd)[..., cols]

    e = DIRECTION_STEP
    Yp = np.zeros((*q.shape, model.p))
    Yr = np.zeros((*q.shape, model.p))
    Yp[..., :r] = yp(q)
    Yr[..., :r] = regressor_batch(model.chain, q, qd, zero)[..., cols]
    Yr[..., :r] -= (yp(q + e * qd) - yp(q - e * qd)) / (2.0 * e)
    extra = ind[~links] - 10 * n  # the friction and armature columns kept in the base
    Yp[..., r:] = _friction_columns(model, zero, qd)[..., extra]  # the armature's qd
    Yr[..., r:] = _friction_columns(model, qd, zero)[..., extra]  # qd, tanh(qd / v_f)
    return Yp, Yr


def filter_pieces(bank, x: Array, pieces, start: int, output: int) -> Array:
    """Output ``output`` of ``bank`` on each continuous piece ``[a, b)`` of ``x (N, ...)`` on its own
    (each from the steady state of its first sample), each piece's first ``start`` samples cut (at
    most all but one), the pieces concatenated; ``pieces`` None: one piece, the whole of ``x``."""
    if pieces is None:
        pieces = ((0, x.shape[0]),)
    parts = []
    for a, b in pieces:
        seg = x[a:b]
        y = filter_record(bank, seg, axis=0, initial=seg[0], outputs=(output,))[..., 0]
        parts.append(y[min(start, b - a - 1) :])
    return np.concatenate(parts, axis=0)


def filtered_regression(
    model: Model,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    *,
    tau_f: float = 0.02,
    sample_period: float = 1e-3,
    torque_held: bool = True,
    pieces=None,
    momentum: tuple[Array, Array] | None = None,
) -> Regression:
    """The exact filtered regression of one record (module docstring).

    Parameters
    ----------
    q, qd, tau : array_like (N, n)
        Measured positions [rad], velocities [rad/s], applied torque [N m].
    tau_f : float
        Filter time constant [s].
    sample_period : float
        T [s].
    torque_held : bool
        The torque is held over each sample (a simulator's or a drive's applied command: the
        filter is fed the mean of neighbouring samples, see the module docstring); False for a
        sampled measurement of a continuous torque (a real log's effort), fed as it is.
    pieces : sequence of (int, int), optional
        The record's continuous pieces ``[a, b)``, each filtered on its own (:class:`Regression`).
    momentum : (ndarray, ndarray), optional
        :func:`momentum_regressors` ``(model, q, qd)``, when the caller has them: they do not depend
        on the filter, so a caller that filters one record at several time constants (an
        identification and its :func:`~adaptive_dd.identification.model_error.model_error_variance`)
        computes them once; default computed here.

    Raises
    ------
    SignalError
        Shapes differ, values are not finite, or ``momentum`` is not ``(N, n, p)`` twice.
    """
    q, qd, tau = (np.asarray(a, dtype=float) for a in (q, qd, tau))
    if not (q.shape == qd.shape == tau.shape and q.ndim == 2 and q.shape[1] == model.n):
        raise SignalError(
            f"q, qd, tau must be (N, {model.n}) records of one length, got {q.shape}, {qd.shape}, {tau.shape}"
        )
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(tau))):
        raise SignalError("q, qd, tau must be finite")
    check_motion(q, model.names)
    bank = design_filter_bank("M2", tau_f, sample_period)
    if momentum is None:
        Yp, Yr = momentum_regressors(model, q, qd)
    else:
        Yp, Yr = momentum
        shape = (q.shape[0], model.n, model.p)
        if np.shape(Yp) != shape or np.shape(Yr) != shape:
            raise SignalError(
                f"momentum must be momentum_regressors(model, q, qd), two {shape} arrays, got "
                f"{np.shape(Yp)} and {np.shape(Yr)}"
            )
    start = int(np.ceil(10 * tau_f / sample_period))
    fp = filter_pieces(bank, Yp, pieces, start, 1)
    fr = filter_pieces(bank, Yr, pieces, start, 0)
    # the torque is held over each sample (zero-order hold); the Tustin filters integrate
    # trapezoidally between samples, so they see the held torque as the mean of neighbours (the
    # filter starts from the steady state of the first value: the mean of the first with itself)
    tau_mid = np.concatenate((tau[:1], 0.5 * (tau[1:] + tau[:-1]))) if torque_held else tau.copy()
    for a, _ in pieces or ():
        tau_mid[a] = tau[a]  # each piece starts on its own first sample
    y = filter_pieces(bank, tau_mid, pieces, start, 0)
    if pieces is None:
        start = min(start, q.shape[0] - 1)
        return Regression(fp + fr, y, start, float(tau_f))
    pieces = tuple((int(a), int(b)) for a, b in pieces)
    return Regression(fp + fr, y, start, float(tau_f), pieces)


@dataclass(frozen=True)
class WlsResult:
    """Weighted least squares on a :class:`Regression`.

    Attributes
    ----------
    sigma : ndarray (p,)
    std : ndarray (p,)
        From ``(Phi^T W Phi)^-1`` with the residuals' per-joint variances (white-residual formula:
        the filtered residuals are coloured, so this is optimistic).
    residual_std : ndarray (n,)
        Per joint [N m].
    """

    sigma: Array
    std: Array
    residual_std: Array


def weighted_least_squares(reg: Regression, names: tuple[str, ...] = ()) -> WlsResult:
    """Two-pass WLS: ordinary least squares, then each joint weighted by ``1 / std`` of its residuals.

    Raises
    ------
    DataError
        The record does not excite some base parameter (:func:`check_excitation`).
    """
    phi, y = reg.phi, reg.y
    n, p = phi.shape[1], phi.shape[2]
    check_excitation(phi, names)
    w = np.ones(n)
    for _ in range(2):
        A = (phi * w[None, :, None]).reshape(-1, p)
        b = (y * w).reshape(-1)
        scale = np.linalg.norm(A, axis=0)
        sol, *_ = np.linalg.lstsq(A / scale, b, rcond=None)
        sigma = sol / scale
        res = y - np.einsum("knp,p->kn", phi, sigma)
        rstd = np.sqrt(np.mean(res**2, axis=0))
        w = 1.0 / np.maximum(rstd, 1e-12 * max(rstd.max(), 1e-300))
    A = (phi * w[None, :, None]).reshape(-1, p)
    scale = np.linalg.norm(A, axis=0)
    cov = np.linalg.inv((A / scale).T @ (A / scale)) / np.outer(scale, scale)
    return WlsResult(sigma, np.sqrt(np.abs(np.diag(cov))), rstd)


MIN_MOTION = 0.01
"""rad: a joint whose position range is below this has not moved (its friction is not excited)."""


def check_motion(q: Array, names: tuple[str, ...]) -> None:
    """Refuse a record in which some joint does not move, naming the base parameters it leaves unseen.

    Raises
    ------
    DataError
        Naming the joint, its range and its friction and armature parameters (those whose base
        name is ``fv<j>``, ``fc<j>``, ``Ia<j>`` or contains them).
    """
    span = np.ptp(q, axis=0)
    for j in np.flatnonzero(span < MIN_MOTION):
        tags = (f"fv{j + 1}", f"fc{j + 1}", f"Ia{j + 1}")
        hit = [nm for nm in names if any(t in nm.replace(" ", "").split("+") for t in tags)]
        raise DataError(
            f"the record does not excite base parameter(s) {', '.join(repr(h) for h in hit) or tags}: "
            f"joint {j + 1} moves only {span[j]:.2g} rad (less than {MIN_MOTION} rad)"
        )


def check_excitation(
    phi: Array, names: tuple[str, ...] = (), rtol: float = 1e-7, weak_ok: bool = False
) -> None:
    """Refuse a regression in which some base parameter is not excited.

    The columns of ``phi (N, n, p)`` are scaled to unit norm; a singular value below
    ``rtol`` times the largest marks a direction the record does not see, and the
    parameters with the largest components in it are named. ``weak_ok``: only a zero column is
    refused (the caller holds the directions the record cannot see at a prior,
    :mod:`~adaptive_dd.identification.held_directions`).

    Raises
    ------
    DataError
        Naming the parameter(s).
    """
    p = phi.shape[-1]
    A = phi.reshape(-1, p)
    norms = np.linalg.norm(A, axis=0)
    label = names if len(names) == p else tuple(f"sigma[{k}]" for k in range(p))
    dead = np.flatnonzero(norms <= 1e-12 * max(norms.max(), 1e-300))
    if dead.size:
        raise DataError(
            "the record does not excite base parameter(s) "
            + ", ".join(repr(label[k]) for k in dead[:5])
            + ": their regressor columns are zero (a joint that does not move?)"
        )
    if weak_ok:
        return
    # the SVD of the triangular factor: A's singular values and right vectors, at a QR's cost
    _, s, vt = np.linalg.svd(np.linalg.qr(A / norms, mode="r"), full_matrices=False)
    weak = np.flatnonzero(s < rtol * s[0])
    if weak.size:
        v = vt[weak[-1]]
        top = np.argsort(-np.abs(v))[:3]
        raise DataError(
            f"the record does not excite base parameter {label[top[0]]!r} (singular value "
            f"{s[weak[-1]] / s[0]:.2g} of the largest; the unseen direction also involves "
            + ", ".join(repr(label[k]) for k in top[1:])
            + "): move the joints it belongs to more, or longer"
        )
