"""Figures. Plotting is kept apart from computing: every function takes results. The benchmark's
figures live in :mod:`adaptive_dd.benchmark_plots`, the common style in :mod:`adaptive_dd.plot_style`;
both are importable from here."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from adaptive_dd.benchmark_plots import (
    plot_benchmark_estimates,
    plot_joint_errors,
    plot_payload_estimates,
    plot_ratios,
    plot_tracking_errors,
)
from adaptive_dd.plant.parameters import SIGMA_NAMES
from adaptive_dd.plot_style import STYLES, _mark_swaps, _save, controller_style, save_figure

__all__ = [
    "STYLES",
    "controller_style",
    "plot_benchmark_estimates",
    "plot_estimates",
    "plot_joint_errors",
    "plot_model_response",
    "plot_payload_estimates",
    "plot_ratios",
    "plot_tracking_errors",
    "plot_trajectory",
    "save_figure",
]


UNITS = ("kg m²", "kg m²", "kg m²", "N m s", "N m s", "N m", "N m")


def plot_trajectory(result, path: str | Path, trial: int = 0) -> Path:
    """Joint angles, velocities (true and measured) and torques of one trial of a simulation.

    Parameters
    ----------
    result : SimulationResult
        What :meth:`adaptive_dd.plant.ArmSimulator.run` returns (``t (N,)`` [s], ``q``, ``qd``,
        ``qd_meas``, ``tau (n_trials, N, 2)``, ``mass (n_trials, N)`` [kg]).
    path : str or Path
        The PNG to write.
    trial : int
        Which trial to draw.

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    The two-link arm driven by no torque for 0.2 s, drawn to a file:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from adaptive_dd.plant.simulator import simulate_open_loop
    >>> from adaptive_dd.plotting import plot_trajectory
    >>> result = simulate_open_loop(np.zeros((1, 200, 2)), np.random.default_rng(0))
    >>> path = plot_trajectory(result, Path(tempfile.mkdtemp()) / "trajectory.png")
    >>> path.name, path.is_file()
    ('trajectory.png', True)
    """
    t = result.t
    fig, ax = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    for j, c in enumerate(("C0", "C1")):
        ax[0].plot(t, result.q[trial, :, j], c, label=f"q{j + 1}")
        ax[1].plot(t, result.qd_meas[trial, :, j], c, alpha=0.3, lw=0.5)
        ax[1].plot(t, result.qd[trial, :, j], c, label=f"qd{j + 1}")
        ax[2].plot(t, result.tau[trial, :, j], c, label=f"tau{j + 1}")
    ax[0].set_ylabel("q [rad]")
    ax[1].set_ylabel("qd [rad/s]\n(light: measured)")
    ax[2].set_ylabel("torque [N m]")
    ax[2].set_xlabel("t [s]")
    for a in ax:
        a.legend(loc="upper right", fontsize=8)
        a.grid(alpha=0.3)
    _mark_swaps(ax, result.t, result.mass[trial])
    return _save(fig, path)


def plot_estimates(
    t,
    theta,
    sigma_true,
    path: str | Path,
    title: str = "",
    names=SIGMA_NAMES,
    reference_label: str = "true value",
    alarms=(),
) -> Path:
    """Estimates over time (mean over trials, band of +-1 std), a reference dashed (Fig. 5).

    One panel per base parameter of the paper's arm, each with its unit; the change detector's
    alarms as vertical red lines.

    Parameters
    ----------
    t : array_like, shape (n_samples,)
        Sample instants [s].
    theta : array_like, shape (n_trials, n_samples, 7)
        The estimates, in the order of ``names`` (the paper's J1 J2 r b1 b2 d1 d2).
    sigma_true : array_like, shape (7,) or (n_samples, 7)
        The reference drawn dashed: the true value, or the final estimate when the truth is
        unknown.
    path : str or Path
        The PNG to write.
    title : str
        The figure's title.
    names : sequence of str
        The seven parameters' names, for the axis labels.
    reference_label : str
        What the dashed line is, for the legend.
    alarms : sequence of float
        Alarm times [s], marked by vertical lines.

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> from adaptive_dd.plant import ClosedFormTwoLink
    >>> from adaptive_dd.plotting import plot_estimates
    >>> t = np.arange(0, 2, 1e-3)
    >>> rng = np.random.default_rng(0)
    >>> settle = (1 - np.exp(-t / 0.2))[None, :, None]
    >>> sigma = ClosedFormTwoLink.sice().sigma  # the paper's Table 1
    >>> theta = sigma * settle + 0.01 * rng.standard_normal((3, t.size, 7))
    >>> plot_estimates(t, theta, sigma, f"{tempfile.mkdtemp()}/estimates.png",
    ...                alarms=[1.0]).name
    'estimates.png'
    """
    theta = np.asarray(theta)
    st = np.broadcast_to(np.asarray(sigma_true), (theta.shape[1], 7))
    fig, axes = plt.subplots(4, 2, figsize=(10, 9), sharex=True)
    for k, ax in enumerate(axes.flat[:7]):
        m, s = theta[..., k].mean(0), theta[..., k].std(0)
        ax.plot(t, m, "C0", lw=1)
        ax.fill_between(t, m - s, m + s, color="C0", alpha=0.25, lw=0)
        ax.plot(t, st[:, k], "k--", lw=1)
        lo, hi = np.nanmin(st[:, k]), np.nanmax(st[:, k])
        pad = 0.6 * max(hi - lo, abs(hi), 1e-3)
        ax.set_ylim(lo - pad, hi + pad)
        ax.set_ylabel(f"{names[k]} [{UNITS[k]}]")
        ax.grid(alpha=0.3)
        for a in alarms:
            ax.axvline(a, color="C3", lw=0.8, alpha=0.7)
    axes.flat[7].axis("off")
    axes.flat[7].text(
        0.05,
        0.5,
        f"solid: estimate (mean ± std over seeds)\ndashed: {reference_label}"
        + ("\nred lines: change alarms" if len(alarms) else ""),
        transform=axes.flat[7].transAxes,
    )
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(title)
    return _save(fig, path)


def plot_model_response(t, q_arm, models: dict, path: str | Path, title: str = "") -> Path:
    """The arm and identified model(s) driven by the same torque (Fig. 7 of the paper).

    Parameters
    ----------
    t : array_like, shape (n_samples,)
        Sample instants [s].
    q_arm : array_like, shape (n_samples, 2)
        The arm's joint angles [rad].
    models : dict of str to array_like, shape (n_samples, 2)
        Each model's joint angles [rad] under the same torque, by label.
    path : str or Path
        The PNG to write.
    title : str
        The figure's title.

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> from adaptive_dd.plotting import plot_model_response
    >>> t = np.linspace(0, 1, 100)
    >>> q = np.column_stack([np.sin(t), np.cos(t)])
    >>> plot_model_response(t, q, {"M2": 1.01 * q}, f"{tempfile.mkdtemp()}/response.png").name
    'response.png'
    """
    fig, ax = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    for j in range(2):
        ax[j].plot(t, q_arm[:, j], "k", lw=2.0, label="arm")
        for i, (label, q) in enumerate(models.items()):
            ax[j].plot(t, q[:, j], f"C{i + 1}--", lw=1.2, label=label)
        ax[j].set_ylabel(f"q{j + 1} [rad]")
        ax[j].grid(alpha=0.3)
        ax[j].legend(loc="upper right", fontsize=8)
    ax[-1].set_xlabel("t [s]")
    fig.suptitle(title)
    return _save(fig, path)
