"""Figures of a benchmark's results: tracking errors, estimates, per-joint errors, ratios to the
floor (re-exported by :mod:`adaptive_dd.plotting`)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from adaptive_dd.plot_style import (
    _mark_alarms,
    _mark_swaps,
    _step,
    controller_style,
    save_figure,
    set_margins,
)

__all__ = [
    "plot_benchmark_estimates",
    "plot_joint_errors",
    "plot_payload_estimates",
    "plot_ratios",
    "plot_tracking_errors",
]


def _check_window(window, res) -> None:
    """A moving RMS's window [s]: positive and finite, at most the run."""
    from adaptive_dd.errors import ParameterError

    ok = isinstance(window, int | float) and np.isfinite(window) and 0 < window <= res.scenario.duration
    if not ok:
        raise ParameterError(
            f"window must be a time in (0, {res.scenario.duration:g}] s (the run), got {window!r}"
        )


def plot_tracking_errors(res, path: str | Path | None = None, window: float = 0.05, formats=("png",)):
    """50 ms moving RMS of ``|e|`` (mean over seeds) for every controller, swaps marked, log scale.

    The tracking error in mrad against time in s, each segment's payload [kg] written above it.

    Parameters
    ----------
    res : BenchmarkResult
        What :func:`~adaptive_dd.benchmark.runner.run_benchmark` returns.
    path : str or Path, optional
        Where to write the figure (its suffix replaced by each of ``formats``); None: not written.
    window : float
        The moving RMS's window [s].
    formats : tuple of str
        File types to write.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (closed if it was written).

    Examples
    --------
    Any result with the scenario's time axis and payload, and each controller's ``|e|`` per seed
    (here made by hand: 0.1 mrad on 2 seeds, 1 mrad for 0.2 s after the swap at 5 s):

    >>> import numpy as np
    >>> from adaptive_dd.benchmark.scenario import load_scenario
    >>> from adaptive_dd.benchmark.types import BenchmarkResult, ControllerRun
    >>> from adaptive_dd.plotting import plot_tracking_errors
    >>> sc = load_scenario()  # the default: 20 s at 1 ms, swaps at 5, 10 and 15 s
    >>> t = np.arange(sc.n_samples) * sc.sample_period  # [s]
    >>> mass = np.select([(t >= a) & (t < b) for a, b, _ in sc.segments()], [m for *_, m in sc.segments()])
    >>> e = np.full((2, t.size), 1e-4, np.float32)  # |q_d - q| [rad], seeds x samples
    >>> e[:, 5000:5200] = 1e-3
    >>> run = ControllerRun(name="my_law", acc=None, e_norm=e, sigma_end=None,
    ...                     failed=np.zeros(2, bool), failed_at=np.full(2, -1))
    >>> res = BenchmarkResult(sc, t, np.zeros((t.size, 2)), np.zeros((t.size, 7)), mass,
    ...                       runs={"my_law": run}, seed_indices=(0, 1))
    >>> fig = plot_tracking_errors(res)
    >>> fig.axes[0].get_ylabel()
    'tracking error |q_d - q|, 50 ms RMS [mrad]'
    >>> y = fig.axes[0].lines[0].get_ydata()  # [mrad]
    >>> round(float(y.min()), 3), round(float(y.max()), 3)
    (0.1, 1.0)
    """
    from adaptive_dd.benchmark.metrics import error_trace

    _check_window(window, res)
    fig, ax = plt.subplots(figsize=(10, 5))
    k = _step(res.t.size)
    for name, run in res.runs.items():
        m = error_trace(res, run, window)
        if m is None:
            continue
        ax.semilogy(res.t[::k], np.maximum(m[::k] * 1e3, 1e-4), label=name, **controller_style(name))
    _mark_swaps(ax, res.t, res.mass)
    for a, b, m in res.scenario.segments():
        ax.text(0.5 * (a + b), 1.0, f"{m:g} kg", transform=ax.get_xaxis_transform(), ha="center", va="bottom")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"tracking error |q_d - q|, {window * 1e3:.0f} ms RMS [mrad]")
    ax.grid(alpha=0.3, which="both")
    if ax.get_legend_handles_labels()[1]:
        ax.legend(fontsize=8, ncol=3)
    else:  # every trial of every controller failed (the report says why)
        ax.text(0.5, 0.5, "every trial failed", transform=ax.transAxes, ha="center", va="center")
    fig.suptitle(
        f"Tracking error of every controller on {res.scenario.name}: {window * 1e3:.0f} ms moving RMS "
        "[mrad] against time [s], mean over seeds, payload [kg] above each segment",
        fontsize=8,
        y=0.985,
    )
    set_margins(fig, left=0.85, right=0.15, bottom=0.55, top=0.6)
    if path is not None:
        save_figure(fig, path, formats, tight=False)
    return fig


