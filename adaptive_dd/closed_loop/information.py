"""Per swap of an N-joint run: the information-limited time to know the payload, beside the
time each estimating controller took (``information_time``, ``mass_learning_time`` and
``com_learning_time`` of each segment in the metrics): its mass within 5 % and its centre of
mass within 1 cm; and the time an optimal test would detect the swap (``two_link_detection_limit``)."""

from __future__ import annotations

import numpy as np

__all__ = ["COM_TOL", "INFO_WINDOW", "add_information_times", "com_learning_time", "mass_learning_time"]

INFO_WINDOW = 1.0
"""[s] after a swap searched for the information-limited time."""

COM_TOL = 0.01
"""[m] the centre of mass counts as known within this distance."""


def mass_learning_time(m_hat: np.ndarray, mass: float, removed: float, T: float, rel: float = 0.05):
    """First time after which the estimated mass stays within ``rel`` of the truth (per row), NaN if never.

    ``rel`` is taken of the payload that changed (``max(mass, removed)``), so a removal is judged
    on the mass that left.
    """
    tol = rel * max(mass, removed)
    outside = np.abs(m_hat - mass) > tol  # (n, N)
    n = outside.shape[-1]
    last = np.where(outside.any(axis=-1), n - 1 - np.argmax(outside[..., ::-1], axis=-1), -1)
    return np.where(last < n - 1, (last + 1) * T, np.nan)


def com_learning_time(
    com_hat: np.ndarray, com: np.ndarray, T: float, tol: float = COM_TOL, axes=None
) -> np.ndarray:
    """First time [s] after which the estimated centre of mass ``com_hat (n, N, 3)`` stays within
    ``tol`` [m] of ``com (3,)`` (per row), NaN if it never settles there (a NaN estimate counts as
    outside). ``axes``: a (3,) mask of the components judged (default all; a planar arm's
    estimate has no out-of-plane component)."""
    ax = np.ones(3, bool) if axes is None else np.asarray(axes, bool)
    d = (com_hat - np.asarray(com, float))[..., ax]
    with np.errstate(invalid="ignore"):
        outside = ~(np.linalg.norm(d, axis=-1) <= tol)  # (n, N)
    n = outside.shape[-1]
    last = np.where(outside.any(axis=-1), n - 1 - np.argmax(outside[..., ::-1], axis=-1), -1)
    return np.where(last < n - 1, (last + 1) * T, np.nan)


def add_information_times(res, out: dict) -> None:
    """Fill ``information_time`` (``known``: the information-limited time to know the payload
    mass to 5 % along ct_oracle's first kept trajectory, None without ct_oracle, beyond the
    window, or for a removal after an empty segment; ``seeds``, ``reference``; ``com_known``,
    ``com_axes`` when a payload came) and ``mass_learning_time`` (median over the
    kept seeds of the first time after which the estimated mass stays within 5 % of the
    payload that changed) of every segment after a swap."""
    from adaptive_dd.closed_loop.types import run_constants

    sc = res.scenario
    rc = run_constants(sc)
    segs = sc.segments()
    info_fn = _information_function()
    oracle = res.runs.get("ct_oracle")
    for i in range(1, len(segs)):
        mass, removed = segs[i][2], segs[i - 1][2]
        k0, k1 = int(rc.seg_start[i]), int(rc.seg_end[i])
        info = None
        k_end = min(k1, k0 + round(INFO_WINDOW / rc.T))
        if info_fn is not None and oracle is not None and oracle.q.shape[0] and not oracle.failed[0]:
            info = info_fn(res, oracle, i, k0, k_end)
        # the two-link arm's keys: a table even when nothing could be computed ("unknown", the
        # time with every other parameter unknown, is the two-link arm's only)
        info = info or {"known": None, "seeds": 0, "reference": None}
        limit = _detection_limit(sc, oracle, i, k0, k_end)
        for name, run in res.runs.items():
            seg = out[name]["segments"][i]
            seg["information_time"] = info
            seg["detection_limit"] = limit
            seg["mass_learning_time"] = None
            seg["com_learning_time"] = None
            seg["learning_seeds"] = 0
            if run.sigma_hat is not None and run.sigma_hat.shape[0]:
                kept = ~run.failed[: run.sigma_hat.shape[0]]
                seg["learning_seeds"] = int(kept.sum())
                with np.errstate(invalid="ignore", divide="ignore"):
                    est = sc.arm.payload_from_sigma(run.sigma_hat[kept, k0:k1])
                tl = mass_learning_time(est.mass, mass, removed, rc.T)
                seg["mass_learning_time"] = None if np.all(np.isnan(tl)) else float(np.nanmedian(tl))
                if mass > 0:  # a payload on: where is its centre of mass
                    com = sc.payload_of(i - 1).get("com", np.zeros(3))
                    tc = com_learning_time(est.com, com, rc.T, axes=sc.arm.payload_identifiable[1:4])
                    seg["com_learning_time"] = None if np.all(np.isnan(tc)) else float(np.nanmedian(tc))


