"""The leaderboard as a LaTeX table for a paper: ``leaderboard.tex`` beside ``leaderboard.csv``.

The table of ``docs/leaderboard.md`` ("leaderboard-table"), in ``booktabs`` form: a row per law
ranked against the others (:func:`~adaptive_dd.arena.leaderboard.contenders`), its floor, and per
column (each given scenario's heaviest segment, then every segment of the drawn arms pooled) the
mean over seeds of the per-seed ratio of its RMS error to its floor's, the p90 in brackets, and
``$\\times N$`` when N trials failed. In each column the law with the lowest RMS error (``rms_rank``
1: the controllers of a column meet the same robots, noise and swaps, so their errors compare
where ratios to different floors do not) is set in bold. A comment above the table gives the
command that wrote the numbers (:func:`~adaptive_dd.arena.page.command_of`).

The columns are set in panels stacked in one ``table*`` float under one caption (the given
scenarios, then the drawn arms), as few as fit a page's text width (:data:`TEXT_WIDTH_PT`: a
1-inch-margin article's 6.5 in) at ``\\small``: a row of ten or more columns does not, and
scaling it down would shrink its type below the caption's.

Write it with ``adaptive-dd leaderboard ... --out DIR`` (``DIR/leaderboard.tex``), or from a
table already written with :func:`write_latex`; the document needs ``\\usepackage{booktabs}``.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from adaptive_dd.arena.columns import contenders, references
from adaptive_dd.arena.page import _columns, command_of, table_rows
from adaptive_dd.benchmark.preflight import (
    GAINS_APART as _GAINS,
)  # a floor_note's words: its law at other gains

__all__ = ["TEXT_WIDTH_PT", "latex_table", "write_latex"]

#: The width a panel may take [pt]: 6.5 in (a 1-inch-margin article; a two-column paper's full
#: width is wider) less 10 pt for the estimate's error (``tests/test_arena_page.py`` typesets tables
#: with ``pdflatex`` where it is installed: no overfull line)
TEXT_WIDTH_PT = 460.0
#: ``\\tabcolsep`` [pt], each side of a column
SEP_PT = 4.0

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


def _width(text: str, tt: bool = False) -> float:
    """The width [pt] of a cell's ``text`` (LaTeX) set at ``\\small`` (9 pt Computer Modern), from
    its visible characters, a little generous (against TeX's own: 69.1 pt for a scenario's name of
    17 letters, 52.4 for "1.012 (1.025)", 55.6 with the mean in bold): in typewriter type ``tt``
    every glyph is 4.59 pt."""
    bold = re.findall(r"\\textbf\{([^}]*)\}", text)
    for cmd in ("\\textbf{", "\\texttt{", "\\multicolumn{1}{c}{", "$", "}", "^\\dagger"):
        text = text.replace(cmd, "")
    text = text.replace("\\times ", "x").replace("\\_", "_").replace("~", " ")
    if tt:
        return 4.65 * len(text)
    return sum(_GLYPH.get(ch, 7.0) for ch in text) + sum(0.9 * len(b) for b in bold)


#: Glyph widths [em] of Computer Modern Roman (cmr10's metrics; "x" stands for the failures'
#: multiplication sign, "_" for ``\\_``), set at 9.3 pt: a little wider than ``\\small``'s cmr9
_EM = dict(zip("abcdefghijklmnopqrstuvwxyz", (
    0.5, 0.556, 0.444, 0.556, 0.444, 0.306, 0.5, 0.556, 0.278, 0.306, 0.528, 0.278, 0.833, 0.556, 0.5,
    0.556, 0.528, 0.392, 0.394, 0.389, 0.556, 0.528, 0.722, 0.528, 0.528, 0.444,
), strict=True))  # fmt: skip
_GLYPH = {k: 9.3 * v for k, v in _EM.items()} | dict.fromkeys("0123456789", 4.7)
_GLYPH |= {".": 2.6, ",": 2.6, " ": 3.1, "(": 3.7, ")": 3.7, "-": 3.1, ":": 2.6, "x": 7.2, "_": 4.7}


def _panels(cells: dict, names: list[str], pooled: set[str]) -> list[list[tuple[str, int]]]:
    """The columns (``cells``: per column its heading and cells, as set) in panels that fit
    :data:`TEXT_WIDTH_PT` beside ``names`` (the laws' and the floors' columns, as set): the given
    scenarios' columns split as evenly as fits, then the drawn arms' segments (scenarios in
    ``pooled``) likewise; never one panel across both, their headings differ."""
    fixed = sum(max(_width(t, tt=True) for t in col) for col in names)
    col = {c: max(map(_width, ts)) for c, ts in cells.items()}
    groups: dict[bool, list] = {False: [], True: []}
    for sc, seg in cells:
        groups[sc in pooled].append((sc, seg))
    panels = []
    for g in groups.values():
        for k in range(1, len(g) + 1):  # the fewest panels that fit (one column each at worst)
            split = [g[j * len(g) // k : (j + 1) * len(g) // k] for j in range(k)]
            if all(
                fixed + sum(col[c] for c in pn) + 2 * SEP_PT * (len(pn) + 2) <= TEXT_WIDTH_PT for pn in split
            ):
                break
        panels += split if g else []
    return panels


def _heading(df, panel, pooled: set[str]) -> list[str]:
    """A panel's heading rows: the scenario over its column (the drawn arms' name once, over their
    segments, with a rule), then the column's payload (:func:`_heads`)."""
    n = len(panel)
    low = "controller & floor & " + " & ".join(_heads(df, *c, pooled)[-1] for c in panel) + " \\\\"
    if panel[0][0] in pooled:
        m = re.fullmatch(r"population\((\d+) arms?\)", panel[0][0])
        arms = f"{m[1]} drawn arm{'s' if m[1] != '1' else ''}" if m else panel[0][0]
        top = f" & & \\multicolumn{{{n}}}{{c}}{{{_tex(arms)}, pooled}} \\\\"
        return [top, f"\\cmidrule(lr){{3-{n + 2}}}", low]
    return [" & & " + " & ".join(_heads(df, *c, pooled)[0] for c in panel) + " \\\\", low]


