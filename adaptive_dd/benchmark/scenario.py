"""Benchmark scenarios: TOML files read with ``tomllib`` and checked key by key.

::

    [run]
    duration = 20.0            # s
    sample_period = 0.001      # s
    seeds = 10                 # Monte-Carlo trials per controller
    seed = 0                   # base seed (optional)
    substeps = 2               # RK4 steps per sample (optional)
    controllers = ["pd", "ct_nominal", "ct_oracle", "adaptive_ct_paper", "adaptive_ct", "slotine_li"]

    [control]                  # optional
    bandwidth = 40.0           # rad/s, shared by all controllers
    damping = 1.0

    [reference]                # q_d(t) = offset + w(t) sum_k a_k sin(2 pi f_k t + phase_k);
                               # a file without [reference] uses the default scenario's
    ramp = 1.0                 # optional: w rises smoothly from 0 to 1 over this many s
    joint1 = { offset = 0.0, amplitude = [0.5, 0.2], frequency = [0.4, 1.1], phase = [0.0, 0.0] }
    joint2 = { offset = 0.0, amplitude = [0.6, 0.2], frequency = [0.5, 1.3], phase = [0.0, 0.0] }

    [[payload]]                # a disk at the tip of link 2 from `at` on; 0 kg before the first
    at = 5.0
    mass = 3.0
    radius = 0.05              # optional, m

    [noise]                    # optional; defaults are Tables 2 and 4
    position_variance = [1e-8, 1e-7]
    velocity_variance = [5e-5, 1e-4]
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.controllers import CONTROLLERS
from adaptive_dd.errors import ScenarioError
from adaptive_dd.plant.arm import Arm, arm_from_tables

__all__ = ["Reference", "Scenario", "default_scenario_path", "load_scenario"]

Array = NDArray[np.float64]

_KEYS = {
    "run": {"duration", "sample_period", "seeds", "seed", "substeps", "controllers"},
    "control": {"bandwidth", "damping"},
    "reference": {"ramp", "joint1", "joint2"},
    "payload": {"at", "mass", "radius"},
    "noise": {"position_variance", "velocity_variance"},
    "arm": None,  # checked by adaptive_dd.plant.arm.arm_from_tables
    "plant": None,
}
_JOINT_KEYS = {"offset", "amplitude", "frequency", "phase"}


@dataclass(frozen=True)
class Reference:
    """``q_d(t) = offset + w(t) sum_k a_k sin(2 pi f_k t + phase_k)`` per joint, w a C^2 ramp."""

    offset: tuple[float, float]
    amplitude: tuple[tuple[float, ...], tuple[float, ...]]
    frequency: tuple[tuple[float, ...], tuple[float, ...]]
    phase: tuple[tuple[float, ...], tuple[float, ...]]
    ramp: float = 0.0

    def sample(self, t: Array) -> tuple[Array, Array, Array]:
        """``q_d, qd_d, qdd_d`` at times t, each of shape ``(len(t), 2)``."""
        t = np.asarray(t, dtype=float)
        w, dw, ddw = self._ramp(t)
        out = np.zeros((3, t.size, 2))
        for j in range(2):
            s = ds = dds = np.zeros_like(t)
            for a, f, p in zip(self.amplitude[j], self.frequency[j], self.phase[j], strict=True):
                om = 2 * np.pi * f
                s = s + a * np.sin(om * t + p)
                ds = ds + a * om * np.cos(om * t + p)
                dds = dds - a * om**2 * np.sin(om * t + p)
            out[0, :, j] = self.offset[j] + w * s
            out[1, :, j] = dw * s + w * ds
            out[2, :, j] = ddw * s + 2 * dw * ds + w * dds
        return out[0], out[1], out[2]

    def _ramp(self, t: Array) -> tuple[Array, Array, Array]:
        if self.ramp <= 0:
            one = np.ones_like(t)
            return one, 0 * one, 0 * one
        x = np.clip(t / self.ramp, 0.0, 1.0)
        inside = (t > 0) & (t < self.ramp)
        w = 10 * x**3 - 15 * x**4 + 6 * x**5
        dw = np.where(inside, (30 * x**2 - 60 * x**3 + 30 * x**4) / self.ramp, 0.0)
        ddw = np.where(inside, (60 * x - 180 * x**2 + 120 * x**3) / self.ramp**2, 0.0)
        return w, dw, ddw


@dataclass(frozen=True)
class Scenario:
    """A checked benchmark scenario (see the module docstring for the file format)."""

    name: str
    duration: float
    sample_period: float
    seeds: int
    controllers: tuple[str, ...]
    reference: Reference
    swap_times: tuple[float, ...]
    swap_masses: tuple[float, ...]
    payload_radius: float = 0.05
    position_variance: tuple[float, float] = (1e-8, 1e-7)
    velocity_variance: tuple[float, float] = (5e-5, 1e-4)
    seed: int = 0
    substeps: int = 2
    bandwidth: float = 40.0
    damping: float = 1.0
    source: str = "<memory>"
    extra: dict = field(default_factory=dict)
    arm: Arm = field(default_factory=Arm.sice)

    @property
    def n_samples(self) -> int:
        return round(self.duration / self.sample_period)

    def segments(self) -> list[tuple[float, float, float]]:
        """``(start, end, mass)`` of each constant-payload segment."""
        edges = [0.0, *self.swap_times, self.duration]
        masses = [0.0, *self.swap_masses]
        return [(edges[i], edges[i + 1], masses[i]) for i in range(len(masses))]


def default_scenario_path() -> Path:
    """The ``payload_swap`` scenario shipped with the package."""
    return Path(str(resources.files("adaptive_dd.scenarios").joinpath("payload_swap.toml")))


def _err(src: str, key: str, msg: str) -> ScenarioError:
    return ScenarioError(f"{src}: [{key}] {msg}" if not key.startswith("[") else f"{src}: {key} {msg}")


def _num(src: str, key: str, v, *, positive: bool = False, integer: bool = False, nonneg: bool = False):
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ScenarioError(f"{src}: key '{key}' must be a number, got {v!r}")
    if integer and not isinstance(v, int):
        raise ScenarioError(f"{src}: key '{key}' must be an integer, got {v!r}")
    if not np.isfinite(v):
        raise ScenarioError(f"{src}: key '{key}' must be finite, got {v!r}")
    if positive and v <= 0:
        raise ScenarioError(f"{src}: key '{key}' must be > 0, got {v!r}")
    if nonneg and v < 0:
        raise ScenarioError(f"{src}: key '{key}' must be >= 0, got {v!r}")
    return v


def _pair(src: str, key: str, v) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2:
        raise ScenarioError(f"{src}: key '{key}' must be a list of two numbers, got {v!r}")
    return tuple(float(_num(src, key, x, nonneg=True)) for x in v)  # type: ignore[return-value]


def load_scenario(path: str | Path | None = None) -> Scenario:
    """Read and check a scenario file (default: the shipped ``payload_swap``).

    Raises
    ------
    ScenarioError
        Naming the file, the key and the reason: unknown table or key, wrong type,
        unknown controller, negative mass, swap at or beyond the duration,
        non-increasing swap times, reference lists of unequal length, ...
    """
    path = Path(path) if path is not None else default_scenario_path()
    src = str(path)
    if not path.is_file():
        raise ScenarioError(f"{src}: no such scenario file")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{src}: not valid TOML: {exc}") from None
    return parse_scenario(data, src, name=path.stem)


def parse_scenario(data: dict, src: str = "<memory>", name: str = "scenario") -> Scenario:
    """Check a scenario given as a dict (the parsed TOML)."""
    for table, val in data.items():
        if table not in _KEYS:
            raise ScenarioError(f"{src}: unknown table [{table}]; allowed: {sorted(_KEYS)}")
        if _KEYS[table] is None:
            continue
        items = val if table == "payload" else [val]
        if table == "payload" and not isinstance(val, list):
            raise ScenarioError(f"{src}: 'payload' must be an array of tables [[payload]]")
        for item in items:
            if not isinstance(item, dict):
                raise ScenarioError(f"{src}: [{table}] must be a table")
            for key in item:
                if key not in _KEYS[table]:
                    raise ScenarioError(
                        f"{src}: unknown key '{table}.{key}'; allowed: {sorted(_KEYS[table])}"
                    )
    run = data.get("run", {})
    duration = float(_num(src, "run.duration", run.get("duration", 20.0), positive=True))
    T = float(_num(src, "run.sample_period", run.get("sample_period", 0.001), positive=True))
    if T > duration / 10:
        raise ScenarioError(f"{src}: key 'run.sample_period' = {T} is too long for duration {duration}")
    seeds = int(_num(src, "run.seeds", run.get("seeds", 10), positive=True, integer=True))
    seed = int(_num(src, "run.seed", run.get("seed", 0), integer=True, nonneg=True))
    substeps = int(_num(src, "run.substeps", run.get("substeps", 2), positive=True, integer=True))
    ctrls = run.get("controllers", list(CONTROLLERS))
    if not isinstance(ctrls, list) or not ctrls:
        raise ScenarioError(f"{src}: key 'run.controllers' must be a non-empty list of names")
    for c in ctrls:
        if c not in CONTROLLERS:
            raise ScenarioError(
                f"{src}: key 'run.controllers': unknown controller {c!r}; known: {CONTROLLERS}"
            )
    if len(set(ctrls)) != len(ctrls):
        raise ScenarioError(f"{src}: key 'run.controllers' lists a controller twice: {ctrls}")
    control = data.get("control", {})
    bw = float(_num(src, "control.bandwidth", control.get("bandwidth", 40.0), positive=True))
    zeta = float(_num(src, "control.damping", control.get("damping", 1.0), positive=True))
    if "reference" in data:
        reference = _parse_reference(src, data["reference"])
    elif src == str(default_scenario_path()):
        raise ScenarioError(f"{src}: the default scenario must define [reference]")
    else:
        reference = load_scenario().reference
    arm = arm_from_tables(data.get("arm"), data.get("plant"), src)
    times, masses, radius = [], [], None
    for i, p in enumerate(data.get("payload", [])):
        where = f"payload[{i}]"
        for key in ("at", "mass"):
            if key not in p:
                raise ScenarioError(f"{src}: key '{where}.{key}' is missing")
        at = float(_num(src, f"{where}.at", p["at"], positive=True))
        m = _num(src, f"{where}.mass", p["mass"])
        if m < 0:
            raise ScenarioError(f"{src}: key '{where}.mass' must be >= 0 kg, got {m}")
        if at >= duration:
            raise ScenarioError(
                f"{src}: key '{where}.at' = {at} s is not before the end of the run ({duration} s)"
            )
        if times and at <= times[-1]:
            raise ScenarioError(
                f"{src}: key '{where}.at' = {at} s: swap times must increase (previous {times[-1]})"
            )
        r = float(_num(src, f"{where}.radius", p.get("radius", arm.payload_radius), nonneg=True))
        if radius is not None and r != radius:
            raise ScenarioError(f"{src}: key '{where}.radius': all payload disks must share one radius")
        radius = r
        times.append(at)
        masses.append(float(m))
    noise = data.get("noise", {})
    pv = _pair(src, "noise.position_variance", noise.get("position_variance", [1e-8, 1e-7]))
    vv = _pair(src, "noise.velocity_variance", noise.get("velocity_variance", [5e-5, 1e-4]))
    return Scenario(
        name=name,
        duration=duration,
        sample_period=T,
        seeds=seeds,
        controllers=tuple(ctrls),
        reference=reference,
        swap_times=tuple(times),
        swap_masses=tuple(masses),
        payload_radius=arm.payload_radius if radius is None else radius,
        position_variance=pv,
        velocity_variance=vv,
        seed=seed,
        substeps=substeps,
        bandwidth=bw,
        damping=zeta,
        source=src,
        arm=arm,
    )


def _parse_reference(src: str, ref: dict) -> Reference:
    ramp = float(_num(src, "reference.ramp", ref.get("ramp", 0.0), nonneg=True))
    offs, amps, freqs, phases = [], [], [], []
    for j in ("joint1", "joint2"):
        spec = ref.get(j, {"offset": 0.0, "amplitude": [], "frequency": [], "phase": []})
        if not isinstance(spec, dict):
            raise ScenarioError(f"{src}: key 'reference.{j}' must be an inline table")
        for key in spec:
            if key not in _JOINT_KEYS:
                raise ScenarioError(
                    f"{src}: unknown key 'reference.{j}.{key}'; allowed: {sorted(_JOINT_KEYS)}"
                )
        off = float(_num(src, f"reference.{j}.offset", spec.get("offset", 0.0)))
        lists = []
        for key in ("amplitude", "frequency", "phase"):
            v = spec.get(key, [0.0] * len(spec.get("amplitude", [])) if key == "phase" else [])
            if not isinstance(v, list):
                raise ScenarioError(f"{src}: key 'reference.{j}.{key}' must be a list, got {v!r}")
            lists.append(tuple(float(_num(src, f"reference.{j}.{key}", x)) for x in v))
        if not (len(lists[0]) == len(lists[1]) == len(lists[2])):
            raise ScenarioError(
                f"{src}: key 'reference.{j}': amplitude, frequency and phase must have equal lengths, "
                f"got {len(lists[0])}, {len(lists[1])}, {len(lists[2])}"
            )
        if any(f <= 0 for f in lists[1]):
            raise ScenarioError(f"{src}: key 'reference.{j}.frequency': frequencies must be > 0 Hz")
        offs.append(off)
        amps.append(lists[0])
        freqs.append(lists[1])
        phases.append(lists[2])
    return Reference(tuple(offs), tuple(amps), tuple(freqs), tuple(phases), ramp)
