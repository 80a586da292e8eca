"""Write ``docs/guide/scenario_keys.md``: every key a scenario file may hold, from the code's tables.

The keys come from the tables the scenario checks themselves use
(:data:`adaptive_dd.benchmark.scenario_base.KEYS`, the ``[arm]`` and ``[plant]`` key lists of
:mod:`adaptive_dd.plant.two_link` and :mod:`adaptive_dd.plant.arm`, the controllers'
settings in :data:`adaptive_dd.controllers.builtins.CONTROLLERS` (both arms) less those the run
derives from the scenario, :data:`adaptive_dd.benchmark.scenario_settings.DERIVED`); the defaults
come from resolving minimal scenarios with :func:`~adaptive_dd.benchmark.scenario.load_scenario`
(what ``adaptive-dd validate`` prints).
Only the one-line meanings below are written by hand, and the build stops when a key of the
code has no meaning here or a meaning names a key the code no longer has: the page cannot
drift from the checks.
"""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path

from sphinx.errors import ExtensionError

MEANING = {
    "run.duration": "Length of every trial [s].",
    "run.sample_period": "Sample period T of the controllers, sensors and estimator [s].",
    "run.seeds": "Trials per controller (seed indices 0 .. seeds-1; seeds"
    " share their noise across controllers).",
    "run.seed": "Base seed of the random generator (each trial draws from it and its index).",
    "run.substeps": "RK4 substeps of the plant per sample (the controller holds its torque between samples).",
    "run.controllers": "Built-in names or import paths `package.module:Class` of your own classes.",
    "control.bandwidth": "Closed-loop bandwidth of every controller [rad/s]; `bandwidth * T <= 0.2`.",
    "control.damping": "Damping ratio of the closed-loop poles, in (0, 10].",
    "reference.ramp": "Length of the C^2 ramp that fades the sines in [s] (0: none).",
    "reference.jointN": "Per joint (`joint1`, `joint2`, ...): `offset` [rad], and lists `amplitude` [rad], "
    "`frequency` [Hz] and `phase` [rad] of a sum of sines.",
    "reference.cartesian": "In place of `jointN`, a closed path of the tool frame solved to joints by "
    "inverse kinematics: `{ circle = RADIUS, normal = [x, y, z], center = [...] }` or "
    "`{ waypoints = [[x, y, z], ...] }` (offsets [m] from the tool at `q0`), with `period` [s], "
    "`q0` [rad] (default zeros), `samples` (256), `tolerance` [m] (1e-4); see "
    "`adaptive_dd.benchmark.cartesian_reference`.",
    "payload.at": "Time of the swap [s] (one `[[payload]]` table per swap).",
    "payload.mass": "Payload mass carried from then on [kg].",
    "payload.radius": "Radius of the payload disk [m]: its inertia where `inertia` is not given (a disk "
    "about the payload frame's z axis; on the two-link arm at the tip).",
    "payload.com": "URDF arm: payload centre of mass in the payload frame [m], 3 numbers.",
    "payload.inertia": "URDF arm: payload inertia about its centre of mass, `[Ixx,"
    " Iyy, Izz, Ixy, Ixz, Iyz]` [kg m^2] (a rigid body's: principal moments"
    " >= 0, each at most the sum of the other two).",
    "noise.position_variance": "Per joint, variance of the measured position's noise [rad^2].",
    "noise.velocity_variance": "Per joint, variance of the measured velocity's noise [(rad/s)^2].",
    "noise.dropout": "Probability that a sample is lost (NaN): the law holds, the estimator skips it.",
    # [arm], the paper's two-link arm
    "arm.l1": "Length of link 1 [m].",
    "arm.l2": "Length of link 2 [m] (where the payload mounts).",
    "arm.m1": "Mass of link 1 [kg] (physical form, eq. 10).",
    "arm.m2": "Mass of link 2 [kg].",
    "arm.a1": "Distance of link 1's centre of mass from joint 1 [m].",
    "arm.a2": "Distance of link 2's centre of mass from joint 2 [m].",
    "arm.I1": "Inertia of link 1 about its centre of mass [kg m^2].",
    "arm.I2": "Inertia of link 2 about its centre of mass [kg m^2].",
    "arm.b": "Viscous friction per joint [N m s/rad], 2 numbers.",
    "arm.d": "Coulomb friction per joint [N m], 2 numbers.",
    "arm.sigma": "Base parameters `[J1, J2, r, b1, b2, d1, d2]` (eq. 9) instead of the physical keys.",
    "arm.payload_radius": "Radius of the payload disk [m] (two-link) or the compact-payload prior (URDF).",
    "arm.torque_limit": "Per joint torque limit [N m] (the D/A saturates there).",
    # [arm], any arm from a URDF
    "arm.urdf": 'A URDF file, relative to the scenario file; or `"example-robot-data:PATH"`, a URDF of '
    "that package (the `[robots]` extra; {doc}`../random_arms`).",
    "arm.robot": "A shipped robot instead of a file: `sice_arm`, `vertical3`, `ur5`, `panda`, `iiwa14`, "
    "`gen3`; or `random:SEED`, a drawn arm.",
    "arm.payload_frame": "The link the payload is fixed to (default: the last link).",
    "arm.gravity": "Gravity vector in the base frame [m/s^2], 3 numbers.",
    "arm.viscous": "Per joint viscous friction [N m s/rad] (the URDF's `damping` otherwise).",
    "arm.coulomb": "Per joint Coulomb friction [N m] (the URDF's `friction` otherwise).",
    "arm.armature": "Per joint rotor inertia reflected to the joint [kg m^2].",
    "arm.encoder_counts": "Per joint encoder counts per revolution (position quantisation).",
    "arm.dac_bits": "Resolution of the torque D/A converter [bits].",
    "arm.general": "`true`: keep the general N-joint kernels for a URDF that is the paper's two-link arm.",
    # [plant]
    "plant.friction": "The simulated plant's friction law: `stick-slip` (default), `tanh`, `stribeck`, "
    "`lugre` (two-link only); the controllers keep the model's viscous + Coulomb friction.",
    "plant.friction_velocity": "Velocity scale v of `tanh` friction, `d tanh(qd / v)` [rad/s].",
    "plant.stribeck_ratio": "Static over Coulomb friction of the Stribeck and LuGre laws.",
    "plant.stribeck_velocity": "Velocity over which the Stribeck excess fades [rad/s].",
    "plant.lugre_stiffness": "LuGre bristle stiffness sigma0 [N m/rad], one or per joint (default 1e5).",
    "plant.lugre_damping": "LuGre bristle damping sigma1 [N m s/rad], one or per joint (sqrt(s0 M_ii(0))).",
    # [controllers.NAME]
    "setting.bandwidth": "This controller's bandwidth instead of `[control]`'s [rad/s].",
    "setting.damping": "This controller's damping instead of `[control]`'s.",
    "setting.label": "The name the controller's results carry.",
    "setting.law": "On an entry of a name of your own only: the built-in or import path it runs, with "
    "its table's settings (a variant).",
    "setting.floor": "The run's controller this one is measured against, per seed; false for none.",
    "setting.sigma": "The fixed model's base parameters (seven, two-link arm).",
    "setting.gamma": "Adaptation gains of Slotine-Li (N-joint arms: derived from the arm and the "
    "reference unless given; `adaptive-dd validate` prints them).",
    "setting.gain": "`natural_adaptive` (N-joint arms): the natural law's one gain; default derived "
    "from Slotine-Li's mass gain, the payload link's mass and `max_mass`.",
    "setting.max_mass": "Largest payload mass Slotine-Li's box admits [kg] (5 two-link, 20 N-joint).",
    "setting.com_radius": "The payload's size in Slotine-Li's box [m]: the disk's radius at the tip"
    " (two-link, 0.1), its centre of mass from the flange (N-joint, 0.3).",
    "setting.uncertainty": "`sliding_mode` (N-joint arms): the arm's error levels that bound its model "
    "error (the keys of `[plant.uncertainty]`; default: the model's stated uncertainty).",
    "setting.delay": "`ct_oracle_late`: how long after each swap its true model switches [s], a "
    "whole number of samples (default 0.01).",
    "setting.boost_bandwidth": "Bandwidth of the feedback boost after a change alarm [rad/s].",
    "setting.boost_duration": "How long the boost lasts after an alarm [s].",
    "setting.boost_ramp": "`adaptive_ct` (N-joint arms): after `boost_duration`, the boost's added "
    "bandwidth falls linearly to none over this long [s] (default 0.25; 0: it ends at once).",
    "setting.observer": "`adaptive_ct` (every arm): feed forward the residual observer's torque "
    "(true by default; false is the law without it).",
    "setting.observer_bandwidth": "`adaptive_ct` (every arm): the residual observer's bandwidth "
    "[rad/s]; default 0.4 / T.",
}

