"""Per swap of a benchmark run, on every arm: the information-limited time to know the payload,
the time an optimal test detects the swap, and the time each estimating controller took.

One key set and one meaning on every arm (:data:`INFORMATION_KEYS`, and the segment keys of
:data:`LEARNING_KEYS`); where a figure exists on one kind of arm only it is ``None`` on the other,
never absent. Every segment after a swap carries:

``information_time`` (a table, :data:`INFORMATION_KEYS`)
    ``known`` [s]: the first time after the swap at which ``Z`` (1.96) times the Cramér-Rao
    standard deviation of the payload mass is within ``REL`` (5 %) of the payload that changed
    (the larger of the one that came and the one that left), every other parameter of the arm
    known; the median over the reference run's kept trajectories, a trajectory where it is not
    reached within :data:`INFO_WINDOW` counting as later than any (None when the median is not
    reached, or without a payload on either side). The bound is the paper's output-error
    model of sigma (:func:`~adaptive_dd.identification.fisher.mass_information_time`) on the
    two-link arm, the M2-filtered regression of the payload's ten parameters
    (:func:`~adaptive_dd.identification.payload_information.payload_information_time`) on an
    N-joint arm: the same question asked of the sensors each estimator reads.
    ``unknown`` [s]: the same with all seven base parameters unknown; the two-link arm only
    (None on an N-joint arm, whose arm is identified before: ``docs/identification_limits.md``).
    ``com_known`` [s]: the time to know the centre of mass of a payload that came within
    :data:`COM_TOL` (1 cm; ``Z`` times the root trace of its covariance); N-joint arms only
    (None on the two-link arm, whose payload sits at the tip by the paper's model, and after a
    removal). ``com_axes``: the components judged (``"xyz"``, or the identifiable ones of a
    planar arm; None where ``com_known`` is not computed). ``seeds``: trajectories the medians
    are over; ``reference``: the run they come from (``ct_oracle``, else the first run with kept
    trajectories; None without one).
``detection_limit`` [s]
    Median over the reference run's kept trajectories of the time an optimal test (GLR at 1 %
    false alarms per trial, the rest of the arm known) detects the swap, as ``known`` counts one
    not reached; None without a change or when the median is not reached.
``mass_learning_time``, ``com_learning_time`` [s]
    Median over a controller's kept, unfailed trajectories of the first time after which its
    estimated mass stays within 5 % of the payload that changed, its centre of mass within 1 cm
    (N-joint arms only: None on the two-link arm), a trajectory that never does counting as later
    than any (as the limits count one not reached); None for a controller without an estimate or
    when the median never does. ``learning_seeds``: the trajectories those medians are over (0: none).

The first segment (no swap) has every one of these keys, ``None`` (``learning_seeds`` 0).
"""

from __future__ import annotations

import numpy as np

from adaptive_dd.benchmark.streaming import SETTLE, segment_bounds

__all__ = [
    "COM_TOL",
    "INFORMATION_KEYS",
    "INFO_WINDOW",
    "LEARNING_KEYS",
    "REL",
    "Z",
    "add_information_times",
    "com_learning_time",
    "mass_learning_time",
]

INFO_WINDOW = 1.0
"""[s] after a swap searched for the information-limited time."""

COM_TOL = 0.01
"""[m] the centre of mass counts as known within this distance."""

REL = 0.05
"""The payload mass counts as known within this fraction of the payload that changed."""

Z = 1.96
"""Standard deviations of the Cramér-Rao bound that must lie within the tolerance (a 95 % interval)."""

INFORMATION_KEYS = ("known", "unknown", "com_known", "com_axes", "seeds", "reference")
"""The keys of every segment's ``information_time`` table, on every arm (module docstring)."""

LEARNING_KEYS = (
    "information_time",
    "detection_limit",
    "mass_learning_time",
    "com_learning_time",
    "learning_seeds",
)
"""The keys :func:`add_information_times` gives every segment, on every arm."""


def mass_learning_time(m_hat: np.ndarray, mass: float, removed: float, T: float, rel: float = REL):
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


def _median_limit(x) -> float | None:
    """Median of limits over trajectories, one not reached (None, inf) counting as later than any;
    None when the median is not reached."""
    v = np.asarray([np.inf if y is None else y for y in x], float)
    m = float(np.median(v)) if v.size else np.inf
    return m if np.isfinite(m) else None


