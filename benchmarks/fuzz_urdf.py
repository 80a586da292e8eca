"""Seeded mutation fuzz of the robot descriptions a scenario names.

Mutates the shipped URDFs (``adaptive_dd/robots/*.urdf``) one value or element at a time: a
number set to 0, a negative, nan, inf, 1e300, 1e-300, text or nothing; a vector given the wrong
count, all zeros or one component changed; a number scaled by 1e-3 .. 1e6 (a unit error); an
attribute or an element deleted. Each mutant is loaded through the scenario path (a scenario
whose ``[arm] urdf`` names it, :func:`~adaptive_dd.benchmark.scenario.parse_scenario`), and the
outcome counted:

* precise errors: ``ScenarioError`` whose message names the URDF file;
* internal errors: any other exception (what the CLI reports with exit 3);
* meaningless accepted silently: a mutant that loads, with no note about the element it
  changed, although the value put in has no physical sense (non-finite, 1e300, <= 0 where only
  a positive value means something, an axis of zero length), or whose loaded model fails an
  independent judgement of Pinocchio's model and the arm's limits (:func:`meaningless`);
* accepted: everything else (a legal change, or an unusual one noted).

Run: ``PYTHONPATH=. python benchmarks/fuzz_urdf.py [--n 2000] [--seed 0]``; a few planted
mutations run in the test suite (``tests/test_urdf_checks.py``).
"""

from __future__ import annotations

import argparse
import math
import random
import tempfile
import warnings
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.errors import ScenarioError
from adaptive_dd.plant.urdf_checks import UrdfWarning
from adaptive_dd.robots import ROBOTS, robot_urdf

BAD = ["0", "0.0", "-0", "-1", "-0.001", "nan", "inf", "-inf", "1e300", "-1e300", "1e-300", "abc", ""]
SCALES = [1e-3, 1e3, 1e6]
POSITIVE = {("mass", "value"), ("inertia", "ixx"), ("inertia", "iyy"), ("inertia", "izz"),
            ("limit", "effort"), ("limit", "velocity")}  # fmt: skip
NONNEGATIVE = {("dynamics", "damping"), ("dynamics", "friction")}
VECTORS = {"xyz", "rpy"}


def targets(root: ET.Element) -> list[tuple[ET.Element, str, str, str]]:
    """Every numeric attribute: ``(element, attribute, owner name, tag)``."""
    out = []
    for owner in [*root.findall("link"), *root.findall("joint")]:
        name = owner.get("name")
        for el in owner.iter():
            for attr in el.attrib:
                if el is owner or attr in ("link", "name", "filename"):
                    continue
                out.append((el, attr, name, el.tag))
    return out


def mutate(text: str, rng: random.Random) -> tuple[str, str, str, bool]:
    """One mutation: ``(kind, new text, owner element name, meaningless by construction)``."""
    root = ET.fromstring(text)
    el, attr, owner, tag = rng.choice(targets(root))
    kind = rng.choice(["bad", "bad", "bad", "vector", "scale", "delete_attr", "delete_element", "negate"])
    bad = False
    if kind == "delete_element":
        parent = next(p for p in root.iter() if el in list(p))
        parent.remove(el)
        return f"delete <{tag}> of '{owner}'", ET.tostring(root, encoding="unicode"), owner, False
    if kind == "delete_attr":
        del el.attrib[attr]
        return f"delete {tag}.{attr} of '{owner}'", ET.tostring(root, encoding="unicode"), owner, False
    raw = el.get(attr)
    if kind == "vector" and attr in VECTORS:
        choice = rng.choice(["zeros", "one", "count"])
        parts = raw.split()
        if choice == "zeros":
            new = "0 0 0"
            bad = tag == "axis"
        elif choice == "count":
            new = " ".join(parts[: rng.choice([1, 2])]) if rng.random() < 0.5 else raw + " 1"
            bad = True
        else:
            i = rng.randrange(len(parts))
            v = rng.choice(BAD)
            parts[i] = v
            new = " ".join(parts)
            bad = _bad_number(v) or (tag == "axis" and all(_zero(p) for p in parts))
    elif kind == "scale" or kind == "negate":
        try:
            vals = [float(x) for x in raw.split()]
        except ValueError:
            vals = []
        if not vals:
            return "unchanged", text, owner, False
        if kind == "negate":
            vals = [-v for v in vals]
            bad = (tag, attr) in POSITIVE and any(v < 0 for v in vals)
            bad |= (tag, attr) in NONNEGATIVE and any(v < 0 for v in vals)
        else:
            vals = [v * rng.choice(SCALES) for v in vals]
        new = " ".join(repr(v) for v in vals)
    else:
        v = rng.choice(BAD)
        new = v if attr not in VECTORS else " ".join([v] * len(raw.split()))
        bad = _bad_number(v) or ((tag, attr) in POSITIVE and _nonpositive(v))
        bad |= (tag, attr) in NONNEGATIVE and _negative(v)
        bad |= tag == "axis" and _zero(v)
    el.set(attr, new)
    return f"{tag}.{attr} of '{owner}' = {new!r}", ET.tostring(root, encoding="unicode"), owner, bad


def _number(v: str) -> float | None:
    try:
        return float(v)
    except ValueError:
        return None