# Keys that arrive with branches not merged yet (issues 28 and 29): written here so the
# page is complete the day they land; not reported as stale while the code lacks them.
ARRIVING = {
    "run.excite": "Seconds of designed excitation run on the plant before the task, the controllers' "
    "model identified from it (URDF arms; 0: none).",
    "plant.urdf": "URDF arms: the simulated robot when it is not the `[arm]` (other inertials, the "
    'same joints and frames; a file or `"example-robot-data:PATH"`); the `[arm]` is then the '
    "controllers' model.",
    "plant.viscous": "Per joint, the plant's own viscous friction [N m s/rad].",
    "plant.coulomb": "Per joint, the plant's own Coulomb friction [N m].",
    "plant.armature": "Per joint, the plant's own armature [kg m^2].",
    "plant.uncertainty": "A plant drawn per seed around the `[arm]` (a table; keys below).",
    "plant.uncertainty.mass": "Relative spread of each link's mass.",
    "plant.uncertainty.com": "Spread of each link's centre of mass [m].",
    "plant.uncertainty.inertia": "Relative spread of each link's inertia.",
    "plant.uncertainty.viscous": "Relative spread of each joint's viscous friction.",
    "plant.uncertainty.coulomb": "Relative spread of each joint's Coulomb friction.",
    "plant.uncertainty.armature": "Relative spread of each joint's armature.",
    "plant.uncertainty.distribution": "`uniform` or `normal`.",
    "model.from": "The controllers' model: a URDF whose link inertials replace the `[arm]`'s (a file or "
    '`"example-robot-data:PATH"`), or the `model.json` that `adaptive-dd identify --out DIR` writes.',
    "model.uncertainty": "How far the controllers' model may be from the robot: a table of the keys "
    "of `[plant.uncertainty]` (a level left out is 0; `{}`: exact); adaptive_ct learns the arm from it. "
    "Default: the `[plant.uncertainty]` levels, else exact.",
    # issue 29 (identification from real logs) and issue 28 part 2/4 (derived settings)
    "arm.repair_inertia": "`true`: repair chain links whose URDF inertia is not a rigid body's "
    "(each repair is reported).",
    "arm.payload_capacity": "Rated payload [kg]; sizes the estimator's re-opening on a change alarm "
    "(default: the detector's generic size); general kernels only (the paper's closed forms refuse it).",
    "arm.payload_offset": "How far a payload's centre of mass may lie from the payload frame [m] (a data "
    "sheet's centre-of-gravity offset; 0: centred on the frame); the length scale of the estimator's "
    "payload prior on the general kernels (the paper's closed forms refuse it: their payload is a disk "
    "centred on the tip).",
}

