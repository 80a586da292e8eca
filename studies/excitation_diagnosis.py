"""Why is adaptive_ct above its floor after an excitation phase? What the identification got
wrong, split by cause, and what that error costs along the task's path.

    python studies/excitation_diagnosis.py SCENARIO.toml [--seeds 10] [--excite 20]

Runs the scenario's excitation phase on each seed's drawn plant
(:mod:`adaptive_dd.closed_loop.excitation_phase`) and identifies the record twice: with the
scenario's sensor noise (what the phase does) and without it. Prints, per seed and over seeds:

* the identified base parameters' error against the plant's in units of the prior's standard
  deviations (``z``, :func:`~adaptive_dd.identification.arm_prior.identified_prior_std`), rms
  and largest;
* the torque that error predicts along the task's reference (rms over time, the norm over
  joints, in units of the floor's torque noise is not known here, so in N m and as a fraction of
  the URDF's own error there), split into the rigid-body part and the friction and armature part,
  for the noisy fit, the noise-free fit (the bias: the model's friction law against the
  plant's, and the filters' discretisation) and the URDF;
* the same error of the noise-free fit with the plant's Coulomb friction written as the
  identification's ``tanh`` law (``--law tanh`` runs the excitation on such plants).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop import excitation_phase as ep
from adaptive_dd.closed_loop.runner import run_closed_loop
from adaptive_dd.closed_loop.types import io_of, plant_of, true_models
from adaptive_dd.identification.model import arm_model, base_regressor
from adaptive_dd.identification.online import derived_row_weights


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--excite", type=float, default=20.0)
    ap.add_argument("--law", default=None, help="the plant's friction law (stick-slip, tanh, ...)")
    ap.add_argument("--save", default=None, help="npz of the excitation's records (read if it exists)")
    ap.add_argument("--vf", type=float, default=None, help="the identification's Coulomb law width [rad/s]")
    ap.add_argument("--task", action="store_true", help="run the task and follow adaptive_ct's estimate")
    a = ap.parse_args()
    if a.task:
        task(a)
        return
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["excite"] = a.excite
    if a.law:
        d.setdefault("plant", {})["friction"] = a.law
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    idx = tuple(range(a.seeds))
    # the phase's Coulomb width is the record's velocity noise (friction_width); here, before the
    # records are drawn, the stated noise's std, which that measures (to a fraction of a per cent)
    s = float(np.sqrt(np.mean(sc.velocity_variance)))
    law = getattr(sc.arm, "friction", "stick-slip")
    model = dataclasses.replace(
        arm_model(sc.arm), friction_velocity=sc.arm.friction_velocity if law == "tanh" else max(s, 1e-9)
    )
    n, T, std = sc.n_joints, sc.sample_period, io_of(sc).std
    if a.save and Path(a.save).exists():  # the records of an earlier run
        z = np.load(a.save)
        run = dataclasses.make_dataclass("Run", ["q", "qd", "tau"])(z["q"], z["qd"], z["tau"])
        plant = z["plant"]
    else:
        exc = ep._excitation_scenario(sc, ep.excitation_reference(sc))
        run = run_closed_loop(exc, seed_indices=idx, keep_trajectories=len(idx)).runs[
            ep.EXCITATION_CONTROLLER
        ]
        plant = true_models(plant_of(exc, idx))[:, 0] @ sc.arm.base.B.T
        if a.save:
            np.savez(a.save, q=run.q, qd=run.qd, tau=run.tau, plant=plant)
    if a.vf:  # the identification's Coulomb law tanh(qd / v_f) at other v_f
        model = dataclasses.replace(model, friction_velocity=a.vf)
    t = np.arange(0.0, sc.duration, 0.01)
    Y = base_regressor(model, *sc.reference.sample(t))  # (m, n, p) along the task's path
    fr = np.array([nm.split(" ")[0].split("*")[-1][:2] in ("fv", "fc", "Ia") for nm in model.names])

    def cost(e):
        """rms over time of the torque error's norm over joints [N m]: all, rigid, friction+armature."""
        out = []
        for sel in (np.ones(model.p, bool), ~fr, fr):
            tau = Y[:, :, sel] @ e[sel]
            out.append(float(np.sqrt(np.mean(np.sum(tau**2, axis=1)))))
        return out

    rows = []
    for k, i in enumerate(idx):
        rng = np.random.default_rng([int(sc.seed), int(i), 3])
        qm = run.q[k] + std[:n] * rng.standard_normal(run.q[k].shape)
        qdm = run.qd[k] + std[n:] * rng.standard_normal(run.qd[k].shape)
        noisy = ep.identify_record(model, qm, qdm, run.tau[k], T)
        clean = ep.identify_record(model, run.q[k], run.qd[k], run.tau[k], T)
        e = noisy.fit - plant[k]
        z = e / noisy.std
        zs = e / np.sqrt(np.diag(noisy.cov))
        V = {  # the prior's torque std along the path: with its correlations, its diagonal only
            key: np.sqrt(np.einsum("tjp,pq,tjq->tj", Y, P, Y).mean(axis=0))
            for key, P in (("cov", noisy.prior_cov), ("diag", np.diag(np.diag(noisy.prior_cov))))
        }
        s2 = float(np.mean((noisy.rstd / derived_row_weights(sc.arm)) ** 2))
        per_joint = np.sqrt(np.mean((Y @ (noisy.fit - plant[k])) ** 2, axis=0))
        print(
            f"seed {i}: torque error along the path per joint, rms [N m] {np.round(per_joint, 4).tolist()}; "
            f"the prior's std there, with correlations {np.round(V['cov'], 4).tolist()}, diagonal only "
            f"{np.round(V['diag'], 4).tolist()}; the estimator's rows' residual variance (unit in its RLS) "
            f"{s2:.3g}",
            flush=True,
        )  # fmt: skip
        r = {
            "urdf": cost(sc.arm.sigma - plant[k]),
            "fit": cost(e),
            "wls": cost(noisy.hat - plant[k]),
            "clean fit": cost(clean.fit - plant[k]),
            "clean wls": cost(clean.hat - plant[k]),
            "noise part": cost(noisy.hat - clean.hat),
            "z rms": float(np.sqrt(np.mean(z**2))),
            "z max": float(np.abs(z).max()),
            "z sandwich rms": float(np.sqrt(np.mean(zs**2))),
            "worst": model.names[int(np.abs(z).argmax())],
            "rstd": noisy.rstd,
        }
        rows.append(r)
        print(
            f"seed {i}: task-path torque error rms [N m] (all / rigid / friction+armature): "
            + "; ".join(f"{key} " + "/".join(f"{x:.3g}" for x in r[key]) for key in
                        ("urdf", "fit", "wls", "clean fit", "clean wls", "noise part"))
            + f"; z rms {r['z rms']:.2f} max {r['z max']:.1f} ({r['worst']}), sandwich-only z rms "
            f"{r['z sandwich rms']:.2f}",
            flush=True,
        )  # fmt: skip
    print(f"{a.scenario}: {a.seeds} seeds, excite {a.excite:g} s, law {a.law or 'scenario'}, p = {model.p}")
    for key in ("urdf", "fit", "wls", "clean fit", "clean wls", "noise part"):
        M = np.array([r[key] for r in rows])
        print(f"  {key:11s} median over seeds (all / rigid / friction+armature): " + " / ".join(
            f"{x:.3g}" for x in np.median(M, axis=0)) + f"  max all {M[:, 0].max():.3g}")  # fmt: skip
    print(
        f"  z rms median {np.median([r['z rms'] for r in rows]):.2f}, "
        f"max {max(r['z max'] for r in rows):.1f}; "
        f"sandwich-only z rms median {np.median([r['z sandwich rms'] for r in rows]):.2f}"
    )


