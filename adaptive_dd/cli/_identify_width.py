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

    from adaptive_dd.identification.friction_width import profile_coulomb_width, simulated_law

    choice = args.coulomb_width
    head = "Coulomb friction fitted as fc tanh(qd / v)"
    laws = []
    if choice == "auto" and rec.simulator_format:  # each record's own file (several: one law for all)
        laws = [simulated_law(src) for src in (rec.record_names or (rec.source,))]
        laws = laws if all(m is not None for m in laws) and len({m[:2] for m in laws}) == 1 else []
    if laws and laws[0][1] is not None:  # a record of adaptive-dd simulate: the tanh it was made with
        v = laws[0][1]
        files = ", ".join(m[2] for m in laws)
        print(f"{head}, v = {v:.3g} rad/s: the width the record was simulated with ({files})")
        return dataclasses.replace(model, friction_velocity=v), None
    if choice == "auto":  # a law with a sign: the noise's width; a law not stated: estimated
        # (profile: on the TIAGo's log it predicts better; on a simulated tanh record without its
        # JSON it finds the width, where the noise's missed it 23-165x and output error stalled)
        choice = "noise" if laws or K is None else "profile"
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
