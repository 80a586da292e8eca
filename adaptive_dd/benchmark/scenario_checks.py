"""Field checks of :class:`~adaptive_dd.benchmark.scenario.Scenario` and the TOML -> fields step.

Each check appends ``"key: reason"`` to a list so that every problem of a
scenario is reported at once; the bounds are ``scenario.LIMITS``.
"""

from __future__ import annotations

import math
from typing import Any

from adaptive_dd.benchmark.controller_entries import _check_controllers, _check_options
from adaptive_dd.benchmark.frozen import _Table, freeze, thaw
from adaptive_dd.benchmark.key_hints import did_you_mean
from adaptive_dd.benchmark.number_checks import _nums, _short, check_number
from adaptive_dd.benchmark.scenario_base import KEYS, LIMITS, Reference, run_estimate
from adaptive_dd.controllers import CONTROLLERS
from adaptive_dd.controllers.plugins import table_name
from adaptive_dd.errors import is_finite_number
from adaptive_dd.plant.parameters import PAYLOAD_RADIUS
from adaptive_dd.plant.sampling import first_sample

__all__ = [
    "check_number",
    "first_sample",
    "freeze",
    "scenario_errors",
    "scenario_fields",
    "table_name",
    "thaw",
]


def scenario_errors(v: dict[str, Any]) -> list[str]:
    """Every problem of the scenario fields ``v`` (a dict of Scenario's fields) as ``key: reason``."""
    L = LIMITS
    e: list[str] = []
    for k in ("name", "source"):
        if not isinstance(v[k], str):
            e.append(f"{k}: must be a string, got {_short(v[k])}")
    d_ok, T_ok = _check_timing(e, v)
    s_ok = check_number(e, "run.seeds", v["seeds"], 1, L["max_seeds"], integer=True)
    check_number(e, "run.seed", v["seed"], 0, L["seed_bound"] - 1, integer=True)
    check_number(e, "run.substeps", v["substeps"], 1, L["max_substeps"], integer=True)
    _check_plant(e, v)
    if check_number(e, "run.excite", v.get("excite", 0.0), 0, L["max_excite"]) and v.get("excite", 0.0) > 0:
        if not _serial(v):
            e.append(
                f"run.excite: {v['excite']} s: the excitation phase needs an N-joint arm from a URDF "
                '([arm] robot = ... or urdf = ...; the paper\'s arm: robot = "sice_arm", general = true)'
            )
    c_ok = _check_controllers(
        e, v["controllers"], v.get("arm") if _serial(v) else None, v["controller_options"]
    )
    _check_control(e, v, T_ok)
    check_number(e, "payload.radius", v["payload_radius"], 0, L["max_radius"])
    n_joints = _n_joints(v)
    for k in ("position_variance", "velocity_variance"):
        _nums(e, f"noise.{k}", v[k], 0, L["max_variance"], n=n_joints)
    check_number(e, "noise.dropout", v.get("dropout", 0.0), 0, 0.5)
    _check_payload(e, v, d_ok and T_ok)
    if not isinstance(v["reference"], Reference):
        e.append(f"reference: must be a Reference, got {_short(v['reference'])}")
    else:
        _check_reference(e, v["reference"], v["sample_period"] if T_ok else None, n_joints)
    _check_options(e, v["controller_options"], v["controllers"] if c_ok else ())
    if d_ok and T_ok and s_ok and c_ok:
        est = run_estimate(
            round(v["duration"] / v["sample_period"]),
            v["seeds"],
            len(v["controllers"]),
            n_joints=n_joints if _serial(v) else None,
        )
        if est.bytes > L["max_bytes"] or est.seconds > L["max_seconds"]:
            e.append(
                f"run: too large: {est}; the limits are {L['max_bytes'] / 2**30:g} GiB and "
                f"{L['max_seconds'] / 3600:g} h (reduce run.duration, run.seeds or run.controllers)"
            )
    return e


