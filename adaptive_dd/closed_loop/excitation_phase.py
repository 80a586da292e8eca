"""Identification feeds adaptation: the excitation phase of a scenario (``[run] excite = SECONDS``).

What a lab does before a task, on each seed's plant:

1. the designed excitation of ``adaptive-dd excite`` (:func:`excitation_reference`: the
   D-optimal Fourier trajectory of :func:`~adaptive_dd.identification.excitation.design_excitation`
   within the arm's limits, from the controllers' model; its coverage of the task's region, the
   positions the scenario's ``[reference]`` visits widened by
   :data:`~adaptive_dd.identification.excitation.TASK_MARGIN`, reported), tracked for ``excite`` seconds by
   ``ct_nominal`` on the model (the robot's own controller), not scored;
2. the record, with sensor noise at the scenario's levels (generator ``(seed, i, 3)``), identified
   as ``adaptive-dd identify`` does: the filtered regression and its weighted least squares
   with the Newey-West sandwich covariance (:func:`~adaptive_dd.identification.log_fit.fit_log`),
   then the physically consistent standard parameters nearest to it
   (:func:`~adaptive_dd.identification.consistency.consistent_arm_fit`), and what it knows of
   each base parameter (:func:`~adaptive_dd.identification.arm_prior.identified_prior_std`);
3. the task run with that identified model as every non-oracle controller's model (the
   oracles are given the plant, as always), one seed at a time (each seed has its own model),
   the results joined seed by seed (:func:`join_results`).

The identification is reported (:class:`ExcitationReport`, ``metrics.json``'s ``excitation``):
per seed, the error of the URDF's and of the identified base parameters against the plant's.
"""

from __future__ import annotations

import dataclasses
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.closed_loop.model_prior import estimator_scale, identified_prior, model_file_prior
from adaptive_dd.errors import ScenarioError

__all__ = [
    "EXCITATION_CONTROLLER",
    "START_ATTEMPTS",
    "TAU_F",
    "ExcitationReport",
    "RecordFit",
    "designed_excitation",
    "estimator_scale",
    "excitation_coverage",
    "excitation_reference",
    "identified_prior",
    "identify_excitation",
    "identify_record",
    "join_results",
    "model_file_prior",
    "run_with_excitation",
]

Array = NDArray[np.float64]

EXCITATION_CONTROLLER = "ct_nominal"
"""The controller that tracks the excitation (on the model: what a lab's robot runs)."""
TAU_F = 0.02
"""[s] time constant of the identification's filters (``adaptive-dd identify``'s default)."""