def _reference(res):
    """The run whose kept trajectories the limits are computed along: ``ct_oracle``, else the
    first run with kept trajectories; None without one."""
    runs = sorted(res.runs.items(), key=lambda x: x[0] != "ct_oracle")
    return next((r for _, r in runs if r.q is not None and r.q.shape[0]), None)


def _kept(run) -> list[int]:
    """The kept trajectories of ``run`` whose trial did not fail."""
    return [j for j in range(run.q.shape[0]) if not run.failed[j]]


def empty_information() -> dict:
    """``information_time`` when nothing could be computed: every key, None (``seeds`` 0)."""
    return dict.fromkeys(INFORMATION_KEYS) | {"seeds": 0}


def add_information_times(res, out: dict) -> None:
    """Fill the :data:`LEARNING_KEYS` of every segment of every controller in ``out`` (the
    metrics' ``{NAME: {"segments": [...]}}``), as the module docstring defines them."""
    sc = res.scenario
    segs = sc.segments()
    start, end, _ = segment_bounds(segs, sc.sample_period, SETTLE)
    ref = _reference(res)
    w = round(INFO_WINDOW / sc.sample_period)
    forms = _chain if sc.closed_forms is None else _two_link
    for name in res.runs:
        out[name]["segments"][0].update(dict.fromkeys(LEARNING_KEYS) | {"learning_seeds": 0})
    for i in range(1, len(segs)):
        mass, removed = segs[i][2], segs[i - 1][2]
        k0, k1 = int(start[i]), int(end[i])
        k_end = min(k1, k0 + w)
        info, limit = empty_information(), None
        if ref is not None and _kept(ref) and max(mass, removed) > 0:
            info = forms.information(sc, ref, i, k0, k_end)
            limit = forms.detection_limit(sc, ref, i, k0, k_end)
        for name, run in res.runs.items():
            seg = out[name]["segments"][i]
            seg.update(information_time=dict(info), detection_limit=limit)
            seg.update(_learning(sc, forms, run, i, k0, k1))


def _learning(sc, forms, run, i: int, k0: int, k1: int) -> dict:
    """``mass_learning_time``, ``com_learning_time`` and ``learning_seeds`` of one run's segment i."""
    out = {"mass_learning_time": None, "com_learning_time": None, "learning_seeds": 0}
    if run.sigma_hat is None or not run.sigma_hat.shape[0]:
        return out
    mass, removed = sc.segments()[i][2], sc.segments()[i - 1][2]
    kept = ~run.failed[: run.sigma_hat.shape[0]]
    m_hat, com_hat = forms.payload(sc, run.sigma_hat[kept, k0:k1])
    out["learning_seeds"] = int(kept.sum())
    never = np.inf  # a trajectory that never learns (NaN) counts as later than any
    tm = mass_learning_time(m_hat, mass, removed, sc.sample_period)
    out["mass_learning_time"] = _median_limit(np.where(np.isnan(tm), never, tm))
    if com_hat is not None and mass > 0:  # a payload on: where is its centre of mass
        com = sc.payload_of(i - 1).get("com", np.zeros(3))
        tc = com_learning_time(com_hat, com, sc.sample_period, axes=sc.arm.payload_identifiable[1:4])
        out["com_learning_time"] = _median_limit(np.where(np.isnan(tc), never, tc))
    return out