def _check_timing(e: list, v: dict) -> tuple[bool, bool]:
    """``run.duration`` and ``run.sample_period``, each in range and the two together; whether each is
    usable by the checks that need it."""
    L = LIMITS
    d_ok = check_number(e, "run.duration", v["duration"], 0, math.inf, lo_open=True)
    T_ok = check_number(
        e, "run.sample_period", v["sample_period"], L["min_sample_period"], L["max_sample_period"]
    )
    if d_ok and T_ok and v["sample_period"] > v["duration"] / 10:
        e.append(
            f"run.sample_period: {v['sample_period']} s is more than a tenth of run.duration "
            f"({v['duration']} s)"
        )
        T_ok = False
    if d_ok and T_ok and v["duration"] / v["sample_period"] > 1e12:
        e.append(
            f"run: too large: {v['duration'] / v['sample_period']:.3g} samples per trial "
            f"(run.duration / run.sample_period)"
        )
        d_ok = False
    return d_ok, T_ok


def _check_control(e: list, v: dict, T_ok: bool) -> None:
    """``[control]``: the bandwidth (one per joint on the general kernels' run) within what the
    sample period carries, the damping."""
    L = LIMITS
    bw = v["bandwidth"]
    if isinstance(bw, tuple) and _serial(v):  # one per joint, N-joint arms only
        bw_ok = _nums(e, "control.bandwidth", bw, 0, 1e5, n=_n_joints(v), lo_open=True)
        bw = max(bw) if bw_ok else bw
    elif isinstance(bw, tuple) and v.get("arm") is None:  # the arm is wrong, and said: not judged here
        bw_ok = False
    elif isinstance(bw, tuple):  # one per joint on the paper's closed forms: they take one bandwidth
        e.append(
            f"control.bandwidth: one number on the paper's two-link closed forms, got {_short(list(bw))} "
            '(one per joint runs on the general kernels: `robot = "sice_arm"` and `general = true` in [arm])'
        )
        bw_ok = False
    else:
        bw_ok = check_number(e, "control.bandwidth", bw, 0, 1e5, lo_open=True)
    if bw_ok and T_ok and bw * v["sample_period"] > L["max_bandwidth_T"]:
        e.append(
            f"control.bandwidth: {bw} rad/s at T = {v['sample_period']} s gives "
            f"bandwidth * T = {bw * v['sample_period']:.3g} > {L['max_bandwidth_T']}"
        )
    check_number(e, "control.damping", v["damping"], 0, L["max_damping"], lo_open=True)


def _n_joints(v: dict) -> int:
    arm = v.get("arm")
    return arm.n_joints if arm is not None else 2


def _check_plant(e: list, v: dict) -> None:
    """A plant (:class:`~adaptive_dd.plant.uncertainty.PlantSpec`) only on an N-joint arm, sized for it."""
    p = v.get("plant")
    if p is None:
        return
    if not _serial(v):
        e.append("plant: a plant apart from the model needs an N-joint arm from a URDF")
        return
    n = _n_joints(v)
    sizes = (len(p.pi_links), len(p.viscous), len(p.coulomb), len(p.armature))
    if sizes != (10 * n, n, n, n):
        e.append(f"plant: sized {sizes} (links, viscous, coulomb, armature) for an arm of {n} joints")


def _serial(v: dict) -> bool:
    """Whether the run takes the general kernels (no closed-form fast path: another geometry,
    ``general = true``, or a plant apart from the arm)."""
    return v.get("arm") is not None and (v.get("plant") is not None or _general(v.get("arm")))


def _general(arm: Any) -> bool:
    """An arm without the paper's closed forms (:func:`~adaptive_dd.plant.two_link.closed_form_view`
    None); False for ``None`` (an ``[arm]`` table that was wrong)."""
    from adaptive_dd.plant.two_link import closed_form_view

    return arm is not None and closed_form_view(arm) is None


