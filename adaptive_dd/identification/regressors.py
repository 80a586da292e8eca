"""From measured signals to the filtered linear regression ``y = Phi sigma``.

Two constructions, each for method M1 (position only) and M2 (position and velocity):

``"paper"`` (eqs. 17 and 19)
    Filter the signals, then evaluate the regressor of eq. (8) on them:
    ``Phi(G0 q, G0 qd, G1 qd)`` with Coulomb columns ``G0 sgn(qd)`` (M2), or
    ``Phi(G0 q, G1 q, G2 q)`` with ``G0 sgn((q(t) - q(t-1))/T)`` (M1); ``y = G0 tau``.
    Because Phi is nonlinear in q and qd, ``G0 tau != Phi(filtered) sigma``:
    a modelling error that no amount of data removes.

``"exact"`` (this package)
    Apply G0 to the whole equation ``tau = Phi sigma``. Since ``q1`` is cyclic in
    the horizontal arm, every column is a linear filter of functions of (q, qd):

    * ``phi13 = d/dt [cos q2 (2 qd1 + qd2)]``
    * ``phi23 = d/dt [cos q2 qd1] + sin q2 qd1 (qd1 + qd2)``

    so ``G0 phi13 = G1[cos q2 (2 qd1 + qd2)]`` and so on, and ``G0 tau = (G0 Phi) sigma``
    holds exactly for the true (noise-free) signals. For M1 the velocity is the
    backward difference of the measured position.

Both work on whole records (offline) and sample by sample (online, through
:class:`OnlineRegressor`); the same channel and assembly functions serve both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.identification.filters import FilterBank, StreamingFilter, design_filter_bank, filter_record
from adaptive_dd.plant.dynamics import _regressor

__all__ = [
    "CONSTRUCTIONS",
    "FilteredRegression",
    "OnlineRegressor",
    "two_link_filtered_regression",
]

Array = NDArray[np.float64]
CONSTRUCTIONS = ("paper", "exact")


@dataclass(frozen=True)
class FilteredRegression:
    """Filtered regression data ``y[k] = phi[k] @ sigma`` (+ error).

    Attributes
    ----------
    phi : ndarray, shape (..., n_samples, 2, 7)
    y : ndarray, shape (..., n_samples, 2)
        Filtered torque ``G0 tau`` [N m].
    construction, method : str
    tau_f : float
    """

    phi: Array
    y: Array
    construction: str
    method: str
    tau_f: float


def _check(construction: str, method: str) -> None:
    if construction not in CONSTRUCTIONS:
        raise ParameterError(f"construction must be one of {CONSTRUCTIONS}, got {construction!r}")
    if method not in ("M1", "M2"):
        raise ParameterError(f"method must be 'M1' or 'M2', got {method!r}")


def _channels(construction: str, method: str, q: Array, qd: Array, tau: Array) -> Array:
    """Raw (unfiltered) channels, shape (..., n_ch). For M1, ``qd`` is the backward difference."""
    if construction == "paper":
        first = q if method == "M1" else np.concatenate((q, qd), axis=-1)
        return np.concatenate((first, np.sign(qd), tau), axis=-1)
    c2, s2 = np.cos(q[..., 1]), np.sin(q[..., 1])
    qd1, qd2 = qd[..., 0], qd[..., 1]
    extra = np.stack((c2 * (2.0 * qd1 + qd2), c2 * qd1, s2 * qd1 * (qd1 + qd2)), axis=-1)
    return np.concatenate((qd, extra, np.sign(qd), tau), axis=-1)


def _assemble(construction: str, method: str, f: Array) -> tuple[Array, Array]:
    """Build (phi, y) from filtered channels ``f (..., n_ch, n_outputs)``."""
    if construction == "paper":
        if method == "M1":
            q_a, qd_a, qdd_a, rest = f[..., 0:2, 0], f[..., 0:2, 1], f[..., 0:2, 2], f[..., 2:, 0]
        else:
            q_a, qd_a, qdd_a, rest = f[..., 0:2, 0], f[..., 2:4, 0], f[..., 2:4, 1], f[..., 4:, 0]
        return _regressor(q_a, qd_a, qdd_a, rest[..., 0:2]), rest[..., 2:4]
    g0, g1 = f[..., 0], f[..., 1]
    shape = f.shape[:-2]
    phi = np.zeros((*shape, 2, 7))
    phi[..., 0, 0] = g1[..., 0]
    phi[..., :, 1] = (g1[..., 0] + g1[..., 1])[..., None]
    phi[..., 0, 2] = g1[..., 2]
    phi[..., 1, 2] = g1[..., 3] + g0[..., 4]
    phi[..., 0, 3] = g0[..., 0]
    phi[..., 1, 4] = g0[..., 1]
    phi[..., 0, 5] = g0[..., 5]
    phi[..., 1, 6] = g0[..., 6]
    return phi, g0[..., 7:9]


def _backward_difference(q: Array, T: float, axis: int = -2) -> Array:
    """``(q(t) - q(t-1)) / T`` along the time axis, 0 at the first sample."""
    d = np.diff(q, axis=axis) / T
    first = np.zeros_like(np.take(q, [0], axis=axis))
    return np.concatenate((first, d), axis=axis)


def two_link_filtered_regression(
    q: ArrayLike,
    tau: ArrayLike,
    qd: ArrayLike | None = None,
    *,
    method: str = "M2",
    construction: str = "paper",
    tau_f: float = 0.006,
    sample_period: float = 1e-3,
    bank: FilterBank | None = None,
) -> FilteredRegression:
    """Filtered regression of a whole record (offline path).

    Parameters
    ----------
    q, tau : array_like, shape (..., n_samples, 2)
        Measured joint angles [rad] and torques [N m].
    qd : array_like, shape (..., n_samples, 2), optional
        Measured velocities [rad/s]; required for M2, ignored by M1.
    method : {"M1", "M2"}
    construction : {"paper", "exact"}
    tau_f, sample_period : float
        Filter time constant and T [s] (or pass a designed ``bank``).

    The filters start in the steady state of the first sample.
    """
    _check(construction, method)
    q = np.asarray(q, dtype=float)
    tau = np.asarray(tau, dtype=float)
    if q.ndim < 2 or q.shape[-1] != 2 or tau.shape != q.shape:
        raise SignalError(f"q and tau must have equal shapes (..., n_samples, 2), got {q.shape}, {tau.shape}")
    bank = bank or design_filter_bank(method, tau_f, sample_period)
    if method == "M2":
        if qd is None:
            raise SignalError("method M2 needs the measured velocity qd")
        qd = np.asarray(qd, dtype=float)
        if qd.shape != q.shape:
            raise SignalError(f"qd must have the shape of q {q.shape}, got {qd.shape}")
    else:
        qd = _backward_difference(q, bank.sample_period)
    u = _channels(construction, method, q, qd, tau)  # (..., N, n_ch)
    u, tainted = _hold_nonfinite(u, _memory(bank))
    f = filter_record(bank, u, axis=-2, initial=u[..., 0, :])  # (..., N, n_ch, n_out)
    phi, y = _assemble(construction, method, f)
    phi[tainted] = np.nan
    y[tainted] = np.nan
    return FilteredRegression(phi, y, construction, method, bank.tau_f)


def _memory(bank: FilterBank) -> int:
    """Samples after which the filters have forgotten an input (10 tau_f)."""
    return int(np.ceil(10.0 * bank.tau_f / bank.sample_period))


def _hold_nonfinite(u: Array, memory: int) -> tuple[Array, NDArray[np.bool_]]:
    """Replace non-finite samples of ``u (..., N, n_ch)`` by the last finite one.

    Returns the held channels and a mask ``(..., N)`` of the samples whose filtered
    output is tainted (a non-finite input within the last ``memory`` samples); the
    caller marks those outputs non-finite so that estimators skip and count them,
    instead of the NaN running through the IIR filters to the end of the record.
    """
    bad = ~np.isfinite(u).all(axis=-1)
    if not bad.any():
        return u, bad
    n = u.shape[-2]
    k = np.arange(n)
    good_idx = np.maximum.accumulate(np.where(~bad, k, -1), axis=-1)
    first_good = np.argmax(~bad, axis=-1)[..., None]  # before any good sample: the first good one
    src = np.where(good_idx >= 0, good_idx, first_good)
    held = np.take_along_axis(u, src[..., None], axis=-2)
    held = np.where(np.isfinite(held), held, 0.0)
    last_bad = np.maximum.accumulate(np.where(bad, k, -(10**9)), axis=-1)
    return held, (k - last_bad) <= memory


class OnlineRegressor:
    """The same construction sample by sample (online path, for adaptive control).

    Parameters
    ----------
    batch_shape : tuple
        Leading shape of each sample, e.g. ``(n_trials,)``.
    method, construction, tau_f, sample_period
        As in :func:`two_link_filtered_regression`.
    """

    def __init__(
        self,
        batch_shape: tuple = (),
        *,
        method: str = "M2",
        construction: str = "exact",
        tau_f: float = 0.006,
        sample_period: float = 1e-3,
    ) -> None:
        _check(construction, method)
        self.method, self.construction = method, construction
        self.bank = design_filter_bank(method, tau_f, sample_period)
        self.batch_shape = tuple(batch_shape)
        self._filter: StreamingFilter | None = None
        self._q_prev: Array | None = None
        self._u_last: Array | None = None
        self._since_bad: NDArray[np.int_] | None = None

    def __call__(self, q: Array, tau: Array, qd: Array | None = None) -> tuple[Array, Array]:
        """Feed one sample; return ``phi (batch..., 2, 7)`` and ``y (batch..., 2)``."""
        if self.method == "M1":
            qd = np.zeros_like(q) if self._q_prev is None else (q - self._q_prev) / self.bank.sample_period
            self._q_prev = q
        elif qd is None:
            raise SignalError("method M2 needs the measured velocity qd")
        u = _channels(self.construction, self.method, q, qd, tau)
        bad = ~np.isfinite(u).all(axis=-1)
        if self._filter is None:
            self._u_last = np.where(np.isfinite(u), u, 0.0)
            self._since_bad = np.full(bad.shape, 10**9)
            self._filter = StreamingFilter(self.bank, u.shape, initial=self._u_last)
        u = np.where(bad[..., None], self._u_last, u)  # hold the last finite sample
        self._u_last = u
        self._since_bad = np.where(bad, 0, self._since_bad + 1)
        phi, y = _assemble(self.construction, self.method, self._filter(u))
        tainted = self._since_bad <= _memory(self.bank)
        if tainted.any():
            phi = np.where(tainted[..., None, None], np.nan, phi)
            y = np.where(tainted[..., None], np.nan, y)
        return phi, y
