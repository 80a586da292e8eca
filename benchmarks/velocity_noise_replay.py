"""Which part of the sensors' noise biases adaptive_ct's N-joint estimator after a pick-up: a replay.

Runs ``benchmarks/scenarios/population.toml`` on ``random:ARM`` (``adaptive_ct``, trial ``SEED``),
keeps the true ``q, qd`` and the applied torque, draws the trial's sensor noise again (the run's
generator ``(seed, SEED)``, :mod:`adaptive_dd.closed_loop.noise`) and runs adaptive_ct's estimator
alone (the same configuration, the same compiled step) over the applied torque with:

- ``measured``: the run's own measurements (true + the run's noise): must equal the closed loop's
  control model (printed: the largest difference of the base parameters);
- ``true``: the true ``q, qd`` (no noise);
- ``qd run``: true ``q``, the run's velocity noise (the noise the feedback put into the torque);
- ``q run``: the run's position noise, true ``qd``;
- ``qd indep``: true ``q``, a velocity noise of the same variance drawn independently of the run
  (errors in the regressors' variables without the feedback's correlation with the torque);
- ``qd run x-1``: true ``q``, the run's velocity noise with its sign flipped (the errors in the
  variables the same in size, their correlation with the torque's feedback part reversed);
- ``qd run, signs kept``: ``qd run`` without the noise at the samples where it flips a joint's
  velocity's sign (the Coulomb column ``fc sgn(qd)`` of the known arm then as the truth's);
- ``qd run, restarts clean``: ``qd run`` without the noise at the first sample and at each
  alarm's sample and the next (where the filters restart in the steady state of one sample);
- ``qd run, 30 ms clean``: ``qd run`` without the noise over the 31 samples from each alarm.

Prints per variant the control model's payload first moments' largest error [kg m] over the
pick-up's first ``--window`` s and at ``--at`` instants, and its inertia trace over the truth's.
Asserts nothing.

Run: ``PYTHONPATH=. python benchmarks/velocity_noise_replay.py ARM [SEED] [--at 4.25 7]``.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import read_toml
from adaptive_dd.closed_loop.types import io_of
from adaptive_dd.identification import online
from adaptive_dd.identification import online_kernel as K

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"


def _replay(arm, cfg, q, qd, tau):
    """The control model's base parameters after every sample ``(N, p)``."""
    c, s = online.est_init(cfg, arm, 1)
    n = q.shape[1]
    w = K.est_work(n, s.theta.shape[1])
    pi = np.empty(c.pi0.shape[0])
    K.est_model_trial(c, s, 0, pi)
    B = arm.base.B
    out = np.empty((q.shape[0], B.shape[0]))
    for k in range(q.shape[0]):
        K.est_step_model(c, s, 0, q[k], qd[k], tau[k], w, pi)
        out[k] = B @ pi
    return out


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("arm", type=int)
    ap.add_argument("seed", type=int, nargs="?", default=0)
    ap.add_argument("--at", type=float, nargs="*", default=[4.25, 7.0])
    ap.add_argument("--window", type=float, default=0.6)
    args = ap.parse_args()
    sc = population_scenario(read_toml(TEMPLATE), str(TEMPLATE), args.arm)
    sc = dataclasses.replace(sc, seeds=args.seed + 1, controllers=("adaptive_ct",))
    res = run_benchmark(sc, progress=False, keep_trajectories=args.seed + 1)
    run = res.runs["adaptive_ct"]
    q, qd, tau = (
        np.ascontiguousarray(np.asarray(x)[args.seed], dtype=float) for x in (run.q, run.qd, run.tau)
    )
    N, n = q.shape
    io = io_of(sc)
    noise = np.random.default_rng([int(sc.seed), int(args.seed)]).standard_normal((N, 2 * n))
    qq = np.round(q / io.res) * io.res if io.quantize_encoder else q
    nq, nv = noise[:, :n] * io.std[:n], noise[:, n:] * io.std[n:]
    indep = np.random.default_rng([int(sc.seed), int(args.seed), 99]).standard_normal((N, n)) * io.std[n:]
    T = float(res.t[1] - res.t[0])
    alarms = [round(x / T) for x in (run.alarm_times or [[]] * (args.seed + 1))[args.seed]]
    clean, clean30 = np.ones(N), np.ones(N)
    clean[0] = clean30[0] = 0.0
    for k in alarms:  # the filters restart on the sample after an alarm
        clean[k : k + 2] = 0.0
        clean30[k : k + 32] = 0.0
    variants = {
        "measured": (qq + nq, qd + nv),
        "true": (q, qd),
        "qd run": (q, qd + nv),
        "q run": (qq + nq, qd),
        "qd indep": (q, qd + indep),
        "qd run x-1": (q, qd - nv),
        "qd run, signs kept": (q, np.where(np.sign(qd + nv) == np.sign(qd), qd + nv, qd)),
        "qd run, restarts clean": (q, qd + nv * clean[:, None]),
        "qd run, 30 ms clean": (q, qd + nv * clean30[:, None]),
    }

    cfg = online.OnlineConfig(sample_period=float(res.t[1] - res.t[0]))
    t = res.t
    sh_run = np.asarray(run.sigma_hat)[args.seed]
    pt = sc.arm.payload_from_sigma(np.broadcast_to(res.sigma_true, sh_run.shape)).params
    t0 = sc.swap_times[0]
    win = (t >= t0) & (t < t0 + args.window)
    print(
        f"random:{args.arm} seed {args.seed}: swaps {sc.swap_times} s, "
        f"noise std {np.round(io.std, 5).tolist()}"
    )
    flip = np.sign(qd + nv) != np.sign(qd)
    print(
        f"in the window: mean |qd| per joint {np.round(np.abs(qd[win]).mean(axis=0), 4).tolist()} rad/s, "
        f"share of samples the run's noise flips qd's sign {np.round(flip[win].mean(axis=0), 3).tolist()}, "
        f"slower than the data selection's threshold "
        f"{np.round((np.abs(qd[win]) < cfg.selection[0]).mean(axis=0), 3).tolist()}"
    )
    for name, (qm, qdm) in variants.items():
        sh = _replay(sc.arm, cfg, np.ascontiguousarray(qm), np.ascontiguousarray(qdm), tau)
        ph = sc.arm.payload_from_sigma(sh).params
        fm = np.abs(ph[win, 1:4] - pt[win, 1:4]).max()
        line = f"{name:>11}: first moments' largest error in {t0}-{t0 + args.window} s {fm:.3f} kg m"
        if name == "measured":
            line += f" (against the closed loop's model: largest difference {np.abs(sh - sh_run).max():.2e})"
        print(line)
        for x in args.at:
            k = min(int(np.searchsorted(t, x)), N - 1)
            tr = (ph[k, 4] + ph[k, 6] + ph[k, 9]) / (pt[k, 4] + pt[k, 6] + pt[k, 9])
            print(
                f"      t = {x:g} s: mass {ph[k, 0]:.3f} ({pt[k, 0]:.3f}), "
                f"first moments {np.round(ph[k, 1:4], 3)} "
                f"({np.round(pt[k, 1:4], 3)}), inertia trace / truth {tr:.2f}"
            )


if __name__ == "__main__":
    main()