def _check_payload_bodies(e: list, v: dict, n_swaps: int) -> None:
    """``swap_com`` and ``swap_inertia`` as a Scenario built in code holds them: empty, or one
    entry per payload change (None: the default), each that many finite numbers."""
    for key, size in (("swap_com", 3), ("swap_inertia", 6)):
        x = v.get(key, ())
        if not isinstance(x, tuple | list) or (len(x) and len(x) != n_swaps):
            e.append(
                f"{key}: one entry per payload change ({n_swaps}, or none), got {_short(x)}; "
                "change it with swap_times and swap_masses"
            )
            continue
        for i, c in enumerate(x):
            ok = c is None or (
                isinstance(c, tuple | list)
                and len(c) == size
                and all(isinstance(y, int | float) and not isinstance(y, bool) for y in c)
                and all(math.isfinite(y) for y in c)
            )
            if not ok:
                e.append(f"{key}[{i}]: must be None or {size} finite numbers, got {_short(c)}")


def _check_payload(e: list, v: dict, timing_ok: bool) -> None:
    L = LIMITS

    times, masses = v["swap_times"], v["swap_masses"]
    if not isinstance(times, tuple) or not isinstance(masses, tuple) or len(times) != len(masses):
        e.append(f"payload: swap_times and swap_masses must be tuples of equal length, got {_short(times)}")
        return
    if len(times) > L["max_swaps"]:
        e.append(f"payload: {len(times)} payload changes; at most {L['max_swaps']}")
        return
    _check_payload_bodies(e, v, len(times))
    d = v["duration"] if timing_ok else math.inf
    ok = True
    for i, (t, m) in enumerate(zip(times, masses, strict=True)):
        last = d - v["sample_period"] * (1 - 1e-9) if timing_ok else d  # the last segment holds a sample
        ok &= check_number(e, f"payload[{i}].at", t, 0, last, lo_open=True)
        grams = is_finite_number(m) and m >= 1000  # (a mass in g)
        if not check_number(e, f"payload[{i}].mass", m, 0, L["max_mass"]) and grams:
            e[-1] += ": a mass in g? give it in kg"
        if ok and i and t <= times[i - 1]:
            e.append(f"payload[{i}].at: {t} s: swap times must increase (previous {times[i - 1]} s)")
            ok = False
        elif (
            ok
            and timing_ok
            and min(t - (times[i - 1] if i else 0.0), d - t) < v["sample_period"] * (1 - 1e-9)
        ):
            e.append(
                f"payload[{i}].at: {t} s is less than one sample (T = {v['sample_period']} s) from "
                "the previous change, t = 0 or the end of the run"
            )
            ok = False
    if not (ok and timing_ok):
        return
    T = v["sample_period"]
    edges = [0, *(first_sample(t, T) for t in times), round(v["duration"] / T)]
    for i in range(len(edges) - 1):
        if edges[i + 1] - edges[i] < 1:
            where = f"payload[{i}].at" if i < len(times) else f"payload[{i - 1}].at"
            e.append(
                f"{where}: segment {i} ({[0.0, *times][i]} s to "
                f"{[*times, v['duration']][i]} s) holds no sample at T = {T} s; changes must be "
                "at least one sample apart, after t = 0 and before the end of the run"
            )


