"""adaptive_ct's arm prior from an identification: after an excitation phase
(:mod:`adaptive_dd.closed_loop.excitation_phase`) or from a model file (``[model] from =
"model.json"``, what ``adaptive-dd identify`` writes). Apart from the excitation phase so that
loading a scenario does not import the excitation's design (no import circle)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ScenarioError

Array = NDArray[np.float64]

__all__ = [
    "estimator_information",
    "estimator_scale",
    "identified_prior",
    "known_payload_mass_std",
    "model_file_prior",
    "scale_to_information",
]

VAGUE = 1e4
"""[parameter units^2] The estimator's start-up variance in :func:`estimator_information`: its
rows, not that start, make what it knows at the record's end."""


def identified_prior(scenario, prior: Array) -> tuple:
    """The scenario's controller options with adaptive_ct's estimator given ``arm_prior_cov =
    prior`` (a ``(p, p)`` covariance: the identification's knowledge of the arm with its
    correlations, :attr:`ExcitationReport.sigma_cov`), unless its table already says ``mode``,
    ``arm_uncertainty`` or ``arm_prior_cov``; ``p0_arm`` is 0 unless the table states it (the
    arm block starts at ``prior`` as it is: the isotropic 1e-6 of the stated-uncertainty prior is
    above the identification's variance for many of a drawn arm's base parameters,
    docs/learning_the_arm.md); the
    payload block's start-up ``payload_mass_std`` is
    :func:`known_payload_mass_std` unless the table states it. After an
    excitation phase the model is the identified one, and what is left to learn of the arm is
    what the identification did not know, not the URDF's stated uncertainty (vertical3, 2 seeds,
    the URDF's prior about the identified model: adaptive_ct 8.7x its floor before the first swap,
    ct_nominal 1.14x)."""
    from adaptive_dd.benchmark.scenario_checks import freeze, thaw

    opts = {n: thaw(o) for n, o in scenario.controller_options}
    for name in adaptive_entries(scenario):  # adaptive_ct and each variant of it
        ac = opts.setdefault(name, {})
        est = ac.get("estimator", {})
        keys = {"mode", "arm_uncertainty", "arm_prior_cov"}
        if isinstance(est, dict) and not keys & est.keys():
            P = np.asarray(prior, dtype=float)
            ac["estimator"] = {**est, "arm_prior_cov": [[float(x) for x in row] for row in P]}
            if "p0_arm" not in est:  # the identification's covariance as it is: nothing added
                ac["estimator"]["p0_arm"] = 0.0
            if "payload_mass_std" not in est:
                ac["estimator"]["payload_mass_std"] = known_payload_mass_std(scenario.arm, P)
    return tuple((n, freeze(o)) for n, o in opts.items())


def adaptive_entries(scenario) -> list[str]:
    """The entries of the scenario's controllers that run ``adaptive_ct``: itself and its variants
    (:func:`~adaptive_dd.controllers.registry.law_of`)."""
    from adaptive_dd.controllers.registry import law_of

    return [n for n in scenario.controllers if law_of(n, scenario.options(n)) == "adaptive_ct"]


def known_payload_mass_std(arm, prior: Array) -> float:
    """[kg] What an identification of covariance ``prior (p, p)`` knows of a mass at the payload
    frame, ``(b^T prior^-1 b)^-1/2`` with ``b`` its direction in the base parameters
    (``arm.payload_basis[:, 0]``): adaptive_ct's payload block starts with it after an
    identification. The payload then on the arm is the one the identification saw, already in
    the identified model; a start-up prior of the default 5 kg let the payload block take up noise
    before any swap (vertical3 after a 20 s phase, 10 seeds: 5.6x the floor in the first segment
    while ct_nominal on the same model was 1.17x)."""
    b = np.asarray(arm.payload_basis, dtype=float)[:, 0]
    x = np.linalg.lstsq(np.asarray(prior, dtype=float), b, rcond=None)[0]
    return float(1.0 / np.sqrt(max(float(b @ x), 1e-300)))


def estimator_information(cfg, arm, q: Array, qd: Array, tau: Array) -> Array:
    """``(p, p)`` The information the online estimator's own rows take from the record ``q, qd,
    tau (N, n)`` about the arm's base parameters: adaptive_ct's estimator ``cfg`` (mode "arm", its
    data selection, row weights and forgetting; the detector off) run over it from a vague start,
    ``P_end^-1 - lam^N P_0^-1``, the arm block. ``arm``: the arm whose kinematics the rows use
    (the regressor is linear in the parameters: the URDF's or an identified model's give the
    same rows).

    Raises
    ------
    DataError
        The record gives the estimator no information (every sample skipped).
    """
    import dataclasses

    from adaptive_dd.errors import DataError
    from adaptive_dd.identification import online
    from adaptive_dd.identification import online_kernel as K

    pb = arm.base.count
    start = (VAGUE * np.eye(pb)).tolist()
    cfg = dataclasses.replace(
        cfg, mode="arm", arm_uncertainty=None, arm_prior_cov=start, detector=None,
        max_trace=1e300,
    )  # fmt: skip
    q, qd, tau = (np.ascontiguousarray(np.asarray(x, dtype=float)) for x in (q, qd, tau))
    c, s = online.est_init(cfg, arm, 1)
    P0 = s.P[0].copy()
    N, n = q.shape
    p = P0.shape[0]
    eps = np.empty((N, n))
    K.est_run_trial(
        c, s, 0, q, qd, tau, np.empty((N, p)), np.empty((N, 10)), eps, np.zeros(N, np.int64), np.empty(N)
    )  # fmt: skip
    used = int(np.isfinite(eps).any(axis=1).sum())  # samples that forgot (the first row of each)
    if used == 0:
        raise DataError("the online estimator used no sample of the record")
    info = np.linalg.inv(s.P[0]) - cfg.lam0**used * np.linalg.inv(P0)
    return 0.5 * (info[:pb, :pb] + info[:pb, :pb].T)


