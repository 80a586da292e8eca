"""The bounds of :func:`~adaptive_dd.identification.log_fit.fit_log`: the Newey-West sandwich
within each continuous piece, its small-sample factors and the fixed-b quantile.

Standard deviations
    On real data the residual is model error more than sensor noise: correlated over time
    and far larger than the sensors' noise. The covariance is the sandwich
    ``A^-1 S A^-1`` with ``A = sum_k Phi_k^T W Phi_k`` and ``S`` the Newey-West (Bartlett)
    estimate of the long-run covariance of the scores ``g_k = Phi_k^T W r_k``, lag ``L`` the
    residual's correlation time (the first lag at which the autocorrelation of the weighted
    residual, pooled over channels, falls below 0.05, times 3) and at least ``16 tau_f / T``
    (:data:`FILTER_LAGS`, :func:`filter_lag`), the autocovariances summed within each continuous
    piece of the record (between a log's gaps, several records). The least lag is for the noise
    of a measured velocity: differentiated by the filters (``G1 = s G0``) it reaches the residual
    correlated as ``(1 - x) exp(-x)``, ``x = m T / tau_f``, a positive core to ``x = 1`` and a
    negative lobe beyond that cancels it (all but 0.5 % by ``x = 8``), so it adds little to the
    estimate's variance. The 0.05 crossing lands in the core (about ``0.8 tau_f``), and a Bartlett
    sum three times as long counts the core and little of the lobe. At ``L = 16 tau_f / T`` the
    Bartlett weights leave ``e tau_f / (L T)`` = e / 16, about a sixth, of the core uncancelled (the
    core sums to ``2 tau_f / (e T)``, the weights take ``2 (tau_f / T)^2 / L`` from the lobe): on
    closed-loop records of the simulator (``benchmarks/log_bounds_coverage.py --cases simulated``,
    40 seeds) each std is 1.25 times the estimates' spread (median over the parameters). A window
    flat over the lobe (a flat-top kernel) would leave none, but its estimate is not positive
    definite, and clipped it holds some directions at zero variance. Scaled
    by what the Bartlett sum lacks of the long-run variance (:func:`_kernel_bias`: its weights'
    shrinkage and the lags beyond ``L``, from the residual's autocorrelation over the lags where
    it is well estimated, run out beyond them as a geometric tail) and by the degrees-of-freedom
    factor ``n_eff / (n_eff - k)``: the fit removes ``k`` directions from the residual, which
    shrinks the scores' variance as ordinary least squares' ``N / (N - k)`` says for white
    residuals (MacKinnon and White, J. Econometrics 29, 1985: HC1), the samples counted here as
    independent ones, ``n_eff`` = rows over the residual's long-run factor
    (:func:`long_run_factor`, the Bartlett weights and lag of the covariance), at most 2
    (:data:`MAX_DOF_FACTOR`). Without it the truth
    fell within +- 1.96 std in 89 % of simulated cases (benchmarks/log_bounds_coverage.py).
    These are to make the variance's estimate right on average (the std the spread the estimate
    would have over records like this one). On simulated records of the small vertical3 arm, each
    seed's std against the exact std of its own estimate on its own motion
    (``benchmarks/log_bounds_coverage.py --exact``, 40 seeds, the torque offsets fitted), the
    variance is right on average (its mean ratio 1.02 with gaps, 1.01 with two records), but not
    per parameter: 0.86-0.92 for the first moments that trade with the torque offsets (``mx3``,
    ``mx2 + 0.35 m3``, ``mx1 + ...``), up to 1.13 for the friction terms; a single factor from the
    pooled residual cannot tell them apart. Each seed's variance is itself a draw (its ratio to the
    exact one varies by 0.14 over the seeds, more where the lag chosen is short): the quantile
    below is for that.

Bounds
    The std is itself an estimate, from a record worth a few hundred independent samples, so
    ``t = (estimate - truth) / std`` has wider tails than a normal variable, as Student's
    ``t`` has. The 95 % bound is ``estimate +- c std`` with ``c`` (:attr:`LogFit.quantile`)
    the fixed-b quantile of the Newey-West ``t`` (Kiefer and Vogelsang, "A new asymptotic
    theory for heteroskedasticity-autocorrelation robust tests", Econometric Theory 21, 2005):
    ``c(b) = 1.96 + 2.9694 b + 0.4160 b^2 - 0.5324 b^3`` (their cubic for the Bartlett kernel,
    :func:`fixed_b_quantile`), ``b`` the bandwidth's fraction of the sample. For stationary scores
    that is the lag plus one over the ``N`` rows of all pieces (each piece adds to the Bartlett
    estimate's variance in proportion to its length), and ``(4 / 3) b`` the Bartlett variance's
    relative variance. A log's scores are not stationary: their level follows the regressors and
    a noise that grows with speed, so a few stretches carry most of a parameter's variance, and
    the residual's correlation reaches over the lag; both make each std more variable than ``N``
    rows would. ``b`` is therefore taken from that relative variance
    (:func:`bandwidth_fraction`: each parameter's influence series, its level's effective rows,
    the Bartlett window convolved with the residual's autocorrelation), averaged over the
    parameters. On simulated records (benchmarks/log_bounds_coverage.py, 200 seeds, the torque
    offsets fitted) the truth falls within the bound in 95.8 % (gaps) and 95.1 % (two records) of
    cases, +- 0.9 % over the seeds; ``--exact`` prints the spread of each seed's variance against
    what ``b`` says of it. The std is checked on the TIAGo record against the spread of estimates over
    disjoint windows (benchmarks/real_log.py).
"""