@dataclasses.dataclass
class ExcitationReport:
    """The excitation phase's identification, per seed.

    ``sigma_plant, sigma_model, sigma_hat, sigma_fit (S, p)``: base parameters of each seed's
    plant, of the controllers' model before the phase, of the weighted least squares and of the
    consistent fit (the model after the phase); ``names (p,)``; ``rstd (S, n)`` the residual
    torque std per joint [N m]; ``sigma_std (S, p)`` what the identification knows of each base
    parameter (:func:`~adaptive_dd.identification.arm_prior.identified_prior_std`: the sandwich
    variance plus the fit's step and the model error); ``sigma_cov (S, p, p)`` the same with the
    sandwich's correlations (:func:`~adaptive_dd.identification.arm_prior.identified_prior_cov`):
    adaptive_ct's prior on the arm after the phase; ``estimator_scale (S,)`` a consistency check,
    reported and not applied: ``sigma_cov`` against the information adaptive_ct's estimator takes
    from the same record (:func:`~adaptive_dd.closed_loop.model_prior.estimator_scale`; 1 means
    the prior counts as much as its record would in the estimator; ones when the scenario runs no
    adaptive_ct; dividing the hand-off by it measured worse, docs/learning_the_arm.md);
    ``coulomb_width (S,)`` [rad/s] per seed the width of the identification's Coulomb law, from
    the record (:func:`~adaptive_dd.identification.friction_width.coulomb_width`); ``held (S,)`` per
    seed the number of directions of the base parameters the record could not see, held at the
    URDF's values (:mod:`~adaptive_dd.identification.held_directions`).
    """

    duration: float
    seed_indices: tuple
    names: tuple
    sigma_plant: Array
    sigma_model: Array
    sigma_hat: Array
    sigma_fit: Array
    rstd: Array
    sigma_std: Array
    sigma_cov: Array
    coulomb_width: Array
    estimator_scale: Array | None = None
    coverage: object = None
    held: Array | None = None

    def errors(self) -> dict[str, Array]:
        """Per seed and base parameter ``(S, p)``, the error against the plant's,
        ``|x - plant| / max(|plant|, 1 % of the largest |plant|)`` (the floor keeps parameters near
        zero from dominating): the model before the phase (``model``), the weighted least squares
        (``wls``) and the consistent fit, the model after it (``fit``)."""
        scale = np.maximum(
            np.abs(self.sigma_plant), 0.01 * np.abs(self.sigma_plant).max(axis=1, keepdims=True)
        )
        return {
            "model": np.abs(self.sigma_model - self.sigma_plant) / scale,
            "wls": np.abs(self.sigma_hat - self.sigma_plant) / scale,
            "fit": np.abs(self.sigma_fit - self.sigma_plant) / scale,
        }

    def to_dict(self) -> dict:
        """JSON-ready: per seed the median and max relative error before and after, the residual std."""
        err = self.errors()
        seeds = {}
        for k, i in enumerate(self.seed_indices):
            seeds[int(i)] = {
                key: {
                    "median": float(np.median(e[k])),
                    "max": float(e[k].max()),
                    "worst": self.names[int(e[k].argmax())],
                }
                for key, e in err.items()
            }
            seeds[int(i)]["residual_std"] = self.rstd[k].tolist()
            if self.estimator_scale is not None:
                seeds[int(i)]["estimator_scale"] = float(self.estimator_scale[k])
            if self.held is not None:
                seeds[int(i)]["held_directions"] = int(self.held[k])
        out = {
            "duration": self.duration,
            "controller": EXCITATION_CONTROLLER,
            "tau_f": TAU_F,
            "coulomb_width": self.coulomb_width.tolist(),
            "seeds": seeds,
        }
        if self.coverage is not None:
            cov = self.coverage
            out["coverage"] = {
                "span": cov.span.tolist(),
                "speed": cov.speed.tolist(),
                "distance_median_p90_max": cov.distance.tolist(),
                "radius": cov.radius,
                "inside": cov.inside,
                "covered": cov.ok,
            }
        return out

    def summary(self) -> str:
        """One line per quantity: median over seeds of each seed's median and max relative error."""
        err = self.errors()
        parts = [
            f"{key}: median {100 * np.median(np.median(e, axis=1)):.3g} %, "
            f"worst {100 * np.median(e.max(axis=1)):.3g} %"
            for key, e in err.items()
        ]
        line = (
            f"excitation {self.duration:g} s, base parameters vs the plant's (median over seeds) - "
            + "; ".join(parts)
        )
        if self.held is not None and np.any(self.held):
            line += (
                f"; held at the URDF's values (the record cannot see them): {int(np.min(self.held))}-"
                f"{int(np.max(self.held))} direction(s) per seed"
            )
        return line if self.coverage is None else line + "\n" + self.coverage.line()


START_ATTEMPTS = 5
"""Random starts tried by :func:`excitation_reference` (the optimum of one may graze a limit)."""


def _task_path(scenario, duration: float | None = None) -> tuple[Array, Array]:
    """The scenario's reference ``q_d, qd_d (m, n)`` over ``duration`` (default the task's) at 20 ms."""
    t = np.arange(0.0, float(duration or scenario.duration), 0.02)
    q, qd, _ = scenario.reference.sample(t)
    return q, qd


_DESIGNED: dict = {}  # scenario name -> its excitation designed beforehand (designed_excitation)


