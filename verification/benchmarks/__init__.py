"""The gallery's benchmarks, one module each with a ``BENCHMARK`` (``verification.report``):
it solves its case file (``verification/cases/<name>.toml``) with wrinkle, compares with its
reference (``verification.references``) and returns the report's rows, figures and text. The
order of the report is the registry of ``python -m verification``."""

__all__: list[str] = []
