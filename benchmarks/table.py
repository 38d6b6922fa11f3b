"""Writing a benchmark's table as CSV (shared by the scripts in this folder)."""

from __future__ import annotations

import csv


def write_csv(path: str, rows: list[dict], fields: list[str]) -> None:
    """Write ``rows`` (dicts) with the columns ``fields`` to ``path`` and say so."""
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=fields, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {path}")
