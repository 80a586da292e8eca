"""Why the general estimator loses to the closed forms on the paper's arm: its payload prior.

Usage::

    python benchmarks/general_payload_prior.py [--seeds 20] [--first 0] [--sizes R ...]
        [--only LABEL ...] [--arms N [--first-arm 0]] [SCENARIO]

Runs ``ct_oracle`` and ``adaptive_ct`` on ``SCENARIO`` (default
``benchmarks/scenarios/sice_general.toml``: the default payload-swap benchmark on the general
kernels) once per variant, changing only the N-joint estimator's packed configuration (payload mode):

``today``
    The shipped settings: the payload's ten parameters re-opened at an alarm with mass standard
    deviation ``s`` along the arm's stated payload shape (a disk of ``[arm] payload_radius``),
    first moments ``s r`` and inertias ``s r^2`` of their own (``[arm] payload_offset`` r); the
    control model's first moments combined with
    ``m c ~ 0 +- r sqrt(E[m^2])`` (the centred prior) and its payload scaled by
    :func:`~adaptive_dd.identification.online_kernel.presence_weight` of the mass's variance.
``no presence``
    The same without the presence weight (``EstCfg.present2 = 0``).
``no centred``
    The same without the centred prior on the control model's first moments given the mass
    (``EstCfg.com_size = 0``; :func:`~adaptive_dd.identification.online_control_model.centred_prior`).
``paper prior``
    The closed forms' prior in payload coordinates: the mass (variance 25 kg^2 at the start, 100
    at a re-opening: ``TwoLinkOnlineConfig.p0_payload``, ``ChangeDetector.p_mass``) and the
    inertia about the payload frame's z axis (``1e-4`` / ``1e-3``: ``p0_j2`` / ``p_j2``); the
    first moments and the other inertias pinned (``1e-8``): a disk centred on the tip, the
    paper's eq. (9).
``paper prior, no presence``
    Both.
``size R`` (one per ``--sizes R``)
    Today's settings with the prior's length scale ``[arm] payload_offset`` = R [m] (first
    moments ``s R``, inertias ``s R^2``, at the start and at every re-opening).

``--only LABEL ...`` runs only the variants of those labels (e.g. ``--only today "size 0.05"``).
``--arms N``: SCENARIO is a template (e.g. ``benchmarks/scenarios/population.toml``) run over N
drawn arms as ``adaptive-dd benchmark SCENARIO --arms N`` does, with ``--seeds`` trials per arm;
each variant prints the pooled table of ``adaptive-dd benchmark --arms``.

Prints per segment the mean / p90 / max of the per-seed ``adaptive_ct / ct_oracle`` RMS ratio
(with the worst seed), the median / max detection delay per swap and the false alarms. Asserts
nothing; the patch lives in this process only (the kernels are not recompiled: the packed
configuration is data).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark import load_scenario, run_benchmark
from adaptive_dd.benchmark.metrics import per_seed_segment_metrics, ratio_statistics
from adaptive_dd.closed_loop.runner import make_controller_of
from adaptive_dd.identification import online_init

ROOT = Path(__file__).resolve().parents[1]
PINNED = 1e-8
VARIANTS = {  # (paper prior, no presence weight)
    "today": (False, False),
    "no presence": (False, True),
    "paper prior": (True, False),
    "paper prior, no presence": (True, True),
}
NO_CENTRED = "no centred"  # today's settings without the centred prior (com_size = 0)


def _paper_prior(mass_var: float, izz_var: float) -> np.ndarray:
    """A payload covariance (10, 10) along the mass and Izz (index 9) only."""
    P = np.diag(np.full(10, PINNED))
    P[0, 0], P[9, 9] = mass_var, izz_var
    return P


def _patched_pack(paper: bool, no_presence: bool, size: float | None = None, centred: bool = True):
    pack = online_init._pack

    def _pack(cfg, arm):
        if size is not None:
            arm = arm.with_(payload_offset=size)
        c, P0 = pack(cfg, arm)
        if cfg.mode != "payload":
            raise SystemExit("general_payload_prior: the scenario's adaptive_ct must be in payload mode")
        if no_presence:
            c = c._replace(present2=0.0)
        if not centred:
            c = c._replace(com_size=0.0)
        if paper:
            c.P_reopen[:] = _paper_prior(100.0, 1e-3)
            P0 = _paper_prior(25.0, 1e-4)
        return c, P0

    return _pack


def _row(sc, res) -> str:
    seeds = list(res.seed_indices)
    ad, orc = res.runs["adaptive_ct"], res.runs["ct_oracle"]
    r = (
        per_seed_segment_metrics(res, ad, settling=False)["rms_error"]
        / per_seed_segment_metrics(res, orc, settling=False)["rms_error"]
    )
    cells = []
    for i in range(r.shape[1]):
        st = ratio_statistics(r[:, i], seeds)
        cells.append(f"{st['mean']:.3f} / {st['p90']:.3f} / {st['max']:.3f} #{st['worst_seed']}")
    delays, false = [], 0
    for al in map(np.asarray, ad.alarm_times):
        near = np.zeros(al.size, bool)
        for k, ts in enumerate(sc.swap_times):
            hit = (al >= ts) & (al < ts + 0.3)
            near |= hit
            delays.append((k, 1e3 * (al[hit][0] - ts) if hit.any() else np.nan))
        false += int((~near).sum())
    dl = [np.array([d for k2, d in delays if k2 == k]) for k in range(len(sc.swap_times))]
    dtxt = ", ".join(f"{np.nanmedian(d):.0f} / {np.nanmax(d):.0f}" for d in dl)
    return "   ".join(cells) + f" | delay [ms] {dtxt} | false alarms {false}"


def _population(a, label: str) -> None:
    """One variant over drawn arms (``--arms``): the pooled table of ``adaptive-dd benchmark --arms``."""
    import tomllib

    from adaptive_dd.benchmark.population import format_population, run_population

    with open(a.scenario, "rb") as f:
        data = tomllib.load(f)
    t0 = time.perf_counter()
    pop = run_population(
        data,
        a.scenario,
        range(a.first_arm, a.first_arm + a.arms),
        seeds=a.seeds,
        controllers=lambda sc: ("ct_oracle", "adaptive_ct"),
    )
    print(f"{label} ({time.perf_counter() - t0:.0f} s):\n{format_population(pop)}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default=str(ROOT / "benchmarks/scenarios/sice_general.toml"))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--sizes", type=float, nargs="*", default=[], help="[arm] payload_offset variants [m]")
    ap.add_argument("--only", nargs="*", default=None, help="run only the variants of these labels")
    ap.add_argument("--arms", type=int, default=0, help="run the template SCENARIO over N drawn arms")
    ap.add_argument("--first-arm", type=int, default=0)
    a = ap.parse_args()
    sc = load_scenario(a.scenario)
    seeds = list(range(a.first, a.first + a.seeds))
    head = "adaptive_ct / ct_oracle per segment, mean / p90 / max"
    print(f"{a.scenario}, seeds {seeds[0]}-{seeds[-1]}: {head}")
    pack = online_init._pack
    variants = {k: (*v, None, True) for k, v in VARIANTS.items()}
    variants[NO_CENTRED] = (False, False, None, False)
    variants.update({f"size {r:g}": (False, False, r, True) for r in a.sizes})
    if a.only is not None:
        unknown = sorted(set(a.only) - set(variants))
        if unknown:
            raise SystemExit(f"general_payload_prior: --only {unknown}: not among {list(variants)}")
        variants = {k: v for k, v in variants.items() if k in a.only}
    for label, (paper, no_presence, size, centred) in variants.items():
        online_init._pack = _patched_pack(paper, no_presence, size, centred)
        if a.arms:
            try:
                _population(a, label)
            finally:
                online_init._pack = pack
            continue
        try:
            t0 = time.perf_counter()
            ctrls = dict(make_controller_of(sc, s) for s in ("ct_oracle", "adaptive_ct"))
            res = run_benchmark(
                sc, progress=False, controllers=ctrls, seed_indices=seeds, keep_trajectories=0
            )
            print(f"{label:>26}: {_row(sc, res)} ({time.perf_counter() - t0:.0f} s)", flush=True)
        finally:
            online_init._pack = pack


if __name__ == "__main__":
    main()
