"""What a run of a scenario will meet, checked before it runs (``adaptive-dd validate``).

* :func:`reference_problems`: the reference against the arm's joint position and velocity limits
  (an arm from a URDF has them; the two-link arm has none);
* :func:`torque_problems`: the reference against the torque limits, by inverse dynamics along it
  with every segment's payload (the heaviest included): a torque beyond the limit there
  saturates even a controller that tracks perfectly (a warning: the benchmark runs through
  saturation and reports it);
* :func:`controller_problems`: every controller of the scenario built as the run builds it
  (built-ins with their settings, plug-ins imported from their path with theirs);
* :func:`inertia_problems`: a joint whose Coulomb friction dwarfs its inertia about its axis (a
  drive's rotor, the armature, missing from the URDF; a warning);
* :func:`floor_problems`: a controller whose ``bandwidth`` or ``damping`` differs from its floor's
  (its ratio to the floor then compares two gains as well as two laws; a warning);
* :func:`capacity_problems`: a payload heavier than the arm's stated rated payload (a warning).

Each returns a list of one-line problems (empty: none), naming the joint, the value, the limit
and the time, or the controller and the reason.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "capacity_problems",
    "controller_problems",
    "floor_problems",
    "inertia_problems",
    "joint_units",
    "preflight",
    "reference_problems",
    "resolved_settings",
    "scenario_floors",
    "torque_peaks",
    "torque_problems",
]

TOL = 1e-9
"""Relative tolerance on a limit (a reference that touches it is within it)."""


CHUNK = 20_000
"""Samples of the reference taken at once by :func:`_torque_maxima` (the regressor of a chunk is
``CHUNK x n x p`` numbers: a run of hours at 1 kHz is read in bounded memory)."""


def _torque_maxima(scenario) -> tuple[np.ndarray, ...]:
    """Per joint, of ``|tau|`` [N m] of inverse dynamics along the reference with each payload
    segment's parameters (segment 0 carries no payload): the largest over every segment, the
    sample where it occurs and the segment, and the largest with segment 0's parameters and its
    sample; each ``(n,)``. The reference is read :data:`CHUNK` samples at a time."""
    T, N = scenario.sample_period, scenario.n_samples
    sig = scenario.segment_sigmas()  # (S, p)
    model = scenario.closed_forms or scenario.arm
    peak = bare = None
    for k0 in range(0, N, CHUNK):
        k = np.arange(k0, min(N, k0 + CHUNK))
        Y = model.regressor(*scenario.reference.sample(k * T))  # (K, n, p)
        tau = np.abs(np.einsum("knp,sp->skn", Y, sig))  # (S, K, n)
        flat = tau.reshape(-1, tau.shape[2])
        i = np.argmax(flat, axis=0)
        cols = np.arange(flat.shape[1])
        cand = (flat[i, cols], k[i % k.size], i // k.size)
        peak = _larger(peak, cand)
        j = np.argmax(tau[0], axis=0)
        bare = _larger(bare, (tau[0][j, cols], k[j]))
    return (*peak, *bare)


def joint_units(arm) -> list[tuple[str, str, str]]:
    """Per joint, the units of its position, velocity and effort: ``("m", "m/s", "N")`` on a
    prismatic joint, else ``("rad", "rad/s", "N m")``."""
    kinds = getattr(arm, "joint_kinds", ())
    n = len(np.atleast_1d(arm.actuator.torque_limit))
    return [
        ("m", "m/s", "N") if j < len(kinds) and kinds[j] == "prismatic" else ("rad", "rad/s", "N m")
        for j in range(n)
    ]


def _larger(best, cand):
    """Per joint, the candidate's ``(value, where...)`` where its value is above the best's, or is
    NaN where the best's is not (as ``argmax`` takes a NaN); on an exact tie the best's, the
    earlier chunk's (the whole reference's ``argmax`` would take the lower segment first)."""
    if best is None:
        return cand
    win = (cand[0] > best[0]) | (np.isnan(cand[0]) & ~np.isnan(best[0]))
    return tuple(np.where(win, c, b) for c, b in zip(cand, best, strict=True))


def torque_peaks(scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per joint, the largest ``|tau|`` [N m] of inverse dynamics along the reference over every
    payload segment's parameters, the sample where it occurs and the segment, each ``(n,)``."""
    return _torque_maxima(scenario)[:3]


