"""Model error an identification can see: estimates that agree when the model is the plant's law.

The exact filtered regression (:mod:`adaptive_dd.identification.regression`) holds for any
filter time constant and any channel weighting, so with the right model the weighted least
squares of :func:`~adaptive_dd.identification.log_fit.fit_log`, its unweighted estimate and
its estimates at ``tau_f / 2`` and ``2 tau_f`` differ by noise only. With a model that is not
the plant's law (the identification's ``tanh`` Coulomb friction against a plant's stick-slip
or Stribeck law) each weighting finds another best fit, and their differences are a
measure of the bias that the sandwich covariance (a variance about the misspecified best fit)
does not hold: Hausman's specification test (Hausman, "Specification tests in econometrics",
Econometrica 46, 1978) read as a variance. :func:`model_error_variance` is the sum of their
squared differences from the fit, per base parameter, added to the prior an identification
hands on (:func:`~adaptive_dd.identification.arm_prior.identified_prior_std`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["FILTER_FACTORS", "model_error_variance"]

Array = NDArray[np.float64]
FILTER_FACTORS = (0.5, 2.0)
"""The other filter time constants, as multiples of the fit's ``tau_f``."""


def model_error_variance(
    model, fit, q: Array, qd: Array, tau: Array, torque_held: bool = True, momentum=None
) -> Array:
    """``(p,)`` sum of the squared differences from ``fit.sigma`` (a
    :class:`~adaptive_dd.identification.log_fit.LogFit` of the record ``q, qd, tau (N, n)``) of the
    unweighted estimate and of the weighted ones at ``tau_f`` times :data:`FILTER_FACTORS`, on the
    same channels and base parameters (zero for those held at the URDF's), each held along the
    fit's held directions (:attr:`~adaptive_dd.identification.log_fit.LogFit.held`). ``momentum``: the
    record's :func:`~adaptive_dd.identification.regression.momentum_regressors` (the fit's, which do not
    depend on the filter), computed here when None."""
    from adaptive_dd.identification.log_fit import _identified_regression, _reweighted_fit, _solve
    from adaptive_dd.identification.regression import filtered_regression

    K, used = fit.identified, fit.used
    ones = np.ones(int(used.sum()))
    weak_ok = fit.held is not None
    phi, y = _centred(fit, *_identified_regression(model, fit.regression, used, K, weak_ok))
    alts = [_solve(phi, y, ones)[0]]
    for f in FILTER_FACTORS:
        reg = filtered_regression(
            model,
            q,
            qd,
            tau,
            tau_f=f * fit.tau_f,
            sample_period=fit.sample_period,
            torque_held=torque_held,
            pieces=fit.regression.pieces,
            momentum=momentum,
        )
        phi, y = _centred(fit, *_identified_regression(model, reg, used, K, weak_ok))
        alts.append(_reweighted_fit(phi, y, ones)[0])
    var = np.zeros(model.p)
    for a in alts:
        full = fit.sigma.copy()
        full[K] = a
        if fit.held is not None:  # the same directions held: what the record cannot see is not error
            full = fit.held.apply(full, model.sigma_ref)
        var[K] += (full[K] - fit.sigma[K]) ** 2
    return var


def _centred(fit, phi: Array, y: Array) -> tuple[Array, Array]:
    """``phi, y`` about each channel's mean when the fit has torque offsets (as it was fitted)."""
    if fit.offset is None:
        return phi, y
    return phi - phi.mean(axis=0), y - y.mean(axis=0)