def _check_reference(e: list, ref: Any, T: float | None, n: int = 2) -> None:
    L = LIMITS

    check_number(
        e, "reference.ramp", ref.ramp, 0, L["max_ramp"]
    )  # may outlast a short run: the ramp is just cut
    fmax = L["nyquist_fraction"] / T if T is not None else math.inf
    for name, obj in (("offset", ref.offset), ("amplitude", ref.amplitude), ("frequency", ref.frequency)):
        if not isinstance(obj, tuple) or len(obj) != n:
            e.append(f"reference.{name}: must hold one entry per joint ({n}), got {_short(obj)}")
            return
    if not isinstance(ref.phase, tuple) or len(ref.phase) != n:
        e.append(f"reference.phase: must hold one entry per joint ({n}), got {_short(ref.phase)}")
        return
    for j in range(n):
        key = f"reference.joint{j + 1}"
        n_e = len(e)
        off_ok = check_number(e, f"{key}.offset", ref.offset[j], -L["max_angle"], L["max_angle"])
        a, f, p = ref.amplitude[j], ref.frequency[j], ref.phase[j]
        a_ok = _nums(e, f"{key}.amplitude", a, -L["max_angle"], L["max_angle"])
        for k in range(n_e, len(e)):  # an angle past the limit: most likely one in degrees
            if "must be in" in e[k] and "inf" not in e[k] and "nan" not in e[k]:
                e[k] += " (radians: an angle in degrees?)"
        f_ok = isinstance(f, tuple) and all(
            [check_number(e, f"{key}.frequency", x, 0, math.inf, lo_open=True) for x in f]
        )
        if not isinstance(f, tuple):
            e.append(f"{key}.frequency: must be a list of numbers, got {_short(f)}")
        _nums(e, f"{key}.phase", p, -L["max_phase"], L["max_phase"])
        if not (a_ok and f_ok and isinstance(p, tuple)):
            continue
        if not len(a) == len(f) == len(p):
            e.append(
                f"{key}: amplitude, frequency and phase must have equal lengths, "
                f"got {len(a)}, {len(f)}, {len(p)}"
            )
        elif len(a) > L["max_terms"]:
            e.append(f"{key}: {len(a)} sine terms; at most {L['max_terms']}")
        if off_ok and abs(ref.offset[j]) + sum(abs(x) for x in a) > L["max_angle"]:
            e.append(f"{key}: |offset| + sum |amplitude| exceeds {L['max_angle']} rad")
        for x in f:
            if x > fmax:
                e.append(
                    f"{key}.frequency: {x} Hz is above {fmax:g} Hz = {L['nyquist_fraction']} / T "
                    f"(at least 10 samples per period; the Nyquist limit is {0.5 / T:g} Hz)"
                )


def _known_tables(e: list, data: dict) -> dict[str, Any]:
    """The tables of a parsed scenario that have the right shape; unknown tables and keys, and
    tables of the wrong shape, added to ``e``."""
    tables: dict[str, Any] = {}
    for t, val in data.items():
        if t not in KEYS:
            homes = [h for h, allowed in KEYS.items() if allowed is not None and t in allowed]
            where = f"[{t}]" if isinstance(val, dict | list) else f"{t} (a key outside any table)"
            hint = (
                f" (did you mean {' or '.join(f'[{h}] {t}' for h in homes)}?)"
                if homes
                else did_you_mean(t, KEYS)
            )
            e.append(f"{where}: unknown{' table' if where.startswith('[') else ''}{hint}; allowed tables: "
                     f"{', '.join(sorted(KEYS))}")  # fmt: skip
        elif t == "payload":
            if not isinstance(val, list) or not all(isinstance(x, dict) for x in val):
                e.append("payload: must be an array of tables [[payload]]")
            else:
                tables[t] = val
        elif not isinstance(val, dict):
            e.append(f"{t}: must be a table [{t}], got {_short(val)}")
        else:
            tables[t] = val
    for t, allowed in KEYS.items():
        if allowed is None:
            continue
        items = tables.get(t, []) if t == "payload" else [tables.get(t, {})]
        for i, item in enumerate(items):
            where = f"{t}[{i}]" if t == "payload" else t
            for k in item:
                if k not in allowed:
                    hint = did_you_mean(str(k), allowed)
                    e.append(f"{where}.{k}: unknown key{hint}; allowed: {', '.join(sorted(allowed))}")
    return tables