def task(a) -> None:
    """Run the task after the phase (ct_oracle, ct_nominal, adaptive_ct) and print, per seed and
    segment, the torque error along that segment's path of the identified model (the arm's error:
    what ct_nominal carries besides the payload) and of adaptive_ct's model at the segment's end,
    both against the plant with that segment's payload [N m, rms over time of the norm]."""
    from adaptive_dd.benchmark.metrics import compute_metrics
    from adaptive_dd.benchmark.runner import run_benchmark

    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["excite"] = a.excite
    d["run"]["controllers"] = ["ct_oracle", "ct_nominal", "adaptive_ct"]
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    idx = list(range(a.seeds))
    res = run_benchmark(sc, progress=False, seed_indices=idx)
    rep = res.cache["excitation_report"]
    m = compute_metrics(res)["controllers"]
    model = arm_model(sc.arm)
    B = sc.arm.base.B
    true = true_models(plant_of(dataclasses.replace(sc, excite=0.0), idx)) @ B.T  # (S, G, p)
    edges = [0.0, *sc.swap_times, sc.duration]
    Ys = []
    for g in range(len(edges) - 1):
        t = np.arange(edges[g], edges[g + 1], 0.01)
        Ys.append(base_regressor(model, *sc.reference.sample(t)))

    def cost(Y, e):
        return float(np.sqrt(np.mean(np.sum((Y @ e) ** 2, axis=1))))

    end = res.runs["adaptive_ct"].sigma_end  # (S, G, p)
    for k, i in enumerate(idx):
        arm_err = rep.sigma_fit[k] - true[k, 0]
        cells = [
            f"{cost(Ys[g], arm_err):.3g} -> {cost(Ys[g], end[k, g] - true[k, g]):.3g}" for g in range(len(Ys))
        ]
        ratio = [
            f"{a_ / o_:.3f}"
            for a_, o_ in zip(
                (s["rms_error_per_seed"][k] for s in m["adaptive_ct"]["segments"]),
                (s["rms_error_per_seed"][k] for s in m["ct_oracle"]["segments"]),
                strict=True,
            )
        ]
        print(f"seed {i}: identified arm -> adaptive_ct at the segment's end: " + "; ".join(cells)
              + "  ratio " + " ".join(ratio), flush=True)  # fmt: skip
    for name in ("adaptive_ct", "ct_nominal"):
        cells = [
            f"{s['ratio_to_floor']['mean']:.3f}/{s['ratio_to_floor']['p90']:.3f}/{s['ratio_to_floor']['max']:.2f}"
            for s in m[name]["segments"]
        ]
        print(f"  {name} / ct_oracle mean/p90/max per segment: " + "  ".join(cells))


if __name__ == "__main__":
    main()
