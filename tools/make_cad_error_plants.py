"""Write the CAD-error plants of ``benchmarks/scenarios/cad_error/``: the UR5 and the Panda as a
vendor's URDF leaves them, the robot off by CAD-level errors, given as a URDF of its own.

Run from the repository root::

    python tools/make_cad_error_plants.py          # rewrite the files
    python tools/make_cad_error_plants.py --check  # exit 1 if a written file differs (numbers to 1e-12)

For each arm, one draw of :func:`~adaptive_dd.identification.arm_prior.draw_parameters` at the
default levels (:class:`~adaptive_dd.identification.arm_prior.ArmUncertainty`: per link the mass
within 10 %, the centre of mass within 1 cm per axis, the inertia about it within 20 %; per joint
viscous and Coulomb friction within 50 %, armature within 30 %; uniform), generator
``numpy.random.default_rng([SEED, k])`` for the arm ``k`` of :data:`ARMS`. The links are written to
``NAME_plant.urdf`` (:func:`~adaptive_dd.plant.urdf_write.write_urdf_links`); the joints' friction
and armature to the scenario's ``[plant]`` table (``[plant] urdf`` takes the links only). The
scenario ``NAME_cad_error.toml`` is the shipped exact scenario with that ``[plant]`` table and no
excitation phase, and ``[model] uncertainty`` at the CAD levels: every controller but the oracles
is given the vendor's URDF and told how far it may be from the robot.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "scenarios" / "cad_error"
ARMS = ("ur5_tool_swap_exact", "panda_payload_exact")
"""The shipped exact scenarios whose arms are perturbed (the files are named after the robot)."""
SEED = 2026

HEADER = """\
# Written by tools/make_cad_error_plants.py (do not edit: run it again).
#
# {robot}: the controllers are given the vendor's URDF (the shipped robot); the simulated robot is
# that URDF off by CAD-level errors, given as a URDF of its own ({robot}_plant.urdf: per link the
# mass within 10 %, the centre of mass within 1 cm per axis, the inertia about it within 20 %) with
# its joints' friction within 50 % and armature within 30 % ([plant] below); one draw, seed {seed}.
# No excitation phase. The controllers are told how far their model may be from the robot as a
# user of a vendor's URDF would state it: CAD level ([model] uncertainty below).
#
#     adaptive-dd benchmark benchmarks/scenarios/cad_error/{robot}_cad_error.toml \\
#         --controllers ct_oracle adaptive_ct
#
"""


def _floats(x) -> str:
    return "[" + ", ".join(repr(round(float(v), 9)) for v in x) + "]"


def plant_files(name: str, k: int) -> dict[str, str]:
    """``{file name: text}`` of the arm of the shipped scenario ``name`` (index ``k`` in
    :data:`ARMS`): its plant URDF and its scenario."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.identification.arm_prior import ArmUncertainty, draw_parameters
    from adaptive_dd.plant.urdf_write import write_urdf_links

    path = ROOT / "adaptive_dd" / "scenarios" / f"{name}.toml"
    arm = load_scenario(path).arm
    robot = name.split("_")[0]
    n = arm.n_joints
    pi = draw_parameters(arm, ArmUncertainty(), np.random.default_rng([SEED, k]))
    tmp = OUT / f".{robot}_plant.urdf.tmp"
    write_urdf_links(
        arm, pi[: 10 * n], tmp, f"{robot} off by CAD-level errors (tools/make_cad_error_plants.py)"
    )
    urdf = tmp.read_text(encoding="utf-8")
    tmp.unlink()
    text = path.read_text(encoding="utf-8")
    plant = (
        "\n# The simulated robot: its links from the URDF of its own, its joints' friction and armature.\n"
        f'[plant]\nurdf = "{robot}_plant.urdf"\n'
        f"viscous = {_floats(pi[10 * n : 11 * n])}\n"
        f"coulomb = {_floats(pi[11 * n : 12 * n])}\n"
        f"armature = {_floats(pi[12 * n :])}\n"
        "\n# What the controllers are told of their model: a URDF from CAD and data sheets.\n"
        "[model]\nuncertainty = { mass = 0.1, com = 0.01, inertia = 0.2, viscous = 0.5, coulomb = 0.5, "
        "armature = 0.3 }\n"
    )
    lines = text.splitlines()
    body = "\n".join(lines[next(i for i, x in enumerate(lines) if not x.startswith("#")) :])
    return {
        f"{robot}_plant.urdf": urdf,
        f"{robot}_cad_error.toml": HEADER.format(robot=robot, seed=SEED) + body.strip("\n") + "\n" + plant,
    }


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def same_text(a: str, b: str, rtol: float = 1e-12) -> bool:
    """``a`` and ``b`` equal but for their numbers' last digits (within ``rtol``): a draw's inertia is
    a product of floats whose last bit differs between machines' libraries."""
    if _NUMBER.sub("#", a) != _NUMBER.sub("#", b):
        return False
    x = [float(v) for v in _NUMBER.findall(a)]
    y = [float(v) for v in _NUMBER.findall(b)]
    return all(abs(u - v) <= rtol * max(abs(u), abs(v)) for u, v in zip(x, y, strict=True))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if a written file differs")
    a = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    stale = []
    for k, name in enumerate(ARMS):
        for fname, text in plant_files(name, k).items():
            target = OUT / fname
            if a.check:
                if not target.is_file() or not same_text(target.read_text(encoding="utf-8"), text):
                    stale.append(str(target))
            else:
                target.write_text(text, encoding="utf-8")
                print(f"wrote {target.relative_to(ROOT)}")
    if stale:
        print("differs from the generator's output: " + ", ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