@contextmanager
def designed_excitation(name: str, reference):
    """Within the block, :func:`excitation_reference` of the scenario named ``name`` is
    ``reference``: that scenario's design made beforehand (the leaderboard's workers design the
    drawn arms' excitations while another compiles the closed loop, then hand each to its arm)."""
    _DESIGNED[name] = reference
    try:
        yield
    finally:
        _DESIGNED.pop(name, None)


def excitation_reference(scenario, progress: bool = False):
    """The designed excitation of the scenario's model as a reference with a 1 s ramp: the first of
    :data:`START_ATTEMPTS` random starts (generators ``(seed, 4, attempt)``) whose optimum keeps
    within the arm's whole limits
    (:meth:`~adaptive_dd.identification.excitation.ExcitationLimits.of_arm`; ``adaptive-dd
    excite``'s design). ``progress``: the design's bar on stderr.

    Raises
    ------
    ScenarioError
        The arm's position limits leave no room, or no start gave a trajectory within the limits
        (naming ``run.excite``).
    """
    from adaptive_dd.errors import ParameterError
    from adaptive_dd.identification.excitation import ExcitationLimits, design_excitation

    if scenario.name in _DESIGNED:
        return _DESIGNED[scenario.name]
    arm = scenario.arm
    try:
        lim = ExcitationLimits.of_arm(arm)
    except ParameterError as exc:
        raise ScenarioError(f"{scenario.source}: run.excite: {exc}") from None
    last = None
    for attempt in range(START_ATTEMPTS):
        rng = np.random.default_rng([int(scenario.seed), 4, attempt])
        try:
            best, _ = design_excitation(arm, lim, rng=rng, progress=progress)
        except ParameterError as exc:
            last = exc
            continue
        return best.reference(ramp=1.0)
    raise ScenarioError(
        f"{scenario.source}: run.excite: no designed excitation within the arm's limits after "
        f"{START_ATTEMPTS} starts ({last})"
    )


def excitation_coverage(scenario, reference, duration: float):
    """How the excitation ``reference`` tracked for ``duration`` [s] covers the task's poses
    (:func:`~adaptive_dd.identification.excitation.coverage`, the references sampled at 20 ms)."""
    from adaptive_dd.identification.excitation import coverage, moving_joints
    from adaptive_dd.identification.model import arm_model

    t = np.arange(0.0, float(duration), 0.02)
    q, qd, _ = reference.sample(t)
    task = _task_path(scenario)
    moves = moving_joints(arm_model(scenario.arm), task[0][::10], np.random.default_rng(0))
    return coverage(task, (q, qd), moves)


def _excitation_scenario(scenario, reference):
    return dataclasses.replace(
        scenario,
        duration=float(scenario.excite),
        reference=reference,
        swap_times=(),
        swap_masses=(),
        swap_com=(),
        swap_inertia=(),
        controllers=(EXCITATION_CONTROLLER,),
        controller_options=(),
        excite=0.0,
    )


@dataclasses.dataclass(frozen=True)
class RecordFit:
    """One record's identification (:func:`identify_record`): the consistent standard parameters
    ``pi (13 n,)``; base parameters of the weighted least squares ``hat`` and of the consistent fit
    ``fit`` ``(p,)``; the residual rms per joint ``rstd (n,)`` [N m]; what it knows of each base
    parameter ``std (p,)`` (:func:`~adaptive_dd.identification.arm_prior.identified_prior_std`) and
    with its correlations ``prior_cov (p, p)``
    (:func:`~adaptive_dd.identification.arm_prior.identified_prior_cov`); the weighted least
    squares' sandwich covariance ``cov (p, p)`` (along the ``held`` directions the record cannot
    see, the prior's: :mod:`~adaptive_dd.identification.held_directions`)."""

    pi: Array
    hat: Array
    fit: Array
    rstd: Array
    std: Array
    cov: Array
    prior_cov: Array
    held: int = 0