def reference_problems(scenario) -> list[str]:
    """The reference beyond the arm's joint position or velocity limits (see the module)."""
    arm, T = scenario.arm, scenario.sample_period
    t = np.arange(scenario.n_samples) * T
    q, qd, _ = scenario.reference.sample(t)
    out = []
    path = getattr(scenario.reference, "path", None)  # a path of the tool frame, solved to joints
    names = tuple(getattr(arm, "joint_names", ()))

    def key(j: int, k: int) -> str:
        if path is None:
            return f"reference.joint{j + 1}"
        name = f"{names[j]!r} (joint{j + 1})" if len(names) > j else f"joint{j + 1}"
        return f"reference.cartesian: at {path.where(t[k])}, joint {name}"

    units = joint_units(arm)
    lim = getattr(arm, "position_limits", None)  # an arm from a URDF
    if lim is not None:
        for j in range(q.shape[1]):
            lo, hi = lim[j]
            u = units[j][0]
            k_lo, k_hi = int(np.argmin(q[:, j])), int(np.argmax(q[:, j]))
            if q[k_lo, j] < lo - TOL * max(1.0, abs(lo)):
                out.append(
                    f"{key(j, k_lo)}: q = {q[k_lo, j]:.4g} {u} at t = {t[k_lo]:.3f} s is below the "
                    f"joint's lower limit {lo:.4g} {u} (by {lo - q[k_lo, j]:.3g} {u})"
                )
            if q[k_hi, j] > hi + TOL * max(1.0, abs(hi)):
                out.append(
                    f"{key(j, k_hi)}: q = {q[k_hi, j]:.4g} {u} at t = {t[k_hi]:.3f} s is above the "
                    f"joint's upper limit {hi:.4g} {u} (by {q[k_hi, j] - hi:.3g} {u})"
                )
    vlim = getattr(arm, "velocity_limits", None)
    if vlim is not None:
        for j in range(qd.shape[1]):
            k = int(np.argmax(np.abs(qd[:, j])))
            v, u = abs(qd[k, j]), units[j][1]
            if np.isfinite(vlim[j]) and vlim[j] > 0 and v > vlim[j] * (1 + TOL):
                out.append(
                    f"{key(j, k)}: |qd| = {v:.4g} {u} at t = {t[k]:.3f} s is beyond the joint's "
                    f"velocity limit {vlim[j]:.4g} {u} ({v / vlim[j]:.2f} times)"
                    + (": slow the path (a longer period)" if path is not None else "")
                )
    return out


def torque_problems(scenario) -> list[str]:
    """Joints whose torque along the reference, by inverse dynamics with some segment's payload,
    is beyond the limit: the actuator will saturate even under perfect tracking (the benchmark
    runs through it and reports the saturation; a warning, not an error)."""
    t = np.arange(scenario.n_samples) * scenario.sample_period
    out = []
    peak, at, seg, bare, bare_at = _torque_maxima(scenario)  # bare: segment 0's, no payload
    segments = scenario.segments()
    limit = np.asarray(scenario.arm.actuator.torque_limit, dtype=float)
    units = joint_units(scenario.arm)
    for j in np.flatnonzero(peak > limit * (1 + TOL)):
        u = units[j][2]
        if bare[j] > limit[j] * (1 + TOL):
            what, k, tau = "the arm alone (no payload)", int(bare_at[j]), bare[j]
            why = _bare_why(scenario, t[k], j, u)
            if peak[j] > bare[j] * (1 + TOL):
                why += f"; with the payloads it needs up to {peak[j]:.4g} {u}"
        else:
            start, end, mass = segments[seg[j]]  # a loaded one: the bare arm is within its limit
            what, k, tau = (
                f"the {mass:g} kg payload (carried from {start:g} to {end:g} s; each is checked along the "
                "whole reference)",
                at[j],
                peak[j],
            )
            why = "the actuator will saturate"
        out.append(
            f"reference.joint{j + 1}: inverse dynamics along the reference with {what} needs |tau| = "
            f"{tau:.4g} {u} at t = {t[k]:.3f} s, beyond the joint's torque limit {limit[j]:.4g} {u} "
            f"({tau / limit[j]:.2f} times): {why}"
        )
    return out