def _heads(df, sc: str, seg: int, pooled: set[str]) -> list[str]:
    """A column's own headings: the scenario's name and its heaviest segment's payload, or a
    segment of the drawn arms and its mean payload."""
    g = df[(df["scenario"] == sc) & (df["segment"] == seg)]
    kg = f"{g['payload_kg'].iloc[0]:.3g}~kg"
    return [f"seg.~{seg}: {kg}"] if sc in pooled else [f"\\multicolumn{{1}}{{c}}{{{_tex(sc)}}}", kg]


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
    >>> print("\\n".join(latex_table(pd.DataFrame(rows)).splitlines()[9:14]))
    \\begin{tabular}{llr}
    \\toprule
     & & \\multicolumn{1}{c}{ur5\\_tool\\_swap} \\\\
    controller & floor & 5~kg \\\\
    \\midrule
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
        + ("; $\\dagger$: told the true model, a reference, not ranked" if told.any() else "")
        + (
            "; $\\ddagger$: the law ran at another bandwidth or damping than its floor (floor\\_note)"
            if "floor_note" in df and df["floor_note"].astype(str).str.contains(_GAINS).any()
            else ""
        )
        + "."
    )
    lines = [
        f"% {command or command_of(df)}",
        "% written by adaptive_dd (adaptive_dd.arena.latex); needs \\usepackage{booktabs}",
        "\\begin{table*}",
        "\\centering",
        "\\small",
        f"\\caption{{{caption}}}",
        "\\label{tab:leaderboard}",
        "\\setlength{\\tabcolsep}{4pt}",
    ]
    names = set(df.loc[df["kind"] == "population", "scenario"])
    mark = {c: "$^\\dagger$" if c in reference else "" for c in df["controller"]}
    rows = [
        (f"\\texttt{{{_tex(c)}}}{mark[c]}", f"\\texttt{{{_tex(f)}}}", [_cell(r) for r in rs])
        for c, f, rs in table_rows(ranked, cols)
    ]
    set_as = {c: [*_heads(df, *c, names), *(r[2][k] for r in rows)] for k, c in enumerate(cols)}
    laws = ([r[0] for r in rows] or ["controller"], [r[1] for r in rows] or ["floor"])
    for k, panel in enumerate(_panels(set_as, laws, names)):
        idx = [cols.index(c) for c in panel]
        lines += ["\\medskip"] if k else []
        lines += ["\\begin{tabular}{ll" + "r" * len(panel) + "}", "\\toprule", *_heading(df, panel, names)]
        lines.append("\\midrule")
        lines += [
            f"{name} & {floor} & " + " & ".join(cells[i] for i in idx) + " \\\\"
            for name, floor, cells in rows
        ]
        lines += ["\\bottomrule", "\\end{tabular}", ""]
    lines[-1:] = ["\\end{table*}", ""]
    return "\n".join(lines)


def _cell(r) -> str:
    """A law's cell of a column (``r``, its table row, or None: "--"): the mean ratio (bold at the
    column's lowest RMS error), the p90 in brackets, the failed trials."""
    if r is None:
        return "--"
    mean = _num(r["ratio_mean"])
    mean = f"\\textbf{{{mean}}}" if r.get("rms_rank") == 1 else mean
    fail = f" $\\times {int(r['failures'])}$" if r["failures"] else ""
    gains = "$^\\ddagger$" if _GAINS in str(r.get("floor_note") or "") else ""
    return f"{mean}{gains} ({_num(r['ratio_p90'])}){fail}"


def write_latex(df, path, command: str | None = None) -> Path:
    """Write :func:`latex_table` of ``df`` (made by ``command``) to ``path`` (``.tex``); returns the path."""
    path = Path(path)
    path.write_text(latex_table(df, command=command), encoding="utf-8")
    return path