def plot_benchmark_estimates(res, path: str | Path | None = None, formats=("png",)):
    """J1, J2, r and the payload mass estimated by the adaptive controllers, against the truth.

    Each estimating controller's change alarms (its first trial's) are ticks at the foot of the
    mass panel. On an N-joint arm, :func:`plot_payload_estimates`.

    Parameters
    ----------
    res : BenchmarkResult
        What :func:`~adaptive_dd.benchmark.runner.run_benchmark` returns.
    path : str or Path, optional
        Where to write the figure (its suffix replaced by each of ``formats``); None: not written.
    formats : tuple of str
        File types to write.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (closed if it was written).

    Examples
    --------
    >>> from adaptive_dd import run_benchmark
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.plotting import plot_benchmark_estimates
    >>> sc = parse_scenario({"run": {"duration": 1.0, "seeds": 1,
    ...                              "controllers": ["ct_oracle", "adaptive_ct"]},
    ...                      "payload": [{"at": 0.5, "mass": 2.0}]})
    >>> fig = plot_benchmark_estimates(run_benchmark(sc, progress=False))  # compiles on a cold cache
    >>> [ax.get_ylabel() for ax in fig.axes]
    ['J1 [kg m²]', 'J2 [kg m²]', 'r [kg m²]', 'payload mass [kg]']
    """
    paper = res.scenario.closed_forms  # the paper's sigma (J1 J2 r ...) on its closed forms' run
    if paper is None or res.sigma_true.shape[-1] != 7:
        return plot_payload_estimates(res, path, formats)
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    panels = [(0, "J1 [kg m²]"), (1, "J2 [kg m²]"), (2, "r [kg m²]")]
    s = slice(None, None, _step(res.t.size))
    t = res.t[s]
    for ax, (k, label) in zip(axes.flat[:3], panels, strict=True):
        ax.plot(t, res.sigma_true[s, k], "k--", lw=1.5, label="true")
        ax.set_ylabel(label)
    axes.flat[3].plot(t, res.mass[s], "k--", lw=1.5, label="true")
    axes.flat[3].set_ylabel("payload mass [kg]")
    for name, run in res.runs.items():
        kept = ~run.failed[: 0 if run.sigma_hat is None else run.sigma_hat.shape[0]]
        if run.sigma_hat is None or not kept.any():
            continue
        sh = run.sigma_hat[kept][:, s].mean(axis=0)
        for ax, (k, _) in zip(axes.flat[:3], panels, strict=True):
            ax.plot(t, sh[:, k], label=name, **controller_style(name))
        axes.flat[3].plot(t, paper.payload_mass_from_sigma(sh), label=name, **controller_style(name))
        _mark_alarms(axes.flat[3], run, name)
    axes.flat[3].set_ylim(-1, 5)
    title = "Estimates of the adaptive controllers against the truth"
    return _finish_estimates(fig, axes, res, title, path, formats)