def identify_record(
    model, q: Array, qd: Array, tau: Array, sample_period: float, torque_held: bool = True, levels=None
) -> RecordFit:
    """Identify one measured record ``q, qd, tau (N, n)`` as ``adaptive-dd identify`` does: the
    weighted least squares with its Newey-West sandwich covariance
    (:func:`~adaptive_dd.identification.log_fit.fit_log`, every channel, every base parameter,
    ``tau_f =`` :data:`TAU_F`), the physically consistent fit nearest to it in that covariance's
    metric, and the prior it implies (:func:`~adaptive_dd.identification.arm_prior.identified_prior_std`,
    with :func:`~adaptive_dd.identification.model_error.model_error_variance`). ``torque_held``: the
    record's torque is a command held over each sample (the closed loop's), else a sampled
    continuous torque (:func:`~adaptive_dd.identification.regression.filtered_regression`).
    ``levels``: the stated uncertainty about the URDF
    (:class:`~adaptive_dd.identification.arm_prior.ArmUncertainty`, default issue 28's), the prior
    along the directions the record cannot see, which are held there
    (:mod:`~adaptive_dd.identification.held_directions`).

    Raises
    ------
    DataError
        The record does not excite some base parameter (named).
    """
    from adaptive_dd.identification.arm_prior import identified_prior_cov
    from adaptive_dd.identification.consistency import consistent_arm_fit
    from adaptive_dd.identification.held_directions import base_prior_std
    from adaptive_dd.identification.log_fit import fit_log
    from adaptive_dd.identification.model_error import model_error_variance
    from adaptive_dd.identification.regression import momentum_regressors

    n = model.n
    mom = momentum_regressors(model, q, qd)  # once, for the fit and the model error's other filters
    wls = fit_log(
        model, q, qd, tau, np.ones(n, bool), np.ones(model.p, bool), tau_f=TAU_F,
        sample_period=sample_period, torque_held=torque_held, prior_std=base_prior_std(model, levels),
        momentum=mom,
    )  # fmt: skip
    fit = consistent_arm_fit(model, wls.sigma, np.linalg.pinv(wls.cov, rcond=1e-12, hermitian=True))
    extra = model_error_variance(model, wls, q, qd, tau, torque_held, momentum=mom)
    del mom
    prior = identified_prior_cov(wls.cov, wls.sigma, fit.sigma, model_error_var=extra)
    held = wls.held.count if wls.held is not None else 0
    return RecordFit(
        fit.pi, wls.sigma, fit.sigma, wls.residual_rms, np.sqrt(np.diag(prior)), wls.cov, prior, held
    )


