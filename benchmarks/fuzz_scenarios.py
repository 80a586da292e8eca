"""Seeded mutation fuzz of the scenario loader (issue 13).

Mutates the shipped scenario files and every table a scenario may hold (``[run]``,
``[control]``, ``[reference]``, ``[[payload]]``, ``[noise]``, ``[arm]`` in both forms,
``[plant]``, ``[controllers.NAME]``): delete / duplicate keys, wrong types, NaN, inf, 1e300,
negative and zero values, the sign of any number, any number scaled by up to 1e9, seeds like
2**64, swaps closer than a sample, frequencies above Nyquist, a BOM, non-UTF-8 bytes, an
empty file, ... and counts:

* precise errors: ``ScenarioError`` whose message names the file;
* crashes: any other exception;
* meaningless accepted: a scenario that loads but fails an independent sanity
  judgement (non-finite numbers, frequency >= 0.5 / T, a segment without a
  sample, seeds out of range, an absurd size, ...).

Run: ``PYTHONPATH=. python benchmarks/fuzz_scenarios.py [--n 2000] [--seed 0]``; a small
configuration runs in the test suite (``tests/test_validation.py``).
"""

from __future__ import annotations

import argparse
import math
import random
import re
import tempfile
from collections import Counter
from pathlib import Path

from adaptive_dd.benchmark.scenario import default_scenario_path, load_scenario
from adaptive_dd.errors import ScenarioError

ROOT = Path(__file__).resolve().parent
BAD_VALUES = [
    "nan", "inf", "-inf", "1e300", "-1e300", "-1", "0", "0.0", "1e-300", "18446744073709551616",
    "9223372036854775808", "1000000000", '"text"', "true", "[]", "[1, 2, 3]", "{ a = 1 }", "-0.0",
    "2.5", "1e-7", "100000", "1.7e308",
]  # fmt: skip
ARM_SIGMA = """[arm]
sigma = [0.52, 0.04, 0.05, 3.0, 0.6, 2.0, 0.5]
l1 = 0.2
l2 = 0.2
"""
PLANT_KEYS = ["friction", "friction_velocity", "stribeck_ratio", "stribeck_velocity"]
CONTROLLER_TABLES = {
    "adaptive_ct": ["boost_bandwidth", "boost_duration", "bandwidth", "damping", "detector",
                    "estimator"],
    "slotine_li": ["gamma", "bandwidth", "damping"],
    "ct_nominal": ["sigma", "bandwidth"],
    "pd": ["sigma", "damping"],
}  # fmt: skip
NUMBER = re.compile(r"(?<![\w.])(\d+\.?\d*(?:e[-+]?\d+)?)")


def sources() -> list[Path]:
    return [default_scenario_path(), *sorted((ROOT / "scenarios").rglob("*.toml"))]


def _value_lines(text: str) -> list[int]:
    return [i for i, ln in enumerate(text.splitlines()) if re.match(r"^\s*[\w.]+\s*=", ln)]


