"""Do the printed bounds hold? Coverage of the truth by the identification's bounds on simulated logs.

Run from the repository root::

    python benchmarks/log_bounds_coverage.py --seeds 20            # vertical3: gaps, two records
    python benchmarks/log_bounds_coverage.py --seeds 10 --pair     # and a loaded/unloaded UR5 pair
    # 200 seeds in parts (with OPENBLAS_NUM_THREADS=1 on a shared machine), then merged:
    python benchmarks/log_bounds_coverage.py --seeds 200 --save gr.npz
    python benchmarks/log_bounds_coverage.py --cases pair --first 0 --seeds 100 --save p0.npz
    python benchmarks/log_bounds_coverage.py --cases pair --first 100 --seeds 100 --save p1.npz
    python benchmarks/log_bounds_coverage.py --load gr.npz p0.npz p1.npz
    # per parameter, against the same seeds run with --torque-offset off (saved as off.npz):
    python benchmarks/log_bounds_coverage.py --load gr.npz --versus off.npz
    # one motion (that of seed 3), the noise drawn again for each of 60 seeds:
    python benchmarks/log_bounds_coverage.py --cases records --same-motion 3 --seeds 60
    # each seed's std against the exact std of its motion (300 noise draws each):
    python benchmarks/log_bounds_coverage.py --cases gaps,records --seeds 40 --exact 300
    # closed-loop records of the simulator, its sensors' noise in the measured velocity:
    python benchmarks/log_bounds_coverage.py --cases simulated --seeds 40

Each seed makes records of the arm by inverse dynamics of the identification's own model
(:func:`adaptive_dd.identification.records.synthetic_log`: a multi-sine, the torque noise 2 % of
each channel's rms, AR(1) over 0.05 s and its level doubling with the joint's speed), so the
model is exact and the truth known, and identifies them as ``identify --arm`` does
(:func:`adaptive_dd.identification.log_fit.fit_log`, the Newey-West sandwich within each piece):

- ``gaps``: one 24 s record at 200 Hz with four gaps (12, 60, 2 and 17 samples) fitted as its
  five pieces;
- ``records``: two 12 s records fitted together;
- ``simulated``: one 10 s closed-loop record of vertical3 tracking its benchmark scenario's
  reference (``--scenario FILE``: another scenario's arm and reference, e.g.
  ``benchmarks/scenarios/ident_ur5.toml``), simulated as ``adaptive-dd simulate --arm`` does
  (:func:`adaptive_dd.identification.records.simulate_record`: the sensors' noise and
  quantisation, so the measured velocity in the regressor is noisy too), the same motion for
  every seed and only the noise drawn again, identified as ``identify --arm`` does on a simulator's
  record (the URDF's prior holding what the record barely sees, no torque offsets, ``tau_f``
  0.02 s at 1 kHz); the parameters seed 0's fit holds at the URDF's values (more than half their
  information from the prior) are left out of the figures, whatever ``--first``;
- ``pair`` (``--pair``): two loaded and two unloaded 12 s records of the UR5 (a 2 kg payload,
  its centre of mass 3 / -2 / 5 cm from the flange), each side fitted jointly, the payload from
  the pair (:func:`adaptive_dd.identification.payload_pair.payload_from_pair`, as ``identify
  --baseline``: ``weighting="diagonal"``).

Printed per case: the fraction of (seed, parameter) with the truth within the printed 95 %
bound, estimate +- c std with ``c`` the fit's fixed-b quantile (:attr:`LogFit.quantile`, 1.96 and
a little more; for the pair, as ``identify --baseline`` prints it, +- 1.96 std of the mass and the
three centre-of-mass coordinates),
with the interval of that mean from the spread of the seeds' own coverages (the seeds are
independent, the parameters of one seed are not); the rms of (estimate - truth) / std, over all
and per parameter (1 for a std right on average; a little above 1 from the std's own randomness);
the spread of the estimates over the seeds against the mean reported std (each seed draws its own
motion, so its std differs: this ratio exceeds 1 by the std's variation over the seeds even when
every std is right, about ``sqrt(1 + CV^2)``); and the three least covered parameters.

``--exact M`` (gaps and records): each seed's fit against the exact std of its own estimate on its
own motion, by Monte Carlo over ``M`` draws of the log's noise (:func:`synthetic_log`'s AR(1),
heteroscedastic law) through the fit's filters, pieces, offsets and final channel weights (held:
the estimate is then linear in the noise). Printed: the coverage and rms of error / std with the
exact std (95 % and 1 but for the seeds' sampling), the mean over the seeds of the fit's variance
over the exact one (1 for a variance right on average), per parameter, the least ones named, and
its correlation over the seeds with the Newey-West lag the fit chose; and how much each
parameter's variance varies over the seeds (the relative variance of its ratio to the exact one,
less the Monte Carlo's own ``2 / (M - 1)``) against ``(4 / 3) b``, ``b`` the bound's bandwidth
fraction (:attr:`LogFit.bandwidth`) and the lag's ``(lag + 1) / rows`` (``--load`` with ``--draws
M``).
"""

