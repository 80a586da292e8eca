"""What ``identify --arm`` writes: ``estimates.csv`` (each base parameter, its std and 95 % half-width)
and ``model.json`` (:class:`~adaptive_dd.identification.identified_model.IdentifiedModel`), with
``model.urdf`` when a consistent arm was fitted."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _arm_width(model, profile) -> float:
    """[rad/s] The one width the identified arm is handed (``model.json``'s ``friction_velocity``,
    :meth:`IdentifiedModel.arm`): the model's, or the median of the profiled joints' widths."""
    if profile is None or not profile.profiled.any():
        return float(np.median(model.friction_velocity))
    return float(np.median(profile.width[profile.profiled]))


def _write_estimates(path, model, fit) -> None:
    from adaptive_dd.outputs import atomic_write

    with atomic_write(path) as fh:
        # half_width_95: estimate +- it is the 95 % bound (quantile x std: the std's quantile is not 1.96)
        # held: the estimate is mostly the prior's (the URDF's value), as the printed table marks it
        fh.write("name,estimate,std,half_width_95,identified,held,urdf\n")
        share = fit.held.share if fit.held is not None else np.zeros(model.p)
        for k, name in enumerate(model.names):
            half = fit.quantile * fit.std[k]
            fh.write(
                f'"{name}",{fit.sigma[k]:.10g},{fit.std[k]:.4g},{half:.4g},{int(fit.identified[k])},'
                f"{int(share[k] > 0.5)},{model.sigma_ref[k]:.10g}\n"
            )


def _write_model(outputs, arm, model, rec, fit, cf, spec, profile, model_error_var, estimator="wls") -> list:
    """``model.json`` (and ``model.urdf`` with a consistent arm ``cf``) of the fit; ``model_error_var``
    its :func:`~adaptive_dd.identification.model_error.model_error_variance`, computed before the fit
    is printed (it fails on a window too short for its slower filter)."""
    from adaptive_dd.identification.identified_model import (
        IdentifiedModel,
        arm_identity,
        save_identified_model,
    )
    from adaptive_dd.plant.urdf_write import write_fitted_urdf

    n = arm.n_joints
    if cf is not None:
        fr = cf.pi[10 * n :]
    else:  # friction from the estimate where identified alone, else the URDF's
        fr = model.pi_ref[10 * n :].copy()
        for k, name in enumerate(model.names):
            if name.startswith(("fv", "fc")) and fit.identified[k] and "+" not in name:
                j = int(name[2:]) - 1
                fr[j if name.startswith("fv") else n + j] = max(fit.sigma[k], 0.0)
    fitted = None
    if cf is not None:
        fitted = write_fitted_urdf(arm, cf.pi, outputs.path("model.urdf"))
    m = IdentifiedModel(
        urdf=str(Path(arm.urdf).resolve()),
        payload_frame=arm.payload_frame,
        gravity=arm.gravity.tolist(),
        repair_inertia=arm.repair_inertia,
        joint_names=list(arm.joint_names),
        friction_velocity=_arm_width(model, profile),
        names=list(model.names),
        sigma=fit.sigma.tolist(),
        sigma_urdf=model.sigma_ref.tolist(),
        std=fit.std.tolist(),
        identified=fit.identified.tolist(),
        covariance=fit.cov.tolist(),
        used=fit.used.tolist(),
        residual_rms=fit.residual_rms.tolist(),
        noise_rms=fit.noise_rms.tolist(),
        viscous=fr[:n].tolist(),
        coulomb=fr[n : 2 * n].tolist(),
        armature=fr[2 * n :].tolist(),
        consistent_sigma=None if cf is None else cf.sigma.tolist(),
        consistent_distance=None if cf is None else float(cf.distance),
        fitted_urdf=None if fitted is None else fitted.name,
        record={
            "source": rec.source,
            "window": [float(rec.t[0]), float(rec.t[-1])],
            # the continuous pieces fitted [s] (a log's gaps, several records) and their records
            "pieces": [[float(rec.t[a]), float(rec.t[b - 1])] for a, b in rec.spans],
            "records": list(rec.record_names) or [rec.source],
            "sample_period": rec.sample_period,
            "tau_f": fit.tau_f,
            # the estimate written: "wls", or "output_error" (its Cramér-Rao covariance; the lag, the
            # bandwidth and model_error_var below are then the least squares' fit's, printed beside it)
            "estimator": estimator,
            "newey_west_lag": fit.lag,
            # sigma +- quantile_95 std is the 95 % bound (WLS: the fixed-b quantile at
            # bandwidth_fraction; output error: 1.96)
            "quantile_95": float(fit.quantile),
            "bandwidth_fraction": float(fit.bandwidth),
            # what adaptive_ct's prior adds for model error ([model] from = "model.json")
            "model_error_var": np.asarray(model_error_var, dtype=float).tolist(),
            "velocity": "measured" if rec.qd_measured else "derived",
            # the directions the record could not see, held at the URDF's values (held_directions)
            "held_directions": [] if fit.held is None else fit.held.describe(model.names),
            "prior_scale": 1.0 if fit.held is None else float(np.sqrt(fit.held.scale2)),
            "prior_conflict": fit.held is not None and fit.held.conflict,
            "scenario": str(spec.source),
            # the Coulomb widths' profile likelihood (identify --coulomb-width profile)
            "coulomb_width_profile": None if profile is None else profile.as_dict(),
            "torque_offset_std": None if fit.offset_std is None else fit.offset_std.tolist(),
        },
        coulomb_width=np.broadcast_to(model.friction_velocity, (n,)).tolist(),
        identity=arm_identity(arm, model, fit.identified),
        torque_offset=None if fit.offset is None else fit.offset.tolist(),
    )
    out = [save_identified_model(outputs.path("model.json"), m)]
    return out + ([fitted] if fitted is not None else [])
