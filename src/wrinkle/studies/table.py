"""The study table: one row per variant, as CSV (always) and Parquet (with pyarrow).

Columns: ``variant`` (from 1), the parameters by their paths, the quantities (those of
``collect`` in its order, or every quantity any variant has, in the order first met), then
``status``, ``message``, ``seconds`` and ``folder``. A quantity a row does not have (a failed
variant) is empty in the CSV and null in Parquet. Both files are written to a temporary file
and moved into place, so an interrupted study leaves the table of the variants done so far.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from wrinkle.output import atomic_write

__all__ = ["CSV_FILE", "PARQUET_FILE", "columns", "write_table"]

CSV_FILE = "study.csv"
PARQUET_FILE = "study.parquet"
TRAILING = ("status", "message", "seconds", "folder")


def columns(
    rows: Sequence[dict[str, Any]], parameters: Sequence[str], collect: Sequence[str] | None
) -> list[str]:
    """The table's column names (the module docstring)."""
    if collect is not None:
        quantities = list(collect)
    else:
        fixed = {"variant", *parameters, *TRAILING}
        quantities = list(dict.fromkeys(k for row in rows for k in row if k not in fixed))
    return ["variant", *parameters, *quantities, *TRAILING]


def _cell(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return ""
    return "" if value is None else value


def write_table(
    rows: Sequence[dict[str, Any]],
    out: str | os.PathLike,
    parameters: Sequence[str],
    collect: Sequence[str] | None = None,
) -> list[Path]:
    """Write ``rows`` as OUT/study.csv and, where pyarrow is installed, OUT/study.parquet;
    returns the paths written."""
    out = Path(out)
    names = columns(rows, parameters, collect)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(names)
    for row in rows:
        writer.writerow([_cell(row.get(name)) for name in names])
    text = buffer.getvalue()

    def write_csv(temporary: Path) -> None:
        temporary.write_text(text, encoding="utf-8")

    atomic_write(out / CSV_FILE, write_csv)
    written = [out / CSV_FILE]
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    table = {}
    for name in names:
        values = [row.get(name) for row in rows]
        text_column = name in ("status", "message", "folder")
        table[name] = pa.array(
            [None if v is None else (str(v) if text_column else float(v)) for v in values],
            type=pa.string() if text_column else pa.float64(),
        )
    atomic_write(
        out / PARQUET_FILE, lambda temporary: pq.write_table(pa.table(table), str(temporary))
    )
    written.append(out / PARQUET_FILE)
    return written