class _two_link:
    """The two-link arm's forms: the paper's sigma (eq. 9) and its output-error information."""

    @staticmethod
    def payload(sc, sigma_hat):
        """``(mass (n, N), None)``: the paper's sigma holds no payload centre of mass."""
        return sc.closed_forms.payload_mass_from_sigma(sigma_hat), None

    @staticmethod
    def information(sc, ref, i: int, k0: int, k1: int) -> dict:
        from adaptive_dd.identification.fisher import mass_information_time

        _, _, mass = sc.segments()[i]
        removed = sc.segments()[i - 1][2]
        kw = dict(
            sigma_after=sc.closed_forms.sigma_with_payload(mass, sc.payload_radius),
            payload_direction=sc.closed_forms.payload_direction(sc.payload_radius),
            position_variance=sc.position_variance, velocity_variance=sc.velocity_variance,
            rel=REL, mass=max(mass, removed), z=Z,
        )  # fmt: skip
        kept = _kept(ref)
        times = {
            others: [
                mass_information_time(
                    ref.q[j, k0 - 1 : k1],
                    ref.qd[j, k0 - 1 : k1],
                    ref.tau[j, k0 - 1 : k1],
                    1,
                    sc.sample_period,
                    others=others,
                    **kw,
                )
                for j in kept
            ]
            for others in ("known", "unknown")
        }
        info = empty_information()
        info.update(known=_median_limit(times["known"]), unknown=_median_limit(times["unknown"]))
        return info | {"seeds": len(kept), "reference": ref.name}

    @staticmethod
    def detection_limit(sc, ref, i: int, k0: int, k1: int) -> float | None:
        from adaptive_dd.identification.two_link_detection_limit import two_link_detection_limit

        _, _, mass = sc.segments()[i]
        removed = sc.segments()[i - 1][2]
        if mass == removed:
            return None
        limits = [
            two_link_detection_limit(
                ref.q[j, k0 - 1 : k1],
                ref.qd[j, k0 - 1 : k1],
                ref.tau[j, k0 - 1 : k1],
                1,
                sc.sample_period,
                sc.closed_forms.sigma_with_payload(mass, sc.payload_radius),
                sc.closed_forms.payload_direction(sc.payload_radius),
                abs(mass - removed),
                sc.position_variance,
                sc.velocity_variance,
                n_tests=sc.n_samples,
            )
            for j in _kept(ref)
        ]
        return _median_limit(limits)


class _chain:
    """An N-joint arm's forms: the payload's ten parameters and the filtered regression's information."""

    @staticmethod
    def payload(sc, sigma_hat):
        """``(mass (n, N), com (n, N, 3))`` implied by the estimates."""
        with np.errstate(invalid="ignore", divide="ignore"):
            est = sc.arm.payload_from_sigma(sigma_hat)
        return est.mass, est.com

    @staticmethod
    def information(sc, ref, i: int, k0: int, k1: int) -> dict:
        from adaptive_dd.identification.payload_information import payload_information_times

        mass, removed = sc.segments()[i][2], sc.segments()[i - 1][2]
        came = mass > 0  # the payload that came, else the one that left
        pay = _payload(sc, i - 1 if came else i - 2)
        T = sc.sample_period
        lo = max(0, k0 - 1)
        ax = sc.arm.payload_identifiable[1:4]
        kw = dict(
            sample_period=T, position_variance=np.asarray(sc.position_variance),
            velocity_variance=np.asarray(sc.velocity_variance), axes=ax,
            mass_tol=REL * max(mass, removed) / pay[0] / Z, com_tol=COM_TOL / Z,
        )  # fmt: skip
        kept = _kept(ref)
        times = []
        for j in kept:  # the mass of the payload that changed, its centre of mass, at Z sigma
            q, qd = ref.q[j, lo:k1], ref.qd[j, lo:k1]
            times.append(
                payload_information_times(sc.arm, q, qd, np.gradient(qd, T, axis=0), pay, k0 - lo, **kw)
            )
        info = empty_information()
        info.update(known=_median_limit([t[0] for t in times]), seeds=len(kept), reference=ref.name)
        if came:
            info["com_axes"] = "".join(a for a, k in zip("xyz", ax, strict=True) if k)
            info["com_known"] = _median_limit([t[1] for t in times])
        return info

    @staticmethod
    def detection_limit(sc, ref, i: int, k0: int, k1: int) -> float | None:
        from adaptive_dd.identification.detection_limit import detection_limit

        before, after = _payload(sc, i - 2), _payload(sc, i - 1)
        if np.array_equal(before, after) or k1 - k0 < 2:
            return None
        times = [
            detection_limit(
                sc.arm,
                ref.q[j, k0:k1],
                ref.qd[j, k0:k1],
                ref.tau[j, k0:k1],
                0,
                sc.sample_period,
                before,
                after,
                sc.position_variance,
                sc.velocity_variance,
                n_tests=sc.n_samples,
            )
            for j in _kept(ref)
        ]
        return _median_limit(times)


def _payload(sc, j: int) -> np.ndarray:
    """Parameters (10,) of the payload of swap ``j`` (zeros: none, or j < 0)."""
    from adaptive_dd.plant.arm import payload_parameters

    if j < 0 or sc.swap_masses[j] <= 0:
        return np.zeros(10)
    p = sc.payload_of(j)
    return payload_parameters(p["mass"], p.get("com"), p.get("inertia"), p.get("radius", 0.0))
