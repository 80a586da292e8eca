"""``adaptive-dd validate``'s listing of a checked scenario: every field as ``key = value``, the
defaults marked (:func:`format_scenario`)."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from adaptive_dd.benchmark.scenario import Scenario

__all__ = ["format_scenario"]

_FIELD_KEY = {
    "name": "name",
    "duration": "run.duration",
    "sample_period": "run.sample_period",
    "seeds": "run.seeds",
    "seed": "run.seed",
    "substeps": "run.substeps",
    "controllers": "run.controllers",
    "bandwidth": "control.bandwidth",
    "damping": "control.damping",
    "reference": "reference",
    "swap_times": "payload.at",
    "swap_masses": "payload.mass",
    "payload_radius": "payload.radius",
    "position_variance": "noise.position_variance",
    "velocity_variance": "noise.velocity_variance",
    "dropout": "noise.dropout",
    "controller_options": "controllers",
    "source": "source",
    "excite": "run.excite",
}


def format_scenario(sc: Scenario) -> str:
    """Every field of a scenario as ``key = value``, defaults marked ``(default)``."""
    lines = [
        f"# {sc.source}: its keys and values are valid (what the run would meet is checked below); "
        f"{sc.estimate()}"
    ]
    order = ("duration", "sample_period", "seeds", "seed", "substeps", "controllers", "bandwidth")
    order += ("damping", "swap_times", "swap_masses", "payload_radius", "position_variance")
    for name in (*order, "velocity_variance", "dropout", "excite"):
        key = _FIELD_KEY[name]
        mark = "   (default)" if key in sc.defaulted else ""
        if mark and name.endswith("_variance"):  # a URDF arm's, or a shipped robot's data sheet's
            mark = "   (default: the arm's sensors)"
        lines.append(f"{key} = {_show(getattr(sc, name))}{mark}")
        if name == "payload_radius" and sc.closed_forms is None and sc.swap_times:
            lines += _payload_bodies(sc)
    ref = sc.reference
    mark = "   (default)" if "reference" in sc.defaulted else ""
    lines.append(f"reference.ramp = {ref.ramp!r}{mark}")
    for j in range(ref.n_joints):
        lines.append(
            f"reference.joint{j + 1} = {{ offset = {ref.offset[j]!r}, amplitude = "
            f"{_show(ref.amplitude[j])}, frequency = {_show(ref.frequency[j])}, phase = "
            f"{_show(ref.phase[j])} }}{mark}"
        )
    for n, _ in sc.controller_options:
        lines.append(f"controllers.{n} = {_brief(sc.options(n))!r}")
    lines += _plant_lines(sc)
    segs = ", ".join(
        f"{a:g}-{b:g} s: {m:g} kg ({k} samples)"
        for (a, b, m), k in zip(sc.segments(), sc.segment_samples(), strict=True)
    )
    lines.append(f"# segments: {segs}")
    return "\n".join(lines)


def _payload_bodies(sc: Scenario) -> list[str]:
    """Each payload's centre of mass and inertia on a URDF arm (None where the default holds)."""
    n = len(sc.swap_times)
    com = [None if c is None else tuple(c) for c in (sc.swap_com or (None,) * n)]
    inertia = [None if c is None else tuple(c) for c in (sc.swap_inertia or (None,) * n)]
    return [
        f"payload.com = {com!r}   (None: the payload frame's origin) [m]",
        f"payload.inertia = {inertia!r}   (None: a disk of payload.radius about the payload frame's z "
        "axis) [kg m^2]",
    ]


def _plant_lines(sc: Scenario) -> list[str]:
    """What the plant is when it is not the model (``[plant]``, ``[model]``), for ``validate``."""
    p, u, arm = sc.plant, sc.model_uncertainty, sc.arm
    stated = [] if u is None else [f"model.uncertainty = {dataclasses.asdict(u)!r}"]
    if arm.friction != "stick-slip":  # the plant's friction law, on every arm
        strib = (
            f"stribeck_ratio = {arm.stribeck_ratio:g}, stribeck_velocity = {arm.stribeck_velocity:g} rad/s"
        )
        law = {
            "tanh": f"friction_velocity = {arm.friction_velocity:g}",
            "stribeck": strib,
            "lugre": (
                f"{strib}, lugre_stiffness = {_brief_list(arm.lugre_stiffness)}, "
                f"lugre_damping = {_brief_list(arm.lugre_sigma1)}"
            ),
        }[arm.friction]
        model = "the controllers' model: viscous + Coulomb, so each floor is a reference, not a floor"
        stated.append(f"plant.friction = {arm.friction!r}   ({law}; {model})")
    if p is None:
        return (
            ["# plant: the [arm] itself (no plant apart from the model)", *stated]
            if sc.closed_forms is None
            else stated
        )
    out = [f"model.urdf = {str(sc.arm.urdf)!r}   (what every non-oracle controller is given)", *stated]
    out.append(f"plant.urdf = {p.urdf!r}" if p.urdf else "# plant links: the [arm]'s URDF")
    out += [f"# plant note: {note}" for note in p.notes]  # what the plant's URDF had that is unusual, kept
    for key in ("viscous", "coulomb", "armature"):
        out.append(f"plant.{key} = {_show(getattr(p, key))}")
    if p.uncertainty is not None:
        out.append(f"plant.uncertainty = {dataclasses.asdict(p.uncertainty)!r}")
    return out


class _Summary(str):
    """A stand-in shown bare by ``repr`` (``<65 x 65 matrix>``)."""

    def __repr__(self) -> str:
        return str(self)


def _brief(v: Any, most: int = 12) -> Any:
    """``v`` with every list of more than ``most`` numbers, or of rows, replaced by its shape: a
    covariance handed on by ``[model] from`` is 65 x 65 on a 7-joint arm, 80 000 characters of
    ``validate``'s output on one line."""
    if isinstance(v, dict):
        return {k: _brief(x, most) for k, x in v.items()}
    if isinstance(v, list | tuple) and v and all(isinstance(x, list | tuple) for x in v):
        return _Summary(f"<{len(v)} x {len(v[0])} matrix>")
    if isinstance(v, list | tuple) and len(v) > most:
        return _Summary(f"<{len(v)} numbers>")
    return v


def _brief_list(v) -> str:
    """Numbers to 4 significant digits, one value when all are equal."""
    return f"{v[0]:.4g}" if len(set(v)) == 1 else "[" + ", ".join(f"{x:.4g}" for x in v) + "]"


def _show(v: Any) -> str:
    if isinstance(v, tuple):
        return "[" + ", ".join(_show(x) for x in v) + "]"
    return repr(v)