def identify_excitation(
    scenario, idx, run_closed_loop, progress: bool = False, scale_check: bool = True
) -> tuple[list[Array], ExcitationReport]:
    """Run the excitation on each seed's plant (``run_closed_loop``: the closed loop's runner,
    :func:`~adaptive_dd.closed_loop.runner.run_closed_loop`) and identify; returns each seed's model
    ``pi (13 n,)`` (consistent) and the report. ``progress``: what it is doing, on stderr (a bar
    per stage: the design, the excitation's closed loop, the identification of each seed).
    ``scale_check=False``: the report's ``estimator_scale`` (a check, reported and not applied) is
    not computed (None), for a caller that reads no report (the leaderboard: a tenth of each
    seed's identification).

    Raises
    ------
    ScenarioError
        ``[run] excite`` too short to identify every base parameter (named).
    """
    from adaptive_dd.closed_loop.types import io_of, plant_of, true_models
    from adaptive_dd.errors import DataError

    _stage(progress, f"run.excite: designing the excitation of the {scenario.n_joints}-joint arm (once)")
    reference = excitation_reference(scenario, progress=progress)
    exc = _excitation_scenario(scenario, reference)
    _stage(progress, f"run.excite: tracking it for {exc.duration:g} s on {len(idx)} seed(s)' plants")
    bar = _bar(progress, exc.n_samples, "run.excite: excitation", "sample")
    res = run_closed_loop(exc, seed_indices=idx, keep_trajectories=len(idx), bar=bar)
    if bar is not None:
        bar.close()
    run = res.runs[EXCITATION_CONTROLLER]
    if run.failed.any():
        raise ScenarioError(
            f"{scenario.source}: run.excite: the excitation failed on seed(s) "
            f"{[int(i) for i, f in zip(idx, run.failed, strict=True) if f]} (tracking lost)"
        )
    from adaptive_dd.identification.friction_width import identification_model
    from adaptive_dd.identification.held_directions import stated_levels
    from adaptive_dd.plant.uncertainty import stated_uncertainty

    scale_cfg = _estimator_config(scenario) if scale_check else None
    std = io_of(scenario).std
    n, T = scenario.n_joints, scenario.sample_period
    B = scenario.arm.base.B
    sig_plant = true_models(plant_of(exc, idx))[:, 0] @ B.T
    pis, kappa, widths = [], [], []
    rows = {"hat": [], "fit": [], "rstd": [], "std": [], "prior_cov": [], "held": []}
    levels = stated_levels(stated_uncertainty(scenario))
    bar = _bar(progress, len(idx), "run.excite: identifying", "seed")
    for k, i in enumerate(idx):
        rng = np.random.default_rng([int(scenario.seed), int(i), 3])
        qm = run.q[k] + std[:n] * rng.standard_normal(run.q[k].shape)
        qdm = run.qd[k] + std[n:] * rng.standard_normal(run.qd[k].shape)
        model = identification_model(scenario.arm, qdm)  # the Coulomb law's width from the record
        widths.append(model.friction_velocity)
        try:
            one = identify_record(model, qm, qdm, run.tau[k], T, levels=levels)
        except DataError as exc_:
            raise ScenarioError(
                f"{scenario.source}: run.excite = {scenario.excite} s: {exc_}; excite longer"
            ) from None
        pis.append(one.pi)
        for key in rows:
            rows[key].append(getattr(one, key))
        if scale_cfg is None:
            kappa.append(1.0)
        else:
            kappa.append(estimator_scale(scale_cfg, scenario.arm, one.prior_cov, qm, qdm, run.tau[k]))
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    report = ExcitationReport(
        float(scenario.excite), tuple(idx), tuple(model.names), sig_plant,
        np.broadcast_to(scenario.arm.sigma, sig_plant.shape).copy(), np.array(rows["hat"]),
        np.array(rows["fit"]), np.array(rows["rstd"]), np.array(rows["std"]), np.array(rows["prior_cov"]),
        np.array(widths), np.array(kappa) if scale_check else None,
        excitation_coverage(scenario, reference, scenario.excite), np.array(rows["held"]),
    )  # fmt: skip
    return pis, report


def _stage(show: bool, text: str) -> None:
    """What the phase is doing now, on stderr."""
    if show:
        import sys

        print(text, file=sys.stderr, flush=True)


def _bar(show: bool, total: int, desc: str, unit: str):
    """A progress bar on stderr, or None."""
    if not show:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, unit=unit, mininterval=0.5, unit_scale=True, leave=False)


def _estimator_config(scenario):
    """adaptive_ct's estimator settings in the scenario (None: it does not run one in mode "arm",
    or its table states its own arm prior, so nothing is handed on)."""
    from adaptive_dd.benchmark.scenario_checks import thaw
    from adaptive_dd.closed_loop.model_prior import adaptive_entries
    from adaptive_dd.controllers.registry import scenario_controller

    entries = adaptive_entries(scenario)
    if not entries:
        return None
    name = entries[0]  # adaptive_ct itself when it runs, else its first variant
    est = (thaw(dict(scenario.controller_options).get(name)) or {}).get("estimator", {})
    if isinstance(est, dict) and {"mode", "arm_uncertainty", "arm_prior_cov"} & est.keys():
        return None
    return getattr(scenario_controller(scenario, name)[1], "online", None)