def _bare_why(scenario, t: float, j: int, u: str = "N m") -> str:
    """What to check when the arm alone needs joint ``j`` beyond its limit at time ``t``: the
    reference when the motion's share (the torque less the part that holds the arm still at that
    posture) is the larger, else the arm's masses and limits."""
    q, qd, qdd = (x[0] for x in scenario.reference.sample(np.array([t])))
    arm = scenario.arm
    tau = arm.inverse_dynamics(q, qd, qdd)[j]
    still = arm.inverse_dynamics(q, np.zeros_like(qd), np.zeros_like(qdd))[j]
    if abs(tau - still) > abs(still):
        return (
            f"the reference's motion needs {abs(tau - still):.4g} {u} of it (the posture alone "
            f"{abs(still):.4g}): lower its amplitudes or frequencies ([reference] frequency is in Hz)"
        )
    return "check the URDF's masses and the joint's effort limit"


def controller_problems(scenario) -> list[str]:
    """Every controller built as the run builds it; one line per controller that cannot be."""
    from adaptive_dd.controllers.registry import built_controllers
    from adaptive_dd.errors import ParameterError

    out = []
    for spec, _, exc in built_controllers(scenario):
        if exc is not None:
            msg = str(exc)
            if not (isinstance(exc, ParameterError) or msg.startswith(("controller", "unknown controller"))):
                msg = f"controller {spec!r}: {type(exc).__name__}: {msg}"
            out.append(msg)
    return out


def resolved_settings(scenario) -> list[str]:
    """``controllers.NAME.key = value`` of each listed built-in's settings with a value default in
    :data:`~adaptive_dd.controllers.CONTROLLERS` (``adaptive_ct``'s boost, ``slotine_li``'s gains
    and box), ``(default)`` marked: what the run will use on this arm, said before it runs
    (several differ between the arms, by the rule the table states)."""
    from adaptive_dd.controllers.plugins import table_name
    from adaptive_dd.controllers.registry import ABSENT, CONTROLLERS
    from adaptive_dd.plant.kind import run_kind

    kind = run_kind(scenario)
    out = []
    for spec in scenario.controllers:
        given = scenario.options(spec)
        entry = CONTROLLERS.get(given.get("law", spec))  # a variant: its law's settings
        if entry is None or not entry.applies_to(kind):  # plug-ins; reported by controller_problems
            continue
        table = table_name(spec)  # where the setting is written (a label names the results only)
        for key, st in entry.settings.items():
            default = st.default(kind)
            if default is None and key in ("gamma", "gain") and key not in given and kind != "two_link":
                out.append(derived_gain(scenario, spec, table, key))
            if default is None or default is ABSENT:
                continue
            v = given.get(key, default)
            if isinstance(v, tuple | list):
                v = list(v)
            mark = "" if key in given else "   (default)"
            out.append(f"controllers.{table}.{key} = {v!r}{' ' + st.unit if st.unit else ''}{mark}")
    if scenario.closed_forms is None:  # adaptive_ct's and each variant's derived settings
        from adaptive_dd.closed_loop.model_prior import adaptive_entries

        for name in adaptive_entries(scenario):
            lines = derived_estimator_settings(scenario, name) + derived_boost(scenario, name)
            out += [x for x in lines if x not in out]  # the arm's own lines once
    return out


def derived_gain(scenario, spec: str, table: str, key: str) -> str:
    """A gradient law's adaptation gains (``gamma``) or ``natural_adaptive``'s ``gain`` as the run
    derives them from the arm and the reference (:mod:`adaptive_dd.closed_loop.adaptation_gain`)."""
    from adaptive_dd.controllers.registry import scenario_controller

    law = scenario_controller(scenario, spec)[1]
    value = getattr(law, key)
    shown = [float(f"{x:.4g}") for x in np.ravel(value)] if key == "gamma" else float(f"{value:.4g}")
    if getattr(law, "name", "") == "craig_hsu_sastry":
        why = "default: the constant (its adaptation reads the acceleration; docs/controllers.md)"
    elif key == "gain":
        why = "derived: slotine_li's derived mass gain / (link mass + payload capacity / 2)^2"
    else:
        why = "derived: each payload parameter at one rate, the fastest at half the feedback's lambda"
    return f"controllers.{table}.{key} = {shown}   ({why})"