TWO_LINK_SCENARIO = "[[payload]]\nat = 1.0\nmass = 1.0\n"
URDF_SCENARIO = '[arm]\nrobot = "ur5"\n\n[[payload]]\nat = 1.0\nmass = 1.0\n\n[reference]\n' + "".join(
    f"joint{j} = {{ offset = 0.0, amplitude = [0.1], frequency = [0.5], phase = [0.0] }}\n"
    for j in range(1, 7)
)


def _defaults(text: str) -> dict[str, str]:
    """``key -> value`` of the fields a minimal scenario leaves to their defaults."""
    from adaptive_dd.benchmark.scenario import format_scenario, load_scenario

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "minimal.toml"
        path.write_text(text)
        sc = load_scenario(path)
    out = {}
    for line in format_scenario(sc).splitlines():
        if line.endswith("(default)"):
            key, _, value = line.removesuffix("(default)").partition(" = ")
            out[key.strip()] = value.strip()
    return out


def _code(v: str) -> str:
    return f"`{v}`" if v else ""


def _ramp_default(scenario_base) -> float:
    """The ramp of a ``[reference]`` table that gives none (the field's default)."""
    return {f.name: f.default for f in dataclasses.fields(scenario_base.Reference)}["ramp"]


def _meaning(key: str) -> str:
    return MEANING.get(key) or ARRIVING.get(key, "")


