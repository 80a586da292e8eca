"""The figures' common style: one colour and line style per controller, saving, the swaps' and
alarms' marks (:mod:`adaptive_dd.plotting`, :mod:`adaptive_dd.benchmark_plots`)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

__all__ = ["MAX_POINTS", "STYLES", "controller_style", "save_figure", "set_margins"]


def _save(fig, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


STYLES = {
    "ct_oracle": ("black", "-", 2.4, 1),
    "ct_oracle_textbook": ("0.45", "-", 1.6, 1),
    "slotine_li_oracle": ("tab:green", "-", 2.4, 1),
    "adaptive_ct": ("tab:blue", "-", 1.0, 3),
    "adaptive_ct_paper": ("tab:orange", "-.", 1.0, 2),
    "slotine_li": ("darkgreen", "--", 1.0, 2),
    "ct_nominal": ("tab:red", "--", 1.0, 2),
    "pd": ("tab:purple", ":", 1.0, 2),
    "ct_oracle_late": ("0.3", "--", 1.6, 1),
    "pd_gravity": ("goldenrod", "-", 1.0, 3),
    "pd_gravity_oracle": ("goldenrod", "-", 2.4, 1),
    "sliding_mode": ("tab:pink", "-", 1.0, 3),
    "composite": ("tab:brown", "-", 1.0, 3),
    "craig_hsu_sastry": ("navy", "-", 1.0, 3),
    "icl": ("tab:olive", "-", 1.0, 3),
    "natural_adaptive": ("tab:cyan", "-", 1.0, 3),
    "momentum_observer_ct": ("teal", "--", 1.0, 3),
}
"""(colour, line style, width, z-order) of each built-in controller, the same in every figure, no
two alike; oracles are drawn wide and underneath (a law's oracle in the law's colour), so the
adaptive curve stays visible on top of them."""
_EXTRA = ("tab:gray", "gold", "lightcoral", "darkviolet", "olivedrab", "sienna", "steelblue", "crimson")


def controller_style(name: str) -> dict:
    """Line properties of a controller: :data:`STYLES`, or a colour fixed by its name."""
    import zlib

    if name in STYLES:
        c, ls, lw, z = STYLES[name]
    elif name.endswith("_oracle"):  # a plug-in's floor: its law's colour, wide and underneath
        c = controller_style(name.removesuffix("_oracle"))["color"]
        ls, lw, z = "-", 2.4, 1
    else:
        c, ls, lw, z = _EXTRA[zlib.crc32(name.encode()) % len(_EXTRA)], "-", 1.0, 3
    return {"color": c, "ls": ls, "lw": lw, "zorder": z}


def save_figure(
    fig, path: str | Path, formats: tuple[str, ...] = ("png",), *, tight: bool = True
) -> list[Path]:
    """Write ``fig`` as ``path`` with each suffix of ``formats`` (png, pdf, svg); close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to write.
    path : str or Path
        The file's path; its suffix is replaced by each of ``formats``. Missing folders are made.
    formats : tuple of str
        File types matplotlib can write, without the dot.
    tight : bool
        Crop the page to what is drawn (``bbox_inches="tight"``: one more pass over every artist);
        False for a figure whose margins are already set (:func:`set_margins`).

    Returns
    -------
    list of Path
        The files written, one per format.

    Examples
    --------
    >>> import tempfile, matplotlib.pyplot as plt
    >>> from adaptive_dd.plotting import save_figure
    >>> fig, ax = plt.subplots()
    >>> folder = tempfile.mkdtemp()
    >>> [p.name for p in save_figure(fig, f"{folder}/error", ("png", "svg"))]
    ['error.png', 'error.svg']
    """
    path = Path(path)
    out = []
    for f in formats:
        p = path.with_suffix("." + f)
        p.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(p, dpi=120, bbox_inches="tight" if tight else None)
        out.append(p)
    plt.close(fig)
    return out


def set_margins(fig, left: float, right: float, bottom: float, top: float, **space) -> None:
    """Place a figure's axes by margins in inches (``space``: ``wspace``, ``hspace`` as
    :meth:`~matplotlib.figure.Figure.subplots_adjust` takes them): the benchmark's figures
    have a known content, so they skip the layout pass that measures every label."""
    w, h = fig.get_size_inches()
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h, **space)


MAX_POINTS = 5000
"""Points per plotted line of the benchmark figures (a 20 s run at 1 kHz is drawn every 4th
sample: the lines are 50 ms moving RMS and estimates, smooth at that scale)."""


def _step(n: int) -> int:
    return max(1, -(-n // MAX_POINTS))


def _mark_swaps(axes, t, mass) -> None:
    idx = np.flatnonzero(np.diff(mass) != 0) + 1
    for a in np.atleast_1d(axes):
        for i in idx:
            a.axvline(t[i], color="k", ls=":", lw=1)


def _mark_alarms(ax, run, name: str, most: int = 50) -> None:
    """The change alarms of a controller's first trial as ticks at the panel's foot, in its colour."""
    alarms = getattr(run, "alarm_times", None)
    if not alarms or alarms[0] is None:
        return
    color = controller_style(name)["color"]
    for t in list(np.asarray(alarms[0], dtype=float).ravel())[:most]:
        ax.axvline(t, ymin=0.0, ymax=0.06, color=color, lw=1.5)
