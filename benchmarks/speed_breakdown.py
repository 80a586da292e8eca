"""Where one UR5 closed-loop sample's time goes: ``python benchmarks/speed_breakdown.py``.

Runs one trial of ``adaptive_ct`` and one of ``ct_oracle`` on the UR5 tool-swap scenario (or the
scenario file given as the one argument, e.g. ``benchmarks/scenarios/sice_general.toml``)
(recording its trajectories), then replays the recorded states through each compiled kernel
of the loop, timed inside numba loops (Python call overhead excluded, compilation excluded):

* the plant step (``closed_loop.plant.plant_step``: stick-slip active set, RK4 substeps) and
  its parts: the rigid-body terms and the Cholesky solve of one RK4 stage, times the stages;
* the law (``closed_loop.laws.law_trial_in``: ct_oracle on the true model, adaptive_ct on its
  trial model);
* the estimator's step (``est_step_trial_in``, its scratch made once, as in the closed loop)
  and its parts (filters, regression, the row-by-row RLS, the detector), and the model that
  control uses (``est_model_trial_in``: the payload's projection);
* the whole loop (``closed_loop_block`` through ``run_closed_loop``, one trial, recorded); "glue" is
  the whole minus the kernels (measurement, divergence rules, metrics, recording, the run's
  Python set-up); "recording" is the whole less the same trial unrecorded.

CPU time of this thread, best of 3, microseconds per sample; nothing is asserted.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from importlib import resources

import numpy as np
from numba import njit

from adaptive_dd.closed_loop.glue import segment_of
from adaptive_dd.closed_loop.laws import OBS_ROWS, law_trial_in, law_work, observe_applied
from adaptive_dd.closed_loop.plant import plant_scratch, plant_step
from adaptive_dd.identification import online_kernel as K
from adaptive_dd.plant import chain_rk4 as SI


def _scenario(path: str | None = None):
    from adaptive_dd.benchmark.scenario import load_scenario

    if path is None:
        path = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap_exact.toml"))
    return load_scenario(path)


@njit(cache=True)
def _plant_loop(pl, rc, q_rec, qd_rec, tau_rec, sc):  # pragma: no cover - compiled
    n = q_rec.shape[1]
    q, qd = np.empty(n), np.empty(n)
    stuck = np.zeros(n, dtype=np.bool_)
    acc = 0.0
    for k in range(q_rec.shape[0]):
        for j in range(n):
            q[j], qd[j] = q_rec[k, j], qd_rec[k, j]
        plant_step(pl, 0, segment_of(rc, k), q, qd, tau_rec[k], rc.T, stuck, sc)
        acc += q[0]
    return acc


@njit(cache=True, fastmath={"contract", "reassoc"})  # the flags of the integrator's RK4 step
def _dynamics_loop(ch, pl, rc, q_rec, qd_rec, tau_rec, sc, solve):  # pragma: no cover - compiled
    """The plant's rigid-body terms (bias, M + armature) at each recorded state, and its
    Cholesky solve for the accelerations if ``solve``."""
    n = q_rec.shape[1]
    stuck = np.zeros(n, dtype=np.bool_)
    sdir = np.ones(n)
    rows, bias, m = sc[3], sc[3][0], sc[1]
    rows[2, :] = 0.0
    t = 0.0
    for k in range(q_rec.shape[0]):
        s = segment_of(rc, k)
        SI._dynamics(ch, pl.pi_seg[0, s], pl.armature[0], q_rec[k], qd_rec[k], sc[0], bias, m)
        if solve:  # the accelerations into rows[2], the holding torques into rows[3]
            SI._solve(
                pl.fv[0],
                pl.fc[0],
                0,
                pl.fparams,
                qd_rec[k],
                tau_rec[k],
                stuck,
                sdir,
                rows,
                0,
                m,
                sc[2],
                sc[4],
                2,
                3,
            )
        t += bias[0] + rows[2, 0]
    return t


@njit(cache=True)
def _law_loop(ch, cfg, pi_true, pi_model, theta, rc, qm, qdm, out):  # pragma: no cover - compiled
    big = 1 << 40
    work = law_work(qm.shape[1])
    obs = np.zeros((OBS_ROWS, qm.shape[1]))
    for k in range(qm.shape[0]):
        s = segment_of(rc, k)
        law_trial_in(
            ch,
            cfg,
            pi_true[s],
            pi_model,
            theta,
            big,
            obs,
            qm[k],
            qdm[k],
            rc.q_d[k],
            rc.qd_d[k],
            rc.qdd_d[k],
            work,
            out,
        )
        observe_applied(obs, out)  # the observer's applied torque, as the closed loop gives it


@njit(cache=True)
def _est_loop(c, s, qm, qdm, tau, with_model, pi_out):  # pragma: no cover - compiled
    a = 0
    w = K.est_work(qm.shape[1], s.theta.shape[1])  # one scratch per trial, as the closed loop's
    for k in range(qm.shape[0]):
        a += K.est_step_trial_in(c, s, 0, qm[k], qdm[k], tau[k], w)
        if with_model:
            K.est_model_trial_in(c, s, 0, pi_out, w)
    return a


@njit(cache=True)
def _model_loop(c, s, n_calls, pi_out):  # pragma: no cover - compiled
    w = K.est_work(pi_out.shape[0] // 13, s.theta.shape[1])
    for _ in range(n_calls):
        K.est_model_trial_in(c, s, 0, pi_out, w)


@njit(cache=True)
def _filter_loop(c, s, qm, qdm, tau, tf, ym, phim):  # pragma: no cover - compiled
    n = qm.shape[1]
    w = K.est_work(n, s.theta.shape[1])
    for k in range(qm.shape[0]):
        K._filtered_signals(c, s, 0, qm[k], qdm[k], tau[k], w)
        for j in range(n):
            tf[k, j] = w.tf[j]
            ym[k, j] = w.ym[j]
            for m in range(10):
                phim[k, j, m] = w.phim[j, m]
    return n


@njit(cache=True)
def _regression_loop(c, tf, ym, phim, p):  # pragma: no cover - compiled
    n = tf.shape[1]
    phi, y = np.empty((n, p)), np.empty(n)
    a = 0.0
    for k in range(tf.shape[0]):
        K._regression(c, tf[k], ym[k], phim[k], phi, y)
        a += y[0]
    return a


@njit(cache=True)
def _rls_loop(c, tf, ym, phim, theta, P, w):  # pragma: no cover - compiled
    n, p = tf.shape[1], theta.shape[0]
    phi, y = np.empty((n, p)), np.empty(n)
    pphi, row, nz = np.empty(p), np.empty(p), np.empty(p, dtype=np.int64)
    # regressions first (not timed separately here: subtract _regression_loop)
    a = 0.0
    for k in range(tf.shape[0]):
        K._regression(c, tf[k], ym[k], phim[k], phi, y)
        for j in range(n):
            for m in range(p):
                row[m] = phi[j, m] / w[j]
            a += K._rls_row(theta, P, row, y[j] / w[j], 1.0 if j > 0 else 0.9999999, pphi, nz)
    return a


def _best(fn, repeat: int = 3) -> float:
    fn()
    best = np.inf
    for _ in range(repeat):
        t0 = time.thread_time()
        fn()
        best = min(best, time.thread_time() - t0)
    return best


def main() -> None:
    from adaptive_dd.closed_loop.runner import run_closed_loop, true_models
    from adaptive_dd.closed_loop.types import io_of, plant_of, run_constants
    from adaptive_dd.controllers import gains_for, make_controller

    path = sys.argv[1] if len(sys.argv) > 1 else None
    sc = _scenario(path)
    if sc.closed_forms is not None:
        raise SystemExit(
            f"{path}: runs on the paper's two-link closed forms, and this script times the general "
            "N-joint kernels; time the closed forms with benchmarks/two_link_speed_ab.py, or add "
            '`robot = "sice_arm"` and `general = true` to [arm] (benchmarks/scenarios/sice_general.toml)'
        )
    N, n = sc.n_samples, sc.n_joints
    rc, pl, io = run_constants(sc), plant_of(sc), io_of(sc)
    print(f"{path or 'UR5 tool swap'}, {N} samples of one trial; CPU microseconds per sample (best of 3)")
    whole = {}
    recs = {}
    for name in ("ct_oracle", "adaptive_ct"):
        opts = tuple(o for o in sc.controller_options if o[0] == name)
        one = dataclasses.replace(sc, seeds=1, controllers=(name,), controller_options=opts)
        run_closed_loop(dataclasses.replace(one, duration=0.2, swap_times=(0.05, 0.1, 0.15)))  # compile
        holder = {}

        def run(one=one, holder=holder):
            holder["res"] = run_closed_loop(one, keep_trajectories=1)

        whole[name] = _best(run) / N * 1e6
        whole[name + " unrecorded"] = (
            _best(lambda one=one: run_closed_loop(one, keep_trajectories=0)) / N * 1e6
        )
        r = holder["res"].runs[name]
        recs[name] = (r.q[0], r.qd[0], r.tau[0])

    q, qd, tau = recs["adaptive_ct"]
    rng = np.random.default_rng(0)
    qm = q + io.std[:n] * rng.standard_normal(q.shape)
    qdm = qd + io.std[n:] * rng.standard_normal(qd.shape)
    c = np.ascontiguousarray
    q, qd, tau, qm, qdm = c(q), c(qd), c(tau), c(qm), c(qdm)
    ch = sc.arm.chain
    scr = plant_scratch(n)
    rows = [
        (
            f"plant_step (stick-slip, RK4 x{pl.substeps})",
            _best(lambda: _plant_loop(pl, rc, q, qd, tau, scr)),
        )
    ]
    calls = 4 * pl.substeps  # RK4 stages per sample (more where a velocity crosses zero)
    t_dyn = _best(lambda: _dynamics_loop(ch, pl, rc, q, qd, tau, scr, False))
    t_sol = _best(lambda: _dynamics_loop(ch, pl, rc, q, qd, tau, scr, True)) - t_dyn
    rows += [
        (f"  of which rigid-body terms, {calls} x {t_dyn / N * 1e6:.3f}", calls * t_dyn),
        (f"  of which Cholesky solves, {calls} x {t_sol / N * 1e6:.3f}", calls * t_sol),
        ("  rest (stages, modes, crossings, calls)", rows[0][1] - calls * (t_dyn + t_sol)),
    ]
    pi_true = true_models(pl)[0]  # trial 0 (the plant is the arm here)
    out = np.empty(n)
    ctrls = {}
    for name in ("ct_oracle", "adaptive_ct"):
        opts = sc.options(name)
        ctrl = make_controller(name, gains_for(sc.arm, sc.bandwidth, sc.damping), opts, arm=sc.arm)
        form = ctrl.compiled_form(1, rc.T)
        ctrls[name] = form
        pim, th = form.state.pi_model[0].copy(), form.state.theta[0].copy()
        rows.append((f"law_trial {name}", _best(lambda cfg=form.cfg, pim=pim, th=th: _law_loop(
            ch, cfg, pi_true, pim, th, rc, qm, qdm, out))))  # fmt: skip
    form = ctrls["adaptive_ct"]
    p = form.es.theta.shape[1]
    pi_out = np.empty(13 * n)

    def fresh():
        ctrl = make_controller(
            "adaptive_ct", gains_for(sc.arm, sc.bandwidth, sc.damping), sc.options("adaptive_ct"), arm=sc.arm
        )
        return ctrl.compiled_form(1, rc.T)

    def est(with_model):
        f = fresh()
        _est_loop(f.ec, f.es, qm, qdm, tau, with_model, pi_out)

    t_step = _best(lambda: est(False))
    t_both = _best(lambda: est(True))
    f = fresh()
    _est_loop(f.ec, f.es, qm, qdm, tau, False, pi_out)
    t_model_end = _best(lambda: _model_loop(f.ec, f.es, N, pi_out))
    tf, ym, phim = np.empty((N, n)), np.empty((N, n)), np.empty((N, n, 10))
    t_filter = _best(lambda: _filter_loop(fresh().ec, fresh().es, qm, qdm, tau, tf, ym, phim))
    t_reg = _best(lambda: _regression_loop(f.ec, tf, ym, phim, p))
    theta0, P0 = f.es.theta[0].copy(), f.es.P[0].copy()
    t_rls = _best(lambda: _rls_loop(f.ec, tf, ym, phim, theta0.copy(), P0.copy(), f.ec.w)) - t_reg
    rows += [
        (f"est_step_trial (p = {p})", t_step),
        (f"  of which filters (+ momentum form: {K.MOMENTUM_CHANNELS} n channels)", t_filter),
        ("  of which regression", t_reg),
        (f"  of which RLS, {n} rows", t_rls),
        ("  rest (selection, detector, ...)", t_step - t_filter - t_reg - t_rls),
        ("est_model_trial (projection), along the run", t_both - t_step),
        ("est_model_trial at the final estimate", t_model_end),
    ]
    for label, t in rows:
        print(f"  {label:48s} {t / N * 1e6:8.3f}")
    t_of = dict(rows)
    plant, law_o, law_a = rows[0][1], t_of["law_trial ct_oracle"], t_of["law_trial adaptive_ct"]
    print(f"  {'whole loop, ct_oracle (run_closed_loop, 1 trial)':48s} {whole['ct_oracle']:8.3f}")
    glue = whole["ct_oracle"] - (plant + law_o) / N * 1e6
    print(f"  {'  glue + set-up (whole - plant - law)':48s} {glue:8.3f}")
    print(f"  {'whole loop, adaptive_ct (run_closed_loop, 1 trial)':48s} {whole['adaptive_ct']:8.3f}")
    glue = whole["adaptive_ct"] - (plant + law_a + t_both) / N * 1e6
    print(f"  {'  glue + set-up (whole - plant - law - est)':48s} {glue:8.3f}")
    for name in ("ct_oracle", "adaptive_ct"):
        rec = whole[name] - whole[name + " unrecorded"]
        print(f"  {'  of which recording the trial (' + name + ')':48s} {rec:8.3f}")
    for name in ("ct_oracle", "adaptive_ct"):
        share = plant / N * 1e6 / whole[name]
        print(f"  plant's share of the whole loop, {name}: {100 * share:.0f} %")


if __name__ == "__main__":
    main()