def derived_boost(scenario, name: str = "adaptive_ct") -> list[str]:
    """``adaptive_ct``'s boost bandwidth per joint on an N-joint arm, as the run derives it from the
    torque limits and the sensors' noise (:mod:`adaptive_dd.closed_loop.boost`)."""
    from adaptive_dd.controllers.registry import scenario_controller

    law = scenario_controller(scenario, name)[1]
    if not hasattr(law, "boost_bandwidths"):
        return []
    wb = [round(float(x), 1) for x in law.boost_bandwidths()]
    return [
        f"controllers.{name} boost bandwidth per joint = {wb} rad/s   (derived: at most "
        "boost_bandwidth, its noise torque 3 std inside the torque limit; at each sample scaled down "
        "as far as the command's torque limits need)"
    ]


def derived_estimator_settings(scenario, name: str = "adaptive_ct") -> list[str]:
    """``adaptive_ct``'s estimator settings on an arm from a URDF that the scenario need not state,
    as the run derives them, each with its rule: the mode (``"arm"`` when the model's stated
    uncertainty, ``[model] uncertainty`` or the ``[plant.uncertainty]`` levels, is not exact), the
    row weights (each equation's error in a first pass over the reference with the payload
    capacity, over the largest in payload mode, on its own scale in mode "arm") and the payload mass
    re-opened at an alarm (``[arm] payload_capacity``, 10
    kg when it is not stated)."""
    from adaptive_dd.controllers.registry import scenario_controller
    from adaptive_dd.identification.online import REOPEN_CAPACITY, reopen_mass_std
    from adaptive_dd.identification.online_config import FLOOR_MAX
    from adaptive_dd.identification.row_weights import pass_mass
    from adaptive_dd.plant.arm import DEFAULT_PAYLOAD_OFFSET

    online = getattr(scenario_controller(scenario, name)[1], "online", None)
    if online is None or not hasattr(online, "mode"):
        return []
    est = scenario.options(name).get("estimator", {})
    arm, pre = scenario.arm, f"controllers.{name}.estimator"
    drawn = getattr(getattr(scenario, "plant", None), "uncertainty", None)
    if "mode" in est:
        why = "given"
    elif "arm_prior_cov" in est:
        why = "derived: [model] from, the identified model's covariance"
    elif drawn is not None and getattr(scenario, "model_uncertainty", None) is drawn:
        why = "derived: the [plant.uncertainty] levels, [model] uncertainty not stated"
    else:
        why = "derived: the model's stated uncertainty ([model] uncertainty)"
    if why != "given" and online.mode != "arm":
        why = "default: no [model] uncertainty or [plant.uncertainty], the arm taken as exact"
    out = [f"{pre}.mode = {online.mode!r}   ({why})"]
    w = online.row_weights  # set by AdaptiveCT.state_task in every mode unless given
    carried = f"{pass_mass(arm, scenario):g} kg"
    if "row_weights" in est:
        why = "given"
    elif online.mode == "payload":
        why = f"derived: each equation's RMS error along the reference carrying {carried} / the largest"
    else:
        why = f"derived: each equation's RMS error [N m] along the reference carrying {carried}"
        why += " x sqrt(tau_f / T)"
    out.append(f"{pre}.row_weights = {[float(f'{x:.4g}') for x in w]}   ({why})")
    if online.detector is not None:
        cap = arm.payload_capacity
        if "reopen_mass_std" in scenario.options(name).get("detector", {}):
            why = "given"
        elif cap is None:
            why = "default: no [arm] payload_capacity stated; state the rated payload [kg] to size it"
        else:
            why = f"derived: {REOPEN_CAPACITY:g} x arm.payload_capacity {cap:g} kg"
        std = reopen_mass_std(online.detector, arm)
        out.append(f"controllers.{name}.detector.reopen_mass_std = {std:.4g} kg   ({why})")
        if "floor" in scenario.options(name).get("detector", {}):
            why = "given"
        else:
            why = (
                f"derived: the heaviest row's noise in the first pass over the threshold "
                f"{online.detector.threshold:g}, at most {FLOOR_MAX:g} N m"
            )
        floor = online.detector.floor  # set by AdaptiveCT.state_task unless given
        out.append(f"controllers.{name}.detector.floor = {floor:.3g} N m   ({why})")
    frame = arm.payload_frame
    why = "the estimator's payload prior: a disk of that radius per kg, its centre of mass within"
    why += f" that offset of {frame!r}"
    if arm.payload_offset == DEFAULT_PAYLOAD_OFFSET:
        why += "; the offset the default: state how far your payloads' centres of mass may lie from it"
    off, rad = arm.payload_offset, arm.payload_radius
    out.append(f"arm.payload_offset = {off:g} m, arm.payload_radius = {rad:g} m   ({why})")
    return out


