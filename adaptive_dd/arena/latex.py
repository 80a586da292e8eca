"""The leaderboard as a LaTeX table for a paper: ``leaderboard.tex`` beside ``leaderboard.csv``.

The table of ``docs/leaderboard.md`` ("leaderboard-table"), in ``booktabs`` form: a row per law
ranked against the others (:func:`~adaptive_dd.arena.leaderboard.contenders`), its floor, and per
column (each given scenario's heaviest segment, then every segment of the drawn arms pooled) the
mean over seeds of the per-seed ratio of its RMS error to its floor's, the p90 in brackets, and
``$\\times N$`` when N trials failed. In each column the law with the lowest RMS error (``rms_rank``
1: the controllers of a column meet the same robots, noise and swaps, so their errors compare
where ratios to different floors do not) is set in bold. A comment above the table gives the
command that wrote the numbers (:func:`~adaptive_dd.arena.page.command_of`).

Write it with ``adaptive-dd leaderboard ... --out DIR`` (``DIR/leaderboard.tex``), or from a
table already written with :func:`write_latex`; the document needs ``\\usepackage{booktabs}``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from adaptive_dd.arena.columns import contenders, references
from adaptive_dd.arena.page import _columns, command_of, table_rows

__all__ = ["latex_table", "write_latex"]

_SPECIAL = {"\\": r"\textbackslash{}", "_": r"\_", "%": r"\%", "&": r"\&", "#": r"\#", "$": r"\$"}
_SPECIAL |= {"{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}"}


def _tex(text: str) -> str:
    """``text`` with LaTeX's special characters escaped (names such as ``adaptive_ct``)."""
    return "".join(_SPECIAL.get(ch, ch) for ch in str(text))


def _num(x: float) -> str:
    """A ratio as the page prints it: three decimals below 10, three significant figures above
    (a whole number from 1000 on, not an exponent)."""
    if not np.isfinite(x):
        return "--"
    return f"{x:.3f}" if abs(x) < 10 else f"{x:.3g}" if abs(x) < 1000 else f"{x:.0f}"


def latex_table(df, caption: str | None = None, command: str | None = None) -> str:
    """The leaderboard ``df`` (:func:`~adaptive_dd.arena.leaderboard.leaderboard`, or
    :func:`~adaptive_dd.arena.page.read_table` of its CSV) as a ``booktabs`` LaTeX table
    (module docstring). ``caption``: the table's caption (default: what the cells are);
    ``command``: the command that made it, in the first line's comment (default: the one
    :func:`~adaptive_dd.arena.page.command_of` reads back from the rows).

    Examples
    --------
    >>> import pandas as pd
    >>> from adaptive_dd.arena.latex import latex_table
    >>> rows = [dict(scenario="ur5_tool_swap", kind="scenario", controller=c, floor=f, segment=1,
    ...              payload_kg=5.0, seeds=10, ratio_mean=m, ratio_p90=p, failures=0,
    ...              rms_error_mrad=e, rms_rank=r)
    ...         for c, f, m, p, e, r in [("adaptive_ct", "ct_oracle", 1.013, 1.07, 0.10, 1),
    ...                                  ("slotine_li", "slotine_li_oracle", 32.4, 34.5, 4.9, 2)]]
    >>> print(latex_table(pd.DataFrame(rows)).splitlines()[9])
    \\texttt{adaptive\\_ct} & \\texttt{ct\\_oracle} & \\textbf{1.013} (1.070) \\\\
    """
    cols = _columns(df)
    told = references(df)  # shown, not ranked
    ranked = df[contenders(df) | told]
    reference = set(df.loc[told, "controller"])
    # the trials per scenario and per drawn arm (failed ones too), as command_of reads them back
    trials = df.loc[df["kind"] != "population", ["seeds", "failures"]].sum(axis=1, min_count=1)
    n = int(trials.max()) if trials.notna().any() else 0
    pooled = bool((df["kind"] == "population").any())
    caption = caption or (
        "Ratio of each law's RMS tracking error to its floor's (the same law given the true model), "
        + (
            f"mean over {n} seeds per scenario" + (" and per drawn arm" if pooled else "")
            if n
            else "mean over the seeds"
        )
        + " (p90), in each scenario's heaviest payload segment"
        + (" and every segment of the drawn arms, pooled over them" if pooled else "")
        + "; bold: the lowest RMS error of the column; $\\times N$: N trials failed"
        + ("; $\\dagger$: told the true model, a reference, not ranked." if told.any() else ".")
    )
    heads = []
    for sc, seg in cols:
        g = df[(df["scenario"] == sc) & (df["segment"] == seg)]
        heads.append(f"{_tex(sc)}:{seg} ({g['payload_kg'].iloc[0]:.3g} kg)")
    lines = [
        f"% {command or command_of(df)}",
        "% written by adaptive_dd (adaptive_dd.arena.latex); needs \\usepackage{booktabs}",
        "\\begin{table}",
        "\\centering",
        f"\\caption{{{caption}}}",
        "\\begin{tabular}{ll" + "r" * len(cols) + "}",
        "\\toprule",
        "controller & floor & " + " & ".join(heads) + " \\\\",
        "\\midrule",
    ]
    for ctrl, floor, rows in table_rows(ranked, cols):
        cells = []
        for r in rows:
            if r is None:
                cells.append("--")
                continue
            mean = _num(r["ratio_mean"])
            mean = f"\\textbf{{{mean}}}" if r.get("rms_rank") == 1 else mean
            fail = f" $\\times {int(r['failures'])}$" if r["failures"] else ""
            cells.append(f"{mean} ({_num(r['ratio_p90'])}){fail}")
        mark = "$^\\dagger$" if ctrl in reference else ""
        lines.append(
            f"\\texttt{{{_tex(ctrl)}}}{mark} & \\texttt{{{_tex(floor)}}} & " + " & ".join(cells) + " \\\\"
        )
    lines += ["\\bottomrule", "\\end{tabular}", "\\end{table}", ""]
    return "\n".join(lines)


def write_latex(df, path, command: str | None = None) -> Path:
    """Write :func:`latex_table` of ``df`` (made by ``command``) to ``path`` (``.tex``); returns the path."""
    path = Path(path)
    path.write_text(latex_table(df, command=command), encoding="utf-8")
    return path