def _payload(sc, j: int) -> np.ndarray:
    """Parameters (10,) of the payload of swap ``j`` (zeros: none, or j < 0)."""
    from adaptive_dd.plant.arm import payload_parameters

    if j < 0 or sc.swap_masses[j] <= 0:
        return np.zeros(10)
    p = sc.payload_of(j)
    return payload_parameters(p["mass"], p.get("com"), p.get("inertia"), p.get("radius", 0.0))


def _detection_limit(sc, oracle, i: int, k0: int, k1: int) -> float | None:
    """Median over ct_oracle's kept trajectories of the time the optimal test detects the swap
    that starts segment i (:func:`~adaptive_dd.identification.detection_limit.detection_limit`);
    None without ct_oracle's trajectories, without a change, or beyond the window."""
    from adaptive_dd.identification.detection_limit import detection_limit

    if oracle is None or oracle.q is None or not oracle.q.shape[0]:
        return None
    before, after = _payload(sc, i - 2), _payload(sc, i - 1)
    if np.array_equal(before, after) or k1 - k0 < 2:
        return None
    times = []
    for j in range(oracle.q.shape[0]):
        if oracle.failed[j]:
            continue
        t = detection_limit(
            sc.arm, oracle.q[j, k0:k1], oracle.qd[j, k0:k1], oracle.tau[j, k0:k1], 0, sc.sample_period,
            before, after, sc.position_variance, sc.velocity_variance, n_tests=sc.n_samples,
        )  # fmt: skip
        times.append(np.inf if t is None else t)
    if not times or not np.isfinite(np.median(times)):
        return None
    return float(np.median(times))


def _information_function():
    """``f(res, oracle_run, segment, k0, k1) -> {"known": seconds} or None``: the time the Cramer-Rao bound on
    the payload mass takes to fall below 5 % of the payload that changed (the new one, or the
    one removed), along the oracle's first kept trajectory (qdd by differentiating the true qd),
    from :func:`adaptive_dd.identification.payload_information.payload_information_time`; and
    (``"com_known"``, when a payload came) the time to know its centre of mass within 1 cm
    (:func:`~adaptive_dd.identification.payload_information.payload_com_information_time`)."""
    from adaptive_dd.identification.payload_information import (
        payload_com_information_time,
        payload_information_time,
    )

    def info(res, oracle, i, k0, k1):
        sc = res.scenario
        j = i - 1 if sc.swap_masses[i - 1] > 0 else i - 2  # the payload that came, or that left
        if j < 0 or sc.swap_masses[j] <= 0:
            return None
        pay = _payload(sc, j)
        T = sc.sample_period
        lo = max(0, k0 - 1)
        q, qd = oracle.q[0, lo:k1], oracle.qd[0, lo:k1]
        qdd = np.gradient(qd, T, axis=0)
        pv, vv = np.asarray(sc.position_variance), np.asarray(sc.velocity_variance)
        kw = dict(sample_period=T, position_variance=pv, velocity_variance=vv)
        t = payload_information_time(sc.arm, q, qd, qdd, pay, k0 - lo, **kw)
        if not np.isfinite(t):
            return None
        out = {"known": t, "seeds": 1, "reference": oracle.name}
        if j == i - 1:  # the payload came: its centre of mass
            ax = sc.arm.payload_identifiable[1:4]
            tc = payload_com_information_time(sc.arm, q, qd, qdd, pay, k0 - lo, tol=COM_TOL, axes=ax, **kw)
            out["com_axes"] = "".join(a for a, k in zip("xyz", ax, strict=True) if k)
            out["com_known"] = float(tc) if np.isfinite(tc) else None
        return out

    return info