def mutate(text: str, rng: random.Random) -> tuple[str, bytes | None]:
    """One random mutation; returns (kind, new bytes)."""
    lines = text.splitlines()
    idx = _value_lines(text)
    kind = rng.choice(
        ["delete", "duplicate", "value", "value", "value", "seed", "swap_close", "nyquist",
         "bom", "bytes", "array_item", "unknown_key", "table", "period", "sign", "sign", "scale",
         "scale", "arm_sigma", "plant", "controllers", "controllers", "empty"]
    )  # fmt: skip
    if kind == "empty":
        return kind, rng.choice([b"", b"\n", b"# only a comment\n", b"\xef\xbb\xbf"])
    if kind == "arm_sigma":
        lines = [ln for ln in lines if not ln.startswith("[arm]")]
        lines += ARM_SIGMA.splitlines()
        if rng.random() < 0.8:
            j = rng.randrange(len(lines) - 3, len(lines))
            k = lines[j].split("=", 1)[0].strip()
            lines[j] = f"{k} = {rng.choice(BAD_VALUES)}" if rng.random() < 0.5 else _negate(lines[j], rng)
        return kind, "\n".join(lines).encode()
    if kind == "plant":
        lines = [ln for ln in lines if not ln.startswith("[plant]")]
        key = rng.choice(PLANT_KEYS)
        val = rng.choice([*BAD_VALUES, '"tanh"', '"stribeck"', '"lugre?"', "0.02", "2.0"])
        lines += ["[plant]", f"{key} = {val}"]
        return kind, "\n".join(lines).encode()
    if kind == "controllers":
        name = rng.choice(list(CONTROLLER_TABLES))
        key = rng.choice(CONTROLLER_TABLES[name])
        val = rng.choice([*BAD_VALUES, "{ threshold = -1.0 }", "{ tau_f = -0.01 }", "{ lam = 2.0 }",
                          "[0.5, 0.04, 0.05, 3.0, 0.6, 2.0, -0.5]", "false", "200.0", "0.5"])  # fmt: skip
        text2 = "\n".join(lines)
        if name not in text2.split("controllers =", 1)[-1].split("\n", 1)[0]:
            lines = [re.sub(r"^controllers = \[", f'controllers = ["{name}", ', ln) for ln in lines]
        lines += [f"[controllers.{name}]", f"{key} = {val}"]
        return kind, "\n".join(lines).encode()
    i = rng.choice(idx)
    key = lines[i].split("=", 1)[0].strip()
    if kind == "delete":
        del lines[i]
    elif kind == "duplicate":
        lines.insert(i, lines[i])
    elif kind == "value":
        lines[i] = f"{key} = {rng.choice(BAD_VALUES)}"
    elif kind == "seed":
        lines.insert(
            _after(lines, "[run]"), f"seed = {rng.choice(['18446744073709551616', '-1', '2.0', 'nan'])}"
        )
    elif kind == "swap_close":
        lines += ["[[payload]]", f"at = {rng.choice(['20.0000001', '0.0000001', '19.9999', '0.0', '1e-12'])}",
                  "mass = 1.0"]  # fmt: skip
    elif kind == "nyquist":
        f = rng.choice(["500.0", "499.9", "1000.0", "250.0", "1e300", "0.0", "-1.0", "101.0"])
        lines = [re.sub(r"frequency = \[[^\]]*\]", f"frequency = [{f}, 1.0]", ln) for ln in lines]
    elif kind == "bom":
        return kind, b"\xef\xbb\xbf" + "\n".join(lines).encode()
    elif kind == "bytes":
        raw = bytearray("\n".join(lines).encode())
        raw[rng.randrange(len(raw))] = rng.choice([0xFF, 0xC3, 0x80, 0xFE])
        return kind, bytes(raw)
    elif kind == "array_item":
        lines[i] = re.sub(
            r"\[([^\]]*)\]", lambda m: f"[{m.group(1)}, {rng.choice(BAD_VALUES)}]", lines[i], count=1
        )
    elif kind == "sign":
        lines[i] = _negate(lines[i], rng)
    elif kind == "scale":
        nums = list(NUMBER.finditer(lines[i].split("=", 1)[1])) if "=" in lines[i] else []
        if nums:
            m = rng.choice(nums)
            off = len(lines[i].split("=", 1)[0]) + 1
            x = float(m.group(1)) * rng.choice([1e3, 1e6, 1e9, 1e-9])
            lines[i] = lines[i][: off + m.start()] + repr(x) + lines[i][off + m.end() :]
    elif kind == "unknown_key":
        lines.insert(i, f"{key}x = 1")
    elif kind == "table":
        lines.insert(0, rng.choice(["[runs]", "[run]", "payload = 3", "[[noise]]"]))
    elif kind == "period":
        lines.insert(_after(lines, "[run]"), "")
        lines = [ln for ln in lines if not ln.strip().startswith("sample_period")]
        lines.insert(
            _after(lines, "[run]"), f"sample_period = {rng.choice(['1e-300', '0.5', '0.01', '1e-6'])}"
        )
    return kind, "\n".join(lines).encode()


def _negate(line: str, rng: random.Random) -> str:
    """The line with the sign of one of its numbers (after the '=') flipped."""
    if "=" not in line:
        return line
    key, val = line.split("=", 1)
    nums = list(NUMBER.finditer(val))
    if not nums:
        return line
    m = rng.choice(nums)
    return key + "=" + val[: m.start()] + "-" + val[m.start() :]


def _after(lines: list[str], header: str) -> int:
    return lines.index(header) + 1 if header in lines else 0


def meaningless(sc) -> str | None:
    """An independent judgement of a loaded scenario; a reason or None."""
    nums = [sc.duration, sc.sample_period, sc.bandwidth, sc.damping, sc.payload_radius,
            *sc.swap_times, *sc.swap_masses, *sc.position_variance, *sc.velocity_variance,
            *sc.reference.offset, sc.reference.ramp]  # fmt: skip
    for j in range(sc.reference.n_joints):
        nums += [*sc.reference.amplitude[j], *sc.reference.frequency[j], *sc.reference.phase[j]]
    if not all(isinstance(x, int | float) and math.isfinite(x) and abs(x) < 1e6 for x in nums):
        return "non-finite or huge number"
    T = sc.sample_period
    if any(f <= 0 or f >= 0.5 / T for fs in sc.reference.frequency for f in fs):
        return "frequency at or above Nyquist"
    if min(sc.segment_samples()) < 1:
        return "segment without a sample"
    if not (0 <= sc.seed < 2**63) or not (1 <= sc.seeds <= 10_000):
        return "seed(s) out of range"
    if any(m < 0 or m > 100 for m in sc.swap_masses) or sc.duration / T > 1e9:
        return "absurd mass or size"
    if sc.estimate().bytes > 8 * 2**30:
        return "run too large"
    return _meaningless_arm(sc.closed_forms or sc.arm) or _meaningless_controllers(sc)


