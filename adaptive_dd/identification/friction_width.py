"""The width of the identification's Coulomb law, from the record: one rule for every route.

The identification writes Coulomb friction as ``fc tanh(qd / v)``
(:mod:`adaptive_dd.identification.model`). A plant whose law has a sign (stick-slip, Stribeck: the
shipped arms') gives, of a measured velocity with noise of std ``s``, ``E[sgn(qd) | qd_measured] =
erf(qd / (sqrt(2) s))``, about ``tanh(qd / s)``: the width that fits is the measured velocity's
noise, not the arm's ``friction_velocity`` (0.02 rad/s by default; on the drawn iiwa's excitation
that wider law made three fifths of the identified model's torque error along the task's path,
``studies/excitation_diagnosis.py``). A plant whose law is that ``tanh`` keeps its own width.

The noise is measured on the record itself (:func:`velocity_noise_std`), so ``adaptive-dd
identify`` (a log, no stated noise) and the excitation phase of ``[run] excite`` (a simulated
record) give the same model on the same record (``[model] from = "model.json"`` and ``[run]
excite`` hand on the same friction).

A real arm's law is neither: :func:`profile_coulomb_width` estimates each joint's width from the
record itself, the profile likelihood of the identification over a grid of widths, with an
interval (``adaptive-dd identify --coulomb-width profile``, the default on a log read through a
``[record]`` table: on the TIAGo log it predicts the held-out torque better than the noise's width,
though its widths move between disjoint windows, ``docs/real_log.md``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.identification.log_covariance import filter_lag, long_run_factor, residual_lag
from adaptive_dd.identification.log_fit import coulomb_index

__all__ = [
    "MIN_WIDTH",
    "WidthProfile",
    "auto_coulomb_width",
    "coulomb_columns",
    "coulomb_index",
    "coulomb_width",
    "derived_velocity_noise_std",
    "identification_model",
    "profile_coulomb_width",
    "simulated_law",
    "simulated_width",
    "velocity_noise_std",
]

Array = NDArray[np.float64]

MIN_WIDTH = 1e-9
"""[rad/s] The width of a noise-free record (the sign itself, kept finite)."""


def velocity_noise_std(qd: Array) -> float:
    """[rad/s] The white noise std of the velocities ``qd (N, n)`` of a record, rms over the joints:
    each joint's second difference's spread over ``sqrt(6)``, the spread read robustly (``1.4826``
    times the median absolute deviation: a stick-slip plant's velocity jumps at sticking would
    inflate a standard deviation; on the paper's arm by up to 40 %). A smooth motion sampled at a
    millisecond adds a negligible ``T^2 d^3 qd / dt^3``. Velocities derived from positions carry
    the derivative's noise, which this measures the same way."""
    qd = np.asarray(qd, dtype=float)
    if qd.ndim != 2 or qd.shape[0] < 3:
        raise ValueError(f"velocity_noise_std: expected a record (N >= 3, n), got shape {qd.shape}")
    d2 = np.diff(qd, 2, axis=0)
    s = 1.4826 * np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0) / np.sqrt(6.0)
    return float(np.sqrt(np.mean(s**2)))


def derived_velocity_noise_std(q: Array, sample_period: float) -> float:
    """[rad/s] The noise std of velocities derived from the positions ``q (N, n)`` by
    :func:`~adaptive_dd.record.derivatives`, rms over the joints: each joint's position noise
    (its fifth difference's robust spread over ``sqrt(252)``: the motion's share is ``T^5 d^5 q /
    dt^5``, where the third difference's read a 1 Hz motion at 100 Hz as noise) times the Savitzky-Golay
    differentiator's gain on white noise (the norm of its coefficients). The derived velocity's
    own differences cannot tell it: its error is smooth over the window, so
    :func:`velocity_noise_std` of it reads a width two orders of magnitude too small."""
    from scipy.signal import savgol_coeffs

    from adaptive_dd.record_derivatives import derivative_samples

    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[0] < 7:
        raise ValueError(f"derived_velocity_noise_std: expected a record (N >= 7, n), got shape {q.shape}")
    d5 = np.diff(q, 5, axis=0)  # the motion's share T^5 q^(5): 1e-6 rad for 1 rad at 1 Hz and 100 Hz
    s = 1.4826 * np.median(np.abs(d5 - np.median(d5, axis=0)), axis=0) / np.sqrt(252.0)
    gain = np.linalg.norm(savgol_coeffs(derivative_samples(sample_period, q.shape[0]), 3, deriv=1,
                                        delta=sample_period))  # fmt: skip
    return float(np.sqrt(np.mean(s**2)) * gain)