def scenario_fields(
    data: Any, is_default: bool, arm: Any = None, default_reference=None
) -> tuple[dict[str, Any], list[str]]:
    """Scenario fields from a parsed TOML dict (defaults filled in) and the structural errors.

    ``arm`` (the scenario's arm, None if its tables were wrong) gives the number and
    names of the joints and, for a URDF arm, the default noise variances; ``default_reference()``
    gives the reference of a two-link scenario without a ``[reference]`` table (the default
    scenario's)."""
    e: list[str] = []
    if not isinstance(data, dict):
        return {}, ["<top>: must be a TOML document"]
    tables = _known_tables(e, data)
    defaulted: set[str] = set()

    def get(table: str, key: str, default: Any) -> Any:
        tab = tables.get(table, {})
        if key in tab:
            return freeze(tab[key])
        defaulted.add(f"{table}.{key}")
        return freeze(default)

    v: dict[str, Any] = {
        "duration": get("run", "duration", 20.0),
        "sample_period": get("run", "sample_period", 0.001),
        "seeds": get("run", "seeds", 10),
        "seed": get("run", "seed", 0),
        "substeps": get("run", "substeps", 2),
        "controllers": get("run", "controllers", _default_controllers(arm)),
        "bandwidth": get("control", "bandwidth", 40.0),
        "damping": get("control", "damping", 1.0),
        "position_variance": get("noise", "position_variance", _default_noise(arm, "position_variance")),
        "velocity_variance": get("noise", "velocity_variance", _default_noise(arm, "velocity_variance")),
        "dropout": get("noise", "dropout", 0.0),
        "excite": get("run", "excite", 0.0),
    }
    _payload_fields(e, tables.get("payload", []), v, defaulted, arm)
    T = v["sample_period"]
    T = float(T) if isinstance(T, int | float) and not isinstance(T, bool) and T > 0 else None
    v["reference"] = _reference_field(e, tables, is_default, defaulted, arm, default_reference, T)
    v["controller_options"] = tuple(
        (str(n), freeze(o) if isinstance(o, dict) else o) for n, o in tables.get("controllers", {}).items()
    )
    for n, o in v["controller_options"]:
        if not isinstance(o, _Table):
            e.append(f"controllers.{n}: must be a table [controllers.{n}], got {_short(o)}")
    v["controller_options"] = tuple(x for x in v["controller_options"] if isinstance(x[1], _Table))
    v["defaulted"] = frozenset(defaulted)
    return v, e


def _default_controllers(arm: Any) -> list:
    kind = "chain" if _general(arm) else "two_link"
    return [c for c, entry in CONTROLLERS.items() if entry.applies_to(kind)]


def _default_noise(arm: Any, key: str) -> list:

    if _general(arm):
        return list(getattr(arm.sensor, key))
    return [1e-8, 1e-7] if key == "position_variance" else [5e-5, 1e-4]


def _payload_fields(e: list, items: list, v: dict, defaulted: set, arm: Any = None) -> None:
    from adaptive_dd.plant.arm import payload_parameters

    times, masses, radii = [], [], []
    coms, inertias = [], []
    for i, p in enumerate(items):
        body = {"com": None, "inertia": None}  # kept only for an entry that is a payload change
        for key, size in (("com", 3), ("inertia", 6)):
            if key not in p:
                continue
            x = p[key]
            ok = False  # an entry refused here is not checked again as the Scenario's swap_com/inertia
            if arm is not None and not _general(arm):
                e.append(
                    f"payload[{i}].{key}: the two-link arm's payload is a disk at the tip (mass, radius); "
                    "a centre of mass or inertia needs a URDF arm ([arm] urdf = ... or robot = ...)"
                )
            elif not (
                isinstance(x, list)
                and len(x) == size
                and all(
                    not isinstance(y, bool)
                    and isinstance(y, int | float)
                    and math.isfinite(y)
                    and abs(y) <= 100
                    for y in x
                )
            ):
                e.append(f"payload[{i}].{key}: must be a list of {size} finite numbers, got {_short(x)}")
            elif key == "com" and math.hypot(*x) > LIMITS["max_com"]:
                e.append(
                    f"payload[{i}].com: {_short(x)} is {math.hypot(*x):.4g} m from the payload frame, beyond "
                    f"{LIMITS['max_com']:g} m: give it in metres (40 mm is 0.04)"
                )
            else:
                ok = True
            body[key] = freeze(x) if ok else None
        if isinstance(body["inertia"], tuple) and len(body["inertia"]) == 6:
            try:
                payload_parameters(1.0, None, body["inertia"])
            except ValueError as exc:
                e.append(f"payload[{i}].inertia: {exc}")
        missing = [k for k in ("at", "mass") if k not in p]
        for k in missing:
            e.append(f"payload[{i}].{k}: missing (each [[payload]] needs at and mass)")
        if not missing:
            times.append(freeze(p["at"]))
            masses.append(freeze(p["mass"]))
            coms.append(body["com"])
            inertias.append(body["inertia"])
        if "radius" in p:
            radii.append(freeze(p["radius"]))
    if len({repr(r) for r in radii}) > 1:
        e.append(f"payload.radius: all payload disks must share one radius, got {radii}")
    if not radii:
        defaulted.add("payload.radius")
    v["swap_times"], v["swap_masses"] = tuple(times), tuple(masses)
    v["swap_com"] = tuple(coms) if any(c is not None for c in coms) else ()
    v["swap_inertia"] = tuple(inertias) if any(c is not None for c in inertias) else ()
    v["payload_radius"] = radii[0] if radii else PAYLOAD_RADIUS