FRICTION_ACCELERATION = 100.0
"""[rad/s^2] The most a joint's Coulomb friction over its inertia about its axis (armature
included) may be before :func:`inertia_problems` warns: 11.5 at most on the shipped arms, 15.7 on
100 drawn arms, 7700 on the UR5's URDF alone (wrist 3: 1 N m against 1.3e-4 kg m^2)."""


DAC_NOISE_SIGMAS = 3.0
"""Position sensor's standard deviations beyond which :func:`inertia_problems` warns of a joint's
D/A rounding."""

DAC_ERROR_FLOOR = 1e-5
"""[rad] (m on a prismatic joint) :func:`inertia_problems` says nothing of a D/A rounding below
this, whatever the sensors: with noise-free sensors every quantised joint's rounding is above
their noise, and a hundredth of a milliradian is below any floor the benchmark reads."""


def lacks_armature(scenario) -> bool:
    """An N-joint arm with no armature on any joint (the URDF states none, ``[arm] armature`` is not
    set), the paper's direct-drive arm excepted: :func:`inertia_problems`' warning, recalled by the
    report where a ratio target is not met."""
    from adaptive_dd.plant.two_link import as_two_link_cached

    if scenario.closed_forms is not None:
        return False
    arm = scenario.arm
    return as_two_link_cached(arm) is None and not np.any(np.asarray(arm.armature, dtype=float))


