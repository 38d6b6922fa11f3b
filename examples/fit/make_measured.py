"""Make measured.csv: the sheet of sheet.toml solved with its own (the "true") parameters,
E_L = 50, E_T = 5, G_LT = 2 N/mm^2 and fibres at 30 degrees, with Gaussian noise of 1 % of
each column's largest value added (seed 2). A stand-in for a measured pull-and-shear test;
``wrinkle fit fit.toml`` identifies the parameters back from it.

    python make_measured.py
"""

import csv
import tempfile
from pathlib import Path

import numpy as np

from wrinkle import open_results, read_case

HERE = Path(__file__).parent
COLUMNS = {  # measured column: the history.csv column it is
    "Fx_N": "pulled edge_Fx",
    "Fy_N": "pulled edge_Fy",
    "ux_mm": "quarter line_ux",
    "uy_mm": "quarter line_uy",
}
PULL_MM = 4.0  # the pulled edge's displacement along the sheet at load factor 1


def main() -> None:
    with tempfile.TemporaryDirectory() as scratch:
        read_case(HERE / "sheet.toml").run(scratch)
        history = open_results(scratch).history
    rng = np.random.default_rng(2)
    table = {"pull_mm": PULL_MM * np.asarray(history["load_factor"])}
    for name, column in COLUMNS.items():
        values = np.asarray(history[column])
        table[name] = values + 0.01 * np.abs(values).max() * rng.standard_normal(values.size)
    with open(HERE / "measured.csv", "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(table)
        for row in zip(*table.values(), strict=True):
            writer.writerow([f"{v:.6g}" for v in row])


if __name__ == "__main__":
    main()
