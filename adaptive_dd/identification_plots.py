"""Figures of N-joint identification (apart from the computing, as :mod:`adaptive_dd.plotting`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["plot_torque_fit"]


def plot_torque_fit(
    t: NDArray[np.float64],
    measured: NDArray[np.float64],
    predicted: NDArray[np.float64],
    path: str | Path,
    title: str = "",
    labels=None,
):
    """Measured against predicted (filtered) torque per joint, with the residual.

    One panel per channel: torque [N m] against time [s].

    Parameters
    ----------
    t : ndarray, shape (N,)
        Sample instants [s].
    measured, predicted : ndarray, shape (N, n)
        The measured (filtered) and the model's torques [N m].
    path : str or Path
        The PNG to write.
    title : str
        The figure's title.
    labels : sequence of str, optional
        The n channels' names (default ``tau1 .. taun``).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written and closed.

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> from adaptive_dd.identification_plots import plot_torque_fit
    >>> t = np.linspace(0, 2, 200)
    >>> measured = np.column_stack([np.sin(t), np.cos(t)])
    >>> fig = plot_torque_fit(t, measured, 0.98 * measured, f"{tempfile.mkdtemp()}/fit.png",
    ...                       labels=["shoulder", "elbow"])
    >>> [ax.get_ylabel() for ax in fig.axes]
    ['shoulder [N m]', 'elbow [N m]']
    """
    import matplotlib.pyplot as plt

    n = measured.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(9, 1.6 * n + 0.8), sharex=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        ax.plot(t, measured[:, j], lw=0.8, color="0.3", label="measured (filtered)")
        ax.plot(t, predicted[:, j], lw=0.8, ls="--", color="tab:red", label="predicted")
        ax.plot(t, measured[:, j] - predicted[:, j], lw=0.6, color="tab:blue", label="residual")
        ax.set_ylabel(f"{labels[j] if labels is not None else f'tau{j + 1}'} [N m]", fontsize=8)
    axes[0, 0].legend(loc="upper right", fontsize=7, ncol=3)
    axes[-1, 0].set_xlabel("t [s]")
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return fig
