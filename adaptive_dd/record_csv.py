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
    whole rows repeated in ``attrs["repeats"]``, and ``attrs["notes"]``: what was read otherwise than
    written (numbers with decimal commas; a last line cut short, left out)."""
    import pandas as pd

    if not path.is_file():
        raise DataError(f"{path}: no such file")
    notes: list[str] = []
    try:
        header = pd.read_csv(path, nrows=0).columns
        head = str(header[0]) if len(header) == 1 else ""
        sep = next((c for c in (";", "\t") if c in head), None)
        frame = pd.read_csv(path, sep=sep or ",", skipinitialspace=False)
        if sep is not None:  # one column whose name holds the separator: a semicolon or tab file
            if _decimal_commas(frame):  # 1,5 for 1.5, as spreadsheets of many locales write it
                frame = pd.read_csv(path, sep=sep, skipinitialspace=False, decimal=",")
                for c in frame.columns:  # a column with a bad cell (ERR) stays text: its numbers too
                    if frame[c].dtype.kind == "O":
                        v = frame[c].astype(str).str.strip()
                        dec = v.str.fullmatch(_DECIMAL_COMMA.pattern)
                        frame[c] = frame[c].where(~dec, v.str.replace(",", ".", regex=False))
                notes.append(f"{path}: numbers written with a decimal comma, read as such")
    except (ValueError, pd.errors.ParserError) as exc:
        raise DataError(f"{path}: not a readable CSV file: {exc}") from None
    if len(frame) and _cut_short(path):  # a logger stopped mid-row: its last number may be cut too
        notes.append(
            f"{path}: line {len(frame) + 1}, the last, has no line end (a logger stopped in the middle of "
            "writing it): left out"
        )
        frame = frame.iloc[:-1]
    frame.columns = [str(c).strip() for c in frame.columns]
    repeats = frame.duplicated(keep="first")  # a row repeated whole: a logger's repeat, no new sample
    if repeats.any():
        frame = frame[~repeats]  # each row keeps its index: its line in the file (_line)
        frame.attrs["repeats"] = int(repeats.sum())
    frame.attrs["notes"] = notes
    return frame


def _cut_short(path: Path) -> bool:
    """Whether the file (gzip-compressed when it is named ``.gz``) does not end with a line end."""
    if path.suffix == ".gz":  # no seeking into a stream: read through it, a block at a time
        import gzip

        last = b""
        with gzip.open(path, "rb") as fh:
            while block := fh.read(1 << 20):
                last = block[-1:]
        return bool(last) and last not in (b"\n", b"\r")
    with path.open("rb") as fh:
        fh.seek(0, 2)
        if fh.tell() == 0:
            return False
        fh.seek(-1, 2)
        return fh.read(1) not in (b"\n", b"\r")


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
    comma = [v for v, dec in marked if dec.any() and (dec | v.str.fullmatch(whole)).mean() >= 0.95]
    numeric = [v for v in texts if v.str.fullmatch(r"[+-]?[\d.,]+([eE][+-]?\d+)?").mean() >= 0.95]
    return bool(comma) and not any(v.str.contains(".", regex=False).any() for v in numeric)