def _meaningless_arm(arm) -> str | None:
    """An arm no direct-drive two-link arm is: lengths, inertias, friction, limits out of scale
    (for a URDF arm: its per-joint friction, armature, limits and gravity)."""
    import numpy as np

    from adaptive_dd.plant.arm import Arm

    if isinstance(arm, Arm):
        vec = np.concatenate([arm.viscous, arm.coulomb, arm.armature])
        lim = np.asarray(arm.actuator.torque_limit, float)
        if not np.all(np.isfinite(vec)) or np.any(vec < 0) or np.any(vec > 1e4):
            return f"joint friction or armature out of scale: {vec}"
        if np.any(lim <= 0) or np.any(lim > 1e5):
            return f"torque limit {lim}"
        if not (0 <= arm.payload_radius <= 0.5) or np.linalg.norm(arm.gravity) > 100:
            return f"payload radius {arm.payload_radius} m or gravity {arm.gravity}"
        return None

    s = np.asarray(arm.sigma, float)
    if not (0 < arm.l1 <= 2 and 0 < arm.l2 <= 2):
        return f"link length out of scale (l1 {arm.l1}, l2 {arm.l2} m)"
    if not np.all(np.isfinite(s)) or np.any(s < 0) or np.any(s > 1e3) or s[0] <= 0 or s[1] <= 0:
        return f"base parameters out of scale: {s}"
    if not (0 <= arm.payload_radius <= 0.5):
        return f"payload radius {arm.payload_radius} m"
    lim = np.asarray(arm.actuator.torque_limit, float)
    if np.any(lim <= 0) or np.any(lim > 1e4):
        return f"torque limit {lim}"
    if not (0 < arm.friction_velocity <= 10):
        return f"friction velocity {arm.friction_velocity}"
    return None


def _meaningless_controllers(sc) -> str | None:
    """Built-in controllers whose settings are meaningless: signs, gains beyond the sample rate."""
    from adaptive_dd.controllers import CONTROLLERS

    for name in sc.controllers:
        o = sc.options(name)
        if name not in CONTROLLERS or not o:
            continue
        for k, v in o.items():
            vals = v.values() if isinstance(v, dict) else (v if isinstance(v, list) else [v])
            for x in vals:
                if isinstance(x, int | float) and not isinstance(x, bool):
                    if not math.isfinite(x) or x < 0 or abs(x) > 1e6:
                        return f"controllers.{name}.{k} = {v!r}"
        bw = o.get("bandwidth", sc.bandwidth)
        if bw * sc.sample_period > 0.2:
            return f"controllers.{name}.bandwidth {bw} at T = {sc.sample_period}"
    return None


def fuzz(n: int, seed: int) -> tuple[Counter, dict[str, str]]:
    """``n`` mutants (seeded); the counts of each outcome and one example of each failure kind."""
    rng = random.Random(seed)
    texts = [p.read_text() for p in sources()]
    counts: Counter = Counter()
    examples: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "mutant.toml"
        for _ in range(n):
            kind, raw = mutate(rng.choice(texts), rng)
            path.write_bytes(raw)
            try:
                sc = load_scenario(path)
            except ScenarioError as exc:
                named = str(path) in str(exc)
                counts["precise error" if named else "error not naming the file"] += 1
                continue
            except Exception as exc:
                counts["crash"] += 1
                examples.setdefault(f"crash {kind}", f"{type(exc).__name__}: {exc}")
                continue
            why = "an empty file accepted" if kind == "empty" else meaningless(sc)
            counts["meaningless accepted" if why else "valid accepted"] += 1
            if why:
                examples.setdefault(f"meaningless {kind}", why)
    return counts, examples


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    counts, examples = fuzz(args.n, args.seed)
    print(f"{args.n} mutations (seed {args.seed}) of {len(sources())} shipped scenario files:")
    for k in (
        "precise error",
        "error not naming the file",
        "crash",
        "meaningless accepted",
        "valid accepted",
    ):
        print(f"  {k:28s} {counts[k]}")
    for k, v in examples.items():
        print(f"  example {k}: {v}")


if __name__ == "__main__":
    main()