def inertia_problems(scenario) -> list[str]:
    """Joints of a URDF arm whose Coulomb friction over their inertia about their axis, at the
    reference's start and armature included, exceeds :data:`FRICTION_ACCELERATION`: a real drive's
    rotor adds far more inertia (a vendor's URDF leaves it out), and without it the friction's
    sign, which a noisy measured speed cannot tell near rest, jerks the joint (``adaptive_ct`` on
    the UR5's URDF alone is 2.4 times its floor unloaded; with the shipped armature 1.0). And
    joints whose D/A rounding (a step ``2 limit / 2^dac_bits``, std ``step / sqrt(12)``) held
    against the law's stiffness, ``step / (sqrt(12) I w^2)`` at its bandwidth ``w``, is beyond
    :data:`DAC_NOISE_SIGMAS` times the position sensor's noise. That figure is what a command
    below the step gives (the rounding then holds one value for long): the SO-100 of
    example-robot-data's wrist roll, 6.5e-5 kg m^2 with a 35 N m limit, 3.0 mrad, and its floor
    is 3.0 mrad where with 0.3 kg it is 0.19 (``benchmarks/scenarios/so100.toml``); where the
    command spans many steps the rounding is whiter and moves the joint less (vertical3's wrist
    with a 5000 N m limit: 0.87 stated, the floor 0.057 -> 0.177 mrad). The shipped arms are at
    most 0.1 of the noise. And an arm with no armature at all (a light arm: the warning's figures).
    A warning: the arm is simulated as stated."""

    if scenario.closed_forms is not None:  # the paper's arm: its Tables 2 and 4
        return []
    arm = scenario.arm
    q0 = scenario.reference.sample(np.zeros(1))[0][0]
    inertia = np.diag(arm.mass_matrix(q0))
    fc = np.asarray(arm.coulomb, dtype=float)
    names = arm.joint_names
    out = []
    rotor = (
        "a drive's rotor adds inertia the URDF leaves out: state [arm] armature (kg m^2 per "
        "joint, from the data sheet: the rotor's inertia times the gear ratio squared)"
    )
    if lacks_armature(scenario):
        out.append(
            "arm: no joint has an armature (the URDF states none and [arm] armature is not set): a "
            "geared drive's rotor adds inertia the URDF leaves out (the rotor's inertia times the gear "
            "ratio squared: state [arm] armature, kg m^2 per joint, from the data sheet; a direct-drive "
            "arm has little). A light arm is the hard case of adaptive_ct against its floor (the "
            "milliseconds before it detects a swap move a light arm further): exact, 10 "
            "seeds, benchmarks/scenarios/jaco2.toml 1.64 unloaded, 1.00 with "
            "armature [0.05, 0.05, 0.05, 0.02, 0.02, 0.02]; vertical3_payload_exact.toml 1.482 in its "
            "1 kg segment, 1.119 with [0.05, 0.05, 0.02]"
        )
    for j in np.flatnonzero(fc > FRICTION_ACCELERATION * inertia):
        out.append(
            f"arm: joint {names[j]!r}: Coulomb friction {fc[j]:.3g} N m against {inertia[j]:.3g} kg m^2 "
            f"about its axis (armature {arm.armature[j]:.3g} included): {fc[j] / inertia[j]:.3g} rad/s^2; "
            + rotor
        )
    act = arm.actuator
    if act.quantize:  # the D/A's rounding held against the law's stiffness (docstring)
        w = np.broadcast_to(np.asarray(scenario.bandwidth, dtype=float), inertia.shape)  # one per joint
        lsb = act._lsb  # the step the loop's actuator rounds to
        err = lsb / np.sqrt(12.0) / inertia / w**2  # [rad]: its acceleration over the loop's w^2
        sensor = arm.sensor
        noise = np.sqrt(np.broadcast_to(sensor.position_variance, err.shape).astype(float))
        if sensor.quantize:  # the encoder's own rounding
            noise = np.hypot(noise, np.asarray(sensor.resolution, dtype=float) / np.sqrt(12.0))
        floor = np.maximum(DAC_NOISE_SIGMAS * noise, DAC_ERROR_FLOOR)
        for j in np.flatnonzero(err > floor):
            lin = arm.joint_kinds[j] == "prismatic"  # N, kg, m/s^2 and mm on a prismatic joint
            f, m, a, e = ("N", "kg", "m/s^2", "mm") if lin else ("N m", "kg m^2", "rad/s^2", "mrad")
            out.append(
                f"arm: joint {names[j]!r}: the D/A's step {lsb[j]:.3g} {f} (2 x torque limit "
                f"{act.torque_limit[j]:.3g} {f} / 2^{act.dac_bits}) against {inertia[j]:.3g} {m} about "
                f"its axis (armature {arm.armature[j]:.3g} included) is {lsb[j] / inertia[j]:.3g} {a}: "
                f"its rounding may move the joint by up to about {1e3 * err[j]:.2g} {e} at {w[j]:g} rad/s, "
                f"beyond {DAC_NOISE_SIGMAS:g} times the position sensor's noise ({1e3 * noise[j]:.2g} {e}), "
                "and every law's floor with it; "
                + (rotor if not lin else "a drive adds mass the URDF leaves out: state [arm] armature [kg]")
                + ", or the drive's own torque limit"
            )
    return out


def scenario_floors(scenario) -> dict[str, str]:
    """``{controller: its floor}`` for the scenario's controllers that have one, in their order (a
    controller that cannot be built is left out: :func:`controller_problems` reports it)."""
    from adaptive_dd.controllers.plugins import floor_of
    from adaptive_dd.controllers.registry import scenario_controller

    out = {}
    for name in scenario.controllers:
        try:  # a plug-in that declares no floor is measured against ct_oracle, as the run does
            floor = floor_of(scenario_controller(scenario, name)[1])
        except Exception:  # a controller that cannot be built: controller_problems reports it
            continue
        if floor is not None:
            out[name] = floor
    return out


def missing_floors(scenario) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
    """The floors the scenario's controllers name that its run lacks, by the names results carry:
    ``(add, cannot)``, each ``{floor: [the controllers it is the floor of]}``; ``add`` the built-ins
    a benchmark adds to the run, ``cannot`` those built for the other kind of arm (the controller is then
    reported with no ratio). A floor no controller of the run carries and no built-in has is in
    neither: the run says its ratios are NaN."""
    from adaptive_dd.benchmark.scenario_settings import result_names
    from adaptive_dd.controllers import CONTROLLERS
    from adaptive_dd.plant.kind import run_kind

    opts = {n: scenario.options(n) for n, _ in scenario.controller_options}
    carried = set(result_names(scenario.controllers, opts, scenario.source, scenario.origin).values())
    kind = run_kind(scenario)
    add: dict[str, list[str]] = {}
    cannot: dict[str, list[str]] = {}
    for name, floor in scenario_floors(scenario).items():
        if floor not in carried and floor in CONTROLLERS:
            (add if CONTROLLERS[floor].applies_to(kind) else cannot).setdefault(floor, []).append(name)
    return add, cannot


