"""Do the printed bounds hold? Coverage of the truth by the identification's bounds on simulated logs.

Run from the repository root::

    python benchmarks/log_bounds_coverage.py --seeds 20            # vertical3: gaps, two records
    python benchmarks/log_bounds_coverage.py --seeds 10 --pair     # and a loaded/unloaded UR5 pair

Each seed makes records of the arm by inverse dynamics of the identification's own model
(:func:`adaptive_dd.identification.records.synthetic_log`: a multi-sine, the torque noise 2 % of
each channel's rms, AR(1) over 0.05 s and its level doubling with the joint's speed), so the
model is exact and the truth known, and identifies them as ``identify --arm`` does
(:func:`adaptive_dd.identification.log_fit.fit_log`, the Newey-West sandwich within each piece):

- ``gaps``: one 24 s record at 200 Hz with four gaps (12, 60, 2 and 17 samples) fitted as its
  five pieces;
- ``records``: two 12 s records fitted together;
- ``pair`` (``--pair``): two loaded and two unloaded 12 s records of the UR5 (a 2 kg payload,
  its centre of mass 3 / -2 / 5 cm from the flange), each side fitted jointly, the payload from
  the pair (:func:`adaptive_dd.identification.payload_pair.payload_from_pair`).

Printed per case: the fraction of (seed, parameter) with the truth within the printed 95 %
bound, estimate +- 1.96 std (for the pair: the mass and the three centre-of-mass coordinates),
and the median over parameters of the spread of the estimates over the seeds against the mean
reported std (1: the std is the spread).
"""

from __future__ import annotations

import argparse
import itertools
import time

import numpy as np

from adaptive_dd.identification.log_fit import fit_log
from adaptive_dd.identification.model import arm_model
from adaptive_dd.identification.records import synthetic_log
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import robot_urdf

T = 0.005
HOLES = [(900, 912), (1900, 1960), (2900, 2902), (3900, 3917)]


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
    )


def summary(label: str, z: list, est: list, std: list) -> None:
    z, est, std = np.abs(np.array(z)), np.array(est), np.array(std)
    ratio = np.std(est, axis=0, ddof=1) / np.mean(std, axis=0)
    print(
        f"{label:<8} truth within +-1.96 std: {100 * np.mean(z < 1.96):5.1f} % of {z.size} "
        f"(seed, parameter); spread over the seeds / mean std: median {np.median(ratio):.2f} "
        f"(min {ratio.min():.2f}, max {ratio.max():.2f})"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--pair", action="store_true", help="also a loaded/unloaded pair of the UR5")
    args = ap.parse_args()
    t0 = time.perf_counter()
    arm = Arm.from_urdf(robot_urdf("vertical3"))
    model = arm_model(arm)
    out = {k: ([], [], []) for k in ("gaps", "records", "pair")}
    for s in range(args.seeds):
        rng = np.random.default_rng([45, s])
        one = synthetic_log(arm, 24.0, T, rng)
        f = fit(model, [one], HOLES)
        for lst, v in zip(out["gaps"], ((f.sigma - one.sigma_true) / f.std, f.sigma, f.std), strict=True):
            lst.append(v)
        two = [synthetic_log(arm, 12.0, T, rng) for _ in range(2)]
        f = fit(model, two)
        for lst, v in zip(
            out["records"], ((f.sigma - two[0].sigma_true) / f.std, f.sigma, f.std), strict=True
        ):
            lst.append(v)
        if args.pair:
            _pair(rng, out["pair"])
    summary("gaps", *out["gaps"])
    summary("records", *out["records"])
    if args.pair:
        summary("pair", *out["pair"])
    print(f"({args.seeds} seeds, {time.perf_counter() - t0:.0f} s)")


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
    pr = payload_from_pair(arm, loaded.sigma, loaded.cov, empty.sigma, empty.cov)
    est = np.array([pr.mass, *pr.com])
    std = np.array([pr.mass_std, *pr.com_std])
    truth = np.array([2.0, *com])
    for lst, v in zip(acc, ((est - truth) / std, est, std), strict=True):
        lst.append(v)


if __name__ == "__main__":
    main()