from __future__ import annotations

import argparse
import inspect
import itertools
import os
import time

import numpy as np

from adaptive_dd.identification.filters import design_filter_bank
from adaptive_dd.identification.log_fit import fit_log
from adaptive_dd.identification.model import arm_model, base_regressor
from adaptive_dd.identification.records import simulate_record, synthetic_log
from adaptive_dd.identification.regression import filter_pieces
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import robot_urdf

T = 0.005
HOLES = [(900, 912), (1900, 1960), (2900, 2902), (3900, 3917)]
SIMULATED = "vertical3_payload.toml"
"""The ``simulated`` case's default scenario (the shipped vertical3 benchmark): its arm and reference,
10 s (``--scenario`` another)."""


OFFSET = {"on": False}
"""Fit a torque offset per channel too (``--torque-offset``; ``identify``'s default on a [record] log)."""


def fit(model, logs, holes=()):
    """``fit_log`` of ``logs`` end to end, each record cut at ``holes`` (sample ranges), as pieces."""
    q, qd, tau, pieces, at = [], [], [], [], 0
    for g in logs:
        keep = np.setdiff1d(np.arange(g.t.size), np.concatenate([np.arange(a, b) for a, b in holes] or [[]]))
        cuts = [0, *(np.flatnonzero(np.diff(keep) > 1) + 1).tolist(), keep.size]
        pieces += [(at + a, at + b) for a, b in itertools.pairwise(cuts)]
        at += keep.size
        q.append(g.q[keep])
        qd.append(g.qd[keep])
        tau.append(g.tau[keep])
    return fit_log(
        model,
        np.concatenate(q),
        np.concatenate(qd),
        np.concatenate(tau),
        np.ones(model.n, bool),
        np.ones(model.p, bool),
        tau_f=0.02,
        sample_period=T,
        hold=False,
        torque_held=False,
        pieces=pieces,
        offset=OFFSET["on"],
    )


def _kept(g, holes):
    """The samples of log ``g`` left after cutting ``holes``."""
    return np.setdiff1d(np.arange(g.t.size), np.concatenate([np.arange(a, b) for a, b in holes] or [[]]))