def plot_payload_estimates(res, path: str | Path | None = None, formats=("png",)):
    """N-joint arms: the payload mass [kg] and centre of mass [mm] (x, y, z in the payload frame)
    that each estimating controller holds (mean over the kept seeds), against the truth.

    Parameters
    ----------
    res : BenchmarkResult
        What :func:`~adaptive_dd.benchmark.runner.run_benchmark` returns.
    path : str or Path, optional
        Where to write the figure (its suffix replaced by each of ``formats``); None: not written.
    formats : tuple of str
        File types to write.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (closed if it was written).

    Examples
    --------
    On the three-joint arm (the first run compiles its closed loop: minutes on a cold cache):

    >>> from adaptive_dd import run_benchmark
    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.plotting import plot_payload_estimates
    >>> ref = {"joint1": {"offset": 0.3, "amplitude": [0.4], "frequency": [0.3]},
    ...        "joint2": {"offset": -0.6, "amplitude": [0.5], "frequency": [0.4]},
    ...        "joint3": {"offset": 0.4, "amplitude": [0.6], "frequency": [0.5]}}
    >>> sc = parse_scenario({"arm": {"robot": "vertical3", "payload_capacity": 1.5},
    ...                      "reference": ref, "payload": [{"at": 0.5, "mass": 1.0}],
    ...                      "run": {"duration": 1.0, "seeds": 1,
    ...                              "controllers": ["ct_oracle", "adaptive_ct"]}})
    >>> fig = plot_payload_estimates(run_benchmark(sc, progress=False))
    >>> [ax.get_ylabel() for ax in fig.axes]
    ['payload mass [kg]', 'centre of mass x [mm]', 'centre of mass y [mm]', 'centre of mass z [mm]']
    """
    arm, sc = res.scenario.arm, res.scenario
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    truth = arm.payload_from_sigma(res.sigma_true)
    com_true = np.full((res.t.size, 3), np.nan)
    starts = np.searchsorted(res.t, [0.0, *sc.swap_times], side="left")
    for i, a in enumerate(starts):
        b = starts[i + 1] if i + 1 < len(starts) else res.t.size
        if i and sc.swap_masses[i - 1] > 0:
            com_true[a:b] = sc.payload_of(i - 1).get("com") or (0.0, 0.0, 0.0)
    axes.flat[0].plot(res.t, truth.mass, "k--", lw=1.5, label="true")
    axes.flat[0].set_ylabel("payload mass [kg]")
    for c, ax in enumerate(axes.flat[1:]):
        ax.plot(res.t, 1e3 * com_true[:, c], "k--", lw=1.5, label="true")
        ax.set_ylabel(f"centre of mass {'xyz'[c]} [mm]")
    for name, run in res.runs.items():
        kept = ~run.failed[: 0 if run.sigma_hat is None else run.sigma_hat.shape[0]]
        if run.sigma_hat is None or not kept.any():
            continue
        with np.errstate(invalid="ignore", divide="ignore"):
            est = arm.payload_from_sigma(run.sigma_hat[kept].mean(axis=0))
        style = controller_style(name)
        axes.flat[0].plot(res.t, est.mass, label=name, **style)
        _mark_alarms(axes.flat[0], run, name)
        com = np.where(np.abs(est.mass)[:, None] >= 0.1, est.com, np.nan)
        for c, ax in enumerate(axes.flat[1:]):
            ax.plot(res.t, 1e3 * com[:, c], label=name, **style)
    top = max(sc.swap_masses or (1.0,))
    axes.flat[0].set_ylim(-0.2 * top - 0.1, 1.4 * top + 0.1)
    for ax in axes.flat[1:]:
        ax.set_ylim(-250, 250)
    return _finish_estimates(fig, axes, res, "Payload held by the estimating controllers", path, formats)


