"""Kalman-filter parameter estimator built on ``filterpy.kalman.KalmanFilter``.

The parameters are the state of a random walk, ``sigma(t+1) = sigma(t) + w``,
``w ~ N(0, Q)``, observed through ``y = Phi(t) sigma + v``, ``v ~ N(0, R)``:
``F = I``, ``H = Phi(t)`` (changing every sample). With ``Q = 0``, ``R = 1`` and
filterpy's fading memory ``alpha = 1/sqrt(lambda)`` this is exactly RLS with
forgetting factor lambda (the tests check it), the trace of ``P`` capped as
:func:`~adaptive_dd.identification.rls.rls_step` caps it (at its start, ``n p0``; with
fading memory only: unexcited, it grows without bound); ``Q > 0`` lets the estimate
track slowly changing parameters without forgetting everything.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError

__all__ = ["KalmanParameterEstimator"]


class KalmanParameterEstimator:
    """Random-walk parameter estimator for one trial.

    Parameters
    ----------
    n_params, n_outputs : int
    q : float
        Random-walk variance per sample (``Q = q I``), >= 0.
    r : float or array_like
        Measurement noise variance (``R = r I`` or a given matrix), > 0.
    p0 : float
        Initial covariance ``p0 I``.
    theta0 : array_like, optional
        Initial estimate (default 0).
    alpha : float
        filterpy's fading-memory factor (>= 1; 1 = none).
    """

    def __init__(
        self,
        n_params: int,
        n_outputs: int = 2,
        q: float = 0.0,
        r: float | ArrayLike = 1.0,
        p0: float = 100.0,
        theta0: ArrayLike | None = None,
        alpha: float = 1.0,
    ) -> None:
        if q < 0:
            raise ParameterError(f"random-walk variance q must be >= 0, got {q}")
        if p0 <= 0:
            raise ParameterError(f"p0 must be > 0, got {p0}")
        if alpha < 1:
            raise ParameterError(f"fading-memory alpha must be >= 1, got {alpha}")
        from filterpy.kalman import KalmanFilter  # here: it imports SciPy's statistics (1 CPU s)

        kf = KalmanFilter(dim_x=n_params, dim_z=n_outputs)
        kf.F = np.eye(n_params)
        kf.Q = q * np.eye(n_params)
        rr = np.asarray(r, dtype=float)
        kf.R = rr * np.eye(n_outputs) if rr.ndim == 0 else rr
        if np.any(np.linalg.eigvalsh(kf.R) <= 0):
            raise ParameterError(f"R must be positive definite, got {kf.R}")
        kf.P = p0 * np.eye(n_params)
        kf.x = np.zeros(n_params) if theta0 is None else np.asarray(theta0, dtype=float).copy()
        kf.alpha = alpha
        self.kf = kf
        self.max_trace = p0 * n_params
        self.n_skipped = 0

    @property
    def theta(self) -> NDArray[np.float64]:
        return np.asarray(self.kf.x).reshape(-1)

    @property
    def P(self) -> NDArray[np.float64]:
        return np.asarray(self.kf.P)

    def update(self, phi: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Predict (random walk) and update with ``y = phi @ sigma``; a non-finite sample is skipped."""
        phi = np.atleast_2d(np.asarray(phi, dtype=float))
        y = np.atleast_1d(np.asarray(y, dtype=float))
        if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(y))):
            self.n_skipped += 1
            return self.theta
        self.kf.predict()
        self.kf.update(y, H=phi)  # x is kept 1-D, so z is 1-D too
        tr = float(np.trace(self.kf.P))
        if self.kf.alpha > 1.0 and tr > self.max_trace:  # fading memory unexcited winds P up (rls_step)
            self.kf.P = self.kf.P * (self.max_trace / tr)
        return self.theta

    def run(self, phi: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Feed a record ``phi (N, m, n)``, ``y (N, m)``; return estimates ``(N, n)``."""
        phi = np.asarray(phi, dtype=float)
        y = np.asarray(y, dtype=float)
        out = np.empty((phi.shape[0], phi.shape[-1]))
        for k in range(phi.shape[0]):
            out[k] = self.update(phi[k], y[k])
        return out