def _uncertainty_module():
    """:mod:`adaptive_dd.plant.uncertainty` (the ``[plant]`` truth and ``[model]`` tables), if present."""
    try:
        from adaptive_dd.plant import uncertainty
    except ImportError:
        return None
    return uncertainty


def _check(used: set[str]) -> None:
    missing = sorted(used - set(MEANING) - set(ARRIVING))
    stale = sorted(set(MEANING) - used - set(ARRIVING))
    if missing or stale:
        raise ExtensionError(
            "docs/_ext/scenario_keys.py is out of step with the scenario checks: "
            + (f"keys without a meaning in MEANING: {missing}; " if missing else "")
            + (f"meanings of keys the code no longer has: {stale}" if stale else "")
        )


def page() -> str:
    from adaptive_dd.benchmark import scenario_base
    from adaptive_dd.benchmark.scenario_settings import DERIVED
    from adaptive_dd.controllers import registry
    from adaptive_dd.plant import arm_tables

    two, urdf = _defaults(TWO_LINK_SCENARIO), _defaults(URDF_SCENARIO)
    used: set[str] = set()
    lines = [
        "# Every scenario key",
        "",
        "```{note}",
        "This page is generated when the documentation is built, from the tables the scenario",
        "checks use (`adaptive_dd/benchmark/scenario_base.py`'s `KEYS`, the `[arm]` and `[plant]`",
        "key lists of `adaptive_dd/plant/arm_tables.py`, the controllers' settings), so",
        "it lists exactly what `adaptive-dd validate` accepts in a benchmark scenario (an",
        "identification scenario's `[record]` table, for a robot's log, is on {doc}`../real_log`).",
        "Defaults are what `validate` prints for a scenario that leaves the key out. Any other key",
        "is an error naming file and key.",
        "```",
        "",
    ]

    def table(
        rows: list[tuple[str, ...]], heads=("key", "default (two-link arm)", "default (URDF arm)", "meaning")
    ):
        out = ["| " + " | ".join(heads) + " |", "|---" * len(heads) + "|"]
        for row in rows:
            out.append("| " + " | ".join(x.replace("|", "\\|") for x in row) + " |")
        return [*out, ""]

    tables = scenario_base.KEYS
    known = {"run", "control", "reference", "payload", "noise", "controllers", "arm", "plant"}
    if _uncertainty_module() is not None:
        known.add("model")
    if set(tables) != known:
        raise ExtensionError(
            f"docs/_ext/scenario_keys.py: the scenario tables changed ({sorted(set(tables) ^ known)}): "
            "add the new table's section to page()"
        )
    for t in ("run", "control", "payload", "noise"):
        keys = sorted(tables[t], key=lambda k: (k not in MEANING, k))
        head = f"## `[[{t}]]`" if t == "payload" else f"## `[{t}]`"
        lines += [head, ""]
        rows = []
        for k in keys:
            key = f"{t}.{k}"
            used.add(key)
            req = "(required)" if t == "payload" and k in ("at", "mass") else ""
            rows.append(
                (
                    f"`{k}`",
                    _code(two.get(key, "")) or req,
                    _code(urdf.get(key, "")) or req,
                    _meaning(key),
                )
            )
        lines += table(rows)
    lines += ["## `[reference]`", ""]
    used |= {"reference.ramp", "reference.jointN", "reference.cartesian"}
    lines += table(
        [
            (
                "`ramp`",
                _code(two.get("reference.ramp", "")),
                _code(repr(_ramp_default(scenario_base))),
                MEANING["reference.ramp"],
            ),
            ("`jointN`", "the paper's two-sine reference", "(required)", MEANING["reference.jointN"]),
            ("`cartesian`", "(none)", "(none)", MEANING["reference.cartesian"]),
        ]
    )

    lines += ["## `[arm]`", "", "Left out: the paper's SICE arm (Table 1). One of three forms:", ""]
    physical = arm_tables._PHYSICAL_KEYS
    sigma_form = arm_tables._SIGMA_KEYS
    optional = arm_tables._ARM_OPTIONAL
    rows = []
    for k in dict.fromkeys(physical + sigma_form + optional):
        used.add(f"arm.{k}")
        form = (
            "physical (required)"
            if k in physical and k not in sigma_form
            else "both forms (required)"
            if k in physical
            else "sigma form (required)"
            if k in sigma_form
            else "optional"
        )
        rows.append((f"`{k}`", form, "", _meaning(f"arm.{k}")))
    lines += [
        "**The paper's kind of two-link arm**, by physical parameters (eq. 10) or by its base",
        "parameters sigma (eq. 9):",
        "",
    ]
    lines += table([(a, b, d) for a, b, _, d in rows], heads=("key", "form", "meaning"))
    rows = []
    for k in arm_tables.URDF_ARM_KEYS:
        used.add(f"arm.{k}")
        note = "one of `urdf`, `robot` (required)" if k in ("urdf", "robot") else "optional"
        rows.append((f"`{k}`", note, "", _meaning(f"arm.{k}")))
    lines += ['**Any serial arm from a URDF** (`urdf = "file"` or `robot = "ur5"`):', ""]
    lines += table([(a, b, d) for a, b, _, d in rows], heads=("key", "form", "meaning"))

    lines += [
        "## `[plant]`",
        "",
        "The simulated plant only (the controllers and estimators keep their model):",
        "",
    ]
    rows = []
    uncertainty = _uncertainty_module()
    plant_keys = arm_tables._PLANT_KEYS + (uncertainty.PLANT_TRUTH_KEYS if uncertainty else ())
    for k in plant_keys:
        used.add(f"plant.{k}")
        rows.append((f"`{k}`", _meaning(f"plant.{k}")))
    lines += table(rows, heads=("key", "meaning"))
    if uncertainty is not None:
        lines += ["### `[plant.uncertainty]`", ""]
        rows = []
        for k in uncertainty.UNCERTAINTY_KEYS:
            used.add(f"plant.uncertainty.{k}")
            rows.append((f"`{k}`", _meaning(f"plant.uncertainty.{k}")))
        lines += table(rows, heads=("key", "meaning"))
        lines += ["## `[model]`", "", "URDF arms: the controllers' model when it is not the `[arm]`:", ""]
        rows = []
        for k in uncertainty.MODEL_KEYS:
            used.add(f"model.{k}")
            rows.append((f"`{k}`", _meaning(f"model.{k}")))
        lines += table(rows, heads=("key", "meaning"))

    lines += [
        "## `[controllers.NAME]`",
        "",
        "One table per controller of `run.controllers` (NAME: the built-in name, or the class name",
        "of an import path). A plug-in class receives its table's keys as keyword arguments (see",
        "{doc}`../controllers`). Settings each built-in takes:",
        "",
    ]
    rows = []
    common = sorted(registry.COMMON)
    for name, entry in registry.CONTROLLERS.items():
        derived = DERIVED.get(name, {})

        def keys_on(kind, entry=entry, derived=derived):
            if not entry.applies_to(kind):
                return None
            return sorted(k for k in entry.settings_on(kind) if k not in derived)

        two_set, serial_set = keys_on("two_link"), keys_on("chain")
        used |= {f"setting.{k}" for k in (*common, *(two_set or ()), *(serial_set or ()))}

        def cell(keys, other):
            return f"{other} only" if keys is None else (", ".join(f"`{k}`" for k in keys) or "none")

        rows.append((f"`{name}`", cell(two_set, "N-joint"), cell(serial_set, "two-link")))
    lines += table(rows, heads=("controller", "two-link arm", "URDF arm"))
    lines += [
        f"Every controller also takes {', '.join(f'`{k}`' for k in common)}. An entry of",
        "`run.controllers` of a name of your own takes `law` too: a variant, the law it names run with",
        "its table's settings (an ablation; {doc}`../controllers`).",
        "",
    ]
    used.add("setting.law")
    lines += table(
        [
            (f"`{k}`", _meaning(f"setting.{k}"))
            for k in sorted({k.removeprefix("setting.") for k in used if k.startswith("setting.")})
        ],
        heads=("setting", "meaning"),
    )

    lines += [
        "### Derived, not keys",
        "",
        "A scenario that sets one of these is refused, the error naming the file, the key and what",
        "the setting is derived from (`adaptive-dd validate FILE` prints the derived values):",
        "",
    ]
    lines += table(
        [(f"`{name}.{k}`", why) for name, keys in DERIVED.items() for k, why in keys.items()],
        heads=("setting", "derived from"),
    )
    _check(used)
    return "\n".join(lines)