def run_with_excitation(
    scenario, idx, run_closed_loop, keep: int = 3, engine: str = "auto", bar=None, scale_check: bool = True
):
    """The excitation phase, then the task with each seed's identified model (module docstring);
    ``run_closed_loop`` runs the closed loop (:func:`~adaptive_dd.closed_loop.runner.run_closed_loop`, which
    calls this function: passed in, the two modules do not import each other). ``bar``: the task's
    progress (samples, tqdm-like), advanced seed by seed; with one that shows (a ``show`` attribute
    true, or none), the phase says what it is doing on stderr. ``scale_check``: as
    :func:`identify_excitation`."""
    from adaptive_dd.closed_loop.types import plant_record
    from adaptive_dd.plant.uncertainty import exact_plant
    from adaptive_dd.plant.urdf_write import write_urdf_links

    idx = tuple(idx)
    shown = bar is not None and bool(getattr(bar, "show", True))  # --no-progress: no phase bars either
    pis, report = identify_excitation(scenario, idx, run_closed_loop, progress=shown, scale_check=scale_check)
    arm, n = scenario.arm, scenario.n_joints
    plant = scenario.plant if scenario.plant is not None else exact_plant(arm)
    parts = []
    with tempfile.TemporaryDirectory(prefix="adaptive_dd_excite_") as tmp:
        for k, (i, pi) in enumerate(zip(idx, pis, strict=True)):
            path = write_urdf_links(arm, pi[: 10 * n], Path(tmp) / f"identified_seed{i}.urdf", "identified")
            model = arm.with_(
                urdf=path, viscous=pi[10 * n : 11 * n], coulomb=pi[11 * n : 12 * n], armature=pi[12 * n :]
            )
            _ = model.pi_links, model.chain, model.base  # read while the file exists
            prior = report.sigma_cov[k]  # unscaled: estimator_scale is reported, not applied
            one = dataclasses.replace(
                scenario,
                arm=model,
                plant=plant,
                excite=0.0,
                controller_options=identified_prior(scenario, prior),
            )
            parts.append(
                run_closed_loop(one, seed_indices=(i,), keep_trajectories=1 if k < keep else 0, engine=engine)
            )
            if bar is not None:
                bar.update(scenario.n_samples * len(parts[-1].runs) / len(idx))  # the trials of one seed
    res = join_results(parts, scenario, idx)
    res.plant = plant_record(dataclasses.replace(scenario, plant=plant), idx)
    res.excitation = report.to_dict()
    res.cache["excitation_report"] = report
    return res


_PER_TRIAL = (
    "sigma_end",
    "failed",
    "failed_at",
    "q",
    "qd",
    "tau",
    "saturated",
    "sigma_hat",
    "dropped",
    "skipped",
)


def _cat(xs):
    if any(x is None for x in xs):
        return None
    return np.concatenate(xs, axis=0)


def join_results(parts: list, scenario, idx):
    """One :class:`~adaptive_dd.benchmark.types.BenchmarkResult` of per-seed runs (in order)."""
    from adaptive_dd.benchmark.types import BenchmarkResult, ControllerRun
    from adaptive_dd.closed_loop.types import StreamedSums

    first = parts[0]
    res = BenchmarkResult(scenario, first.t, first.q_d, first.sigma_true, first.mass, seed_indices=tuple(idx))
    for name, run0 in first.runs.items():
        runs = [p.runs[name] for p in parts]
        acc = StreamedSums(*(np.concatenate([getattr(r.acc, f) for r in runs]) for f in StreamedSums._fields))
        alarms = None if run0.alarm_times is None else [a for r in runs for a in r.alarm_times]
        cat = {f: _cat([getattr(r, f) for r in runs]) for f in _PER_TRIAL}
        error = "; ".join(dict.fromkeys(r.error for r in runs if r.error))
        res.runs[name] = ControllerRun(
            name=name, acc=acc, e_norm=acc.e_norm, error=error, alarm_times=alarms, floor=run0.floor,
            engine=run0.engine, **cat,
        )  # fmt: skip
    return res