def coulomb_width(
    qd: Array,
    friction: str = "stick-slip",
    friction_velocity: float = 0.02,
    q: Array | None = None,
    sample_period: float | None = None,
) -> float:
    """[rad/s] The width ``v`` of the identification's ``fc tanh(qd / v)`` on the record of
    velocities ``qd (N, n)``: ``friction_velocity`` when the arm's law is ``"tanh"``, else the
    record's velocity noise (at least :data:`MIN_WIDTH`): :func:`velocity_noise_std` of measured
    velocities, :func:`derived_velocity_noise_std` of the positions ``q`` at ``sample_period`` when
    the velocities were derived from them (``q`` given)."""
    if friction == "tanh":
        return float(friction_velocity)
    if q is not None:
        if sample_period is None:
            raise ValueError("coulomb_width: velocities derived from q need the sample_period they were at")
        return max(derived_velocity_noise_std(q, sample_period), MIN_WIDTH)
    return max(velocity_noise_std(qd), MIN_WIDTH)


def simulated_law(source: str):
    """``(law, v, path)`` of a record ``adaptive-dd simulate`` wrote (the ``trajectory.json`` beside
    the CSV): its plant's Coulomb law, ``v`` the width of ``fc tanh(qd / v)`` (None for another
    law); None when there is no such file or it does not say."""
    import json
    from pathlib import Path

    path = Path(str(source)).with_suffix(".json")
    try:
        made = json.loads(path.read_text(encoding="utf-8"))
        law = made.get("coulomb_law")
        v = made.get("friction_velocity") if law == "tanh" else None
    except (OSError, ValueError, AttributeError):
        return None
    if not isinstance(law, str) or (law == "tanh" and not (isinstance(v, int | float) and v > 0)):
        return None
    return law, (float(v) if v is not None else None), str(path)


def auto_coulomb_width(rec, profiled: bool = True):
    """``--coulomb-width auto``'s choice on the read record ``rec`` (``identify`` and
    ``benchmarks/real_log.py`` alike): ``(v, files)`` where every record's ``trajectory.json`` (of
    ``adaptive-dd simulate``) states one ``tanh`` law of width ``v``; ``("noise", None)`` where they
    state one law with a sign, or where nothing can be profiled (``profiled`` False); else
    ``("profile", None)``: a law not stated is estimated."""
    laws = []
    if rec.simulator_format:  # each record's own file (several: one law for all)
        laws = [simulated_law(src) for src in (rec.record_names or (rec.source,))]
        laws = laws if all(m is not None for m in laws) and len({m[:2] for m in laws}) == 1 else []
    if laws and laws[0][1] is not None:
        return laws[0][1], ", ".join(m[2] for m in laws)
    return ("noise" if laws or not profiled else "profile"), None


def simulated_width(source: str):
    """``(v, path)`` of a record ``adaptive-dd simulate`` wrote with its plant's ``fc tanh(qd / v)``
    (:func:`simulated_law`), else None (no such file, another law, unreadable)."""
    made = simulated_law(source)
    return (made[1], made[2]) if made is not None and made[1] is not None else None


def identification_model(arm, qd: Array, q: Array | None = None, sample_period: float | None = None):
    """The :class:`~adaptive_dd.identification.model.Model` a record with velocities ``qd (N, n)``
    of ``arm`` is identified with: the arm's, its Coulomb law's width :func:`coulomb_width` (``q``
    and ``sample_period`` given when the velocities were derived from the positions ``q``)."""
    from adaptive_dd.identification.model import arm_model

    v = coulomb_width(qd, getattr(arm, "friction", "stick-slip"), arm.friction_velocity, q, sample_period)
    return dataclasses.replace(arm_model(arm), friction_velocity=v)


PROFILE_GRID = np.geomspace(1e-4, 0.5, 38)
"""[rad/s] The widths the profile tries: ten a decade (26 % apart) from 1e-4 to 0.5 rad/s."""
CHI2_95 = 3.841
"""The chi-square(1) 95 % quantile: the profile's interval."""