def _finish_estimates(fig, axes, res, title: str, path, formats):
    """The estimates' panels finished: grid and swaps on each, the legend on the first, time under
    the lowest row, ``title`` with what is drawn; written to ``path`` (if given)."""
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        _mark_swaps(ax, res.t, res.mass)
    if axes.flat[0].get_legend_handles_labels()[1]:
        axes.flat[0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(
        f"{title} (mean over the seeds with kept trajectories; ticks: change alarms of the first seed)",
        fontsize=9,
    )
    set_margins(fig, left=0.9, right=0.15, bottom=0.65, top=0.45, wspace=0.25, hspace=0.08)
    if path is not None:
        save_figure(fig, path, formats, tight=False)
    return fig


def plot_joint_errors(res, path: str | Path | None = None, window: float = 0.05, formats=("png",)):
    """Small multiples, one panel per joint: the 50 ms moving RMS of ``q_d - q`` [mrad] against
    time [s] of the first kept seed of every controller (log scale, swaps marked); readable for 7
    joints.

    Parameters
    ----------
    res : BenchmarkResult
        What :func:`~adaptive_dd.benchmark.runner.run_benchmark` returns.
    path : str or Path, optional
        Where to write the figure (its suffix replaced by each of ``formats``); None: not written.
    window : float
        The moving RMS's window [s].
    formats : tuple of str
        File types to write.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (closed if it was written).

    Examples
    --------
    Any result with the reference ``q_d`` and each controller's first kept trajectory ``q``
    (here made by hand on the default scenario's two joints, off by 0.1 and 1 mrad):

    >>> import numpy as np
    >>> from adaptive_dd.benchmark.scenario import load_scenario
    >>> from adaptive_dd.benchmark.types import BenchmarkResult, ControllerRun
    >>> from adaptive_dd.plotting import plot_joint_errors
    >>> sc = load_scenario()
    >>> t = np.arange(sc.n_samples) * sc.sample_period  # [s]
    >>> q_d = np.zeros((t.size, 2))  # [rad]
    >>> q = (q_d + [1e-4, 1e-3])[None]  # (kept seeds, samples, joints) [rad]
    >>> run = ControllerRun(name="my_law", acc=None, e_norm=None, sigma_end=None,
    ...                     failed=np.zeros(1, bool), failed_at=np.full(1, -1), q=q)
    >>> res = BenchmarkResult(sc, t, q_d, np.zeros((t.size, 7)), np.zeros(t.size),
    ...                       runs={"my_law": run}, seed_indices=(0,))
    >>> fig = plot_joint_errors(res)
    >>> [ax.get_title() for ax in fig.axes[:2]]
    ['joint 1', 'joint 2']
    >>> [round(float(ax.lines[0].get_ydata().max()), 3) for ax in fig.axes[:2]]  # [mrad]
    [0.1, 1.0]
    """
    from adaptive_dd.benchmark.metrics import moving_rms

    _check_window(window, res)
    n = res.scenario.n_joints
    T = res.scenario.sample_period
    cols = 2 if n <= 4 else 3
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.4 * rows), sharex=True, squeeze=False)
    w = max(1, round(window / T))
    for name, run in res.runs.items():
        if run.q is None or not run.q.shape[0] or run.failed[0]:
            continue
        e = res.q_d - run.q[0]
        m = moving_rms(e, w, axis=0)
        for j in range(n):
            axes.flat[j].semilogy(
                res.t, np.maximum(1e3 * m[:, j], 1e-4), label=name, **controller_style(name)
            )
    for j, ax in enumerate(axes.flat):
        if j >= n:
            ax.axis("off")
            continue
        ax.set_title(f"joint {j + 1}", fontsize=9)
        ax.grid(alpha=0.3, which="both")
        _mark_swaps(ax, res.t, res.mass)
    for r in range(rows):
        axes[r, 0].set_ylabel(f"|e_j|, {window * 1e3:.0f} ms RMS [mrad]")
    for c in range(cols):  # the lowest panel drawn in each column carries the time axis
        last = max(j for j in range(c, n, cols)) if c < n else None
        if last is not None:
            axes.flat[last].set_xlabel("t [s]")
            axes.flat[last].xaxis.set_tick_params(labelbottom=True)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    if labels:
        fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 4), fontsize=8)
    else:  # every controller's first trial failed: nothing to draw (the report says why)
        fig.text(0.5, 0.5, "every controller's trial failed on this seed", ha="center", va="center")
    fig.suptitle(f"Tracking error per joint (seed {res.seed_indices[0]})")
    fig.tight_layout(rect=(0, 0.06, 1, 0.97))
    if path is not None:
        save_figure(fig, path, formats)
    return fig


