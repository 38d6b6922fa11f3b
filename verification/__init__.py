"""wrinkle's verification gallery: the laboratory, kept in the repository, not installed.

- ``verification.references``: independent reference solutions (closed forms, relaxed-energy
  minimisation), each with its derivation; they share no code with the element's wrinkling
  routine;
- ``verification.benchmarks``: one module per benchmark, which solves its case file with
  wrinkle, compares with its reference and returns the report's rows, figures and text;
- ``verification.cases``: the benchmarks' case files (``<name>.toml``);
- ``verification.report``: the framework (checks, convergence studies, the report);
- ``verification.paper_test``: the paper's shear-stretch sequence, shared by the benchmark and
  ``examples/paper_test.py``.

Run it from a checkout with ``python -m verification [--quick] [--only NAME] [--out DIR]``;
the installed package (``wrinkle``) imports nothing from here.
"""

__all__: list[str] = []