from __future__ import annotations

import numpy as np
import scipy.signal
from numpy.typing import NDArray

__all__ = [
    "FILTER_LAGS",
    "MAX_DOF_FACTOR",
    "NORMAL_975",
    "TAIL_RATIO",
    "bandwidth_fraction",
    "filter_lag",
    "fixed_b_quantile",
    "lag_source",
    "long_run_factor",
    "newey_west",
    "newey_west_lag",
    "newey_west_parts",
    "pooled_autocorrelation",
    "residual_lag",
]

Array = NDArray[np.float64]
MAX_DOF_FACTOR = 2.0
"""The degrees-of-freedom factor's cap, reached at ``k = n_eff / 2``: beyond it a record holds too few
independent samples for its parameters for a first-order correction (the TIAGo's 20 s windows:
``n_eff`` 64-91 for 53 parameters)."""
FILTER_LAGS = 16.0
"""The Bartlett lag is at least this many filter time constants ``tau_f`` (module docstring)."""
TAIL_RATIO = 0.99
"""The geometric tail's ratio's cap in :func:`_kernel_bias` (a tail at most 99 times its first term)."""
NORMAL_975 = 1.959963984540054
"""The standard normal's 97.5 % quantile: estimate +- this many std is the 95 % interval."""


def fixed_b_quantile(b: float) -> float:
    """The 97.5 % quantile of ``|t|``, ``t`` an estimate studentised by its Bartlett (Newey-West)
    standard deviation of bandwidth a fraction ``b`` of the sample, under fixed-b asymptotics.

    Kiefer and Vogelsang (Econometric Theory 21, 2005), the cubic fitted to their simulated
    critical values for the Bartlett kernel: ``1.96 + 2.9694 b + 0.4160 b^2 - 0.5324 b^3``, for
    ``0 <= b <= 1`` (1.96 at ``b = 0``, the normal's; 2.26 at ``b = 0.1``).

    Raises
    ------
    ValueError
        ``b`` outside [0, 1].
    """
    if not 0.0 <= b <= 1.0:
        raise ValueError(f"fixed_b_quantile: b = {b} is the bandwidth's fraction of the sample, in [0, 1]")
    return NORMAL_975 + b * (2.9694 + b * (0.4160 - 0.5324 * b))


def pooled_autocorrelation(u: Array, upto: int, bounds=None) -> Array:
    """``rho_0 .. rho_upto`` of ``u (N,)`` pooled over its pieces ``bounds`` (default one): each
    piece's mean removed, the autocovariances of the lags it has summed over the pieces (by FFT,
    zero-padded to twice the piece), divided by the pooled variance."""
    bounds = [(0, u.size)] if bounds is None else list(bounds)
    ac = np.zeros(upto + 1)
    for a, b in bounds:
        seg = u[a:b] - u[a:b].mean()
        f = np.fft.rfft(seg, 2 * (b - a))
        c = np.fft.irfft(f * np.conj(f))[: min(b - a, upto + 1)]
        ac[: c.size] += c
    return ac / max(ac[0], 1e-300)


