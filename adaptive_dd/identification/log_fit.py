"""Weighted least squares on a real robot's log, with bounds that mean something on real data.

The regression is the exact filtered one of :mod:`adaptive_dd.identification.regression`
(``G0 tau = Phi sigma``, no acceleration needed; ``tau_f`` sized to the sample rate by
:func:`filter_time_constant`). What a real log adds:

Channels left out
    Torque channels that carry nothing (a wrist reading 0, a torso channel holding the
    robot's weight) are excluded: their rows leave the regression. The base parameters that
    the remaining channels cannot see, for any motion, stay at the URDF's values
    (:func:`identifiable_subset`: the standard regressor's rows of the kept channels at random
    states, unpivoted QR in the base order, as :mod:`adaptive_dd.plant.base_parameters` does);
    the others absorb the deviation of those fixed in combination with them.

Weights (the stated rule)
    Ordinary least squares first; then each kept channel j is weighted by ``c_j / s_j`` (``c_j``
    the user's ``torque_weight``, 1 by default), with
    ``s_j`` the rms of its filtered residual, floored at a tenth of the median over the kept
    channels (so a channel the model fits suspiciously well, a near-constant one, cannot take
    all the weight); three passes.

Torque offsets
    A real torque channel reads ``tau + b_j`` with ``b_j`` a constant (a strain gauge's zero, a
    current loop's bias, a conversion's offset). With ``offset`` each kept channel's ``b_j`` is
    fitted too: ``G0`` passes a constant unchanged, so it is a column of ones in that channel's
    rows, profiled out by fitting each channel's rows about their mean (exact for the per-channel
    weights; the sandwich is that of the fit with the offset columns, so the std of the
    parameters that trade with an offset, a gravity term that hardly changes over the record,
    carry it). ``identify --torque-offset`` (default: on for a record read through a ``[record]``
    table, off for the simulator's records, whose torques have none).

Standard deviations and bounds
    The Newey-West sandwich within each continuous piece, scaled for what the Bartlett sum leaves
    out and the degrees of freedom, and the fixed-b quantile ``c`` of the 95 % bound
    ``estimate +- c std``: :mod:`adaptive_dd.identification.log_covariance`.

Noise levels
    Each channel's sensor noise is estimated from the logged torque's second difference
    (white noise of std ``s`` has a second difference of std ``sqrt(6) s``; real torque
    content makes this an upper bound), then passed through ``G0``. A residual far above it
    (:data:`MODEL_ERROR_RATIO`) is reported as model error, with the ratio.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import DataError, ParameterError
from adaptive_dd.identification.filters import design_filter_bank, filter_record
from adaptive_dd.identification.held_directions import Held, base_prior_std, hold_unseen
from adaptive_dd.identification.log_covariance import (  # noqa: F401  (re-exported: tests import them here)
    MAX_DOF_FACTOR,
    NORMAL_975,
    _bartlett_sum,
    _dof_factor,
    _kernel_bias,
    bandwidth_fraction,
    filter_lag,
    fixed_b_quantile,
    long_run_factor,
    newey_west,
    newey_west_parts,
)
from adaptive_dd.identification.model import Model, base_regressor
from adaptive_dd.identification.regression import (
    Regression,
    check_excitation,
    filter_pieces,
    filtered_regression,
)

__all__ = [
    "LogFit",
    "filter_time_constant",
    "fit_log",
    "fixed_b_quantile",
    "identifiable_subset",
    "long_run_factor",
    "predict_torque",
]

Array = NDArray[np.float64]
COULOMB_STD_COLUMN = 11
"""The Coulomb columns of the standard regressor start at ``11 n`` (links ``10 n``, viscous ``n``)."""
WEIGHT_FLOOR = 0.1
"""``s_j`` is at least this fraction of the median residual rms of the kept channels."""
MODEL_ERROR_RATIO = 10.0
"""A filtered residual this many times the filtered sensor noise is reported as model error."""


@dataclass(frozen=True)
class LogFit:
    """The weighted least squares of one log.

    Attributes
    ----------
    sigma : ndarray (p,)
        Base parameters; those not identified hold the URDF's values.
    identified : ndarray of bool (p,)
    cov : ndarray (p, p)
        Newey-West sandwich covariance (zero rows and columns for those not identified).
    std : ndarray (p,)
    residual_rms : ndarray (n,)
        Filtered residual per channel [N m] (nan: excluded).
    noise_rms : ndarray (n,)
        The channel's sensor noise after ``G0`` (module docstring) [N m].
    weights : ndarray (n,)
        ``1 / s_j`` (0: excluded).
    lag : int
        Newey-West lag [samples].
    n_eff : float
        Independent samples the record is worth: its rows over the residual's long-run factor
        (:func:`long_run_factor`).
    dof_factor : float
        The variance's small-sample factor ``n_eff / (n_eff - k)``, ``k`` the columns fitted
        (module docstring), already in ``cov``.
    kernel_factor : float
        What the Bartlett sum lacks of the long-run variance, undone (its weights' shrinkage and the
        lags beyond the lag: :func:`_kernel_bias`), already in ``cov``.
    quantile : float
        ``c``: ``sigma +- c std`` is the 95 % bound, ``c`` the fixed-b quantile of the Newey-West
        ``t`` (:func:`fixed_b_quantile` of ``bandwidth``, module docstring), 1.96 and a little more.
    bandwidth : float
        ``b``, the fixed-b bandwidth fraction of ``quantile``: the Bartlett variance's relative variance
        over 4/3, from the scores' changing level and the residual's correlation
        (:func:`~adaptive_dd.identification.log_covariance.bandwidth_fraction`); about the lag plus
        one over the rows for stationary scores.
    tau_f, sample_period : float
    regression : Regression
    used : ndarray of bool (n,)
    offset : ndarray (n,) or None
        Each channel's constant torque offset [N m] (the sensor's zero, fitted with ``offset``: 0 on
        the channels left out), None when not fitted; a prediction adds it.
    offset_std : ndarray (n,) or None
        Its standard deviation, from the same sandwich as ``cov`` [N m].
    columns : int
        ``k``, the columns fitted: the identified parameters, the offsets and the Coulomb widths
        counted as estimated (``dof_factor``'s ``k``).
    held : Held or None
        The directions the record cannot see, held at the URDF's values
        (:func:`~adaptive_dd.identification.held_directions.hold_unseen`); None when not asked.

    Examples
    --------
    Made by :func:`fit_log` (whose example makes one): ``fit.sigma`` and ``fit.std`` are the
    estimate and its standard deviation per base parameter, in ``model.names``' order, and
    ``fit.held`` names the directions the record could not see.

    >>> from adaptive_dd.identification.log_fit import LogFit
    >>> "cov" in LogFit.__dataclass_fields__ and "held" in LogFit.__dataclass_fields__
    True
    """

    sigma: Array
    identified: NDArray[np.bool_]
    cov: Array
    std: Array
    residual_rms: Array
    noise_rms: Array
    weights: Array
    lag: int
    tau_f: float
    sample_period: float
    regression: Regression
    used: NDArray[np.bool_]
    held: Held | None = None
    n_eff: float = float("nan")
    dof_factor: float = 1.0
    kernel_factor: float = 1.0
    quantile: float = NORMAL_975
    bandwidth: float = 0.0
    offset: Array | None = None
    offset_std: Array | None = None
    columns: int = 0

    def model_error_channels(self) -> list[tuple[int, float]]:
        """``(joint, residual / noise)`` of the kept channels above :data:`MODEL_ERROR_RATIO`."""
        ratio = self.residual_rms / np.maximum(self.noise_rms, 1e-300)
        return [(int(j), float(ratio[j])) for j in np.flatnonzero(self.used) if ratio[j] > MODEL_ERROR_RATIO]


def coulomb_index(model) -> dict[int, int]:
    """``{joint: base column}`` of the joints whose Coulomb parameter is a base parameter alone."""
    n = model.n
    ind = [int(i) for i in np.asarray(model.independent)]
    return {j: ind.index(COULOMB_STD_COLUMN * n + j) for j in range(n) if COULOMB_STD_COLUMN * n + j in ind}


def filter_time_constant(sample_period: float) -> float:
    """``tau_f`` sized to the sample rate: two samples, at least 0.02 s [s].

    ``G0`` then has its double pole at ``1 / (4 pi T)``, a twelfth of the sample rate (8 Hz
    at 100 Hz), well below the Nyquist frequency; on the TIAGo log a longer filter (3-12
    samples) predicted the held-out torque slightly worse (benchmarks/real_log.py).
    """
    return max(0.02, 2.0 * float(sample_period))


def identifiable_subset(
    model: Model, used, lower, upper, rng: np.random.Generator, n_samples: int = 80
) -> NDArray[np.bool_]:
    """Base parameters that the torque channels ``used`` see for some motion (module docstring)."""
    used = np.asarray(used, dtype=bool)
    lo = np.where(np.isfinite(lower), lower, -np.pi)
    hi = np.where(np.isfinite(upper), upper, np.pi)
    n = model.n
    q = rng.uniform(lo, hi, (n_samples, n))
    qd = rng.uniform(-2.0, 2.0, (n_samples, n))
    qdd = rng.uniform(-5.0, 5.0, (n_samples, n))
    W = base_regressor(model, q, qd, qdd)[:, used, :].reshape(-1, model.p)
    norms = np.linalg.norm(W, axis=0)
    keep = norms > 1e-9 * norms.max()
    if used.all():
        return keep
    import scipy.linalg

    cols = np.flatnonzero(keep)
    R = scipy.linalg.qr(W[:, cols] / norms[cols], mode="r")[0]
    keep[cols] = np.abs(np.diag(R)) > 1e-9 * np.sqrt(W.shape[0])
    return keep


def _solve(phi: Array, y: Array, w: Array, factors=None) -> tuple[Array, Array]:
    """Weighted least squares of ``y (N, m) ~ phi (N, m, r) x``; returns ``x`` and the column scale.
    ``factors``: :func:`_channel_factors` of ``phi, y`` (computed when None)."""
    Rc, col2 = _channel_factors(phi, y) if factors is None else factors
    r = phi.shape[-1]
    scale = np.sqrt(np.einsum("j,jr->r", w**2, col2))
    scale = np.where(scale > 0, scale, 1.0)
    # the least squares of the triangular factor of [A | y], A the weighted regressor: the same
    # (min-norm) solution as of A, whose singular values R shares. [A | y]'s rows of channel j are
    # w_j [phi_j | y_j] = w_j Q_j R_j (Q_j orthonormal columns), so R is the triangular factor of the
    # stacked w_j R_j (m (r + 1) rows): a QR per channel once for any weights, not one of the tall A
    # per weighting; the same numbers to round-off
    stacked = (w[:, None, None] * Rc) * np.append(1.0 / scale, 1.0)
    R = np.linalg.qr(stacked.reshape(-1, r + 1), mode="r")
    sol, *_ = np.linalg.lstsq(R[:r, :r], R[:r, r], rcond=phi.shape[0] * phi.shape[1] * np.finfo(float).eps)
    return sol / scale, scale


def _channel_factors(phi: Array, y: Array) -> tuple[Array, Array]:
    """Per channel ``j`` the triangular factor ``R_j`` of ``[phi_j | y_j]`` ``(m, <= r + 1, r + 1)``
    and the squared column norms of ``phi_j`` ``(m, r)`` (:func:`_solve`)."""
    Rc = np.linalg.qr(np.concatenate([phi, y[:, :, None]], axis=2).transpose(1, 0, 2), mode="r")
    return Rc, np.einsum("kjr,kjr->jr", phi, phi)


def _noise_rms(tau: Array, tau_f: float, T: float, pieces=None) -> Array:
    """Each channel's white-noise std from its second difference (within each piece), after ``G0`` [N m]."""
    pieces = ((0, tau.shape[0]),) if pieces is None else pieces
    d2 = np.concatenate([np.diff(tau[a:b], 2, axis=0) for a, b in pieces if b - a > 2])
    s = np.std(d2, axis=0) / np.sqrt(6.0)
    bank = design_filter_bank("M2", tau_f, T)
    m = int(20 * tau_f / T) + 10
    imp = np.zeros((m, 1))
    imp[0] = 1.0
    h = filter_record(bank, imp, axis=0, initial=np.zeros(1))[:, 0, 0]
    return s * np.sqrt(np.sum(h**2))


def _too_small(factor: float) -> str:
    """How much too small a std is that should be ``factor`` (> 1) times larger: a share below a
    factor of 2 (``1x`` read as not at all), else the factor."""
    if factor < 2:
        return f"about {100 * (1 - 1 / factor):.0f} % too small"
    return f"too small by about {factor:.2g}x"


def too_few_samples(n_eff: float, k: int, duration: float) -> str:
    """What a fit of ``k`` columns to about ``n_eff`` independent samples over ``duration`` [s] is
    worth when they are fewer than :data:`MAX_DOF_FACTOR` a column, and the window that would give
    that many (the independent samples grow with it at the record's own rate): fewer than one a
    column, the columns cannot be told apart (``identify`` refuses); fewer than two, the std's
    small-sample factor ``n_eff / (n_eff - k)`` is beyond its first-order reach and capped (the std
    too small)."""
    need = duration * MAX_DOF_FACTOR * k / max(n_eff, 1.0)
    short = np.sqrt(n_eff / max(n_eff - k, 1e-9) / MAX_DOF_FACTOR)  # how much too small the std is
    what = (
        "too few to tell them apart (the estimates and their std are not to be trusted, even along the "
        "directions held at the prior)"
        if n_eff < k
        else f"the std's small-sample factor is capped at {MAX_DOF_FACTOR:g} where n_eff / (n_eff - k) is "
        f"{n_eff / (n_eff - k):.3g}: the std is {_too_small(short)}"
    )
    return (
        f"about {n_eff:.0f} independent samples for {k} columns fitted: {what}; give a window of at least "
        f"about {need:.3g} s, or fit fewer columns"
    )


def fit_log(
    model: Model,
    q: Array,
    qd: Array,
    tau: Array,
    used,
    identified,
    *,
    tau_f: float,
    sample_period: float,
    channel_weight=None,
    torque_held: bool = True,
    prior_std=None,
    hold: bool = True,
    width_estimated=None,
    pieces=None,
    offset: bool = False,
    momentum=None,
) -> LogFit:
    """Weighted least squares of one log (module docstring).

    Parameters
    ----------
    q, qd, tau : ndarray (N, n)
        Uniformly sampled positions [rad, m], velocities, torques [N m].
    used : array_like of bool (n,)
        Torque channels in the fit.
    identified : array_like of bool (p,)
        Base parameters to fit (:func:`identifiable_subset`); the others hold the URDF's values.
    tau_f, sample_period : float
        [s].
    channel_weight : array_like (n,), optional
        Multiplies each channel's weight from the rule (a user's ``torque_weight``).
    torque_held : bool
        The torque is held over each sample (a command, as a simulator's or a drive's current
        loop applies it: the default) rather than sampled from a continuous signal (a joint
        torque sensor): :func:`~adaptive_dd.identification.regression.filtered_regression`.
    prior_std : array_like (p,), optional
        The prior's standard deviation of each base parameter about the URDF's value (default:
        :func:`~adaptive_dd.identification.held_directions.base_prior_std` at issue 28's levels).
    hold : bool
        Hold at the URDF's values the directions the record cannot see (module docstring of
        :mod:`~adaptive_dd.identification.held_directions`; ``False``: the plain weighted least
        squares, every direction estimated).
    width_estimated : array_like of bool (n,), optional
        Joints whose Coulomb width was estimated on this record
        (:func:`~adaptive_dd.identification.friction_width.profile_coulomb_width`): the covariance
        is that of the fit with those widths free too (:func:`_width_columns`), so the std of the
        parameters that trade with a width (its joint's Coulomb level first) carries its uncertainty.
    pieces : sequence of (int, int), optional
        The record's continuous pieces ``[a, b)`` (between a log's gaps, or several records end to
        end, :attr:`adaptive_dd.record.LogRecord.pieces`): each filtered on its own, its filters'
        settling cut, the pieces fitted together, the covariance's autocovariances within each
        piece only; default one piece.
    offset : bool
        Fit a constant torque offset per kept channel too (a torque sensor's or a current loop's
        zero: module docstring), :attr:`LogFit.offset`.
    momentum : (ndarray, ndarray), optional
        The record's :func:`~adaptive_dd.identification.regression.momentum_regressors`, when the
        caller computed them (to hand the same to
        :func:`~adaptive_dd.identification.model_error.model_error_variance`); default computed here.

    Returns
    -------
    LogFit
        The estimate, its sandwich covariance, the per-channel residual and weights, and the held
        directions.

    Raises
    ------
    DataError
        The log does not excite some base parameter (named; with ``hold``, only a parameter whose
        column is zero: the directions it barely sees are held), or is too short.

    Examples
    --------
    A noise-free record made from the URDF's own parameters gives them back:

    >>> import numpy as np
    >>> from adaptive_dd.identification.log_fit import fit_log, predict_torque
    >>> from adaptive_dd.identification.model import arm_model
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> arm = Arm.from_urdf(robot_urdf("vertical3"))
    >>> model = arm_model(arm)
    >>> T = 1e-3
    >>> t = np.arange(0.0, 3.0, T)[:, None]
    >>> q = 0.8 * np.sin([1.1, 1.7, 2.3] * t) + 0.4 * np.sin([3.1, 4.3, 5.9] * t)
    >>> qd, qdd = np.gradient(q, T, axis=0), np.gradient(np.gradient(q, T, axis=0), T, axis=0)
    >>> tau = predict_torque(model, arm.sigma, q, qd, qdd)  # the URDF's torques along the motion [N m]
    >>> fit = fit_log(model, q, qd, tau, np.ones(3, bool), np.ones(arm.base.count, bool),
    ...               tau_f=0.01, sample_period=T)
    >>> bool(np.allclose(fit.sigma, arm.sigma, atol=0.05)), fit.sigma.shape
    (True, (17,))
    """
    q, qd, tau = (np.asarray(x, dtype=float) for x in (q, qd, tau))
    used = np.asarray(used, dtype=bool)
    K = np.asarray(identified, dtype=bool)
    if used.shape != (model.n,) or K.shape != (model.p,):
        raise ParameterError(
            f"fit_log: used is one flag per joint ({model.n},) and identified one per base parameter "
            f"({model.p},), got {used.shape} and {K.shape}"
        )
    reg = filtered_regression(
        model,
        q,
        qd,
        tau,
        tau_f=tau_f,
        sample_period=sample_period,
        torque_held=torque_held,
        pieces=pieces,
        momentum=momentum,
    )
    bounds = reg.row_bounds()
    phi, y = _identified_regression(model, reg, used, K, weak_ok=hold)
    cw = np.ones(model.n) if channel_weight is None else np.asarray(channel_weight, dtype=float)
    ones = _offset_columns(y.shape[0], int(used.sum())) if offset else None
    if offset:  # the offsets profiled out (Frisch-Waugh): each channel's rows about their mean
        phi_fit, y_fit = phi - phi.mean(axis=0), y - y.mean(axis=0)
    else:
        phi_fit, y_fit = phi, y
    x, res, w, scale = _reweighted_fit(phi_fit, y_fit, cw[used])
    extra = [] if ones is None else [ones]
    if width_estimated is not None and np.any(width_estimated):
        extra.append(
            _width_columns(model, qd, reg, sample_period, used, K, x, np.asarray(width_estimated, dtype=bool))
        )
    r = phi.shape[2]
    floor = filter_lag(tau_f, sample_period)  # the filters' own correlation summed (log_covariance)
    if extra:  # the sandwich of the fit with the offsets and widths free too; sigma's block
        aug = np.concatenate([phi, *extra], axis=2)
        scale_aug = np.linalg.norm((aug * w[None, :, None]).reshape(-1, aug.shape[2]), axis=0)
        scale_aug = np.where(scale_aug > 0, scale_aug, 1.0)
        cov_aug, lag, influence = newey_west_parts(aug, res, w, scale_aug, bounds, floor)
        k = aug.shape[2]
    else:
        cov_aug, lag, influence = newey_west_parts(phi, res, w, scale, bounds, floor)
        k = r
    u = (res * w).sum(axis=1)  # the weighted residual pooled over the channels
    b_frac = bandwidth_fraction(influence[:, :r], u, lag, bounds)
    kernel = _kernel_bias(u, lag, bounds)
    n_eff, dof = _dof_factor(res, w, lag, bounds, k)
    if n_eff < MAX_DOF_FACTOR * k:  # said; below one a column, refused by identify
        import warnings

        from adaptive_dd.errors import RunWarning

        warnings.warn(too_few_samples(n_eff, k, reg.y.shape[0] * sample_period), RunWarning, 2)
    cov_aug = kernel * dof * cov_aug
    cov_k = cov_aug[:r, :r]
    sigma, cov, residual, weights = _in_full(model, K, used, x, cov_k, res, w)
    held = None
    if hold:
        s0 = base_prior_std(model) if prior_std is None else np.asarray(prior_std, dtype=float)
        sigma, cov, held = hold_unseen(sigma, cov, model.sigma_ref, s0, K)
        residual[used] = np.sqrt(np.mean((y_fit - phi_fit @ sigma[K]) ** 2, axis=0))
    b = b_std = None
    if offset:  # each channel's mean residual of the final estimate, held directions included
        b, b_std = np.zeros(model.n), np.zeros(model.n)
        b[used] = np.mean(y - phi @ sigma[K], axis=0)
        m = int(used.sum())
        b_std[used] = np.sqrt(np.abs(np.diag(cov_aug[r : r + m, r : r + m])))
    return LogFit(
        sigma=sigma,
        identified=K,
        cov=cov,
        std=np.sqrt(np.abs(np.diag(cov))),
        residual_rms=residual,
        noise_rms=_noise_rms(tau, tau_f, sample_period, reg.pieces),
        weights=weights,
        lag=lag,
        tau_f=float(tau_f),
        n_eff=float(n_eff),
        dof_factor=float(dof),
        kernel_factor=float(kernel),
        quantile=fixed_b_quantile(b_frac),
        bandwidth=b_frac,
        sample_period=float(sample_period),
        regression=reg,
        used=used,
        held=held,
        offset=b,
        offset_std=b_std,
        columns=int(k),
    )


def _offset_columns(rows: int, m: int) -> Array:
    """``(rows, m, m)``: the regression's columns of a constant offset in each of ``m`` channels (the
    filter ``G0`` passes a constant unchanged)."""
    return np.broadcast_to(np.eye(m), (rows, m, m)).copy()


def _identified_regression(
    model: Model, reg, used: NDArray[np.bool_], K: NDArray[np.bool_], weak_ok: bool = False
):
    """``phi (N, m, k)`` and ``y (N, m)`` of the used channels and the identified parameters, the
    torque of the parameters held at the URDF's values moved to ``y``; checked: enough samples,
    every identified parameter excited (``weak_ok``: but for directions the fit holds)."""
    names = tuple(nm for nm, k in zip(model.names, K, strict=True) if k)
    phi_all = reg.phi[:, used, :]
    y = reg.y[:, used] - phi_all[:, :, ~K] @ model.sigma_ref[~K]
    phi = phi_all[:, :, K]
    if y.shape[0] * used.sum() < 3 * K.sum():
        raise DataError(
            f"{y.shape[0]} samples of {used.sum()} channels for {K.sum()} parameters: a longer window "
            "is needed"
        )
    check_excitation(phi, names, weak_ok=weak_ok)
    return phi, y


def _width_columns(model: Model, qd: Array, reg, sample_period: float, used, K, x: Array, free) -> Array:
    """``(N', m, e)``: the regression's columns of the log-widths of the joints ``free`` at the
    estimate ``x``, ``fc_j d tanh(qd_j / v_j) / d log v_j = -fc_j (qd_j / v_j) sech^2(qd_j / v_j)``
    filtered by ``G0`` in joint j's channel (zero where the joint's Coulomb is not fitted)."""
    n = model.n
    v = np.broadcast_to(np.asarray(model.friction_velocity, dtype=float), (n,))
    u = np.asarray(qd, dtype=float) / v
    d = -u / np.cosh(np.clip(u, -350, 350)) ** 2
    bank = design_filter_bank("M2", reg.tau_f, sample_period)
    fd = filter_pieces(bank, d, reg.pieces, reg.start, 0)
    col = np.cumsum(K) - 1
    kept = np.flatnonzero(used)
    index = coulomb_index(model)
    joints = [j for j in np.flatnonzero(free) if j in index and used[j] and K[index[j]]]
    out = np.zeros((fd.shape[0], kept.size, len(joints)))
    for e, j in enumerate(joints):
        out[:, int(np.flatnonzero(kept == j)[0]), e] = x[col[index[j]]] * fd[:, j]
    return out


def _in_full(model: Model, K, used, x: Array, cov_k: Array, res: Array, w: Array):
    """The fit in the full vectors: sigma and its covariance over all ``p`` base parameters (the
    others at the URDF's values, zero covariance), the residual RMS and weight of all ``n``
    channels (NaN and 0 where unused)."""
    sigma = model.sigma_ref.copy()
    sigma[K] = x
    cov = np.zeros((model.p, model.p))
    cov[np.ix_(K, K)] = cov_k
    n = model.n
    residual = np.full(n, np.nan)
    residual[used] = np.sqrt(np.mean(res**2, axis=0))
    weights = np.zeros(n)
    weights[used] = w
    return sigma, cov, residual, weights


def _reweighted_fit(phi: Array, y: Array, cw: Array) -> tuple[Array, Array, Array, Array]:
    """The weighted fit after three rounds of the weighting rule (module docstring): the
    estimate, its residuals ``(N, m)``, the channel weights ``cw / rms`` used and the column
    scale of the weighted regressor (:func:`_solve`)."""
    w = cw.copy()
    factors = _channel_factors(phi, y)  # one QR per channel for the four weightings
    for _ in range(3):
        x, _ = _solve(phi, y, w, factors)
        res = y - phi @ x
        rms = np.sqrt(np.mean(res**2, axis=0))
        s = np.maximum(rms, WEIGHT_FLOOR * np.median(rms))
        w = cw / np.maximum(s, 1e-300)
    x, scale = _solve(phi, y, w, factors)
    return x, y - phi @ x, w, scale


def predict_torque(model: Model, sigma: Array, q: Array, qd: Array, qdd: Array) -> Array:
    """Joint torques ``(N, n)`` [N m] of base parameters ``sigma`` along a motion.

    Parameters
    ----------
    model : Model
        The arm's identification model (:func:`~adaptive_dd.identification.model.arm_model`).
    sigma : ndarray, shape (p,)
        Base parameters, in ``model.names``' order.
    q, qd, qdd : ndarray, shape (N, n)
        Positions [rad], velocities [rad/s] and accelerations [rad/s^2].

    Returns
    -------
    ndarray, shape (N, n)
        The joint torques [N m] the base parameters give along the motion.

    Examples
    --------
    >>> import numpy as np
    >>> from adaptive_dd.identification.log_fit import fit_log, predict_torque
    >>> from adaptive_dd.identification.model import arm_model
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> arm = Arm.from_urdf(robot_urdf("vertical3"))
    >>> model = arm_model(arm)
    >>> T = 1e-3
    >>> t = np.arange(0.0, 3.0, T)[:, None]
    >>> q = 0.8 * np.sin([1.1, 1.7, 2.3] * t) + 0.4 * np.sin([3.1, 4.3, 5.9] * t)
    >>> qd, qdd = np.gradient(q, T, axis=0), np.gradient(np.gradient(q, T, axis=0), T, axis=0)
    >>> tau = predict_torque(model, arm.sigma, q, qd, qdd)  # the URDF's torques along the motion [N m]
    >>> tau.shape
    (3000, 3)
    """
    return base_regressor(model, q, qd, qdd) @ np.asarray(sigma, dtype=float)
