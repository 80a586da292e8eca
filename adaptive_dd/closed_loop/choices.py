"""The closed loop's compile-time choices: what the per-sample glue calls, chosen by type.

:mod:`adaptive_dd.closed_loop.glue` calls the plant (:func:`plant_advance`), the law
(:func:`law_command`, :func:`law_estimate`), the estimator (:func:`estimator_sample`) and their
scratch through these functions; each is only a name and a contract, compiled only: the overloads
for the type of its record give its implementation, the N-joint arm's in
:mod:`adaptive_dd.closed_loop.chain_choices` and the paper's two-link arm's in
:mod:`adaptive_dd.benchmark.compiled`. All are importable from :mod:`adaptive_dd.closed_loop.glue`.
"""

from __future__ import annotations

__all__ = [
    "estimator_sample",
    "estimator_work",
    "law_command",
    "law_delay",
    "law_estimate",
    "law_work_of",
    "plant_advance",
    "plant_joints",
    "plant_work",
]


def plant_work(pl, n):  # pragma: no cover - replaced by the overloads
    """Scratch of one trial's plant step, allocated once per trial (not per sample)."""
    raise NotImplementedError("compiled only")


def plant_joints(pl, q):  # pragma: no cover - replaced by the overloads
    """The plant's number of joints: a compile-time constant where the plant's type fixes it (the
    two-link arm: its loops over joints are then unrolled), else ``q.shape[1]``."""
    raise NotImplementedError("compiled only")


def plant_advance(pl, i, s, q, qd, stuck, tau, T, pw):  # pragma: no cover - replaced by the overloads
    """Trial i's plant ``q, qd (S, n)`` by one sample under ``tau (n,)`` (zero-order hold) in
    payload segment s, in place; ``stuck (S, n)`` receives the joints held by Coulomb friction."""
    raise NotImplementedError("compiled only")


def law_work_of(law, n):  # pragma: no cover - replaced by the overloads
    """Scratch of one trial's law, allocated once per trial."""
    raise NotImplementedError("compiled only")


def law_command(law, ls, pl, i, s, T, q, qd, q_d, qd_d, qdd_d, lw, out):  # pragma: no cover
    """Trial i's command ``out (n,)`` [N m] from its measured ``q, qd (n,)`` and the reference at
    this sample; ``ls`` the law's per-trial state (updated in place when the law adapts), ``pl``
    the plant (the oracles' true model of segment s)."""
    raise NotImplementedError("compiled only")


def law_delay(law):  # pragma: no cover - replaced by the overloads
    """Samples after each swap before the law's true model (an oracle's) switches to the new
    segment's: 0 but for ``ct_oracle_late``, the floor told of each swap late."""
    raise NotImplementedError("compiled only")


def law_estimate(law, ls, i, lw, out):  # pragma: no cover - replaced by the overloads
    """Trial i's estimate in base parameters (a view of the state, or written into ``out (p,)``)."""
    raise NotImplementedError("compiled only")


def estimator_work(ec, es):  # pragma: no cover - replaced by the overloads
    """Scratch of one trial's estimator, reused from sample to sample (an empty array without one)."""
    raise NotImplementedError("compiled only")


def estimator_sample(ec, es, ls, i, q, qd, tau, ew):  # pragma: no cover - replaced by the overloads
    """One sample of trial i's estimator on the measured ``q, qd`` (NaN if lost) and the applied
    ``tau``: 1 on an alarm, else 0; the law's model, its count of samples since the last alarm and
    its residual observer's applied torques
    (:func:`~adaptive_dd.closed_loop.residual_observer.observe_applied`) updated. An array ``ec``
    means no estimator; an ``EstCfg`` the N-joint online estimator
    (:func:`~adaptive_dd.identification.online_kernel.est_step_trial_in`)."""
    raise NotImplementedError("compiled only")


def _is(typ, cls) -> bool:
    return getattr(typ, "instance_class", None) is cls
