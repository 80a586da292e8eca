"""The records of ``identify --arm`` and ``predict``: the command line's files, grouped into records.

Each record is as many files as the scenario's ``[record] files`` names (one without a
``[record]`` table or without ``files``), in the same order: ``identify --arm tiago.toml p1.csv
v1.csv e1.csv p2.csv v2.csv e2.csv`` is two records of the TIAGo's three files each. An argument
ending in ``.toml`` is one record with its own ``[record]`` table (its ``files`` beside it): records
whose columns, conversions or window differ. No file on the command line: the scenario's record.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from adaptive_dd.errors import DataError, ScenarioError

__all__ = ["group_records", "read_records"]


def group_records(scenario: str, files) -> list[tuple[str, list[str] | None]]:
    """``[(description, files), ...]``: the TOML whose ``[record]`` reads each record and its files
    (None: the description's own ``files``).

    Raises
    ------
    DataError
        The CSV files are not a whole number of records (naming the count and the group size).
    """
    from adaptive_dd.io import read_toml

    if not files:
        return [(scenario, None)]
    table = read_toml(Path(scenario), ScenarioError).get("record") or {}
    own = table.get("files")
    size = len(own) if isinstance(own, list) and own else 1
    groups: list[tuple[str, list[str] | None]] = []
    csv = [f for f in files if not str(f).endswith(".toml")]
    if len(csv) % size:
        raise DataError(
            f"{len(csv)} file(s) on the command line ({', '.join(csv)}): each record is {size} file(s), as "
            f"[record] files of {scenario} names ({', '.join(map(str, own))}); give whole records, or a "
            "TOML with its own [record] per record"
        )
    pending = list(csv)
    for f in files:
        if str(f).endswith(".toml"):
            groups.append((str(f), None))
        elif pending and f == pending[0]:
            groups.append((scenario, pending[:size]))
            del pending[:size]
    return groups


def read_records(scenario: str, arm, files=None, window=None):
    """The scenario's :class:`~adaptive_dd.record.RecordSpec` and its records read, merged into one
    :class:`~adaptive_dd.record.LogRecord` whose pieces are the records' (and their gaps' pieces),
    every record on the first one's sample period; also the records one by one."""
    from adaptive_dd.cli._common import identification_tables, read_arm_log
    from adaptive_dd.record import read_log, record_spec
    from adaptive_dd.record_pieces import merge_records

    recs, names, spec0 = [], [], None
    for desc, fs in group_records(scenario, files):
        if desc == scenario and spec0 is None and not recs:
            spec, rec = read_arm_log(desc, arm, fs, window)
        else:
            from adaptive_dd.io import read_toml

            data = read_toml(Path(desc), ScenarioError)
            identification_tables(desc, data)
            table = data.get("record")
            if desc != scenario and table is None:
                raise ScenarioError(f"{desc}: a record description needs a [record] table (docs/real_log.md)")
            spec = record_spec(table, arm.joint_names, arm.joint_kinds, desc, files=fs)
            if spec.sample_period is None and recs:
                spec = dataclasses.replace(spec, sample_period=recs[0].sample_period)
            rec = read_log(spec, window=tuple(window) if window else None, arm=arm)
        spec0 = spec0 or spec
        recs.append(rec)
        names.append(rec.source)
    return spec0, merge_records(recs, names), recs