def scale_to_information(prior: Array, info: Array) -> float:
    """``kappa``: the median over directions of the generalised eigenvalues of the covariance
    ``prior (p, p)`` against the inverse of the information ``info (p, p)``.

    Raises
    ------
    DataError
        No positive median (the information is zero along most directions).
    """
    from adaptive_dd.errors import DataError

    C = np.asarray(prior, dtype=float)
    d, V = np.linalg.eigh(0.5 * (C + C.T))
    S = V * np.sqrt(np.maximum(d, 0.0))
    kappa = float(np.median(np.linalg.eigvalsh(S.T @ np.asarray(info, dtype=float) @ S)))
    if not (np.isfinite(kappa) and kappa > 0.0):
        raise DataError(f"the record gives the online estimator no information to scale the prior ({kappa})")
    return kappa


def estimator_scale(cfg, arm, prior: Array, q: Array, qd: Array, tau: Array) -> float:
    """The identification's covariance ``prior (p, p)`` in the units of the online estimator's
    own rows: ``kappa``, the median over directions of the generalised eigenvalues of ``prior``
    against the inverse of the information the estimator takes from the record ``q, qd, tau (N,
    n)`` the identification was made on (:func:`estimator_information`,
    :func:`scale_to_information`). The hand-off is ``prior / kappa``: the identified model then
    counts, in the median direction, as much as that record would have had the estimator tracked
    it itself, while keeping what the identification knows of each direction (its sandwich's
    correlations, the consistent fit's step, the model error). A consistency check, reported by
    the excitation phase and not applied: the hand-off divided by it measured worse on the drawn
    iiwa (first segment 1.141 against 1.123 unscaled, 10 seeds; docs/learning_the_arm.md).

    The estimator's recursive least squares takes each row as one independent unit of noise
    (rows divided by the torque-resolution weights), while ``prior`` is in the parameters' own
    units; the rows' residual variance in those units (about 0.03 on the drawn iiwa) would say
    the prior counts 35x its data, but the filtered rows are correlated over hundreds of samples,
    so the estimator also over-counts its data; the two nearly cancel (``kappa`` 0.7 and 2.2 on the
    iiwa's seeds 0 and 1) and only the comparison on the record itself says by how much."""
    return scale_to_information(prior, estimator_information(cfg, arm, q, qd, tau))


def _stated_variance(scenario, arm) -> Array:
    """``diag(B C B^T)`` of the model's stated uncertainty (``[model] uncertainty``, by default the
    plant's draw levels: :func:`~adaptive_dd.plant.uncertainty.stated_uncertainty`; normal levels
    given the uniform levels of the same variance; the default levels when stated exact) about
    ``arm``."""
    from adaptive_dd.identification.arm_prior import ArmUncertainty, prior_covariance
    from adaptive_dd.plant.uncertainty import stated_uncertainty

    unc = stated_uncertainty(scenario)
    keys = ("mass", "com", "inertia", "viscous", "coulomb", "armature")
    if unc is None:
        levels = ArmUncertainty()
    else:
        scale = np.sqrt(3.0) if unc.distribution == "normal" else 1.0
        levels = ArmUncertainty(**{k: float(getattr(unc, k)) * scale for k in keys})
    B = arm.base.B
    return np.diag(B @ prior_covariance(arm, levels) @ B.T).copy()


def model_file_prior(scenario, path) -> tuple:
    """``[model] from = "model.json"``: the scenario's controller options with adaptive_ct's arm
    prior what that identification knows (:func:`identified_prior`), by the rule of the
    excitation phase (:func:`~adaptive_dd.identification.arm_prior.identified_prior_std`: the
    file's sandwich covariance, the consistent fit's step and the model error its ``record``
    holds (``model_error_var``, written by ``identify`` since this rule; none in older files); the
    stated uncertainty for the base parameters it held at the URDF's), unscaled as after an
    excitation phase.

    Raises
    ------
    ScenarioError
        Naming ``model.from``: the file's base parameters are not the [arm]'s, or it has no
        consistent fit.
    """
    from adaptive_dd.errors import DataError, ParameterError
    from adaptive_dd.identification.arm_prior import identified_prior_cov
    from adaptive_dd.identification.identified_model import load_identified_model

    if not adaptive_entries(scenario):
        return scenario.controller_options
    where = f"{scenario.source}: key 'model.from' = {str(path)!r}"
    try:
        m = load_identified_model(path)
    except DataError as exc:
        raise ScenarioError(f"{where}: {exc}") from None
    if list(m.names) != list(scenario.arm.base.names):
        raise ScenarioError(
            f"{where}: its {len(m.names)} base parameters are not the [arm]'s {len(scenario.arm.base.names)} "
            "(identified on another arm or URDF)"
        )
    if m.consistent_sigma is None:
        raise ScenarioError(f"{where}: the model has no physically consistent fit to start from")
    extra = m.record.get("model_error_var") if isinstance(m.record, dict) else None
    if extra is not None and np.shape(extra) != (len(m.names),):
        raise ScenarioError(f"{where}: key 'record.model_error_var' must have {len(m.names)} entries")
    try:
        prior = identified_prior_cov(
            np.asarray(m.covariance), np.asarray(m.sigma), np.asarray(m.consistent_sigma),
            np.asarray(m.identified, dtype=bool), _stated_variance(scenario, scenario.arm), extra,
        )  # fmt: skip
    except ParameterError as exc:
        raise ScenarioError(f"{where}: {exc}") from None
    return identified_prior(scenario, prior)