@dataclass(frozen=True)
class WidthProfile:
    """Each joint's Coulomb width from the record's profile likelihood (:func:`profile_coulomb_width`).

    Attributes
    ----------
    width : ndarray (n,)
        [rad/s] The width per joint: the profile's minimum where profiled, else the rule's
        (:func:`coulomb_width`).
    profiled : ndarray of bool (n,)
        Joints whose Coulomb parameter is fitted on a kept torque channel.
    grid : ndarray (G,)
        [rad/s] The widths tried.
    criterion : ndarray (n, G)
        ``N_eff sum_j log(rms_j^2)`` relative to its minimum, each joint's width moved along the grid
        with the others at theirs (NaN: not profiled): the profile's ``-2 log`` likelihood ratio.
    interval : ndarray (n, 2)
        [rad/s] The widths about the best where the criterion stays within 3.84, each end
        interpolated in ``log(width)`` between the grid's points where it crosses (an approximate
        95 % interval).
    n_eff : float
        Samples after the residual's correlation is discounted (``N`` over its long-run factor).
    """

    width: Array
    profiled: NDArray[np.bool_]
    grid: Array
    criterion: Array
    interval: Array
    n_eff: float

    def describe(self, names) -> list[str]:
        """One line per profiled joint: its width and interval."""
        return [
            f"{names[j]} {self.width[j]:.3g} (95 % {self.interval[j, 0]:.3g}-{self.interval[j, 1]:.3g})"
            for j in np.flatnonzero(self.profiled)
        ]

    def as_dict(self) -> dict:
        """For ``model.json``."""
        return {
            "grid": self.grid.tolist(),
            "criterion": [[None if not np.isfinite(x) else float(x) for x in row] for row in self.criterion],
            "interval": [[float(a), float(b)] for a, b in self.interval],
            "profiled": self.profiled.tolist(),
            "n_eff": self.n_eff,
        }


def coulomb_columns(qd: Array, width, tau_f: float, sample_period: float, start: int, pieces=None) -> Array:
    """``(N', n)``: the filtered regression's Coulomb columns ``G0 tanh(qd / width)`` of the velocities
    ``qd (N, n)`` (:func:`~adaptive_dd.identification.regression.filtered_regression`'s, transient
    ``start`` cut from each of the record's ``pieces``, default one): joint j's enters its own
    channel only."""
    from adaptive_dd.identification.filters import design_filter_bank
    from adaptive_dd.identification.regression import filter_pieces

    c = np.tanh(np.asarray(qd, dtype=float) / np.asarray(width, dtype=float))
    bank = design_filter_bank("M2", tau_f, sample_period)
    return filter_pieces(bank, c, pieces, start, 0)


def profile_coulomb_width(
    model,
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
    grid: Array = PROFILE_GRID,
    sweeps: int = 3,
    pieces=None,
    offset: bool = False,
) -> WidthProfile:
    """Each joint's width of the Coulomb law ``fc_j tanh(qd_j / v_j)`` that explains the record best.

    The record's weighted least squares (:func:`~adaptive_dd.identification.log_fit.fit_log`'s
    regression and weights, the widths of ``model`` to start) is refitted with joint j's Coulomb
    column at each width of ``grid`` (the others kept), and the width chosen minimises the
    Gaussian profile likelihood with a variance per channel, ``sum_j log rms_j^2`` of the kept
    channels; the joints in turn, until no width moves (at most ``sweeps`` rounds). Only the Coulomb
    columns change with the widths, so the regression is built once (the columns swapped,
    :func:`coulomb_columns`; each refit a projection off the other columns). The interval is the
    likelihood ratio's, the residual's correlation discounted as the Newey-West covariance does
    (``N_eff``); it is approximate: the residual of a real log is model error, not noise.

    Only joints whose Coulomb parameter is identified and fitted on a kept channel are profiled.
    ``pieces``: the record's continuous pieces, ``offset``: a torque offset per channel fitted too, as
    :func:`~adaptive_dd.identification.log_fit.fit_log`'s.
    """
    from adaptive_dd.identification.log_fit import _identified_regression, _reweighted_fit
    from adaptive_dd.identification.regression import filtered_regression

    used = np.asarray(used, dtype=bool)
    K = np.asarray(identified, dtype=bool)
    n = model.n
    width = np.broadcast_to(np.asarray(model.friction_velocity, dtype=float), (n,)).copy()
    reg = filtered_regression(
        model, q, qd, tau, tau_f=tau_f, sample_period=sample_period, torque_held=torque_held, pieces=pieces
    )
    phi, y = _identified_regression(model, reg, used, K, weak_ok=True)
    if offset:  # the offsets profiled out, as fit_log does: each channel's rows about their mean
        phi, y = phi - phi.mean(axis=0), y - y.mean(axis=0)
    cw = np.ones(n) if channel_weight is None else np.asarray(channel_weight, dtype=float)
    _, res, w, _ = _reweighted_fit(phi, y, cw[used])
    u = (res * w).sum(axis=1)  # the Bartlett factor at fit_log's lag, within the pieces as it takes it
    bounds = reg.row_bounds()
    n_eff = y.shape[0] / long_run_factor(u, residual_lag(u, bounds, filter_lag(tau_f, sample_period)), bounds)
    col = np.cumsum(K) - 1  # base column -> column of phi
    kept = np.flatnonzero(used)
    joints = {  # joint -> (its channel among the kept, its Coulomb column in phi)
        j: (int(np.flatnonzero(kept == j)[0]), int(col[k]))
        for j, k in coulomb_index(model).items()
        if used[j] and K[k]
    }
    grid = np.asarray(grid, dtype=float)
    crit = np.full((n, grid.size), np.nan)
    cols = {  # joint j's candidate columns (N', G)
        j: coulomb_columns(qd[:, j : j + 1] / grid, 1.0, tau_f, sample_period, reg.start, reg.pieces)
        for j in joints
    }
    if offset:
        cols = {j: c - c.mean(axis=0) for j, c in cols.items()}
    at = {}
    for j, (r, c) in joints.items():  # start from the grid's nearest to the model's width
        at[j] = int(np.argmin(np.abs(np.log(grid / width[j]))))
        phi[:, r, c] = cols[j][:, at[j]]
    for _ in range(sweeps):
        moved = False
        for j, (r, c) in joints.items():
            J = _profile(phi, y, w, r, c, cols[j])
            best = int(np.argmin(J))
            crit[j] = n_eff * (J - J.min())
            moved |= best != at[j]
            at[j] = best
            phi[:, r, c] = cols[j][:, best]
        if not moved:
            break
    for j in joints:
        width[j] = grid[at[j]]
    interval = np.array(
        [_interval(grid, crit[j], at[j]) if j in joints else [np.nan, np.nan] for j in range(n)]
    )
    profiled = np.zeros(n, dtype=bool)
    profiled[list(joints)] = True
    return WidthProfile(width, profiled, grid, crit, interval, float(n_eff))