def floor_problems(scenario) -> list[str]:
    """Controllers whose ``[controllers.NAME]`` ``bandwidth`` or ``damping`` differs from their
    floor's (the floor's own table, else ``[control]``): the ratio to the floor then measures the
    gains as well as the law (:func:`floor_mismatches`, one line each)."""
    return [msg for msgs in floor_mismatches(scenario).values() for msg in msgs]


GAINS_APART = "but its floor"
"""The words of a :func:`floor_mismatches` message (a row's ``floor_note``) the leaderboard's
table and command look for."""


def gains_apart(mine: dict, theirs: dict, scenario) -> list[tuple[str, Any, Any]]:
    """``[(key, law's, floor's)]`` of ``bandwidth`` and ``damping`` where a law's settings ``mine``
    and its floor's ``theirs`` differ, each defaulting to the scenario's ``[control]``."""
    out = []
    for key, default in (("bandwidth", scenario.bandwidth), ("damping", scenario.damping)):
        a, b = mine.get(key, default), theirs.get(key, default)
        if np.any(np.asarray(a, dtype=float) != np.asarray(b, dtype=float)):
            out.append((key, a, b))
    return out


def floor_mismatches(scenario) -> dict[str, list[str]]:
    """``{controller (its run.controllers entry): [what differs from its floor's gains]}`` for the
    controllers of :func:`floor_problems`; a plug-in's settings are its table's (its class name),
    as the run reads them."""
    from adaptive_dd.controllers.plugins import table_name

    out: dict[str, list[str]] = {}
    for name, floor in scenario_floors(scenario).items():
        theirs = scenario.options(table_name(floor)) if floor in scenario.controllers else {}
        for key, a, b in gains_apart(scenario.options(table_name(name)), theirs, scenario):
            out.setdefault(name, []).append(
                f"controllers.{table_name(name)}.{key} = {a} {GAINS_APART} {floor} runs at {b}: its "
                f"ratio to the floor compares two {key}s as well as two laws; give "
                f"[controllers.{floor}] the same"
            )
    return out


def capacity_problems(scenario) -> list[str]:
    """Payloads heavier than the arm's stated rated payload (``[arm] payload_capacity``): the
    estimator's re-opening at an alarm is sized from it, and a data sheet's arm would not carry them."""
    cap = getattr(scenario.arm, "payload_capacity", None)
    if cap is None or scenario.closed_forms is not None:
        return []
    return [
        f"payload[{i}].mass = {m:g} kg is above [arm] payload_capacity = {cap:g} kg (the rated payload, "
        "which sizes adaptive_ct's re-opening at an alarm): state the arm's rating, or a payload within it"
        for i, m in enumerate(scenario.swap_masses)
        if m > cap * (1 + TOL)
    ]


LONG_DURATION = 1000.0
"""[s] A trial at least this long is said before the run (:func:`duration_problems`): a duration
written in milliseconds reads as one (the shipped scenarios run 2-30 s)."""


def duration_problems(scenario) -> list[str]:
    """A ``run.duration`` of :data:`LONG_DURATION` or more: a duration given in ms is accepted as
    seconds (a warning: a long run may be meant; its estimate is printed too)."""
    d = scenario.duration
    if d < LONG_DURATION:
        return []
    return [
        f"run.duration = {d:g} s ({d / 3600:.2g} h of simulated time per trial): a duration in ms? "
        "[run] duration is in seconds"
    ]


def preflight(scenario) -> tuple[list[str], list[str]]:
    """``(problems, warnings)``: :func:`reference_problems` and :func:`controller_problems` (the
    run would be meaningless or fail), :func:`torque_problems` (it will saturate),
    :func:`inertia_problems` (an armature the URDF leaves out), :func:`floor_problems`,
    :func:`capacity_problems` (a payload above the rated one) and :func:`duration_problems`."""
    problems = reference_problems(scenario) + controller_problems(scenario)
    warnings = torque_problems(scenario) + inertia_problems(scenario) + floor_problems(scenario)
    return problems, warnings + capacity_problems(scenario) + duration_problems(scenario)
