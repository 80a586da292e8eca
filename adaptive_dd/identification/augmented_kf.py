"""Online estimation of sigma: an extended Kalman filter on the state augmented with sigma.

State ``x = [q1, q2, qd1, qd2, J1, J2, r, b1, b2, d1, d2]`` (11). Between samples the arm
part moves by the compiled stick-slip step (:func:`adaptive_dd.plant.two_link_integrator.two_link_plant_step`)
under the known applied torque, sigma stays (or walks with variance ``param_variance``):

    x_{k+1} = [f(x_k, sigma, tau_k); sigma],     y_k = [q_k, qd_k] + e_k   (measured rows)

The covariance is propagated with ``F = [[A_k, P_k], [0, I]]`` from the forward
sensitivity equations of :mod:`adaptive_dd.identification.sensitivity`, and process noise
``G_k Q_tau G_k^T`` from a small white torque noise (model error, linearisation). The
measurement update is the linear Kalman update (the outputs are part of the state), in
Joseph form; the same equations as ``filterpy.kalman.update`` (the tests check it).

Pure core and thin wrapper, as elsewhere in :mod:`adaptive_dd.identification`:
:func:`akf_predict`, :func:`akf_update` and :func:`akf_step` take and return an immutable
:class:`AKFState` (batch axis first); :class:`AugmentedKalmanFilter` keeps the state and
the last torque, sample by sample, for use inside a control loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.experiments import TABLE2
from adaptive_dd.identification.fisher import SIGNALS, output_variances
from adaptive_dd.identification.sensitivity import local_sensitivities
from adaptive_dd.plant.parameters import project_sigma
from adaptive_dd.plant.two_link_integrator import two_link_plant_step

__all__ = [
    "AKFConfig",
    "AKFState",
    "AugmentedKalmanFilter",
    "akf_init",
    "akf_predict",
    "akf_step",
    "akf_update",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class AKFConfig:
    """Settings of the augmented-state EKF.

    Attributes
    ----------
    sample_period : float
        T [s].
    substeps : int
        RK4 steps per sample of the model.
    position_variance, velocity_variance : (float, float)
        Measurement noise variances [rad^2], [(rad/s)^2] (Table 2 / Table 4).
    torque_variance : (float, float)
        White torque noise of the model [(N m)^2]: covers linearisation and model error.
    param_variance : float
        Random walk of sigma per sample, relative (``Q_sigma = param_variance diag(sigma^2)``);
        0 for constant parameters, > 0 to track a payload swap.
    measured : tuple of {"q", "qd"}
    jacobian_substeps : int
        RK4 steps per sample of the sensitivity equations that propagate P (the state
        itself moves by ``substeps``); one is plenty for a covariance and halves the cost.
    """

    sample_period: float = TABLE2["sample_period"]
    substeps: int = 2
    position_variance: tuple[float, float] = TABLE2["position_variance"]
    velocity_variance: tuple[float, float] = TABLE2["velocity_variance"]
    torque_variance: tuple[float, float] = (1e-6, 1e-6)
    param_variance: float = 0.0
    measured: tuple[str, ...] = SIGNALS
    jacobian_substeps: int = 1

    def __post_init__(self) -> None:
        if not self.sample_period > 0 or min(self.substeps, self.jacobian_substeps) < 1:
            raise ParameterError(
                f"AKFConfig: need sample_period > 0 and substeps >= 1, got {self.sample_period}, "
                f"{self.substeps}"
            )
        if min(self.torque_variance) < 0 or self.param_variance < 0:
            raise ParameterError(
                f"AKFConfig: torque_variance and param_variance must be >= 0, got "
                f"{self.torque_variance}, {self.param_variance}"
            )
        output_variances(self.position_variance, self.velocity_variance, self.measured)


@dataclass(frozen=True)
class AKFState:
    """Estimate and covariance of the augmented state.

    Attributes
    ----------
    x : ndarray (..., 11)
        ``[q1 q2 qd1 qd2 J1 J2 r b1 b2 d1 d2]``.
    P : ndarray (..., 11, 11)
    stuck, slip : ndarray (..., 2)
        Friction modes of the predicted arm (as :func:`two_link_plant_step` keeps them).
    """

    x: Array
    P: Array
    stuck: NDArray[np.bool_]
    slip: Array

    @property
    def sigma(self) -> Array:
        """Current estimate of sigma, ``(..., 7)``."""
        return self.x[..., 4:]

    @property
    def sigma_std(self) -> Array:
        """Standard deviations of sigma from P, ``(..., 7)``."""
        return np.sqrt(np.abs(np.diagonal(self.P, axis1=-2, axis2=-1)[..., 4:]))


def akf_init(
    sigma0: ArrayLike,
    sigma_std: ArrayLike,
    q0: ArrayLike,
    qd0: ArrayLike,
    cfg: AKFConfig = AKFConfig(),
) -> AKFState:
    """Initial state: sigma0 with std ``sigma_std``, the arm at ``q0, qd0`` known to the sensor noise.

    Parameters
    ----------
    sigma0, sigma_std : array_like (..., 7)
    q0, qd0 : array_like (..., 2)
        E.g. the first measurement.
    """
    sg = np.asarray(sigma0, dtype=float)
    q0, qd0 = np.asarray(q0, dtype=float), np.asarray(qd0, dtype=float)
    shape = np.broadcast_shapes(sg.shape[:-1], q0.shape[:-1], qd0.shape[:-1], np.shape(sigma_std)[:-1])
    x = np.concatenate(
        [np.broadcast_to(a, (*shape, a.shape[-1])) for a in (q0, qd0, project_sigma(sg))], axis=-1
    )
    var_x = np.concatenate((cfg.position_variance, cfg.velocity_variance))
    var = np.concatenate(
        (np.broadcast_to(var_x, (*shape, 4)), np.broadcast_to(np.square(sigma_std), (*shape, 7))), axis=-1
    )
    p = var[..., :, None] * np.eye(11)
    return AKFState(x, p, np.zeros((*shape, 2), dtype=bool), np.ones((*shape, 2)))


def akf_predict(state: AKFState, tau: ArrayLike, cfg: AKFConfig) -> AKFState:
    """Propagate over one sample with the applied torque ``tau (..., 2)`` held."""
    x = state.x
    sg = project_sigma(x[..., 4:])
    q1, qd1, stuck, slip = two_link_plant_step(
        x[..., :2],
        x[..., 2:4],
        state.stuck,
        state.slip,
        np.asarray(tau, float),
        sg,
        cfg.sample_period,
        cfg.substeps,
    )
    tau2 = np.broadcast_to(np.asarray(tau, float)[..., None, :], (*x.shape[:-1], 2, 2))
    a, g, p = local_sensitivities(
        np.stack((x[..., :2], q1), -2),
        np.stack((x[..., 2:4], qd1), -2),
        tau2,
        sg,
        cfg.sample_period,
        cfg.jacobian_substeps,
    )
    f = np.zeros_like(state.P)
    f[..., :4, :4], f[..., :4, 4:] = a[..., 0, :, :], p[..., 0, :, :]
    f[..., 4:, 4:] = np.eye(7)
    qn = np.zeros_like(state.P)
    gk = g[..., 0, :, :]
    qn[..., :4, :4] = gk @ np.diag(cfg.torque_variance) @ np.swapaxes(gk, -1, -2)
    qn[..., 4:, 4:] = cfg.param_variance * sg[..., :, None] ** 2 * np.eye(7)
    pn = f @ state.P @ np.swapaxes(f, -1, -2) + qn
    xn = np.concatenate((q1, qd1, x[..., 4:]), axis=-1)
    return AKFState(xn, 0.5 * (pn + np.swapaxes(pn, -1, -2)), stuck, slip)


def akf_update(
    state: AKFState, q_meas: ArrayLike, qd_meas: ArrayLike, cfg: AKFConfig
) -> tuple[AKFState, dict]:
    """Kalman update with the measured ``q, qd (..., 2)``; returns the state and ``{"innovation", "S"}``.

    Joseph form ``(I - K H) P (I - K H)^T + K R K^T``; sigma is projected onto physically
    consistent values afterwards (:func:`~adaptive_dd.plant.parameters.project_sigma`).
    """
    var = output_variances(cfg.position_variance, cfg.velocity_variance, cfg.measured)
    rows = np.flatnonzero(np.isfinite(var))
    y = np.concatenate((np.asarray(q_meas, float), np.asarray(qd_meas, float)), axis=-1)[..., rows]
    if not np.all(np.isfinite(y)):
        raise SignalError(f"akf_update: non-finite measurement {y}")
    h = np.eye(11)[rows]
    r = np.diag(var[rows])
    innov = y - state.x[..., rows]
    ph = state.P[..., :, rows]  # P H^T
    s = state.P[..., rows[:, None], rows[None, :]] + r
    k = np.swapaxes(np.linalg.solve(s, np.swapaxes(ph, -1, -2)), -1, -2)
    x = state.x + np.einsum("...ij,...j->...i", k, innov)
    ikh = np.eye(11) - k @ h
    p = ikh @ state.P @ np.swapaxes(ikh, -1, -2) + k @ r @ np.swapaxes(k, -1, -2)
    x[..., 4:] = project_sigma(x[..., 4:])
    stuck = state.stuck & (x[..., 2:4] == 0.0)
    return AKFState(x, 0.5 * (p + np.swapaxes(p, -1, -2)), stuck, state.slip), {"innovation": innov, "S": s}


def akf_step(
    state: AKFState, tau_prev: ArrayLike, q_meas: ArrayLike, qd_meas: ArrayLike, cfg: AKFConfig
) -> tuple[AKFState, dict]:
    """One sample: predict over the last sample (torque ``tau_prev``), update with this one's measurement."""
    return akf_update(akf_predict(state, tau_prev, cfg), q_meas, qd_meas, cfg)