def _interval(grid: Array, crit: Array, best: int) -> list[float]:
    """The widths about ``grid[best]`` where the criterion ``crit (G,)`` stays within
    :data:`CHI2_95`: each end where it crosses the threshold, linearly in ``log(width)`` between the
    last grid point inside and the first outside (the grid's end where it does not cross)."""
    if not np.isfinite(crit[best]):  # no profile to read an interval from
        return [np.nan, np.nan]
    lg = np.log(grid)
    ends = []
    for step in (-1, 1):
        k = best
        while 0 <= k + step < grid.size and crit[k + step] <= CHI2_95:
            k += step
        if not 0 <= k + step < grid.size or not np.isfinite(crit[k + step]):
            ends.append(float(grid[k]))
            continue
        f = (CHI2_95 - crit[k]) / (crit[k + step] - crit[k])  # crit[k] <= threshold < crit[k + step]
        ends.append(float(np.exp(lg[k] + f * (lg[k + step] - lg[k]))))
    return ends


def _profile(phi: Array, y: Array, w: Array, r: int, c: int, columns: Array) -> Array:
    """``sum_j log rms_j^2`` (G,) of the weighted fit of ``y ~ phi`` with ``phi[:, r, c]`` each column
    of ``columns (N, G)`` in turn (the weights ``w`` kept): ``y`` and the candidates projected off the
    other columns once (Frisch-Waugh), each candidate then a one-column fit."""
    N, m, k = phi.shape
    A = (phi * w[None, :, None]).reshape(-1, k)
    others = np.delete(A, c, axis=1)
    scale = np.linalg.norm(others, axis=0)
    Q = np.linalg.qr(others / np.where(scale > 0, scale, 1.0))[0]
    yw = (y * w).reshape(-1)
    ry = yw - Q @ (Q.T @ yw)
    cand = columns * w[r]  # (N, G): channel r's rows; the others zero
    ra = -(Q @ (Q.reshape(N, m, -1)[:, r, :].T @ cand))  # (N m, G)
    ra.reshape(N, m, -1)[:, r, :] += cand
    beta = (ra.T @ ry) / np.maximum(np.sum(ra**2, axis=0), 1e-300)
    res = (ry[:, None] - ra * beta).reshape(N, m, -1) / w[None, :, None]
    return np.sum(np.log(np.mean(res**2, axis=0)), axis=0)