def exact_std(model, logs, holes, f, draws: int, rng) -> np.ndarray:
    """``(p,)`` the std of ``f``'s estimate (``fit(model, logs, holes)``) over ``draws`` draws of the
    logs' noise on their motion, as :func:`synthetic_log` draws it, through the fit's filters, pieces
    and offsets, its final channel weights held (module docstring, ``--exact``)."""
    law = inspect.signature(synthetic_log).parameters
    noise, corr, het = (law[k].default for k in ("noise", "correlation", "heteroscedastic"))
    a = np.exp(-T / corr)
    parts = []
    for g in logs:  # the noise of each log: AR(1), its level the channel's torque rms times (1 + het speed)
        qdd = np.gradient(g.qd, T, axis=0)
        level = noise * np.sqrt(np.mean((base_regressor(model, g.q, g.qd, qdd) @ g.sigma_true) ** 2, axis=0))
        speed = np.abs(g.qd) / np.maximum(np.abs(g.qd).max(axis=0), 1e-300)
        e = np.empty((g.t.size, model.n, draws))
        e[0] = rng.standard_normal((model.n, draws))
        z = rng.standard_normal(e.shape) * np.sqrt(1 - a * a)
        for k in range(1, g.t.size):
            e[k] = a * e[k - 1] + z[k]
        parts.append((e * (level * (1 + het * speed))[:, :, None])[_kept(g, holes)])
    reg = f.regression
    yn = filter_pieces(
        design_filter_bank("M2", reg.tau_f, T), np.concatenate(parts), reg.pieces, reg.start, 0
    )
    phi, w = reg.phi, f.weights
    if OFFSET["on"]:  # the offsets profiled out as the fit does: each channel's rows about their mean
        phi, yn = phi - phi.mean(axis=0), yn - yn.mean(axis=0)
    A = np.einsum("kjr,kjs,j->rs", phi, phi, w**2)
    err = np.linalg.solve(A, np.einsum("kjr,kjm,j->rm", phi, yn, w**2))  # (p, draws)
    return np.std(err, axis=1, ddof=1)


def exact_summary(label: str, z, std, xstd, lag, names, draws=None, b=None, rows=None) -> None:
    """Print the fit's std against the exact std of each seed's motion (``--exact``); with the fit's
    bandwidth fractions ``b`` and ``rows`` (seeds,), the variance's spread against what ``b`` says."""
    err = np.asarray(z) * np.asarray(std)
    zx = err / xstd
    ratio = (np.asarray(std) / xstd) ** 2  # (seeds, p)
    per = ratio.mean(axis=0)
    seed = ratio.mean(axis=1)
    low = np.argsort(per)[:4]
    print(
        f"{label:<8} exact std of each seed's motion: truth within +-1.96 exact std "
        f"{100 * np.mean(np.abs(zx) < 1.96):.1f} %, rms of error / exact std {np.sqrt(np.mean(zx**2)):.3f}; "
        f"fit's variance / exact: mean {ratio.mean():.3f} (per parameter {per.min():.2f}-{per.max():.2f}; "
        f"per seed sd {seed.std(ddof=1):.3f}, correlation with the lag {np.corrcoef(seed, lag)[0, 1]:+.2f})"
    )
    print("         narrowest: " + "; ".join(f"{names[k][:32]} {per[k]:.2f}" for k in low))
    if b is not None and draws:
        # each parameter's log variance ratio about its mean over the seeds, less the Monte Carlo's own
        # 2 / (M - 1): the relative variance of the fit's variance, against the Bartlett one's 4/3 b
        lr = np.log(ratio)
        spread = np.var(lr - lr.mean(axis=0)) - 2.0 / (draws - 1)
        print(
            f"         the fit's variance's relative variance over the seeds {spread:.3f}; (4/3) b of the "
            f"bound's bandwidth fraction {4 / 3 * np.mean(b):.3f}, of the lag's (lag + 1) / rows "
            f"{4 / 3 * np.mean((np.asarray(lag) + 1) / np.asarray(rows)):.3f}"
        )


