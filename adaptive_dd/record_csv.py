"""A log file read as a table: the separator (comma, semicolon or tab) and a spreadsheet's
decimal commas found, headers stripped, rows a logger repeated whole read once
(:func:`~adaptive_dd.record.read_log` reads every file of a record through it)."""

from __future__ import annotations

import re
from pathlib import Path

from adaptive_dd.errors import DataError

__all__ = ["read_csv"]


def read_csv(path: Path):
    """``path`` as a pandas DataFrame: each row keeps its index (its line in the file), the count of
    whole rows repeated in ``attrs["repeats"]``, ``attrs["decimal_comma"]`` when the numbers were
    written with decimal commas."""
    import pandas as pd

    if not path.is_file():
        raise DataError(f"{path}: no such file")
    try:
        header = pd.read_csv(path, nrows=0).columns
        head = str(header[0]) if len(header) == 1 else ""
        sep = next((c for c in (";", "\t") if c in head), None)
        frame = pd.read_csv(path, sep=sep or ",", skipinitialspace=False)
        if sep is not None:  # one column whose name holds the separator: a semicolon or tab file
            if _decimal_commas(frame):  # 1,5 for 1.5, as spreadsheets of many locales write it
                frame = pd.read_csv(path, sep=sep, skipinitialspace=False, decimal=",")
                frame.attrs["decimal_comma"] = True
    except (ValueError, pd.errors.ParserError) as exc:
        raise DataError(f"{path}: not a readable CSV file: {exc}") from None
    frame.columns = [str(c).strip() for c in frame.columns]
    repeats = frame.duplicated(keep="first")  # a row repeated whole: a logger's repeat, no new sample
    if repeats.any():
        frame = frame[~repeats]  # each row keeps its index: its line in the file (_line)
        frame.attrs["repeats"] = int(repeats.sum())
    return frame


_DECIMAL_COMMA = re.compile(r"[+-]?(\d+,\d*|,\d+)([eE][+-]?\d+)?")


def _decimal_commas(frame) -> bool:
    """True when a text column of a semicolon or tab file holds numbers written with a decimal comma
    (every cell of it such a number or a whole one, at least one with a comma, and no cell of any
    column with a decimal point)."""
    texts = [
        frame[c].dropna().astype(str).str.strip() for c in frame.columns if frame[c].dtype.kind not in "biuf"
    ]
    whole = r"[+-]?\d+"  # a spreadsheet writes 0 as 0: whole numbers beside the comma decimals
    marked = [(v, v.str.fullmatch(_DECIMAL_COMMA.pattern)) for v in texts if v.size]
    comma = [v for v, dec in marked if dec.any() and (dec | v.str.fullmatch(whole)).all()]
    return bool(comma) and not any(v.str.contains(".", regex=False).any() for v in texts)