class AugmentedKalmanFilter:
    """Sample-by-sample online estimator of sigma (thin stateful wrapper of :func:`akf_step`).

    Parameters
    ----------
    sigma0, sigma_std : array_like (..., 7)
        Initial estimate and its standard deviation.
    cfg : AKFConfig

    Call :meth:`step` once per sample with the measurement at that sample and the torque
    that will be applied over it; the first call only updates.
    """

    def __init__(self, sigma0: ArrayLike, sigma_std: ArrayLike, cfg: AKFConfig = AKFConfig()) -> None:
        self.sigma0, self.sigma_std0 = np.asarray(sigma0, float), np.asarray(sigma_std, float)
        self.cfg = cfg
        self.state: AKFState | None = None
        self._tau: Array | None = None

    @property
    def theta(self) -> Array:
        """Current estimate of sigma ``(..., 7)`` (sigma0 before the first sample)."""
        return self.sigma0 if self.state is None else self.state.sigma

    def step(self, q_meas: ArrayLike, qd_meas: ArrayLike, tau: ArrayLike) -> Array:
        """Feed the measurement at this sample and the torque applied over it; return sigma_hat."""
        if self.state is None:
            st = akf_init(self.sigma0, self.sigma_std0, q_meas, qd_meas, self.cfg)
            self.state, _ = akf_update(st, q_meas, qd_meas, self.cfg)
        else:
            self.state, _ = akf_step(self.state, self._tau, q_meas, qd_meas, self.cfg)
        self._tau = np.asarray(tau, dtype=float)
        return self.state.sigma

    def run(self, q_meas: ArrayLike, qd_meas: ArrayLike, tau: ArrayLike) -> Array:
        """Feed whole records ``(..., N, 2)``; return the estimates ``(..., N, 7)``."""
        q_meas, qd_meas, tau = (np.asarray(a, dtype=float) for a in (q_meas, qd_meas, tau))
        out = np.empty((*q_meas.shape[:-1], 7))
        for k in range(q_meas.shape[-2]):
            out[..., k, :] = self.step(q_meas[..., k, :], qd_meas[..., k, :], tau[..., k, :])
        return out