def every_key() -> dict[str, tuple[str, ...]]:
    """Every key and nested field a scenario may set, by where it is set: the scenario tables'
    keys (``[reference]``'s ``jointN`` counted once), the ``[arm]`` keys of both forms, ``[plant]``,
    ``[plant.uncertainty]`` and ``[model]``, the controllers' settings (each name once: the
    common ones and every built-in's, on either arm) and the estimator's and detector's fields
    on either arm (less the settings the run derives from the scenario, :data:`DERIVED`, which a
    scenario cannot set). ``python docs/_ext/scenario_keys.py`` prints the count."""
    from adaptive_dd.benchmark import scenario_base
    from adaptive_dd.benchmark.scenario_settings import DERIVED
    from adaptive_dd.controllers import registry
    from adaptive_dd.plant import arm_tables

    out: dict[str, tuple[str, ...]] = {}
    for t, keys in scenario_base.KEYS.items():
        if keys is not None:
            out[t] = tuple(sorted(keys))
    out["reference"] = ("cartesian", "jointN", "ramp")
    arm = (
        arm_tables._PHYSICAL_KEYS
        + arm_tables._SIGMA_KEYS
        + arm_tables._ARM_OPTIONAL
        + arm_tables.URDF_ARM_KEYS
    )
    out["arm"] = tuple(sorted(set(arm)))
    uncertainty = _uncertainty_module()
    plant = arm_tables._PLANT_KEYS + (uncertainty.PLANT_TRUTH_KEYS if uncertainty else ())
    out["plant"] = tuple(sorted(set(plant)))
    if uncertainty is not None:
        out["plant.uncertainty"] = tuple(uncertainty.UNCERTAINTY_KEYS)
        out["model"] = tuple(uncertainty.MODEL_KEYS)
    settings = set(registry.COMMON) | {"law"}  # law: a variant's (an entry of a name of its own)
    for name, entry in registry.CONTROLLERS.items():
        settings |= set(entry.settings) - set(DERIVED.get(name, ()))
    out["controllers.NAME"] = tuple(sorted(settings))
    return out


def generate(app) -> None:
    out = Path(app.srcdir) / "guide" / "scenario_keys.md"
    out.parent.mkdir(exist_ok=True)
    text = page()
    if not out.exists() or out.read_text() != text:
        out.write_text(text)


def setup(app):
    generate(app)  # at setup, before Sphinx lists the source files (autosummary reads them then)
    return {"parallel_read_safe": True, "version": "1"}


if __name__ == "__main__":
    import sys

    if "--write" in sys.argv[1:]:  # the committed page (tests/test_first_run.py holds it to page())
        target = Path(__file__).resolve().parents[1] / "guide" / "scenario_keys.md"
        target.write_text(page())
        print(f"wrote {target}")
    keys = every_key()
    for where, names in keys.items():
        print(f"{where} ({len(names)}): {', '.join(names)}")
    print(f"every key and nested field a scenario may set: {sum(len(v) for v in keys.values())}")