def newey_west_lag(ac: Array, longest: int, floor: int = 0) -> int:
    """The Bartlett lag of an autocorrelation ``ac``: three times its first lag below 0.05 (all of
    ``longest``, the longest piece, if it never falls below), at least ``floor`` (:func:`filter_lag`),
    at most ``longest / 4``."""
    below = np.flatnonzero(ac < 0.05)
    return int(min(max(3 * (below[0] if below.size else longest), floor), longest // 4))


def residual_lag(u: Array, bounds, floor: int = 0) -> int:
    """:func:`newey_west_lag` of the weighted residual ``u (N,)`` pooled over the pieces ``bounds``
    (``[(r0, r1), ...]``), at least ``floor`` (:func:`filter_lag`), at most a quarter of the longest
    piece."""
    longest = max(b - a for a, b in bounds)
    return newey_west_lag(pooled_autocorrelation(u, longest - 1, bounds), longest, floor)


def lag_source(lag: int, bounds, floor: int) -> str:
    """What set a :func:`residual_lag` ``lag`` on the pieces ``bounds``, in words: the cap at a quarter
    of the longest piece (and the least lag ``floor`` it fell short of), the filters' least lag, or
    the residual's correlation."""
    longest = max(b - a for a, b in bounds)
    if lag >= longest // 4:
        said = f"capped at a quarter of the longest piece, {longest} rows"
        return said if lag >= floor else f"{said}; the filters' least, {FILTER_LAGS:g} tau_f, is {floor}"
    if lag == floor:
        return f"the filters' least: {FILTER_LAGS:g} tau_f"
    return "three times the residual's correlation time"


def filter_lag(tau_f: float, sample_period: float) -> int:
    """The least Bartlett lag [samples] of a record filtered at ``tau_f`` (module docstring):
    ``FILTER_LAGS tau_f / T``."""
    return int(np.ceil(FILTER_LAGS * tau_f / sample_period))


def long_run_factor(u: Array, lag: int, bounds=None) -> float:
    """``1 + 2 sum_m (1 - m / (lag + 1)) rho_m``, ``rho`` the autocorrelation of ``u (N,)`` pooled over
    its pieces ``bounds`` (default one): how many samples one independent sample is worth, at least 1."""
    ac = pooled_autocorrelation(u, lag, bounds)
    m = np.arange(1, lag + 1)
    return float(max(1.0, 1.0 + 2.0 * np.sum((1.0 - m / (lag + 1)) * ac[1:])))


def _kernel_bias(u: Array, lag: int, bounds) -> float:
    """What the Bartlett sum at ``lag`` lacks of the long-run variance of ``u (N,)``, undone:
    ``F / F_L``, ``F_L`` the Bartlett long-run factor (:func:`long_run_factor`) and
    ``F = 1 + 2 sum_{m <= m0} rho_m + 2 rho_m0 r / (1 - r)`` the whole one, ``rho`` the
    autocorrelation pooled over the pieces ``bounds``: summed over the lags to ``m0 = lag / 3`` (its
    0.05 crossing by :func:`newey_west`'s rule, where it is well estimated; further where the lag is
    the filters' least, :func:`filter_lag`, so that a lobe that cancels the core is summed too), and run out
    beyond ``m0`` as a geometric tail of ratio ``r`` (its decay from ``m0 - h`` to ``m0``,
    ``h = m0 / 2``; at most :data:`TAIL_RATIO`): the estimated autocorrelation of a fit's residual
    beyond ``m0`` is biased low and noisy, and an autoregressive correlation decays geometrically.
    The Bartlett weights ``1 - m / (lag + 1)`` discount autocovariances the residual does have, and
    the lags beyond ``lag`` are not summed: on an AR(1) of coefficient 0.905 at a lag of three times
    its 0.05 crossing the two leave out about 6 % of the variance (benchmarks/log_bounds_coverage.py's
    residual). At least 1."""
    m0 = max(1, lag // 3)
    ac = _autocorrelation(u, lag, bounds, m0)
    r = _tail_ratio(ac, m0)
    whole = 1.0 + 2.0 * np.sum(ac[1:]) + 2.0 * max(ac[m0], 0.0) * r / (1.0 - r)
    return float(max(1.0, whole / long_run_factor(u, lag, bounds)))


def _autocorrelation(u: Array, lag: int, bounds, upto: int) -> Array:
    """``rho_0 .. rho_upto`` of ``u (N,)``, pooled over the pieces ``bounds``: as estimated up to its
    0.05 crossing ``m0 = lag / 3`` (:func:`newey_west`'s rule) and run out beyond it as
    :func:`_kernel_bias`'s geometric tail."""
    m0 = max(1, lag // 3)
    ac = pooled_autocorrelation(u, m0, bounds)
    if upto <= m0:
        return ac[: upto + 1]
    return np.concatenate([ac, max(ac[m0], 0.0) * _tail_ratio(ac, m0) ** np.arange(1, upto - m0 + 1)])


def _tail_ratio(ac: Array, m0: int) -> float:
    """The geometric tail's ratio beyond the crossing ``m0``: the autocorrelation's decay per lag
    over the last half before it, at most :data:`TAIL_RATIO` (0 where it is not positive)."""
    h = max(1, m0 // 2)
    if ac[m0] > 0.0 and ac[m0 - h] > 0.0:
        return float(min((ac[m0] / ac[m0 - h]) ** (1.0 / h), TAIL_RATIO))
    return 0.0


def _dof_factor(res: Array, w: Array, lag: int, bounds, k: int) -> tuple[float, float]:
    """``(n_eff, n_eff / (n_eff - min(k, n_eff / 2)))``: the residual's independent samples and the
    variance's degrees-of-freedom factor (module docstring), at most 2: the factor is a first-order
    correction in ``k / n_eff`` (:data:`MAX_DOF_FACTOR`)."""
    u = (res * w).sum(axis=1)
    n_eff = u.size / long_run_factor(u, lag, bounds)
    return n_eff, n_eff / (n_eff - min(k, n_eff * (1.0 - 1.0 / MAX_DOF_FACTOR)))


def _bartlett_window(lag: int) -> Array:
    """The Bartlett weights ``1 - |m| / (lag + 1)`` for ``m = -lag .. lag``."""
    return 1.0 - np.abs(np.arange(-lag, lag + 1)) / (lag + 1)


def _bartlett_sum(g: Array, lag: int, bounds) -> Array:
    """``sum_k sum_{|m| <= lag} (1 - |m| / (lag + 1)) g_{k+m} g_k^T`` within each piece ``(r0, r1)``.

    Computed as ``h^T g`` with ``h`` each column of ``g (N, r)`` convolved with the Bartlett
    window inside its piece (zero beyond the piece's ends): ``O(N r log N + N r^2)`` where the sum
    over lags is ``O(lag N r^2)``; the same numbers (a test holds them to the lag-by-lag sum)."""
    kernel = _bartlett_window(lag)
    h = np.zeros_like(g)
    for a, b in bounds:
        h[a:b] = scipy.signal.oaconvolve(g[a:b], kernel[:, None], mode="same", axes=0)
    return h.T @ g


def newey_west(
    phi: Array, res: Array, w: Array, scale: Array, bounds=None, floor: int = 0
) -> tuple[Array, int]:
    """Sandwich covariance ``(r, r)`` of the weighted fit and the lag used (module docstring).

    ``bounds``: the rows ``[(r0, r1), ...]`` of each continuous piece (a log's pieces between its
    gaps, or several records): the scores' autocovariances are summed within each piece only (the
    pieces are taken as independent of each other), the lag from their autocorrelation pooled
    over the pieces; default one piece. ``floor``: the least lag (:func:`filter_lag`)."""
    cov, lag, _ = newey_west_parts(phi, res, w, scale, bounds, floor)
    return cov, lag


def newey_west_parts(
    phi: Array, res: Array, w: Array, scale: Array, bounds=None, floor: int = 0
) -> tuple[Array, int, Array]:
    """:func:`newey_west`'s covariance and lag, and the estimate's influence series ``(N, r)``: row
    ``k`` is what row ``k``'s score adds to the estimate, ``A^-1 g_k`` (in ``phi``'s units), the
    series whose Bartlett sum is each parameter's variance (:func:`bandwidth_fraction`)."""
    N, _, _r = phi.shape
    bounds = [(0, N)] if bounds is None else list(bounds)
    P = phi / scale
    g = np.einsum("kjr,kj->kr", P, (w**2) * res)  # scores (N, r)
    A = np.einsum("kjr,kjs,j->rs", P, P, w**2)
    u = (res * w).sum(axis=1)
    lag = residual_lag(u, bounds, floor)
    S = _bartlett_sum(g, lag, bounds)
    # A^-1 S A^-1 in A's eigenbasis, symmetric by construction: on a record that barely sees a
    # direction (the Gen3's rounded angles: A's condition number 1e10) the product of a
    # pseudo-inverse left it asymmetric by 1e-4 and with a negative eigenvalue along that direction
    d, U = np.linalg.eigh(0.5 * (A + A.T))
    d_inv = 1.0 / np.maximum(d, d.max() * 1e-15)  # an unseen direction: a huge variance, not none
    M = U.T @ (0.5 * (S + S.T)) @ U
    cov = U @ (d_inv[:, None] * M * d_inv[None, :]) @ U.T
    cov = 0.5 * (cov + cov.T)
    influence = ((g @ U) * d_inv) @ U.T / scale
    return cov / np.outer(scale, scale), lag, influence


def bandwidth_fraction(influence: Array, u: Array, lag: int, bounds=None) -> float:
    """The fixed-b bandwidth fraction ``b`` of the bound's quantile (:func:`fixed_b_quantile`): the
    Bartlett variance's own relative variance over ``4 / 3``, averaged over the parameters (the
    columns of ``influence (N, r)``, :func:`newey_west_parts`), ``u (N,)`` the weighted residual
    pooled over channels, ``lag`` the Newey-West lag, ``bounds`` the pieces.

    For a stationary score series and a lag long against its correlation the Bartlett variance of
    bandwidth ``L`` over ``N`` rows has relative variance ``(4 / 3) (L + 1) / N`` and ``b`` is the
    bandwidth's fraction ``(L + 1) / N``. Two things make it larger on a real log. The scores'
    level changes over the record (the regressors' size, a noise that grows with speed): a series
    of level ``a_t`` is worth ``N_a = (sum a^2)^2 / sum a^4`` rows of a constant level; ``a_t^2``
    is each parameter's influence squared smoothed by the Bartlett window, ``N_a`` raised by
    ``1 + 2 F2 / W`` for that smoothing's own noise (``F2 = sum_m rho_m^2``, ``W = 1.5 (L + 1)``
    the window's effective length, Gaussian scores). And the residual's correlation reaches over
    the lag: the relative variance is ``2 sum_m f_m^2 / (N_a f_0^2)``, ``f`` the Bartlett window
    convolved with the autocorrelation ``rho`` (pooled over the pieces, run out beyond its 0.05
    crossing as :func:`_kernel_bias` does), ``(4 / 3) (L + 1)`` for a white one. At most 1."""
    N = u.size
    bounds = [(0, N)] if bounds is None else list(bounds)
    rho = _autocorrelation(u, lag, bounds, 8 * lag)
    sym = np.concatenate([rho[:0:-1], rho])
    kernel = _bartlett_window(lag)
    f = np.convolve(kernel, sym)
    rel = 2.0 * np.sum(f**2) / f[f.size // 2] ** 2  # times 1 / N_a: the Bartlett variance's relative variance
    window = kernel / kernel.sum()
    level = np.zeros_like(influence)
    for a, b in bounds:
        mass = scipy.signal.oaconvolve(np.ones(b - a), window, mode="same")
        level[a:b] = scipy.signal.oaconvolve(influence[a:b] ** 2, window[:, None], mode="same", axes=0)
        level[a:b] /= np.maximum(mass, 1e-300)[:, None]
    n_a = level.sum(axis=0) ** 2 / np.maximum((level**2).sum(axis=0), 1e-300)
    n_a = np.minimum(n_a * (1.0 + 2.0 * np.sum(sym**2) / (1.5 * (lag + 1))), N)
    return float(min(1.0, np.mean(0.75 * rel / n_a)))
