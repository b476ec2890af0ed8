"""The results table of a sweep: ``results.parquet`` and ``results.csv``, one row a point.

Columns, in order: ``point`` (the point's number), one column per swept key named by the
key (numbers stay numbers; text, lists and mappings are written as text, lists and
mappings as JSON), then the point's record (:func:`~.worker.point_record`): ``status``
(completed / failed / interrupted), ``criterion`` (what the run failed on), the path
completed [%] and the time lost to slowing the task [s], the worst realised range and
speed ratio of the leader, the follower and the grasp (above 1 is outside the limit) and
the worst of them all, the same after the start-up recovery with the time it took [s]
and the smallest joint margin from then on [rad] (:mod:`.recovery`), the smallest joint
margin [rad] and grasp margin [m] of the whole run, the worst closure and leader
tracking errors [m, rad], the step-time median and 99th percentile [s], the number of
steps of each status, the point's wall time [s] and the worker that ran it, the
message, and ``key`` (the point's identity in the store).

A point not run yet when a sweep stopped has status ``interrupted``, its criterion saying
why, and no numbers. Both files are written atomically: a reader sees the previous
complete table or the new one. Missing numbers are NaN in Parquet, empty in the CSV.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .._io import atomic_open, atomic_write_with
from .points import PointTask
from .worker import empty_record

PARQUET_FILE = "results.parquet"
CSV_FILE = "results.csv"

#: Columns before the record's: the point's number (the swept keys follow).
POINT_COLUMN = "point"

#: Record fields that are not table columns.
_NOT_COLUMNS = ("key", "code")


def _record_columns() -> list[str]:
    cols = [c for c in empty_record("failed", None, "") if c not in _NOT_COLUMNS]
    cols.remove("message")
    return [*cols, "message", "key"]


def _cell(value: Any) -> Any:
    """Return a swept value as one table cell: a number, a boolean or text."""
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    return json.dumps(value, sort_keys=True)


def _value_type(values: Sequence[Any]) -> str:
    """``"int"``, ``"float"``, ``"bool"`` or ``"str"``: the type of a swept column."""
    if values and all(isinstance(v, bool) for v in values):
        return "bool"
    if values and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return "int" if all(isinstance(v, int) for v in values) else "float"
    return "str"


def build_rows(tasks: Sequence[PointTask], swept: Sequence[str],
               records: dict[str, dict[str, Any]],
               pending_reason: str = "not run") -> list[dict[str, Any]]:
    """One row per point, in point order.

    Parameters
    ----------
    tasks : sequence of PointTask
        The sweep's points.
    swept : sequence of str
        The swept keys (column names).
    records : dict
        Stored records by point key.
    pending_reason : str
        Criterion of the points that have no record (status ``interrupted``).
    """
    rows = []
    for t in tasks:
        rec = records.get(t.key) or {**empty_record("interrupted", pending_reason, ""),
                                     "key": t.key}
        row: dict[str, Any] = {POINT_COLUMN: t.index}
        row.update({k: t.values.get(k) for k in swept})
        row.update({c: rec.get(c) for c in _record_columns()})
        rows.append(row)
    return rows


def _column_types(rows: Sequence[dict[str, Any]], swept: Sequence[str]) -> dict[str, str]:
    template = empty_record("failed", None, "")
    types = {POINT_COLUMN: "int"}
    for k in swept:
        types[k] = _value_type([r[k] for r in rows])
    for c in _record_columns():
        v = template.get(c)
        types[c] = ("float" if isinstance(v, float) else "int" if isinstance(v, int)
                    and not isinstance(v, bool) else "str")
    return types


def write_table(out: Path, rows: Sequence[dict[str, Any]], swept: Sequence[str]) -> None:
    """Write ``results.parquet`` and ``results.csv`` into ``out``, each atomically."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    types = _column_types(rows, swept)
    arrow = {"int": pa.int64(), "float": pa.float64(), "bool": pa.bool_(), "str": pa.string()}
    columns = {}
    for name, kind in types.items():
        cells = [_cell(r.get(name)) for r in rows]
        if kind == "float":
            cells = [math.nan if c is None else float(c) for c in cells]
        elif kind == "str":
            cells = [None if c is None else str(c) for c in cells]
        columns[name] = pa.array(cells, type=arrow[kind])
    table = pa.table(columns)
    atomic_write_with(out / PARQUET_FILE, lambda tmp: pq.write_table(table, tmp))
    with atomic_open(out / CSV_FILE) as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(list(types))
        for r in rows:
            w.writerow([_csv_cell(_cell(r.get(name))) for name in types])


def _csv_cell(value: Any) -> Any:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return ""
    return repr(value) if isinstance(value, float) else value


def read_table(out: Path) -> list[dict[str, Any]]:
    """Return the rows of ``out/results.parquet`` (dicts by column name).

    Raises
    ------
    InvalidInputError
        There is no results table in ``out``.
    """
    import pyarrow.parquet as pq

    from ..errors import InvalidInputError

    path = out / PARQUET_FILE
    if not path.is_file():
        raise InvalidInputError(f"{out} holds no sweep results ({PARQUET_FILE} is missing); "
                                "run 'dualarm-qp sweep SWEEP.yaml --out DIR' first")
    return list(pq.read_table(path).to_pylist())
