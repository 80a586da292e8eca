"""Reproduction of the paper's Tables 3 (M1) and 5 (M2), with our estimators beside.

One Monte-Carlo batch of the Table 2 experiment (with Table 4 velocity noise) is
simulated; every (method, estimator, split) runs once over all ``tau_f`` and
seeds stacked in one batch. Estimation error: ``|sigma_hat - sigma| / sigma * 100``
at the end of the 10 000 samples (docs/paper_reading.md), reported as mean and std over seeds.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from adaptive_dd.errors import ParameterError
from adaptive_dd.experiments import TABLE2, table2_torque, trial_rngs
from adaptive_dd.identification.estimators import ESTIMATORS, prepare_regression, solve_regression
from adaptive_dd.identification.fisher import FisherResult
from adaptive_dd.identification.limits import (
    LIMIT_ESTIMATORS,
    bound_rows,
    format_bound_table,
    run_information_estimators,
    table2_bound,
)
from adaptive_dd.plant.parameters import SIGMA_NAMES, project_sigma
from adaptive_dd.plant.simulator import simulate_open_loop
from adaptive_dd.plant.two_link import ClosedFormTwoLink

__all__ = [
    "EXTRA_ESTIMATORS",
    "PAPER_TABLES",
    "TAU_F_GRID",
    "ReproduceResult",
    "format_bounds",
    "format_comparison",
    "format_summary",
    "format_table",
    "model_responses",
    "paper_comparison",
    "run_reproduce",
]

TAU_F_GRID = (0.002, 0.004, 0.006, 0.008, 0.01, 0.02)

PAPER_TABLES = {
    "M1": np.array(
        [
            [55.8, 70.5, 34.0, 17.8, 3.1, 23.5, 1.9],
            [21.7, 23.3, 17.9, 15.9, 17.1, 24.1, 37.8],
            [5.1, 3.4, 4.8, 16.4, 16.7, 24.3, 37.7],
            [18.4, 14.4, 16.5, 15.8, 15.7, 22.6, 36.2],
            [23.8, 18.0, 20.3, 15.0, 15.1, 21.0, 35.4],
            [28.2, 19.7, 21.8, 12.4, 13.6, 16.6, 32.2],
        ]
    ),
    "M2": np.array(
        [
            [20.2, 21.5, 29.1, 1.5, 5.0, 0.8, 9.4],
            [12.1, 14.2, 16.3, 0.6, 2.4, 0.5, 5.0],
            [9.3, 12.1, 13.2, 0.3, 1.7, 0.9, 3.6],
            [8.4, 11.0, 11.7, 0.1, 1.3, 1.3, 3.0],
            [7.9, 10.4, 10.9, 0.1, 1.1, 1.7, 2.4],
            [7.2, 8.3, 8.5, 1.6, 0.4, 3.8, 1.2],
        ]
    ),
}
"""Tables 3 (M1) and 5 (M2) of the paper: error [%] per tau_f of TAU_F_GRID (rows)."""

DEFAULT_ESTIMATORS = ("paper", "batch_ls", "exact", "exact_batch_ls")
EXTRA_ESTIMATORS = ("output_error", "akf")
"""Estimators that work on the whole state, not the filtered regression (no tau_f, M2 data)."""


@dataclass
class ReproduceResult:
    """Errors per configuration; ``errors[(method, split, estimator)]`` is ``(n_tau_f, n_seeds, 7)`` [%].

    ``signed`` holds the same errors with their sign; ``crb`` the Cramér-Rao bound of the
    experiment (None without noise); ``extra[name]`` the final estimates ``(n_seeds, 7)``
    of the estimators of :data:`EXTRA_ESTIMATORS`.
    """

    tau_f: tuple
    seeds: int
    errors: dict = field(default_factory=dict)
    theta: dict = field(default_factory=dict)  # (method, split, estimator) -> (n_tau_f, seeds, N, 7)
    sim: object = None
    signed: dict = field(default_factory=dict)
    crb: FisherResult | None = None
    extra: dict = field(default_factory=dict)

    def rows(self) -> list[dict]:
        """Tidy rows: method, split, estimator, tau_f, param, mean_pct, std_pct, paper_pct, and
        against the bound: crb_std_pct, bias_pct, est_std_pct (std of the signed estimate
        over seeds, ddof 1), std_over_crb.

        ``mean_pct`` and ``std_pct`` are the mean and std (ddof 1, as every std here) of ``|error|``
        (as in the paper's tables); the estimate's own spread, comparable with the bound, is
        ``est_std_pct``.
        """
        out = []
        for (method, split, est), err in self.errors.items():
            for i, tf in enumerate(self.tau_f):
                for k, name in enumerate(SIGMA_NAMES):
                    paper = None
                    if est == "paper" and split == "15" and tf in TAU_F_GRID:
                        paper = float(PAPER_TABLES[method][TAU_F_GRID.index(tf), k])
                    e = err[i, :, k]
                    row = {
                        "method": method,
                        "split": split,
                        "estimator": est,
                        "tau_f": float(tf),
                        "param": name,
                        "mean_pct": float(np.mean(e)),
                        "std_pct": float(np.std(e, ddof=1)) if e.size > 1 else float("nan"),
                        "paper_pct": paper,
                    }
                    out.append(row | self._against_bound(self.signed[(method, split, est)][i, :, k], k))
        if self.crb is not None:
            for r in bound_rows(self.crb, self.extra):
                out.append({"method": None, "split": None, "tau_f": None} | r)
        return out

    def _against_bound(self, e: np.ndarray, k: int) -> dict:
        crb = None if self.crb is None else float(self.crb.crb_std_pct[k])
        std = float(np.std(e, ddof=1)) if e.size > 1 else float("nan")
        return {
            "crb_std_pct": crb,
            "bias_pct": float(np.mean(e)),
            "est_std_pct": std,
            "std_over_crb": None if crb is None else std / crb,
        }

    def write_json(self, path: str | Path) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.rows(), indent=1))
        return path


def run_reproduce(
    seeds: int = 10,
    seed: int = 0,
    tau_f: tuple = TAU_F_GRID,
    methods: tuple = ("M1", "M2"),
    estimators: tuple = DEFAULT_ESTIMATORS,
    splits: tuple = ("15", "16", "full"),
    n_samples: int = TABLE2["n_samples"],
    progress: bool = True,
    keep_theta: tuple = (),
    noise: bool = True,
    extra_estimators: tuple = (),
) -> ReproduceResult:
    """Simulate the Table 2 (+ Table 4) experiment and estimate with every configuration.

    Parameters
    ----------
    seeds : int
        Monte-Carlo trials (noise seeds ``(seed, i)``).
    tau_f : tuple of float
        Filter time constants [s].
    methods, estimators, splits : tuple of str
        ``splits`` applies to the ``paper`` estimator; the others use ``full``.
    keep_theta : tuple of (method, split, estimator)
        Configurations whose whole estimate history to keep (for figures).
    noise : bool
        Table 2 / Table 4 sensor noise (False: noise-free sensors, quantization kept),
        to separate modelling errors from noise. With noise, the Cramér-Rao bound of the
        experiment is computed too (``res.crb``).
    extra_estimators : tuple of {"output_error", "akf"}
        Run these too on the measured data (see :mod:`adaptive_dd.identification.limits`).

    Returns
    -------
    ReproduceResult
        Every configuration's estimates and errors per seed, and the bounds.

    Examples
    --------
    The paper's estimator with one filter constant on two short noisy records:

    >>> from adaptive_dd.identification.reproduce import run_reproduce
    >>> res = run_reproduce(seeds=2, tau_f=(0.01,), methods=("M2",), estimators=("paper",),
    ...                     splits=("15",), n_samples=2000, progress=False)
    >>> list(res.errors)
    [('M2', '15', 'paper')]
    >>> res.errors[("M2", "15", "paper")].shape  # tau_f x seeds x the 7 base parameters [%]
    (1, 2, 7)
    >>> row = res.rows()[0]
    >>> row["param"], row["paper_pct"]  # the paper's figure beside it (M2: Table 5)
    ('J1', 7.9)
    """
    _check_configurations(seeds, tau_f, estimators, extra_estimators)
    arm = ClosedFormTwoLink.sice()  # the paper's arm
    sensor = replace(
        arm.sensor,
        position_variance=TABLE2["position_variance"] if noise else (0.0, 0.0),
        velocity_variance=TABLE2["velocity_variance"] if noise else (0.0, 0.0),
    )
    sim = simulate_open_loop(table2_torque(seeds, n_samples), trial_rngs(seed, seeds), arm=arm, sensor=sensor)
    jobs = [(m, s, e) for m in methods for e in estimators for s in (splits if e == "paper" else ("full",))]
    res = ReproduceResult(tuple(tau_f), seeds, sim=sim)
    _estimate_all(res, arm.sigma, jobs, keep_theta, progress)
    if noise:
        res.crb = table2_bound(sim.tau[0])
    if extra_estimators:
        names = tuple(e for e in LIMIT_ESTIMATORS if e in extra_estimators)
        res.extra, _ = run_information_estimators(sim.q_meas, sim.qd_meas, sim.tau, names)
    return res


def _check_configurations(seeds: int, tau_f: tuple, estimators: tuple, extra_estimators: tuple) -> None:
    if seeds < 1:
        raise ParameterError(f"seeds must be >= 1, got {seeds}")
    bad = [e for e in estimators if e not in ESTIMATORS] + [
        e for e in extra_estimators if e not in EXTRA_ESTIMATORS
    ]
    if bad:
        raise ParameterError(f"unknown estimator(s) {bad}; choose from {ESTIMATORS + EXTRA_ESTIMATORS}")
    if any(t <= 0 for t in tau_f):
        raise ParameterError(f"tau_f values must be > 0, got {tau_f}")


def _estimate_all(res: ReproduceResult, sigma, jobs: list, keep_theta: tuple, progress: bool) -> None:
    """Run every ``(method, split, estimator)`` of ``jobs`` on ``res.sim`` at every ``res.tau_f``
    and store the errors [%] against ``sigma`` (and the histories asked for) in ``res``. The
    filtered regression is prepared once per method and kind of estimator."""
    from tqdm.auto import tqdm

    sim, tau_f = res.sim, res.tau_f
    prepared = {}
    bar = tqdm(total=len(jobs), desc="reproduce", unit="config", disable=not progress)
    for method, split, est in jobs:
        key = (method, est.startswith("exact"))
        if key not in prepared:
            parts = [
                prepare_regression(sim.q_meas, sim.tau, sim.qd_meas, estimator=est, method=method, tau_f=tf)
                for tf in tau_f
            ]
            prepared[key] = tuple(np.stack(p) for p in zip(*parts, strict=True))
        phi, y, active = prepared[key]
        bar.set_postfix_str(f"{method} {est} split {split}")
        theta, _, _ = solve_regression(
            phi,
            y,
            active,
            estimator=est,
            split=split,
            progress=(lambda f: bar.update(f)) if est == "kalman" else None,
        )
        if est != "kalman":
            bar.update(1)
        res.signed[(method, split, est)] = 100 * (theta[..., -1, :] - sigma) / sigma
        res.errors[(method, split, est)] = np.abs(res.signed[(method, split, est)])
        if (method, split, est) in keep_theta:
            res.theta[(method, split, est)] = theta
    bar.close()


def format_bounds(res: ReproduceResult, tau_f: float | None = None) -> str:
    """Per parameter the bound beside every estimator's bias, std and std / bound.

    Filtered-regression estimators at ``tau_f`` (default: 0.02 if run, else the largest).
    """
    if res.crb is None:
        return "no bound: noise-free sensors"
    tf = tau_f if tau_f is not None else (0.02 if 0.02 in res.tau_f else max(res.tau_f))
    i = res.tau_f.index(tf)
    estimates, kinds = {}, {}
    for (method, split, est), e in res.signed.items():
        label = f"{method} {est}" + (f" ({split})" if est == "paper" else "") + f" tau_f={tf:g}"
        estimates[label] = ClosedFormTwoLink.sice().sigma * (1 + e[i] / 100.0)
        kinds[label] = est
    for name, est in res.extra.items():
        estimates[name], kinds[name] = est, name
    return format_bound_table(res.crb, estimates, kinds=kinds)


def paper_comparison(res: ReproduceResult, method: str) -> list[dict]:
    """Ours against the paper (estimator ``paper``, split 15) per tau_f of the paper's grid and
    parameter: ``tau_f, param, ours_pct`` (mean ``|error|`` over seeds), ``paper_pct`` and
    ``ratio = ours / paper``.

    Parameters
    ----------
    res : ReproduceResult
        What :func:`run_reproduce` returned.
    method : {"M1", "M2"}
        Table 3 (M1) or Table 5 (M2).

    Returns
    -------
    list of dict
        One row per tau_f and parameter: ``tau_f, param, ours_pct, paper_pct, ratio``.

    Examples
    --------
    A result whose errors are half the paper's Table 5 on each of 3 seeds:

    >>> import numpy as np
    >>> from adaptive_dd.identification.reproduce import (
    ...     PAPER_TABLES, TAU_F_GRID, ReproduceResult, paper_comparison)
    >>> err = np.repeat(0.5 * PAPER_TABLES["M2"][:, None, :], 3, axis=1)  # (tau_f, seed, 7) [%]
    >>> res = ReproduceResult(tau_f=TAU_F_GRID, seeds=3, errors={("M2", "15", "paper"): err})
    >>> rows = paper_comparison(res, "M2")
    >>> len(rows), rows[0]["tau_f"], rows[0]["param"], round(rows[0]["ratio"], 3)
    (42, 0.002, 'J1', 0.5)
    >>> paper_comparison(res, "M1")  # no Table 3 run
    []
    """
    err = res.errors.get((method, "15", "paper"))
    if err is None:
        return []
    out = []
    for i, tf in enumerate(res.tau_f):
        if tf not in TAU_F_GRID:
            continue
        for k, name in enumerate(SIGMA_NAMES):
            ours, paper = float(err[i, :, k].mean()), float(PAPER_TABLES[method][TAU_F_GRID.index(tf), k])
            out.append({"tau_f": float(tf), "param": name, "ours_pct": ours, "paper_pct": paper,
                        "ratio": ours / paper if paper > 0 else float("nan")})  # fmt: skip
    return out


def format_comparison(res: ReproduceResult, method: str) -> str:
    """The paper's value beside ours and their ratio, per tau_f (rows) and parameter (columns):
    cells ``ours / paper = ratio`` [%] (estimator ``paper``, split 15)."""
    rows = paper_comparison(res, method)
    if not rows:
        return ""
    head = f"{'tau_f':>6} " + " ".join(f"{n:>18s}" for n in SIGMA_NAMES)
    lines = [head]
    for tf in dict.fromkeys(r["tau_f"] for r in rows):
        cells = [
            f"{r['ours_pct']:5.1f}/{r['paper_pct']:4.1f}={r['ratio']:5.2f}" for r in rows if r["tau_f"] == tf
        ]
        lines.append(f"{tf:6.3f} " + " ".join(f"{c:>18s}" for c in cells))
    return "\n".join(lines)


def format_table(res: ReproduceResult, method: str, split: str, estimator: str, with_paper: bool) -> str:
    """The paper's table layout: rows tau_f, columns J1..d2, cells ``mean±std`` (and paper); the
    std over the seeds with ddof 1, as :meth:`ReproduceResult.rows` and the JSON have it."""
    err = res.errors[(method, split, estimator)]
    head = f"{'tau_f':>6} " + " ".join(f"{n:>17s}" for n in SIGMA_NAMES)
    lines = [head]
    for i, tf in enumerate(res.tau_f):
        cells = []
        for k in range(7):
            e = err[i, :, k]
            c = f"{e.mean():5.1f}±{e.std(ddof=1) if e.size > 1 else float('nan'):<4.1f}"
            if with_paper and tf in TAU_F_GRID:
                c += f"({PAPER_TABLES[method][TAU_F_GRID.index(tf), k]:4.1f})"
            cells.append(f"{c:>17s}")
        lines.append(f"{tf:6.3f} " + " ".join(cells))
    return "\n".join(lines)


def format_summary(res: ReproduceResult) -> str:
    """One line per configuration and tau_f: the worst mean error over the seven parameters."""
    lines = [f"{'method':6} {'estimator':15} {'split':5} " + " ".join(f"{t:>7.3f}" for t in res.tau_f)]
    for (method, split, est), err in res.errors.items():
        worst = err.mean(axis=1).max(axis=1)
        lines.append(f"{method:6} {est:15} {split:5} " + " ".join(f"{w:7.2f}" for w in worst))
    return "\n".join(lines)


def model_responses(models: dict, n_samples: int = TABLE2["n_samples"]) -> tuple[np.ndarray, dict]:
    """The arm and identified models driven by the same Table 2 torque (Fig. 7).

    Parameters
    ----------
    models : dict
        Label -> estimated sigma (7,); projected onto physically consistent values.
    n_samples : int

    Returns
    -------
    q_arm : ndarray (n_samples, 2)
        The true arm, noise-free sensors.
    q_models : dict
        Label -> ndarray (n_samples, 2).
    """
    sice = ClosedFormTwoLink.sice()
    clean = replace(sice.sensor, quantize=False, position_variance=(0, 0), velocity_variance=(0, 0))
    tau = table2_torque(1, n_samples)
    rec = simulate_open_loop(tau, np.random.default_rng(0), arm=sice, sensor=clean)
    q_models = {}
    for label, sigma in models.items():
        model = simulate_open_loop(
            tau, np.random.default_rng(0), arm=sice, sigma0=project_sigma(sigma), sensor=clean
        )
        q_models[label] = model.q[0]
    return rec.q[0], q_models
