"""The leaderboard's flags: each trial that saturated, lost tracking or failed, from when, and why.

A trial's row can read well while the trial did not: a law saturated from the start and failing
seconds later, or one whose error grew to half a radian in its last segment without crossing the
failure rule's ``max_error``. Per trial (scenario, controller, seed) the flags say so:

- **saturated**: in a segment, the command beyond a joint's torque limit on more than
  :data:`~adaptive_dd.benchmark.metrics.SATURATION_LIMIT` of the samples (the benchmark's limit
  for a floor); from the segment's first saturated sample (the run streams it per segment);
- **lost tracking**: the joint-space error ``|q_d - q|`` beyond :data:`LOST_ERROR`, from the first
  sample it is;
- **failed**: the run's failure rule (non-finite, ``max_error``, runaway speed, the controller
  raised), at the sample it fired, with the run's reason.

The table counts the first two per row (``saturated_seeds``, ``lost_seeds``; ``failures`` the
third) and ``leaderboard.json`` lists every flagged trial with its first flag's time and every
reason (:func:`trial_flags`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["LOST_ERROR", "lost_times", "trial_flags"]

LOST_ERROR = 0.2
"""[rad] a joint-space tracking error beyond which a trial has lost tracking (11.5 deg: three orders
of magnitude above the floors' 0.1 mrad; no task tolerates it)."""


def lost_times(e_segments: list, t0: list[float], T: float, n_seeds: int, until=None) -> np.ndarray:
    """``(n_seeds, n_segments)``: per seed and segment the time [s] of the first sample whose error
    norm exceeds :data:`LOST_ERROR` (NaN: none); ``e_segments`` the error norm per segment
    (``(n_seeds, samples)`` or None), ``t0`` each segment's start [s]; ``until (n_seeds,)`` [s]:
    each trial's failure (inf: none), after which nothing is flagged (the failure is the flag: the
    arm is stopped and the reference runs away from it)."""
    out = np.full((n_seeds, len(e_segments)), np.nan)
    for i, e in enumerate(e_segments):
        if e is None or e.shape[1] == 0:
            continue
        over = e > LOST_ERROR
        if until is not None:
            times = t0[i] + T * np.arange(e.shape[1])
            over &= times[None, :] < np.asarray(until, float)[:, None] - 0.5 * T
        hit = over.any(axis=1)
        out[hit, i] = t0[i] + T * np.argmax(over[hit], axis=1)
    return out


def trial_flags(cells: list[dict]) -> list[dict]:
    """Every flagged trial of ``cells`` (a scenario's or an arm's, not the population's):
    ``{"scenario", "controller", "seed", "t_s", "flag", "reasons"}`` with the first flag's time
    [s] and name, and every reason in time order."""
    from adaptive_dd.benchmark.metrics import SATURATION_LIMIT

    events: dict = {}
    for c in cells:
        for j, seed in enumerate(c["seed"]):
            ev = events.setdefault((c["scenario"], c["controller"], int(seed)), [])
            sat = c["sat_flag"][j] if "sat_flag" in c else c["sat"][j]  # a failed trial's too
            if sat > SATURATION_LIMIT:
                known = np.isfinite(c["sat_t"][j])  # not when the sums were built by hand
                t = float(c["sat_t"][j]) if known else c["t0"]
                when = (
                    "its first saturated sample" if known else "the segment's start: no sample time streamed"
                )
                ev.append(
                    (t, "saturated", f"command saturated on {100 * sat:.1f} % of segment "
                     f"{c['segment']}'s samples (from t = {t:.3f} s, {when})")
                )  # fmt: skip
            if np.isfinite(c["lost_t"][j]):
                ev.append((float(c["lost_t"][j]), "lost tracking", f"|q_d - q| beyond {LOST_ERROR:g} rad "
                           f"at t = {c['lost_t'][j]:.3f} s (segment {c['segment']})"))  # fmt: skip
            failed = c.get("failed_trial", np.isfinite(c["fail_t"]))[j]
            if c["segment"] == 0 and failed:
                t = float(c["fail_t"][j])  # NaN: not recorded (a plug-in that raised in compiled code)
                at = f"at t = {t:.3f} s" if np.isfinite(t) else "(time not recorded)"
                ev.append((t, "failed", f"failed {at}: {c['why'][j]}"))
    out = []
    for (sc, ctrl, seed), ev in events.items():
        if ev:
            ev.sort(key=lambda x: (np.isnan(x[0]), x[0]))  # an event of no recorded time last
            t = None if np.isnan(ev[0][0]) else round(ev[0][0], 6)
            out.append(
                {"scenario": sc, "controller": ctrl, "seed": seed, "t_s": t,
                 "flag": ev[0][1], "reasons": [r for _, _, r in ev]}
            )  # fmt: skip
    return out