def summary(label: str, z, est, std, names=None, quantile=None) -> None:
    """Print the coverage of one case: ``z``, ``est``, ``std`` are (seeds, parameters), ``quantile``
    (seeds,) the bound's half-width in std (default 1.96)."""
    z, est, std = np.abs(np.asarray(z)), np.asarray(est), np.asarray(std)
    c = np.full(z.shape[0], 1.96) if quantile is None else np.asarray(quantile, dtype=float)
    ratio = np.std(est, axis=0, ddof=1) / np.mean(std, axis=0)
    rms = np.sqrt(np.mean(z**2, axis=0))  # per parameter: 1 for a std right on average
    inside = z < c[:, None]
    per_seed = inside.mean(axis=1)
    # the seeds are independent, the parameters of one seed are not: the interval of the mean
    # coverage from the spread of the seeds' own coverages (normal approximation)
    half = 1.96 * np.std(per_seed, ddof=1) / np.sqrt(per_seed.size) if per_seed.size > 1 else np.nan
    print(
        f"{label:<8} truth within +-c std (c median {np.median(c):.3f}): {100 * inside.mean():5.1f} % "
        f"of {z.size} "
        f"({z.shape[0]} seeds x {z.shape[1]}; +-{100 * half:.1f} % over the seeds); "
        f"rms of error / std: {np.sqrt(np.mean(z**2)):.3f}, per parameter median {np.median(rms):.2f} "
        f"(min {rms.min():.2f}, max {rms.max():.2f}); spread over the seeds / mean std: median "
        f"{np.median(ratio):.2f} (min {ratio.min():.2f}, max {ratio.max():.2f})"
    )
    cover = inside.mean(axis=0)
    worst = np.argsort(cover)[:3]
    names = names or [f"#{k}" for k in range(z.shape[1])]
    print(
        "         least covered: "
        + "; ".join(
            f"{names[k][:32]} {100 * cover[k]:.0f} % (rms error / std {rms[k]:.2f}, "
            f"spread / std {ratio[k]:.2f})"
            for k in worst
        )
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first", type=int, default=0, help="first seed (to split a long run)")
    ap.add_argument("--pair", action="store_true", help="also a loaded/unloaded pair of the UR5")
    ap.add_argument("--cases", default="gaps,records", help="comma-separated: gaps, records, simulated, pair")
    ap.add_argument(
        "--torque-offset",
        choices=("on", "off"),
        default="on",
        help="fit a torque offset per channel, as identify does on a [record] log (default on)",
    )
    ap.add_argument(
        "--same-motion",
        type=int,
        metavar="S",
        help="gaps and records: every seed the motion of seed S, only the noise drawn again (does the std "
        "hold for one motion?)",
    )
    ap.add_argument(
        "--exact",
        type=int,
        default=0,
        metavar="M",
        help="gaps and records: each seed's std against the exact std of its motion, M noise draws",
    )
    ap.add_argument(
        "--scenario",
        help="the simulated case's scenario (its arm and reference; default vertical3_payload.toml)",
    )
    ap.add_argument("--save", help="write the per-seed results to this .npz")
    ap.add_argument("--draws", type=int, help="with --load: the --exact M of the saved runs")
    ap.add_argument("--load", nargs="+", help="summarise saved .npz files (merged) instead of running")
    ap.add_argument(
        "--versus",
        nargs="+",
        help="with --load: saved .npz files of the same seeds run otherwise (e.g. --torque-offset off); "
        "prints per parameter the coverage, rms of error / std and the ratio of the mean std of both",
    )
    args = ap.parse_args()
    cases = [c for c in args.cases.split(",") if c] + (
        ["pair"] if args.pair and "pair" not in args.cases else []
    )
    if args.load:
        out, names = _load(args.load)
        for c in ("gaps", "records", "simulated", "pair"):
            if f"{c}_z" in out:
                summary(c, out[f"{c}_z"], out[f"{c}_est"], out[f"{c}_std"], names.get(c), out.get(f"{c}_q"))
            if f"{c}_xstd" in out:
                exact_summary(
                    c,
                    out[f"{c}_z"],
                    out[f"{c}_std"],
                    out[f"{c}_xstd"],
                    out[f"{c}_lag"],
                    names[c],
                    args.draws,
                    out.get(f"{c}_b"),
                    out.get(f"{c}_rows"),
                )
        if args.versus:
            _versus(out, _load(args.versus)[0], names)
        return
    t0 = time.perf_counter()
    OFFSET["on"] = args.torque_offset == "on"
    arm = Arm.from_urdf(robot_urdf("vertical3"))
    model = arm_model(arm)
    names = {
        "gaps": list(model.names),
        "records": list(model.names),
        "pair": ["mass", "com x", "com y", "com z"],
    }
    kept = {}
    if args.scenario and "simulated" not in cases:
        ap.error(f"--scenario {args.scenario}: it sets the simulated case's arm; add --cases simulated")
    if "simulated" in cases:
        sim = _simulated_scenario(args.scenario)
        # the parameters left out: those seed 0's fit holds, whatever --first (parts saved apart merge)
        f0 = _simulated(sim, np.random.default_rng([45, 0, 4]))[0]
        kept["simulated"] = np.ones(f0.sigma.size, bool) if f0.held is None else f0.held.share <= 0.5
        names["simulated"] = [
            x for x, k in zip(arm_model(sim.arm).names, kept["simulated"], strict=True) if k
        ]
    out = {k: ([], [], [], []) for k in cases}
    exact = {k: ([], [], [], []) for k in cases}  # --exact: each seed's exact std, the fit's lag, b, rows
    for s in range(args.first, args.first + args.seeds):
        if ("gaps" in out or "records" in out) and args.same_motion is None:
            rng = np.random.default_rng([45, s])
            one = synthetic_log(arm, 24.0, T, rng)
            two = [synthetic_log(arm, 12.0, T, rng) for _ in range(2)]
        elif "gaps" in out or "records" in out:  # the motions of seed S, the noise of seed s
            rng, noise = np.random.default_rng([45, args.same_motion]), np.random.default_rng([45, s, 2])
            one = synthetic_log(arm, 24.0, T, rng, noise_rng=noise)
            two = [synthetic_log(arm, 12.0, T, rng, noise_rng=noise) for _ in range(2)]
        for c in ("gaps", "records"):
            if c not in out:
                continue
            logs, holes = ([one], HOLES) if c == "gaps" else (two, ())
            f = fit(model, logs, holes)
            for lst, v in zip(
                out[c], ((f.sigma - logs[0].sigma_true) / f.std, f.sigma, f.std, f.quantile), strict=True
            ):
                lst.append(v)
            if args.exact:
                exact[c][0].append(
                    exact_std(model, logs, holes, f, args.exact, np.random.default_rng([45, s, 3]))
                )
                exact[c][1].append(f.lag)
                exact[c][2].append(f.bandwidth)
                exact[c][3].append(f.regression.y.shape[0])
        if "simulated" in out:
            f, truth = _simulated(sim, np.random.default_rng([45, s, 4]))
            f, truth = _Kept(f, kept["simulated"]), truth[kept["simulated"]]
            for lst, v in zip(
                out["simulated"], ((f.sigma - truth) / f.std, f.sigma, f.std, f.quantile), strict=True
            ):
                lst.append(v)
        if "pair" in out:
            _pair(np.random.default_rng([45, s, 1]), out["pair"])
        # saved after every seed, so that a long run can be read while it goes on
        if args.save:
            tmp = f"{args.save}.part.npz"
            np.savez(
                tmp,
                **{
                    f"{c}_{k}": np.array(v)
                    for c in cases
                    for k, v in zip(("z", "est", "std", "q"), out[c], strict=True)
                },
                **{f"{c}_names": np.array(names[c]) for c in cases},
                **{
                    f"{c}_{k}": np.array(v)
                    for c in cases
                    if exact[c][0]
                    for k, v in zip(("xstd", "lag", "b", "rows"), exact[c], strict=True)
                },
            )
            os.replace(tmp, args.save)
    for c in cases:
        z, est, std, q = out[c]
        summary(c, z, est, std, names[c], q)
        if exact[c][0]:
            xstd, lag, b, rows = exact[c]
            exact_summary(c, z, std, np.array(xstd), lag, names[c], args.exact, b, rows)
    print(f"({args.seeds} seeds from {args.first}, {time.perf_counter() - t0:.0f} s)")


class _Kept:
    """A fit's estimate, std and quantile on the parameters ``keep`` only."""

    def __init__(self, f, keep):
        self.sigma, self.std, self.quantile = f.sigma[keep], f.std[keep], f.quantile


def _simulated_scenario(path: str | None):
    """The ``simulated`` case's scenario: ``path``, or the shipped :data:`SIMULATED`."""
    from importlib import resources

    from adaptive_dd.benchmark.scenario import load_scenario

    return load_scenario(path or str(resources.files("adaptive_dd.scenarios").joinpath(SIMULATED)))


def _simulated(sc, rng):
    """The ``simulated`` case of one seed: ``(fit, truth)`` (module docstring)."""
    arm = sc.arm
    rec = simulate_record(arm, sc.reference, 10.0, [rng])
    model = arm_model(arm)
    n = model.n
    f = fit_log(
        model,
        rec.q[0],
        rec.qd[0],
        rec.tau[0],
        np.ones(n, bool),
        np.ones(model.p, bool),
        tau_f=0.02,
        sample_period=rec.sample_period,
    )
    return f, rec.sigma_true


def _load(files):
    """The saved runs ``files`` merged: ``({key: array}, {case: parameter names})``."""
    merged = {}
    for f in files:
        with np.load(f, allow_pickle=False) as d:
            for key in d.files:
                merged.setdefault(key, []).append(d[key])
    out = {k: np.concatenate(v) for k, v in merged.items() if not k.endswith("_names")}
    names = {k[: -len("_names")]: [str(x) for x in v[0]] for k, v in merged.items() if k.endswith("_names")}
    return out, names


def _versus(a: dict, b: dict, names: dict) -> None:
    """Per parameter of each case in both runs: coverage, rms of error / std, and the mean std of ``a``
    over ``b``'s (the same seeds run otherwise)."""

    def per(d, c):
        z, q = np.abs(d[f"{c}_z"]), np.asarray(d[f"{c}_q"], dtype=float)
        std = d[f"{c}_std"]
        return (z < q[:, None]).mean(0), np.sqrt(np.mean(z**2, axis=0)), std.mean(0), z.shape[0]

    for c in ("gaps", "records", "pair"):
        if f"{c}_z" not in a or f"{c}_z" not in b:
            continue
        (ca, ra, sa, na), (cb, rb, sb, nb) = per(a, c), per(b, c)
        print(
            f"{c}: per parameter, --load ({na} seeds) against --versus ({nb} seeds): covered "
            f"{100 * ca.mean():.1f} / {100 * cb.mean():.1f} %"
        )
        for k in np.argsort(ca):
            nm = (names.get(c) or [f"#{i}" for i in range(ca.size)])[k]
            print(
                f"  {nm[:30]:<30} covered {100 * ca[k]:5.1f} / {100 * cb[k]:5.1f} %, rms error / std "
                f"{ra[k]:.2f} / {rb[k]:.2f}, mean std ratio {sa[k] / sb[k]:.2f}"
            )


_UR5 = {}


def _pair(rng, acc) -> None:
    from adaptive_dd.identification.payload_pair import payload_from_pair
    from adaptive_dd.plant.payload import payload_parameters

    if not _UR5:
        _UR5["arm"] = Arm.from_urdf(robot_urdf("ur5"))
        _UR5["model"] = arm_model(_UR5["arm"])
    arm, model = _UR5["arm"], _UR5["model"]
    com = np.array([0.03, -0.02, 0.05])
    pp = payload_parameters(2.0, com, np.diag([4e-3, 5e-3, 3e-3]))
    loaded = fit(model, [synthetic_log(arm, 12.0, T, rng, payload=pp) for _ in range(2)])
    empty = fit(model, [synthetic_log(arm, 12.0, T, rng) for _ in range(2)])
    pr = payload_from_pair(arm, loaded.sigma, loaded.cov, empty.sigma, empty.cov, weighting="diagonal")
    est = np.array([pr.mass, *pr.com])
    std = np.array([pr.mass_std, *pr.com_std])
    truth = np.array([2.0, *com])
    for lst, v in zip(acc, ((est - truth) / std, est, std, 1.96), strict=True):
        lst.append(v)


if __name__ == "__main__":
    main()
