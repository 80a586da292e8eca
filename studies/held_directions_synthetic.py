"""Holding the directions a record cannot see, on inverse-dynamics records of drawn arms (no
simulation): ``python studies/held_directions_synthetic.py SCENARIO...``. Per arm and seed, a 10 s
random three-sine record within the joint limits (T = 2 ms, torque noise 1 % of each joint's
peak), the plant drawn at issue 28's levels; the base parameters' error against the plant's,
median and worst, without and with the hold. A proxy: not the designed excitation.
"""

import sys

import numpy as np

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.identification.arm_prior import ArmUncertainty, draw_parameters
from adaptive_dd.identification.log_fit import fit_log, predict_torque
from adaptive_dd.identification.model import arm_model
from adaptive_dd.record import derivatives

for f in sys.argv[1:]:
    sc = load_scenario(f)
    arm = sc.arm
    model = arm_model(arm)
    n = model.n
    T = 0.002
    t = np.arange(5000) * T
    lo, hi = arm.position_limits[:, 0], arm.position_limits[:, 1]
    lo = np.where(np.isfinite(lo), lo, -np.pi)
    hi = np.where(np.isfinite(hi), hi, np.pi)
    mid, half = 0.5 * (lo + hi), 0.25 * (hi - lo)
    for seed in range(2):
        rng = np.random.default_rng([5, seed])
        w, ph = rng.uniform(0.5, 2.5, (n, 3)), rng.uniform(0, 6, (n, 3))
        q = mid + np.minimum(half, 1.0) * sum(np.sin(w[:, k] * t[:, None] + ph[:, k]) for k in range(3)) / 3
        qd, qdd = derivatives(q, T)
        truth = model.B @ draw_parameters(arm, ArmUncertainty(), rng)
        tau = predict_torque(model, truth, q, qd, qdd)
        tau = tau + 0.01 * np.abs(tau).max(axis=0) * rng.standard_normal(tau.shape)
        scale = np.maximum(np.abs(truth), 0.01 * np.abs(truth).max())
        for hold in (False, True):
            fit = fit_log(
                model,
                q,
                qd,
                tau,
                np.ones(n, bool),
                np.ones(model.p, bool),
                tau_f=0.02,
                sample_period=T,
                hold=hold,
                torque_held=False,
            )
            e = np.abs(fit.sigma - truth) / scale
            print(
                f,
                seed,
                "hold",
                hold,
                "median %.3g %%" % (100 * np.median(e)),
                "worst %.3g %%" % (100 * e.max()),
                model.names[e.argmax()][:20],
                "held",
                0 if fit.held is None else fit.held.count,
                flush=True,
            )