def _reference_field(
    e: list,
    tables: dict,
    is_default: bool,
    defaulted: set,
    arm: Any = None,
    default_reference=None,
    sample_period: float | None = None,
) -> Any:

    n = arm.n_joints if arm is not None else 2
    names = tuple(getattr(arm, "joint_names", ()))
    if "reference" not in tables:
        if is_default or n != 2:
            e.append(
                "reference: the default scenario must define [reference]"
                if is_default
                else f"reference: an arm of {n} joints needs a [reference] table with joint1 .. joint{n}, "
                "each as joint1 = { offset = 0.0, amplitude = [0.3, 0.1], frequency = [0.3, 0.8] } "
                "[rad, rad, Hz] within the joint's limits (`adaptive-dd validate` checks positions, "
                "speeds and the torque along it)"
            )
            return Reference((0.0,) * n, ((),) * n, ((),) * n, ((),) * n)
        defaulted.add("reference")
        if default_reference is None:
            raise ValueError("scenario_fields: no [reference] table and no default_reference given")
        return default_reference()
    ref = tables["reference"]
    if isinstance(ref, dict) and "cartesian" in ref:  # a path of the tool frame, solved to joints
        from adaptive_dd.benchmark.cartesian_reference import parse_cartesian

        other = sorted(k for k in ref if k not in ("cartesian", "ramp"))
        if other:
            e.append(f"reference: cartesian is given with {other}; give the path or the joints, not both")
        out = parse_cartesian(e, ref["cartesian"], arm, freeze(ref.get("ramp", 0.0)), sample_period)
        return out if out is not None else Reference((0.0,) * n, ((),) * n, ((),) * n, ((),) * n)
    keys = [f"joint{j + 1}" for j in range(n)]
    numbered = list(keys)
    for k in ref:
        if k == "ramp" or k in numbered:
            continue
        if k in names:
            j = names.index(k)
            keys[j] = k
            if numbered[j] in ref:
                e.append(
                    f"reference.{k}: the same joint as reference.{numbered[j]} (its URDF name); "
                    "give each joint once, by number or by name"
                )
        else:
            e.append(
                f"reference.{k}: not a joint of this {n}-joint arm; use joint1 .. joint{n}"
                + (f" or the URDF joint names {list(names)}" if names else "")
            )
    for j, k in enumerate(keys):
        if k not in ref and not (names and names[j] in ref):
            e.append(f"reference.{k}: missing; the arm has {n} joints and each needs a reference")
    parts: dict[str, list] = {"offset": [], "amplitude": [], "frequency": [], "phase": []}
    for j in keys:
        spec = ref.get(j, {})
        if not isinstance(spec, dict):
            e.append(f"reference.{j}: must be an inline table {{ offset = ..., amplitude = [...] }}")
            spec = {}
        for k in spec:
            if k not in parts:
                e.append(f"reference.{j}.{k}: unknown key; allowed: amplitude, frequency, offset, phase")
        amp = freeze(spec.get("amplitude", []))
        parts["offset"].append(freeze(spec.get("offset", 0.0)))
        parts["amplitude"].append(amp)
        parts["frequency"].append(freeze(spec.get("frequency", [])))
        zeros = (0.0,) * len(amp) if isinstance(amp, tuple) else ()
        parts["phase"].append(freeze(spec.get("phase", zeros)))
    return Reference(
        tuple(parts["offset"]),
        tuple(parts["amplitude"]),
        tuple(parts["frequency"]),
        tuple(parts["phase"]),
        freeze(ref.get("ramp", 0.0)),
    )