def _bad_number(v: str) -> bool:
    x = _number(v)
    return x is None or not math.isfinite(x) or abs(x) >= 1e30


def _nonpositive(v: str) -> bool:
    x = _number(v)
    return x is not None and x <= 0


def _negative(v: str) -> bool:
    x = _number(v)
    return x is not None and x < 0


def _zero(v: str) -> bool:
    x = _number(v)
    return x is not None and x == 0


def meaningless(arm) -> str | None:
    """An independent judgement of a loaded arm (Pinocchio's model and the arm's limits): a reason
    or None."""
    model = arm.model
    for i in range(1, model.njoints):
        Y = model.inertias[i]
        m, c, inertia = Y.mass, np.asarray(Y.lever), np.asarray(Y.inertia)
        if (
            not (math.isfinite(m) and 0 <= m <= 1e5)
            or not np.all(np.isfinite(inertia))
            or not np.all(np.isfinite(c))
        ):
            return f"body {i}: mass {m} or inertia not finite or out of scale"
        if m > 0 and (np.linalg.eigvalsh(inertia).min() < -1e-9 or np.linalg.norm(c) > 20):
            return f"body {i}: inertia not positive semidefinite or centre of mass {c}"
        p = model.jointPlacements[i].translation
        if not np.all(np.isfinite(p)) or np.linalg.norm(p) > 20:
            return f"joint {i}: placement {p}"
        axis = getattr(model.joints[i].extract(), "axis", None)
        if axis is not None and abs(np.linalg.norm(axis) - 1) > 1e-6:
            return f"joint {i}: axis {axis} not of unit length"
    lim = np.asarray(arm.actuator.torque_limit, float)
    vel = np.asarray(arm.velocity_limits, float)
    pos = np.asarray(arm.position_limits, float)
    fr = np.concatenate([arm.viscous, arm.coulomb])
    if np.any(~(lim > 0)) or np.any(lim > 1e5):
        return f"torque limit {lim}"
    if np.any(~(vel > 0)):
        return f"velocity limit {vel}"
    if np.any(~(pos[:, 0] < pos[:, 1])):
        return f"position limits {pos}"
    if not np.all(np.isfinite(fr)) or np.any(fr < 0):
        return f"friction {fr}"
    return None


def scenario(urdf: Path, frame: str, n: int) -> dict:
    """A minimal scenario naming the URDF (the reference at rest: its limits are not judged here)."""
    ref = {f"joint{j + 1}": {"offset": 0.0, "amplitude": [1e-3], "frequency": [0.5]} for j in range(n)}
    return {
        "arm": {"urdf": str(urdf), "payload_frame": frame},
        "run": {"duration": 2.0, "seeds": 1, "controllers": ["ct_oracle", "adaptive_ct"]},
        "reference": ref,
        "payload": [{"at": 1.0, "mass": 0.5}],
    }


def load(text: str, path: Path, frame: str, n: int):
    """Write the mutant and load a scenario naming it: the arm, or the exception raised."""
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)  # the notes are judged, not printed
        try:
            return parse_scenario(scenario(path, frame, n), src=str(path.with_suffix(".toml"))).arm
        except Exception as exc:  # judged by the caller
            return exc


def fuzz(n: int, seed: int) -> tuple[Counter, dict[str, str]]:
    """``n`` mutants (seeded); the counts of each outcome and examples of each failure kind."""
    rng = random.Random(seed)
    robots = []
    for name, info in sorted(ROBOTS.items()):
        text = robot_urdf(name).read_text()
        n_joints = sum(1 for j in ET.fromstring(text).findall("joint") if j.get("type") != "fixed")
        robots.append((name, text, info.payload_frame, n_joints))
    counts: Counter = Counter()
    examples: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(n):
            name, text, frame, n_joints = rng.choice(robots)
            kind, mutant, owner, bad = mutate(text, rng)
            path = Path(tmp) / f"{name}_mutant.urdf"
            got = load(mutant, path, frame, n_joints)
            if isinstance(got, ScenarioError):
                named = str(path) in str(got)
                counts["precise error" if named else "error not naming the file"] += 1
                if not named:
                    examples.setdefault(f"unnamed {kind}", str(got)[:300])
                continue
            if isinstance(got, Exception):
                counts["internal error"] += 1
                examples.setdefault(f"internal {name}: {kind}", f"{type(got).__name__}: {got}"[:300])
                continue
            noted = any(f"'{owner}'" in note for note in got.urdf_notes)
            why = meaningless(got) or (None if noted or not bad else "a meaningless value, no note")
            counts["meaningless accepted silently" if why else "accepted"] += 1
            if why:
                examples.setdefault(f"silent {name}: {kind}", why)
    return counts, examples


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    counts, examples = fuzz(args.n, args.seed)
    print(
        f"{args.n} mutations (seed {args.seed}) of the {len(ROBOTS)} shipped URDFs, "
        "loaded as a scenario's arm:"
    )
    for k in (
        "precise error",
        "error not naming the file",
        "internal error",
        "meaningless accepted silently",
        "accepted",
    ):
        print(f"  {k:30s} {counts[k]}")
    for k, v in examples.items():
        print(f"  example {k}: {v}")


if __name__ == "__main__":
    main()