def _segment_label(rows) -> str:
    """A segment's tick label: its times and mass, or their ranges where the rows differ (a population's
    arms carry their own payloads: the first row's alone named one arm's)."""

    def span(col: str, unit: str) -> str:
        lo, hi = float(rows[col].min()), float(rows[col].max())
        return f"{lo:g}{unit}" if np.isclose(lo, hi) else f"{lo:.3g}-{hi:.3g}{unit}"

    a, b = span("start_s", ""), span("end_s", "")
    times = f"{a}-{b} s" if "-" not in a + b else f"{a} to {b} s"
    return f"{times}\n{span('mass_kg', ' kg')}"


def plot_ratios(frame, path: str | Path | None = None, formats=("png",)):
    """Per controller and segment: the mean per-seed ratio to the floor with its 95 % interval
    (percentile bootstrap, the report's ``ci95``:
    :func:`~adaptive_dd.benchmark.intervals.mean_interval`).

    The benchmark's leaderboard as a figure: one group of markers per payload segment, one marker
    per controller (its colour of :data:`STYLES`), the ratio of its RMS tracking error to its
    floor's on a log scale (1: as good as the same law given the true model).

    Parameters
    ----------
    frame : pandas.DataFrame
        ``per_seed.csv`` or :meth:`BenchmarkResult.to_frame`: the columns ``controller``,
        ``segment``, ``start_s``, ``end_s``, ``mass_kg`` and ``ratio_to_floor`` (rows without a
        ratio, the floors', are left out).
    path : str or Path, optional
        Where to write the figure (its suffix replaced by each of ``formats``); None: not written.
    formats : tuple of str
        File types to write.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (closed if it was written).

    Examples
    --------
    >>> import numpy as np
    >>> import pandas as pd
    >>> from adaptive_dd.plotting import plot_ratios
    >>> rng = np.random.default_rng(0)
    >>> rows = [{"controller": c, "seed": k, "segment": s, "start_s": 5.0 * s, "end_s": 5.0 * s + 5,
    ...          "mass_kg": m, "ratio_to_floor": r * rng.lognormal(0.0, 0.05)}
    ...         for c, r in (("adaptive_ct", 1.05), ("ct_nominal", 40.0))
    ...         for s, m in enumerate((0.0, 3.0)) for k in range(10)]
    >>> fig = plot_ratios(pd.DataFrame(rows))
    >>> fig.axes[0].get_ylabel()
    'RMS error / floor RMS error, per seed [-]'
    """
    import pandas as pd

    from adaptive_dd.benchmark.intervals import mean_interval

    df = pd.DataFrame(frame)
    df = df[np.isfinite(pd.to_numeric(df["ratio_to_floor"], errors="coerce"))]
    segments = df.drop_duplicates("segment").sort_values("segment")
    names = list(dict.fromkeys(df["controller"]))
    fig, ax = plt.subplots(figsize=(max(7.5, 1.6 * len(segments) + 4.0), 4.5))
    width = 0.8 / max(len(names), 1)
    for i, name in enumerate(names):
        sub = df[df["controller"] == name]
        x = np.arange(len(segments)) + (i - (len(names) - 1) / 2) * width
        mean, err = np.full(len(segments), np.nan), np.zeros((2, len(segments)))
        for k, seg in enumerate(segments["segment"]):
            r = sub.loc[sub["segment"] == seg, "ratio_to_floor"].to_numpy(dtype=float)
            if r.size:
                mean[k] = r.mean()
                ci = mean_interval(r)  # the report's interval (ratio_statistics' ci95)
                if ci is not None:
                    err[:, k] = mean[k] - ci[0], ci[1] - mean[k]
        style = controller_style(name)
        ax.errorbar(x, mean, yerr=err, fmt="o", ms=4, capsize=3, color=style["color"], label=name)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_yscale("log")
    labels = [_segment_label(df[df["segment"] == g]) for g in segments["segment"]]
    ax.set_xticks(np.arange(len(segments)), labels)
    ax.set_xlabel("payload segment [s, kg]")
    ax.set_ylabel("RMS error / floor RMS error, per seed [-]")
    ax.grid(alpha=0.3, which="both", axis="y")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.suptitle(
        "Ratio of each controller's RMS tracking error to its floor's per payload segment: mean over "
        "seeds with its 95 % interval",
        fontsize=8,
    )
    fig.tight_layout()
    if path is not None:
        save_figure(fig, path, formats)
    return fig
