"""``adaptive-dd excite --arm SCENARIO``: an exciting trajectory for the arm, designed, with its
identification bound beside a plain multi-sine's; writes the scenario with the designed ``[reference]``.

Any arm from a URDF, the paper's kind included (designed on its general model); an arm given by
the paper's tables alone (no URDF) is refused.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

from adaptive_dd.cli._common import (
    NAME_WIDTH,
    POS,
    SEED,
    add_command,
    closed_form_view,
    load_arm,
    number,
    short,
)
from adaptive_dd.errors import ParameterError

__all__ = ["add_parser", "excitation_bounds", "ramp_within_limits", "run"]


def add_parser(sub) -> None:
    """The options of ``excite``."""
    e = add_command(sub, "excite", help="design an exciting trajectory for an arm from a URDF")
    e.add_argument("--arm", required=True, metavar="SCENARIO", help="scenario TOML with [arm] urdf/robot")
    e.add_argument("--harmonics", type=number(int, 1, 20), default=5, help="Fourier harmonics (default 5)")
    e.add_argument("--f0", type=POS, default=0.1, help="base frequency [Hz] (default 0.1: 10 s period)")
    e.add_argument("--acceleration", type=POS, default=5.0, help="|qdd| limit [rad/s^2] (default 5)")
    e.add_argument("--margin", type=number(float, 0.0, 1.0), default=0.1, help="position margin [rad]")
    e.add_argument("--maxiter", type=number(int, 1, 10000), default=100, help="SLSQP iterations")
    e.add_argument("--duration", type=POS, default=10.0, help="record length for the bounds [s]")
    e.add_argument("--ramp", type=number(float, 0.0, 100.0), default=0.5, help="reference ramp [s]")
    e.add_argument("--seed", type=SEED, default=0, help="seed of the random start")
    e.add_argument("--out", default="results/excite/scenario.toml", help="scenario file to write")
    e.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``adaptive-dd excite --arm SCENARIO``: design an exciting trajectory; its bound beside a multi-sine."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.identification.excitation import (
        ExcitationLimits,
        design_excitation,
        multisine,
        reference_toml,
    )
    from adaptive_dd.io import read_toml
    from adaptive_dd.outputs import atomic_write, check_output_file

    sc = load_scenario(args.arm)
    arm = sc.arm
    from adaptive_dd.benchmark.scenario_base import LIMITS

    top, most = args.harmonics * args.f0, LIMITS["nyquist_fraction"] / sc.sample_period
    if top > most:  # refused before the design: the scenario written would be refused by validate
        raise ParameterError(
            f"--f0 {args.f0:g} Hz x --harmonics {args.harmonics}: {top:g} Hz is above "
            f"{LIMITS['nyquist_fraction']:g} / T = {most:g} Hz at the scenario's T = {sc.sample_period:g} s "
            "(what a scenario's reference may hold); lower --f0 or --harmonics"
        )
    if closed_form_view(arm) is not None:  # the paper's kind of arm: its general model
        arm = load_arm(args.arm, general="excite")
    if args.ramp > args.duration:  # a record inside the ramp: its bound's information matrix is singular
        raise ParameterError(
            f"--ramp {args.ramp:g} s is longer than --duration {args.duration:g} s: the record for the "
            "bounds would hold the ramp alone; lengthen --duration or shorten --ramp"
        )
    from adaptive_dd.benchmark.scenario_base import run_estimate

    est = run_estimate(round(args.duration / sc.sample_period), 1, 3, arm.n_joints)  # three tracked records
    if est.bytes > LIMITS["max_bytes"] or est.seconds > LIMITS["max_seconds"]:
        raise ParameterError(f"--duration {args.duration:g} s: records too large ({est}); reduce --duration")
    out = check_output_file(args.out)  # before the design, not after it
    lim = ExcitationLimits.of_arm(arm, acceleration=args.acceleration, margin=args.margin)
    plain = multisine(arm, lim, args.harmonics, args.f0)
    _stage(
        f"designing the excitation of the {arm.n_joints}-joint arm: SLSQP, up to {args.maxiter} iterations "
        "(the first run compiles the kernels; minutes on a 7-joint arm)"
    )
    best, res = design_excitation(
        arm,
        lim,
        harmonics=args.harmonics,
        f0=args.f0,
        maxiter=args.maxiter,
        rng=np.random.default_rng(args.seed),
        progress=True,
    )
    _stage(
        f"bounding the designed and a plain multi-sine trajectory: each tracked for {args.duration:g} s "
        "and the Cramér-Rao bound of its record ..."
    )
    ramp = ramp_within_limits(best.reference(ramp=args.ramp), arm, 1.0 / args.f0)
    trajectories = {"plain multi-sine": plain, "designed": best}
    if "reference" in read_toml(Path(args.arm)):  # the file's own motion, beside: what it already gives
        trajectories = {"scenario's reference": _AsIs(sc.reference), **trajectories}
    if ramp > args.duration:
        raise ParameterError(
            f"--ramp {args.ramp:g} s was lengthened to {ramp:g} s (the ramp took a joint beyond its velocity "
            f"limit), longer than --duration {args.duration:g} s; lengthen --duration"
        )
    rows = excitation_bounds(arm, trajectories, args.duration, ramp)
    _print_bounds(args, arm, res, rows)
    if ramp != args.ramp:
        print(
            f"--ramp {args.ramp:g} s lengthened to {ramp:g} s (the bounds above with it): the ramp into the "
            "designed trajectory "
            "took a joint beyond its velocity limit (the design keeps to the limits once under way)"
        )
    text = reference_toml(best.reference(ramp=ramp), f"designed by adaptive-dd excite --arm {args.arm}")
    with atomic_write(out) as fh:
        fh.write(_replace_reference(Path(args.arm).read_text(), text, Path(args.arm), Path(out)))
    print(f"wrote {out} (the scenario with the designed [reference])")
    return 0


def _stage(text: str) -> None:
    """What ``excite`` is doing now, on stderr (the result goes to stdout)."""
    print(text, file=sys.stderr, flush=True)


def ramp_within_limits(ref, arm, period: float, tries: int = 8) -> float:
    """The reference's ramp [s], doubled until the ramp and one ``period`` after it keep every
    joint within its velocity limit (the design keeps to the limits once the ramp is over, not
    during it: the Kinova Gen3's design with the default 0.5 s reached 4.9 times joint 7's limit);
    the last doubling if none does."""
    import dataclasses

    vmax = np.asarray(arm.velocity_limits, dtype=float)
    ramp = float(ref.ramp)
    for _ in range(tries):
        _, qd, _ = dataclasses.replace(ref, ramp=ramp).sample(np.arange(0.0, ramp + period, 1e-3))
        if np.all(np.abs(qd) <= vmax):
            return ramp
        ramp = max(2.0 * ramp, 0.5)
    return ramp


def _print_bounds(args: argparse.Namespace, arm, res, rows: dict) -> None:
    """The limits, SLSQP's outcome, each trajectory's worst and median bound, and their ratio."""
    print(
        f"{arm.n_joints}-joint arm of {args.arm}: {args.harmonics} harmonics of {args.f0} Hz; limits: "
        "positions "
        f"less {args.margin} rad, {0.8:.0%} of velocity and torque limits, |qdd| <= {args.acceleration} "
        "rad/s^2"
    )
    print(f"SLSQP: {res.nit} iterations, {res.message}")
    print(f"{'trajectory':<20} {'worst bound':>12}  {'worst base parameter':<{NAME_WIDTH}} {'median':>9}")
    for label, (worst, name, med) in rows.items():
        print(f"{label:<20} {100 * worst:11.3g}%  {short(name):<{NAME_WIDTH}} {100 * med:8.3g}%")
    bad = [label for label, (worst, _, _) in rows.items() if not np.isfinite(worst)]
    if bad:  # said, not printed as a ratio of NaNs
        print(
            f"warning: the bound of the {' and '.join(bad)} record is not finite: the identification "
            f"model's sensitivities diverge along it (a stiff friction model at T = 1 ms, or a record "
            "that leaves the arm's range): the two cannot be compared",
            file=sys.stderr,
        )
    else:
        ratio = rows["plain multi-sine"][0] / rows["designed"][0]
        own = rows.get("scenario's reference")
        print(
            f"the designed trajectory shrinks the worst bound {ratio:.1f}x (Cramér-Rao std of the "
            f"segmented output error on a {args.duration} s record tracking it, relative to each "
            "parameter's magnitude)"
            + (
                f"; against the scenario's own reference {own[0] / rows['designed'][0]:.3g}x (its median "
                f"bound {own[2] / rows['designed'][2]:.3g}x)"
                if own
                else ""
            )
        )


_PATH_KEY = re.compile(r"(?m)^[ \t]*(urdf|from|files)[ \t]*=[ \t]*")
_HEADER = re.compile(r"^\s*\[\[?\s*[A-Za-z_\"']")
"""A table header's line: ``[name]`` or ``[[name]]`` (an array's nested line, ``[0.1, 0.2],``, is not)."""


def _replace_reference(src: str, table: str, source: Path | None = None, out: Path | None = None) -> str:
    """The scenario text with its ``[reference]`` table and sub-tables (``[reference.joint1]``) replaced
    by ``table``; with ``source`` and ``out`` (the files read and written) the relative paths of its
    ``urdf``, ``from`` and ``files`` that name files beside ``source`` rewritten relative to ``out``'s
    folder (written elsewhere, ``results/excite/`` by default, they named nothing)."""
    lines, skip = [], False
    for line in src.splitlines():
        if _HEADER.match(line):
            name = line.strip().strip("[]").split("]")[0].strip()
            skip = name == "reference" or name.startswith("reference.")
        if not skip:
            lines.append(line)
    kept = "\n".join(lines).rstrip()
    kept = kept if source is None or out is None else _rebased(kept, source.parent, out.parent)
    return kept + "\n\n" + table


def _rebased(text: str, src_dir: Path, out_dir: Path) -> str:
    """``text`` with each quoted path of a path key (a key at a line's start; a string, or an array of
    them over one line or several, comments included) that names a file or folder relative to
    ``src_dir`` rewritten relative to ``out_dir`` (absolute paths, empty strings and other values
    kept)."""
    import os

    def moved(p: str) -> str:
        if not p or os.path.isabs(p) or not (src_dir / p).exists():
            return p
        return Path(os.path.relpath((src_dir / p).resolve(), out_dir.resolve())).as_posix()

    out, at = [], 0
    for m in _PATH_KEY.finditer(text):
        if m.start() < at:  # inside the value of the key before
            continue
        out.append(text[at : m.end()])
        k, depth = m.end(), 0
        while k < len(text):  # one value: its strings rewritten, its comments kept as they are
            c = text[k]
            if c == '"':
                end = text.index('"', k + 1) if '"' in text[k + 1 :] else len(text)
                out.append('"' + moved(text[k + 1 : end]) + '"')
                k = end + 1
            else:
                if c == "#":
                    end = text.find("\n", k)
                    end = len(text) if end < 0 else end
                    out.append(text[k:end])
                    k = end
                    continue
                out.append(c)
                k += 1
                depth += {"[": 1, "]": -1}.get(c, 0)
            if depth == 0 and (c in '"]' or c == "\n"):
                break
        at = k
    return "".join(out) + text[at:]


def excitation_bounds(arm, trajectories: dict, duration: float, ramp: float = 0.5) -> dict:
    """``{label: (worst relative bound, its parameter's name, median)}`` of each trajectory's record,
    each tracked from rest through a ``ramp`` [s] (the one the written scenario holds)."""
    from adaptive_dd.identification.excitation import relative_bounds
    from adaptive_dd.identification.model import arm_model
    from adaptive_dd.identification.output_error import cramer_rao_bound, measurement_std
    from adaptive_dd.identification.records import simulate_record

    model = arm_model(arm)
    std = measurement_std(arm)
    zero = np.isnan(relative_bounds(np.ones(model.p), model.sigma_ref, model.names))  # no magnitude
    out = {}
    for label, tr in trajectories.items():
        rec = simulate_record(arm, tr.reference(ramp=ramp), duration, [np.random.default_rng(0)], noise=False)
        crb, _ = cramer_rao_bound(model, rec.sigma_true, rec.q_true[0], rec.qd_true[0], rec.tau[0], std)
        rb = relative_bounds(crb, model.sigma_ref, model.names)[~zero]  # a kind that is 0 left out
        k = int(np.argmax(rb))  # a NaN of the bound itself (diverged sensitivities) stays NaN
        out[label] = (float(rb[k]), model.names[np.flatnonzero(~zero)[k]], float(np.median(rb)))
    if zero.any():
        left = [short(model.names[i]) for i in np.flatnonzero(zero)]
        print(
            f"note: {', '.join(left)} left out of the worst and median bounds: the URDF gives every "
            "parameter of their kind 0 (no magnitude to compare a bound with)",
            file=sys.stderr,
        )
    return out


class _AsIs:
    """A reference as :func:`excitation_bounds` takes a trajectory: tracked as it is written (its own
    ramp), whatever ramp the designed one needs."""

    def __init__(self, ref) -> None:
        self.ref = ref

    def reference(self, ramp: float = 0.5):
        return self.ref
