"""``adaptive-dd identify --arm``'s Coulomb width (``--coulomb-width``): the width a simulated
record was made with, the record's noise's, a given one, or the record's profile likelihood."""

from __future__ import annotations

import numpy as np

from adaptive_dd.errors import DataError

__all__ = ["choose_coulomb_width"]


def choose_coulomb_width(args, arm, model, rec, K, tau_f: float, torque_held: bool, offset: bool = False):
    """The identification model with the Coulomb width ``--coulomb-width`` asks for, printed, and the
    :class:`~adaptive_dd.identification.friction_width.WidthProfile` when profiled (else None);
    ``K`` None (``--payload-only``: no least squares to profile) refuses ``profile``."""
    import dataclasses

    from adaptive_dd.identification.friction_width import auto_coulomb_width, profile_coulomb_width

    choice = args.coulomb_width
    head = "Coulomb friction fitted as fc tanh(qd / v)"
    if choice == "auto":  # profile where the law is not stated: on a simulated tanh record without
        # its JSON it finds the width the noise's missed 23-165x (output error stalled)
        choice, files = auto_coulomb_width(rec, profiled=K is not None)
        if files is not None:  # a record of adaptive-dd simulate: the tanh it was made with
            print(f"{head}, v = {choice:.3g} rad/s: the width the record was simulated with ({files})")
            return dataclasses.replace(model, friction_velocity=choice), None
    if choice == "noise":
        why = (
            "the arm's friction_velocity (its law is tanh)"
            if getattr(arm, "friction", "") == "tanh"
            else "the width of the record's velocity noise (adaptive_dd.identification.friction_width)"
            if rec.qd_measured
            else "the width of the noise of the velocities derived from the positions (the positions' "
            "noise through the derivative's filter; adaptive_dd.identification.friction_width)"
        )
        hint = "; --coulomb-width profile estimates it" if K is not None else "; --coulomb-width V sets it"
        print(f"{head}, v = {model.friction_velocity:.3g} rad/s: {why}{hint}")
        return model, None
    if choice != "profile":
        print(f"{head}, v = {choice:.3g} rad/s (--coulomb-width)")
        return dataclasses.replace(model, friction_velocity=float(choice)), None
    if K is None:
        raise DataError(
            "--coulomb-width profile: with --payload-only there is no least squares to profile; give a "
            "width (--coulomb-width V) or leave the default (auto: the noise's width here)"
        )
    try:
        pr = profile_coulomb_width(
            model,
            rec.q,
            rec.qd,
            rec.tau,
            rec.used,
            K,
            tau_f=tau_f,
            sample_period=rec.sample_period,
            channel_weight=rec.weight,
            torque_held=torque_held,
            pieces=rec.pieces or None,
            offset=offset,
        )
    except DataError as exc:
        raise DataError(f"{rec.source}: {exc}") from None
    names = arm.joint_names
    print(
        f"{head}, v per joint from the record's profile likelihood over {pr.grid.size} widths "
        f"{pr.grid[0]:.2g}-{pr.grid[-1]:.2g} rad/s (95 % interval, N_eff {pr.n_eff:.0f}): "
        + ", ".join(pr.describe(names))
    )
    rest = [names[j] for j in np.flatnonzero(~pr.profiled)]
    if rest:
        print(
            f"  not profiled (Coulomb not fitted on their channel): {', '.join(rest)} at the record's "
            f"velocity noise, {model.friction_velocity:.3g} rad/s"
        )
    return dataclasses.replace(model, friction_velocity=pr.width), pr
